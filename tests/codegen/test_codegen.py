"""The generated C99 compensators, compiled with the system compiler, against Python."""

from __future__ import annotations

import ctypes
import platform
import re
import shutil
import subprocess

import numpy as np
import pytest

import hystcomp
from hystcomp._kernels import chain
from hystcomp._kernels import preisach as pk
from hystcomp.codegen import export_c, generate_c
from hystcomp.errors import InvalidParameterError
from hystcomp.identify.excitation import sinusoid_sequence
from hystcomp.models.hammerstein import HammersteinModel
from tests.conftest import invertible_weights, monotone_theta, random_walk

CC = shutil.which("cc")
STRICT = ["-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic"]
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler 'cc' on this machine")

# Runs the generated compensator over a whole reference, with a reset at sample `reset_at`.
DRIVER = """
#include "{p}.h"

unsigned long drive(const double *x_ref, double *v, long n, long reset_at)
{
    {p}_state s;
    long k;
    {p}_init(&s);
    for (k = 0; k < n; k++) {
        if (k == reset_at) {
            {p}_reset(&s);
        }
        v[k] = {p}_step(&s, x_ref[k]);
    }
    return s.nonfinite_count;
}
"""


def _bipolar_pi(rng):
    """5 plays (not a multiple of the kernel's padding) on a bipolar amplifier, with offsets."""
    r = np.array([0.0, 20.0, 55.0, 110.0, 190.0])
    return hystcomp.PrandtlIshlinskii.from_parameters(
        thresholds=r,
        weights=invertible_weights(rng, 5, scale=0.3),
        initial_state=np.array([10.0, 5.0, 0.0, -20.0, 0.0]),
        voltage_range=(-150.0, 150.0),
        input_offset=-150.0,
        output_offset=-118.5,
    )


def _small_mpi(rng):
    """3 plays and a single dead-zone (the loop-free case), with offsets."""
    return hystcomp.ModifiedPrandtlIshlinskii.from_parameters(
        thresholds=[0.0, 0.9, 2.1],
        weights=invertible_weights(rng, 3, scale=10.0),
        deadzone_thresholds=[0.0],
        deadzone_weights=[1.3],
        voltage_range=(0.0, 3.6),
        output_offset=-120.0,
    )


def _descended_mpi(rng):
    """The paper's MPI model with its plays started descended, as the MPI fit may choose:
    non-zero initial states (eq. 26 carries them into the inverse)."""
    params = hystcomp.presets.paper_mpi().parameters()
    params["initial_state"] = np.asarray(params["thresholds"], dtype=float)
    return hystcomp.ModifiedPrandtlIshlinskii.from_parameters(**params)


MODELS = {
    "paper_pi": lambda rng: hystcomp.presets.paper_pi(),
    "paper_mpi": lambda rng: hystcomp.presets.paper_mpi(),
    "descended_mpi": _descended_mpi,
    "bipolar_pi": _bipolar_pi,
    "small_mpi": _small_mpi,
}


def _reference(model, rng, n=20_000):
    """A reference that leaves the reachable range (to hit the clamp), with a few NaNs, infs
    and huge finite samples (whose result may overflow to NaN: held in both languages)."""
    lo, hi = model.voltage_range_
    x = model.simulate(np.linspace(lo, hi, 200))
    span = x.max() - x.min()
    ref = random_walk(rng, n, x.min() - 0.3 * span, x.max() + 0.3 * span, span / 40)
    ref[rng.choice(n, size=12, replace=False)] = np.nan
    ref[[n // 7, n // 3]] = [np.inf, -np.inf]
    ref[[n // 5, n // 2]] = [1.7e308, -1.7e308]
    ref[[n // 9, n // 4]] = [1e200, -1e160]  # beyond the plays' input limit, no overflow
    return ref


def _compile(compensator, folder, prefix):
    export_c(compensator, folder, prefix=prefix)
    (folder / "driver.c").write_text(DRIVER.replace("{p}", prefix))
    lib = folder / f"lib{prefix}.so"
    cmd = [CC, *STRICT, "-shared", "-fPIC", "-o", str(lib), f"{prefix}.c", "driver.c"]
    build = subprocess.run(cmd, cwd=folder, capture_output=True, text=True, check=False)
    assert build.returncode == 0, build.stderr
    drive = ctypes.CDLL(str(lib)).drive
    drive.restype = ctypes.c_ulong
    drive.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_long, ctypes.c_long]
    return drive


def _run_c(drive, x, reset_at=-1):
    x = np.ascontiguousarray(x, dtype=np.float64)
    v = np.empty_like(x)
    held = drive(x.ctypes.data, v.ctypes.data, x.size, reset_at)
    return v, held


def _step_python(comp, x, reset_at=-1):
    """What :func:`_run_c` asks of the C, asked of the Python stepper one sample at a time."""
    s = comp.stepper()
    v = []
    for k, u in enumerate(x):
        if k == reset_at:
            s.reset()
        v.append(s.step(u))
    return np.asarray(v)


@needs_cc
@pytest.mark.parametrize("name", sorted(MODELS))
@pytest.mark.parametrize("slewing", [False, True])
def test_c_matches_python_sample_for_sample(name, slewing, tmp_path, rng):
    model = MODELS[name](rng)
    lo, hi = model.voltage_range_
    # a limit of 1 % of the range per sample binds on this reference
    slew_rate = 0.01 * (hi - lo) * 20_000.0 if slewing else None
    comp = model.inverse(slew_rate=slew_rate, sample_rate=20_000.0)
    x = _reference(model, rng)
    v_c, held = _run_c(_compile(comp, tmp_path, "comp"), x)
    stepper = comp.stepper()
    v_py = stepper.step_block(x)
    np.testing.assert_allclose(v_c, v_py, rtol=0, atol=1e-9)
    assert held == stepper.nonfinite_count >= np.count_nonzero(~np.isfinite(x)) >= 14
    assert v_c.min() == lo  # the reference leaves the range: the clamp is exercised
    assert v_c.max() == hi
    if slewing:
        assert np.abs(np.diff(v_c)).max() <= comp.max_step * (1 + 1e-12)
        assert np.isclose(np.abs(np.diff(v_c)).max(), comp.max_step)  # and it binds


@needs_cc
def test_c_reset_returns_to_the_initial_state(tmp_path, rng):
    model = _bipolar_pi(rng)  # non-zero initial play states (eq. 26 in the C tables)
    comp = model.inverse()
    x = _reference(model, rng, n=4000)
    drive = _compile(comp, tmp_path, "comp")
    v_c, held = _run_c(drive, x, reset_at=2500)
    stepper = comp.stepper()
    first = stepper.step_block(x[:2500])
    stepper.reset()
    second = stepper.step_block(x[2500:])
    np.testing.assert_allclose(v_c, np.concatenate([first, second]), rtol=0, atol=1e-9)
    assert held == stepper.nonfinite_count  # counted since the reset only


@needs_cc
def test_generated_source_is_freestanding_c99(tmp_path):
    comp = hystcomp.presets.paper_mpi().inverse(slew_rate=1e5)
    header, source = export_c(comp, tmp_path / "out", prefix="stage_x")
    text = source.read_text()
    assert re.findall(r"#include\s*(\S+)", text) == ['"stage_x.h"', "<math.h>"]
    assert re.findall(r"#include", header.read_text()) == []
    for word in ("malloc", "calloc", "free(", "printf", "static double", "float "):
        assert word not in text  # no allocation, no I/O, no mutable globals, no single floats
    # an object file alone compiles under the strictest flags, also as C++ for the header
    cmd = [CC, *STRICT, "-c", "stage_x.c", "-o", "stage_x.o"]
    build = subprocess.run(cmd, cwd=header.parent, capture_output=True, text=True, check=False)
    assert build.returncode == 0, build.stderr


def test_parameters_are_written_with_full_precision():
    comp = hystcomp.presets.paper_mpi().inverse()
    _, source = generate_c(comp)
    table = re.search(r"play_w\[16\] = \{([^}]*)\}", source).group(1)
    values = np.array([float(t) for t in table.replace("\n", " ").split(",")])
    play_w = chain.unpack_chain(comp.packed).play_w
    assert np.array_equal(values, play_w)  # 17 significant digits read back exactly


def test_slew_limit_and_range_are_baked_in():
    comp = hystcomp.presets.paper_pi().inverse(slew_rate=1e5, sample_rate=20_000.0)
    header, source = generate_c(comp, prefix="ax", source="pi.json")
    assert "v = s->last + 5.0;" in source  # 1e5 V/s / 20 kHz
    assert "if (v > 120.0)" in source
    assert "from pi.json" in header
    assert "100000 V/s at 20000 Hz" in header
    _, no_slew = generate_c(hystcomp.presets.paper_pi().inverse())
    assert "s->last +" not in no_slew


@pytest.mark.parametrize("prefix", ["1axis", "my-comp", "_x", "", "x y", "ü"])
def test_prefix_must_be_a_c_identifier(prefix):
    comp = hystcomp.presets.paper_pi().inverse()
    with pytest.raises(InvalidParameterError, match="prefix must be a C identifier"):
        generate_c(comp, prefix=prefix)


def test_output_folder_is_made_only_if_its_parent_exists(tmp_path):
    comp = hystcomp.presets.paper_pi().inverse()
    h, c = export_c(comp, tmp_path / "new")
    assert (h.name, c.name) == ("hystcomp_compensator.h", "hystcomp_compensator.c")
    with pytest.raises(InvalidParameterError, match="parent 'missing' is not an existing folder"):
        export_c(comp, "missing/new")
    with pytest.raises(InvalidParameterError, match="exists and is not a folder"):
        export_c(comp, h)  # a file where the folder should be


# --- Preisach compensators (eqs. 1-10): the bounded memory, eq. (10) and the exact inverse ---

# Also returns the memory depth (stored extrema, as PreisachStepper.memory_depth) per sample.
PREISACH_DRIVER = """
#include "{p}.h"

unsigned long drive(const double *x_ref, double *v, long *depth, long n, long reset_at)
{
    {p}_state s;
    long k;
    {p}_init(&s);
    for (k = 0; k < n; k++) {
        if (k == reset_at) {
            {p}_reset(&s);
        }
        v[k] = {p}_step(&s, x_ref[k]);
        depth[k] = s.top + 1;
    }
    return s.nonfinite_count;
}
"""


@pytest.fixture(scope="module")
def identified_preisach():
    """Preisach models identified from a non-polynomial (tanh) Preisach system: a quartic X
    on a bipolar amplifier with a sensor offset, and a 25 x 25 table."""
    _, v = sinusoid_sequence(sample_rate=5_000.0)
    nodes = np.linspace(0.0, 120.0, 61)
    a, b = np.meshgrid(nodes, nodes, indexing="ij")
    table = 0.2 * (a - b) + 9.0 * np.tanh((a - b) / 60.0) ** 2 * (1 + a / 120.0)
    x = hystcomp.Preisach.from_parameters(table=np.tril(table)).simulate(v)
    return {
        "quartic_bipolar": hystcomp.Preisach(degree=4, everett="polynomial", fit_method="auto").fit(
            2.5 * v - 150.0, x - 120.0
        ),
        "table": hystcomp.Preisach(everett="table", fit_method="auto").fit(v, x),
    }


def _preisach_model(name, identified):
    if name == "paper_eq6":  # eq. 6 as printed: X(v, v) != 0
        return hystcomp.presets.paper_preisach()
    if name == "paper_zero_diagonal":
        return hystcomp.presets.paper_preisach(zero_diagonal=True)
    return identified[name]


def _compile_preisach(compensator, folder, prefix="comp", flags=()):
    export_c(compensator, folder, prefix=prefix)
    return build_preisach(folder, prefix, flags)


def build_preisach(folder, prefix, flags=()):
    """Compile the exported ``folder/prefix.c`` with :data:`PREISACH_DRIVER`; returns
    ``run(x, reset_at=-1) -> (v, depth, nonfinite_count)``."""
    (folder / "driver.c").write_text(PREISACH_DRIVER.replace("{p}", prefix))
    lib = folder / f"lib{prefix}.so"
    cmd = [CC, *STRICT, *flags, "-shared", "-fPIC", "-o", str(lib), f"{prefix}.c", "driver.c"]
    build = subprocess.run([*cmd, "-lm"], cwd=folder, capture_output=True, text=True, check=False)
    assert build.returncode == 0, build.stderr
    drive = ctypes.CDLL(str(lib)).drive
    drive.restype = ctypes.c_ulong
    drive.argtypes = [ctypes.c_void_p] * 3 + [ctypes.c_long, ctypes.c_long]

    def run(x, reset_at=-1):
        x = np.ascontiguousarray(x, dtype=np.float64)
        v = np.empty_like(x)
        depth = np.empty(x.size, dtype=np.int64)
        held = drive(x.ctypes.data, v.ctypes.data, depth.ctypes.data, x.size, reset_at)
        return v, depth, held

    return run


def _run_python(compensator, x):
    """The Python stepper, one sample at a time, with its memory depth after each."""
    stepper = compensator.stepper()
    v = np.empty_like(x)
    depth = np.empty(x.size, dtype=np.int64)
    for k, x_k in enumerate(x):
        v[k] = stepper.step(x_k)
        depth[k] = stepper.memory_depth
    return v, depth, stepper.nonfinite_count


def _held(rng, x, fraction=0.3):
    """``x`` with stretches of up to 200 samples held constant: there eq. (10) settles and
    rounding decides the memory's reversals."""
    x = x.copy()
    k = 0
    while k < x.size:
        run = int(rng.integers(1, 200))
        if rng.random() < fraction and np.isfinite(x[k]):
            x[k : k + run] = x[k]
        k += run
    return x


@needs_cc
@pytest.mark.parametrize("name", ["paper_eq6", "paper_zero_diagonal", "quartic_bipolar", "table"])
@pytest.mark.parametrize("method", ["multiplicative", "exact"])
@pytest.mark.parametrize("slewing", [False, True])
def test_preisach_c_matches_python_sample_for_sample(
    name, method, slewing, identified_preisach, tmp_path, rng
):
    model = _preisach_model(name, identified_preisach)
    lo, hi = model.voltage_range_
    slew_rate = 0.01 * (hi - lo) * 20_000.0 if slewing else None
    comp = model.inverse(method=method, slew_rate=slew_rate, sample_rate=20_000.0)
    x = _reference(model, rng, n=40_000)  # nested reversals, beyond the range, NaN, inf
    v_c, depth_c, held = _compile_preisach(comp, tmp_path)(x)
    v_py, depth_py, held_py = _run_python(comp, x)
    np.testing.assert_allclose(v_c, v_py, rtol=0, atol=1e-9)
    assert held == held_py == np.count_nonzero(~np.isfinite(x)) == 14
    assert v_c.min() == lo  # the clamp is exercised (also by the huge finite samples)
    assert v_c.max() == hi
    assert depth_c.max() == depth_py.max() >= 7  # nested reversals were stored
    if slewing:
        assert np.abs(np.diff(v_c)).max() <= comp.max_step * (1 + 1e-12)
        assert np.isclose(np.abs(np.diff(v_c)).max(), comp.max_step)


@needs_cc
@pytest.mark.parametrize("method", ["multiplicative", "exact"])
def test_preisach_c_reset_returns_to_the_initial_state(method, tmp_path, rng):
    model = hystcomp.presets.paper_preisach()
    comp = model.inverse(method=method)
    x = _reference(model, rng, n=6000)
    v_c, depth_c, held = _compile_preisach(comp, tmp_path)(x, reset_at=3500)
    stepper = comp.stepper()
    first = stepper.step_block(x[:3500])
    stepper.reset()
    second = stepper.step_block(x[3500:])
    np.testing.assert_allclose(v_c, np.concatenate([first, second]), rtol=0, atol=1e-9)
    assert held == stepper.nonfinite_count  # counted since the reset only
    assert depth_c[3500] <= 2  # the memory restarted from beta_0 = v_min


def _damped_reversals(rng, x_lo, x_hi, n_bursts=40):
    """Bursts of reversals of shrinking amplitude about random centres in the reachable
    range ``x_lo .. x_hi`` (each minor loop nested in the previous one), between stretches
    of random walk that also leave the range. No reachable sample repeats the one before it
    (a held reference is another test: there the exact inverse's root finder, which the C
    follows only within its tolerance, may store a different tiny loop, and a full memory
    then wipes out a different pair)."""
    span = x_hi - x_lo
    parts = []
    for _ in range(n_bursts):
        centre = rng.uniform(x_lo + 0.3 * span, x_hi - 0.3 * span)
        turns = centre + 0.3 * span * 0.85 ** np.arange(30) * (-1.0) ** np.arange(30)
        parts.append(np.interp(np.arange(29 * 8 + 1) / 8.0, np.arange(30), turns))
        parts.append(random_walk(rng, 300, x_lo - 0.3 * span, x_hi + 0.3 * span, span / 50))
    return np.concatenate(parts)


@needs_cc
@pytest.mark.parametrize("name", ["paper_eq6", "paper_zero_diagonal", "quartic_bipolar", "table"])
@pytest.mark.parametrize("method", ["multiplicative", "exact"])
@pytest.mark.parametrize("slewing", [False, True])
def test_preisach_c_full_memory_behaves_as_python(
    name, method, slewing, identified_preisach, tmp_path, rng
):
    # a memory of 9 extrema (4 stored pairs) overflows on every burst of nested reversals
    bound = 9
    model = _preisach_model(name, identified_preisach)
    lo, hi = model.voltage_range_
    slew_rate = 0.01 * (hi - lo) * 20_000.0 if slewing else None
    bounded = hystcomp.Preisach.from_parameters(**model.parameters(), max_extrema=bound)
    comp = bounded.inverse(method=method, slew_rate=slew_rate, sample_rate=20_000.0)
    x_lo, x_hi = np.percentile(model.simulate(np.linspace(*model.voltage_range_, 200)), [0, 100])
    x = _damped_reversals(rng, x_lo, x_hi)
    x = np.where(rng.random(x.size) < 1e-3, np.nan, x)
    v_c, depth_c, held = _compile_preisach(comp, tmp_path)(x)
    v_py, depth_py, held_py = _run_python(comp, x)
    np.testing.assert_allclose(v_c, v_py, rtol=0, atol=1e-9)
    assert held == held_py > 0
    assert depth_c.max() == depth_py.max() == bound
    assert np.count_nonzero(depth_py == bound) > 100  # full, and wiping out, many times
    # the bound changes the output (else this would not test it): unbounded, it differs
    unbounded = model.inverse(method=method, slew_rate=slew_rate).stepper().step_block(x)
    assert np.abs(v_py - unbounded).max() > 1e-6


def _numba_fuses_multiply_adds() -> bool:
    """Whether numba compiles the kernels for a processor with fused multiply-adds, which
    the generated C mirrors with fma() (x86-64 since 2013, every 64-bit ARM)."""
    if platform.machine().lower() in ("aarch64", "arm64"):
        return True
    try:
        import llvmlite.binding as llvm

        return bool(llvm.get_host_cpu_features().get("fma", False))
    except (ImportError, RuntimeError):  # pragma: no cover - unknown host
        return False


def _eq6_table():
    """Eq. 6 sampled on a 25 x 25 grid: a table whose diagonal X(v, v) is not 0."""
    nodes = np.linspace(0.0, 120.0, 25)
    table = hystcomp.presets.paper_preisach().everett_function(nodes[:, None], nodes[None, :])
    return hystcomp.Preisach.from_parameters(table=table)


# -ffp-contract=fast lets the compiler fuse any a * b + c it likes (the default of GCC's GNU
# modes); -march=native gives it the instructions to do so on x86-64.
CONTRACTING = ("-ffp-contract=fast", *(["-march=native"] if platform.machine() == "x86_64" else []))


@needs_cc
@pytest.mark.skipif(
    not _numba_fuses_multiply_adds(),
    reason="numba does not fuse multiply-adds on this processor, the C's fma() does",
)
@pytest.mark.parametrize("name", ["paper_eq6", "eq6_table"])
@pytest.mark.parametrize("method", ["multiplicative", "exact"])
@pytest.mark.parametrize("flags", [(), CONTRACTING], ids=["iso", "contracting"])
def test_preisach_c_rounds_as_python_on_held_references(name, method, flags, tmp_path, rng):
    # Where eq. (10) settles on a held reference, the sign of a last-bit change of v decides
    # a reversal, and X(v, v) != 0 (eq. 6 as printed) then steps the output by about 1 V.
    # The C writes X and eq. (10) as the compiled kernel evaluates them, so it decides alike,
    # whatever the compiler contracts. (The exact inverse holds its voltage in that step.)
    # After a numba upgrade, a failure here means the kernel is compiled in another order:
    # compare its inspect_asm() with the C of hystcomp/codegen/preisach.py.
    model = hystcomp.presets.paper_preisach() if name == "paper_eq6" else _eq6_table()
    comp = model.inverse(method=method)
    x = _held(rng, _reference(model, rng, n=40_000))
    v_c, depth_c, held = _compile_preisach(comp, tmp_path, flags=flags)(x)
    v_py, depth_py, held_py = _run_python(comp, x)
    np.testing.assert_allclose(v_c, v_py, rtol=0, atol=1e-9)
    assert held == held_py
    if method == "multiplicative":
        np.testing.assert_array_equal(depth_c, depth_py)  # the same decisions, every sample


@needs_cc
def test_preisach_source_is_freestanding_c99(tmp_path):
    comp = _eq6_table().inverse(method="exact", slew_rate=1e5)
    header, source = export_c(comp, tmp_path, prefix="stage_x")
    text = source.read_text()
    assert re.findall(r"#include\s*(\S+)", text) == ['"stage_x.h"', "<math.h>"]
    for word in ("malloc", "calloc", "free(", "printf", "float "):
        assert word not in text
    # file-scope statics are constant tables or functions: no mutable global state
    statics = re.findall(r"^static (.*)$", text, flags=re.MULTILINE)
    assert statics
    assert all(s.startswith("const double ") or "(" in s for s in statics), statics
    assert "double e[1024];" in header.read_text()  # the bound of the memory, in the state
    cmd = [CC, *STRICT, "-c", "stage_x.c", "-o", "stage_x.o"]
    build = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, check=False)
    assert build.returncode == 0, build.stderr


@pytest.mark.parametrize("degree", [1, 2, 3, 5])
def test_preisach_coefficients_are_baked_in_with_full_precision(degree, rng):
    theta = monotone_theta(rng, degree, 120.0, 30.0)  # invertible: every branch rises
    model = hystcomp.Preisach.from_parameters(
        theta=theta, voltage_range=(-20.0, 100.0), output_offset=-3.5, max_extrema=64
    )
    header, source = generate_c(model.inverse(rho=0.25, slew_rate=2e4), prefix="ax")
    n = degree + 1
    table = re.search(rf"ax_everett_coef\[{n * n}\] = \{{([^}}]*)\}}", source).group(1)
    values = np.array([float(v) for v in table.replace("\n", " ").split(",")])
    expected = pk.coefficient_matrix(model.theta_, degree).ravel()
    assert np.array_equal(values, expected)  # 17 significant digits read back exactly
    assert "/ 0.25;" in source  # rho of eq. 10
    assert "(s->h - 3.5)" in source  # x[k-1] = H + x_0
    assert "v = s->last + 1.0;" in source  # 2e4 V/s at 20 kHz
    assert "if (v < -20.0)" in source
    assert f"Everett polynomial of degree {degree}" in header
    assert "rho 0.25 um/V" in header
    assert "double e[64];" in header


def test_preisach_exact_inverse_is_named_in_the_header():
    model = hystcomp.presets.paper_preisach()
    header, source = generate_c(model.inverse(method="exact"))
    assert "exact inverse" in header
    assert "_exact_input(s, x_ref)" in source
    header, source = generate_c(model.inverse())
    assert "inverse multiplicative structure (paper eqs. 7-10)" in header
    assert "_exact_input" not in source


# --- The count of clamped outputs: C's clamped_count against Stepper.clamped_count ---

COUNT_DRIVER = """
#include "{p}.h"

unsigned long count_clamped(const double *x_ref, double *v, long n)
{
    {p}_state s;
    long k;
    {p}_init(&s);
    for (k = 0; k < n; k++) {
        v[k] = {p}_step(&s, x_ref[k]);
    }
    return s.clamped_count;
}
"""


def _creeping(delay=0):
    """Dynamics with a 700 Hz resonance, two creep modes and ``delay`` samples of latency."""
    return hystcomp.LinearDynamics.from_parameters(
        sample_rate=20_000.0,
        resonance_hz=700.0,
        damping_ratio=0.1,
        creep_time_constants=[0.004, 0.4],
        creep_weights=[0.01, 0.01],
        delay_samples=delay,
    )


def _library(comp, folder, driver, entry):
    """``comp`` exported to ``folder`` with ``driver`` (``{p}`` for the prefix), built with
    the strict flags into a shared library: its function ``entry``."""
    export_c(comp, folder, prefix="comp")
    (folder / "driver.c").write_text(driver.replace("{p}", "comp"))
    lib = folder / "libcomp.so"
    cmd = [CC, *STRICT, "-shared", "-fPIC", "-o", str(lib), "comp.c", "driver.c", "-lm"]
    build = subprocess.run(cmd, cwd=folder, capture_output=True, text=True, check=False)
    assert build.returncode == 0, build.stderr
    return getattr(ctypes.CDLL(str(lib)), entry)


def _counting_compensators(identified):
    """Every template's compensator (one with the inverse of the dynamics in front), each
    beside the model it inverts."""
    rng = np.random.default_rng(5)
    mpi = hystcomp.presets.paper_mpi()
    pi = _bipolar_pi(rng)
    dynamics = hystcomp.LinearDynamics.from_parameters(
        sample_rate=20_000.0, resonance_hz=700.0, damping_ratio=0.1
    )
    creeping = _creeping()
    table, quartic = identified["table"], identified["quartic_bipolar"]
    return {
        "bipolar_pi": (pi.inverse(), pi),
        "paper_mpi_slewing": (mpi.inverse(slew_rate=2e5, sample_rate=20_000.0), mpi),
        "paper_mpi_dynamics": (HammersteinModel(mpi, dynamics).inverse(), mpi),
        "preisach_multiplicative": (table.inverse(method="multiplicative"), table),
        "preisach_exact_bipolar": (quartic.inverse(method="exact"), quartic),
        "preisach_exact_dynamics": (
            HammersteinModel(table, creeping).inverse(method="exact"),
            table,
        ),
    }


@needs_cc
@pytest.mark.parametrize(
    "name",
    [
        "bipolar_pi",
        "paper_mpi_slewing",
        "paper_mpi_dynamics",
        "preisach_multiplicative",
        "preisach_exact_bipolar",
        "preisach_exact_dynamics",
    ],
)
def test_c_counts_clamped_outputs_as_python(name, identified_preisach, tmp_path, rng):
    comp, model = _counting_compensators(identified_preisach)[name]
    count = _library(comp, tmp_path, COUNT_DRIVER, "count_clamped")
    count.restype = ctypes.c_ulong
    count.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_long]
    # a reference that leaves the reachable range at both ends, with a few NaNs
    low, high = model.reachable_range()
    span = high - low
    phase = np.linspace(0.0, 8.0 * np.pi, 12_000)
    x = 0.5 * (low + high) + 0.6 * span * np.sin(phase) + rng.normal(0.0, 0.01 * span, phase.size)
    x[rng.choice(x.size, size=8, replace=False)] = np.nan
    v = np.empty_like(x)
    clamped_c = count(x.ctypes.data, v.ctypes.data, x.size)
    stepper = comp.stepper()
    np.testing.assert_allclose(v, stepper.step_block(x), rtol=0, atol=1e-9)
    assert comp.voltage_range[0] == v.min()
    assert v.max() <= comp.voltage_range[1]
    assert clamped_c == stepper.clamped_count
    # the reference is out of reach often (with the dynamics, their inverse's clamp counts)
    assert 0.05 * x.size < clamped_c < 0.9 * x.size


def test_a_model_is_refused_with_the_call_that_exports_its_compensator():
    from hystcomp.codegen import generate_c
    from hystcomp.errors import InvalidTypeError

    with pytest.raises(InvalidTypeError, match=r"model\.inverse\(\)"):
        generate_c(hystcomp.presets.paper_pi())


PRIMED_DRIVER = """
#include "{p}.h"

long run_primed(const double *x_ref, double *v, long n)
{
    {p}_state s;
    long k;
    {p}_init(&s);
    for (k = 0; k < COMP_PREVIEW; k++) {
        {p}_prime(&s, x_ref[k]);
    }
    for (k = COMP_PREVIEW; k < n; k++) {
        v[k - COMP_PREVIEW] = {p}_step(&s, x_ref[k]);
    }
    return COMP_PREVIEW;
}
"""


@needs_cc
@pytest.mark.parametrize(("slewing", "delay"), [(False, 0), (True, 0), (True, 3)])
@pytest.mark.parametrize("name", ["paper_mpi_dynamics", "preisach_exact_dynamics"])
def test_c_primed_on_the_look_ahead_is_the_batch_run(
    name, slewing, delay, identified_preisach, tmp_path
):
    """NAME_prime feeds the look-ahead to the filter alone, as the stepper's prime(): then
    NAME_step gives the batch run (the reference known ahead) from its first sample, slew
    limit included, for a reference that starts away from rest (and a rig's latency)."""
    _, model = _counting_compensators(identified_preisach)[name]
    options = {"slew_rate": 2e5} if slewing else {}
    if model.kind == "preisach":
        options["method"] = "exact"
    comp = HammersteinModel(model, _creeping(delay)).inverse(**options)
    low, high = model.reachable_range()
    t = np.arange(6000) / 20_000.0
    x = low + (high - low) * (0.5 + 0.3 * np.sin(2 * np.pi * 30.0 * t))
    d = comp.preview
    run = _library(comp, tmp_path, PRIMED_DRIVER, "run_primed")
    run.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_long]
    run.restype = ctypes.c_long
    ahead = np.ascontiguousarray(np.r_[x, np.full(d, x[-1])])
    v = np.empty(x.size)
    assert run(ahead.ctypes.data, v.ctypes.data, ahead.size) == d  # the header's NAME_PREVIEW
    batch = comp.simulate(x)
    np.testing.assert_allclose(v, batch, rtol=0, atol=1e-9)
    assert abs(batch[0] - comp.stepper().last_output) > 5.0  # it starts away from rest


@needs_cc
@pytest.mark.parametrize("flag", ["-ffast-math", "-ffinite-math-only"])
def test_a_build_that_would_drop_the_nan_test_stops(flag, tmp_path):
    export_c(hystcomp.presets.paper_mpi().inverse(), tmp_path, prefix="comp")
    cmd = [CC, *STRICT, flag, "-c", "comp.c"]
    build = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, check=False)
    assert build.returncode != 0
    assert "without -ffast-math or -ffinite-math-only" in build.stderr
