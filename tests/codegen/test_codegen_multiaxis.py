"""The C export of a multi-axis compensator: one state struct, the Python stepper's outputs."""

from __future__ import annotations

import ctypes
import shutil
import subprocess

import numpy as np
import pytest

import hystcomp
from hystcomp.codegen.multiaxis import export_multiaxis_c, generate_multiaxis_c
from hystcomp.errors import InvalidTypeError
from hystcomp.models.multiaxis import MultiAxisModel
from tests.conftest import invertible_weights, random_walk

CC = shutil.which("cc")
STRICT = ["-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic"]
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler 'cc' on this machine")

DRIVER = """
#include "{p}.h"

void drive(const double *x_ref, double *v, long n, long n_axes, long reset_at)
{
    {p}_state s;
    long k;
    {p}_init(&s);
    for (k = 0; k < n; k++) {
        if (k == reset_at) {
            {p}_reset(&s);
        }
        {p}_step(&s, x_ref + k * n_axes, v + k * n_axes);
    }
}
"""


def _stage(rng, n_axes):
    """N axes of PI, MPI and Preisach models, coupled by a few percent."""
    axes = []
    mpi = hystcomp.presets.paper_mpi()
    for i in range(n_axes):
        if i % 3 == 0:
            axes.append(
                hystcomp.PrandtlIshlinskii.from_parameters(
                    thresholds=np.linspace(0, 60, 8),
                    weights=invertible_weights(rng, 8, 0.3),
                    voltage_range=(0.0, 120.0),
                )
            )
        elif i % 3 == 1:
            axes.append(mpi)
        else:
            axes.append(hystcomp.presets.paper_preisach())
    coupling = np.eye(n_axes) + rng.uniform(-0.06, 0.06, (n_axes, n_axes)) * (1 - np.eye(n_axes))
    return MultiAxisModel.from_parameters(axes=axes, coupling=coupling)


def _build(compensator, folder, prefix="stage"):
    export_multiaxis_c(compensator, folder, prefix=prefix)
    (folder / "driver.c").write_text(DRIVER.replace("{p}", prefix))
    sources = [*sorted(p.name for p in folder.glob(f"{prefix}*.c")), "driver.c"]
    lib = folder / "libstage.so"
    cmd = [CC, *STRICT, "-shared", "-fPIC", "-o", str(lib), *sources]
    build = subprocess.run(cmd, cwd=folder, capture_output=True, text=True, check=False)
    assert build.returncode == 0, build.stderr
    drive = ctypes.CDLL(str(lib)).drive
    drive.restype = None
    drive.argtypes = [ctypes.c_void_p, ctypes.c_void_p] + [ctypes.c_long] * 3
    return drive


@needs_cc
@pytest.mark.parametrize("n_axes", [2, 3])
def test_c_matches_the_python_stepper_for_n_axes(n_axes, tmp_path, rng):
    model = _stage(rng, n_axes)
    comp = model.inverse()
    reach = np.array([a.reachable_range() for a in model.axes_])
    X = np.column_stack(
        [random_walk(rng, 6000, lo - 0.05 * (hi - lo), hi, 0.01 * (hi - lo)) for lo, hi in reach]
    )
    X[100, 0] = np.nan  # held on every axis it couples into, in C as in Python
    drive = _build(comp, tmp_path)
    v_c = np.empty_like(X)
    reset_at = 4000
    drive(X.ctypes.data, v_c.ctypes.data, X.shape[0], n_axes, reset_at)
    stepper = comp.stepper()
    v_py = np.empty_like(X)
    for k, row in enumerate(X):
        if k == reset_at:
            stepper.reset()
        v_py[k] = stepper.step(row)
    lo = np.array([r[0] for r in comp.voltage_range])
    hi = np.array([r[1] for r in comp.voltage_range])
    assert np.all((v_c >= lo) & (v_c <= hi))
    assert np.abs(v_c - v_py).max() <= 1e-9 * (hi - lo).max()
    assert sum(stepper.clamped_count) > 0  # the walk leaves the reach: the clamp was exercised


def test_one_state_struct_and_the_step_signature():
    rng = np.random.default_rng(1)
    files = generate_multiaxis_c(_stage(rng, 3).inverse(), prefix="xyz")
    header = files["xyz.h"]
    assert "void xyz_step(xyz_state *s, const double *x_ref, double *v);" in header
    assert "xyz_axis1_state axis1;" in header
    assert "xyz_axis3_state axis3;" in header
    assert header.count("} xyz_state;") == 1
    assert set(files) == {"xyz.h", "xyz.c"} | {f"xyz_axis{i}.{e}" for i in (1, 2, 3) for e in "hc"}


def test_the_decoupling_is_written_with_full_precision():
    rng = np.random.default_rng(2)
    comp = _stage(rng, 2).inverse()
    text = generate_multiaxis_c(comp, prefix="xy")["xy.c"]
    for value in np.ravel(comp.decoupling):
        assert repr(float(value)) in text


def test_a_single_axis_compensator_is_refused():
    with pytest.raises(InvalidTypeError, match="multi-axis compensator"):
        generate_multiaxis_c(hystcomp.presets.paper_pi().inverse(), prefix="x")
