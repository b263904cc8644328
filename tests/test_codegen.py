"""The generated C99 compensators, compiled with the system compiler, against Python."""

from __future__ import annotations

import ctypes
import re
import shutil
import subprocess

import numpy as np
import pytest

import hystcomp
from hystcomp.codegen import export_c, generate_c
from hystcomp.errors import InvalidParameterError
from tests.conftest import invertible_weights, random_walk

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


MODELS = {
    "paper_pi": lambda rng: hystcomp.presets.paper_pi(),
    "paper_mpi": lambda rng: hystcomp.presets.paper_mpi(),
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
    play_w = hystcomp.operators.unpack_chain(comp.packed).play_w
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
    with pytest.raises(InvalidParameterError, match="parent 'missing' must be an existing"):
        export_c(comp, "missing/new")
