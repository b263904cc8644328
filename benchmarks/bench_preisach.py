"""Speed of the classical Preisach model and its compensators (``python benchmarks/bench_preisach.py``).

* Flatness: the forward model's cost per sample on a plain triangle (a memory of 2 extrema)
  and on a decaying oscillation with 50 nested extrema (a memory of 51) of the same length.
  The kernel keeps prefix sums of the closed pairs' contributions, so the second must cost no
  more than the first (target: ratio <= 1.25, timing noise included). For contrast, the cost
  of evaluating eqs. (3)-(4) by summing over the memory at every sample (a compiled loop) on
  the same signal.
* The compensators per sample: the inverse multiplicative structure (eq. 10) and the exact
  inverse, on a triangle reference, against the same compensator exported as C
  (``hystcomp.codegen``), built with the compiler licences that numba has, as in
  ``bench_realtime.py``: ``cc -O3 -march=native`` (numba compiles for the host CPU too) and
  the fast-math subset of the kernels (:data:`bench_realtime.C_FASTMATH`), and run over the
  same reference by a C loop: target at most 1.5x the C time. The C has the parameters
  baked in as constants (the reciprocal of eq. 10's ``rho`` among them); the kernel reads
  them from the packed array.
* Streaming: the cost of one ``Stepper.step`` call in a Python loop, written as in
  ``bench_realtime.py`` (``for xk in samples: stepper.step(xk)``), for the forward model and
  both compensators; target < 300 ns, as for the PI/MPI stepper. The call includes the
  sample's work, so the exact inverse, which solves for a root at every sample, costs its batch
  time per sample more than the others. For contrast, the inverse MPI's stepper in the same
  rounds.

* The longest step of the exported C with the memory full (:func:`_worst_step_rows`), with
  numba's flags and with plain ``cc -O2``: information, for the 20 kHz budget of 50 µs.

Times are the best of several runs, on the paper's model (``presets.paper_preisach()``).
Rows: ``name``, ``value``, ``unit``, ``target`` (``"<= x"`` or None), ``ok`` (bool or None).
"""

from __future__ import annotations

import ctypes
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numba
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.bench_realtime import C_FASTMATH, best_of

from hystcomp import presets
from hystcomp._kernels import preisach as pk
from hystcomp.codegen import export_c

N_SAMPLES = 1_000_000
REPEAT = 7
STEP_SAMPLES = 100_000  # 2.5 periods of the triangle
SAMPLE_PERIOD_NS = 50_000.0  # 20 kHz
CC = shutil.which("cc")
C_FLAGS = ["-O3", "-march=native", *C_FASTMATH]  # numba's licences, as bench_realtime
C_TARGET = 1.5  # numba kernel time / exported C time


def run() -> list[dict]:
    model = presets.paper_preisach()
    triangle = _piecewise_linear(np.r_[np.tile([0.0, 120.0], 25), 0.0], N_SAMPLES)
    extrema = 60.0 + 60.0 * (-1.0) ** np.arange(51) * 0.93 ** np.arange(51)
    decaying = _piecewise_linear(extrema, N_SAMPLES)

    packed = model._packed()
    t_triangle = _per_sample(packed, triangle)
    t_decaying = _per_sample(packed, decaying)
    depth = _final_depth(packed, decaying)
    t_naive = _per_sample_naive(model, decaying)
    rows = [
        _row("forward, triangle (memory of 2)", t_triangle, "ns/sample"),
        _row(f"forward, decaying oscillation (memory of {depth})", t_decaying, "ns/sample"),
        _row("forward cost ratio, nested / plain", t_decaying / t_triangle, "x", 1.25),
        _row("for contrast: eqs. (3)-(4) summed anew each sample, nested", t_naive, "ns/sample"),
    ]
    x_ref = 1.0 + model.simulate(triangle) * 0.9
    for method in ("multiplicative", "exact"):
        comp = model.inverse(method=method)
        rows += _compensator_rows(comp, method, x_ref)
    rows += _stepper_rows(model, triangle, x_ref)
    if CC is not None:
        rows += _worst_step_rows(model)
    return rows


TIMED_DRIVER = """#define _POSIX_C_SOURCE 199309L
#include <time.h>
#include "bench_preisach.h"
void bench_timed(const double *x_ref, double *v, double *ns, long n)
{
    static bench_preisach_state s;
    struct timespec a, b;
    long k;
    bench_preisach_init(&s);
    for (k = 0; k < n; k++) {
        clock_gettime(CLOCK_MONOTONIC, &a);
        v[k] = bench_preisach_step(&s, x_ref[k]);
        clock_gettime(CLOCK_MONOTONIC, &b);
        ns[k] = (double)(b.tv_sec - a.tv_sec) * 1e9 + (double)(b.tv_nsec - a.tv_nsec);
    }
}
"""
#: Cycles of the worst-case reference of :func:`_worst_step_rows`.
WORST_CYCLES = 20


def _worst_step_rows(model) -> list[dict]:
    """The longest step of the exported C (numba's flags, each step timed with
    ``clock_gettime``): a reference whose reversals fill the memory (1024 extrema, nested,
    8 samples per branch), then a rise to the top that wipes it all out, repeated; the
    median over the cycles of each cycle's longest step, and the median step, against the
    20 kHz period (information: the mean is what the rows above time)."""
    k = np.arange(model.max_extrema)
    nested = 60.0 + 60.0 * (-1.0) ** k * (1.0 - (k + 1) / (model.max_extrema + 2))
    cycle = np.r_[np.repeat(nested, 8), np.linspace(nested[-1], 120.0, 8), np.full(8, 0.0)]
    x_ref = 1.0 + 0.9 * model.simulate(np.tile(cycle, WORST_CYCLES))
    rows = []
    builds = {"numba's flags": C_FLAGS, "cc -O2 (the docs' build)": ["-O2"]}
    for method in ("multiplicative", "exact"):
        comp = model.inverse(method=method)
        for build, flags in builds.items():
            with tempfile.TemporaryDirectory() as tmp:
                timed = _exported_c(comp, Path(tmp), TIMED_DRIVER, "bench_timed", 3, flags)
                v, ns = np.empty_like(x_ref), np.empty_like(x_ref)
                timed(x_ref.ctypes.data, v.ctypes.data, ns.ctypes.data, x_ref.size)
            worst = float(np.median(ns.reshape(WORST_CYCLES, -1).max(axis=1)))
            name = f"compensator '{method}', exported C, {build}"
            rows += [
                _row(f"{name}, worst step, memory full", worst / 1e3, "us"),
                _row(f"{name}, median step", np.median(ns), "ns"),
            ]
    return rows


DRIVER = """#include "bench_preisach.h"
void bench_run(const double *x_ref, double *v, long n)
{
    static bench_preisach_state s; /* about 16 kB: not on the stack */
    long k;
    bench_preisach_init(&s);
    for (k = 0; k < n; k++) {
        v[k] = bench_preisach_step(&s, x_ref[k]);
    }
}
"""


def _compensator_rows(comp, method: str, x_ref: np.ndarray) -> list[dict]:
    """Batch cost per sample of the numba kernel and, if there is a C compiler, of the
    exported C over the same reference, timed in interleaved rounds."""
    out = np.empty_like(x_ref)
    funcs = {"numba": lambda: pk.preisach_run(comp.packed.copy(), x_ref, out)}
    with tempfile.TemporaryDirectory() as tmp:
        if CC is not None:
            run_c = _exported_c(comp, Path(tmp))
            out_c = np.empty_like(x_ref)
            funcs["c"] = lambda: run_c(x_ref.ctypes.data, out_c.ctypes.data, x_ref.size)
        t = {name: value / x_ref.size * 1e9 for name, value in _best_of(funcs).items()}
    rows = [_row(f"compensator '{method}', batch", t["numba"], "ns/sample", SAMPLE_PERIOD_NS / 50)]
    if CC is None:
        return [*rows, _row("exported C reference: skipped, no C compiler 'cc'", np.nan, "")]
    ratio = t["numba"] / t["c"]
    dv = float(np.abs(out - out_c).max())
    return [
        _row(f"compensator '{method}', exported C, numba's flags (reference)", t["c"], "ns/sample"),
        *rows,
        _row(f"compensator '{method}', numba time / exported C time", ratio, "x", C_TARGET),
        _row(f"compensator '{method}', max |v| difference numba vs C", dv, "V", 1e-9),
    ]


def _exported_c(comp, tmp: Path, driver_text=DRIVER, entry="bench_run", arrays=2, flags=None):
    """The exported C of ``comp`` with a driver, built with numba's flags (or ``flags``):
    the driver's function ``entry``, which takes ``arrays`` pointers to doubles and a count."""
    _, source = export_c(comp, tmp, prefix="bench_preisach")
    driver = tmp / "driver.c"
    driver.write_text(driver_text)
    lib = tmp / "bench_preisach.so"
    flags = C_FLAGS if flags is None else flags
    cmd = [CC, "-std=c99", *flags, "-shared", "-fPIC", "-o", str(lib), str(source), str(driver)]
    subprocess.run([*cmd, "-lm"], check=True, capture_output=True, text=True)
    run = getattr(ctypes.CDLL(str(lib)), entry)
    run.argtypes = [ctypes.c_void_p] * arrays + [ctypes.c_long]
    return run


def _best_of(funcs: dict, repeat: int = REPEAT) -> dict:
    """:func:`bench_realtime.best_of` after one call of each (compile, or load from the cache)."""
    for func in funcs.values():
        func()
    return best_of(funcs, repeat)


def _stepper_rows(model, v: np.ndarray, x_ref: np.ndarray) -> list[dict]:
    """Per-call cost of ``Stepper.step`` from Python, in rounds interleaved over the steppers."""
    n = STEP_SAMPLES
    mpi = presets.paper_mpi()
    runs = [  # name, stepper, samples, target in ns
        ("forward model", model.stepper(), v[:n], 300),
        ("compensator 'multiplicative'", model.inverse().stepper(), x_ref[:n], 300),
        ("compensator 'exact'", model.inverse(method="exact").stepper(), x_ref[:n], 300),
        ("for contrast: inverse MPI", mpi.inverse().stepper(), mpi.simulate(v[:n]), None),
    ]

    def loop(stepper, samples):
        def call():
            stepper.reset()
            for xk in samples:
                stepper.step(xk)

        return call

    funcs = [loop(stepper, u.tolist()) for _, stepper, u, _ in runs]
    for func in funcs:
        func()  # compile, or load from the cache
    best = [np.inf] * len(funcs)
    for _ in range(REPEAT):  # a slow spell of the machine hits every stepper alike
        for i, func in enumerate(funcs):
            start = time.perf_counter()
            func()
            best[i] = min(best[i], time.perf_counter() - start)
    return [
        _row(f"{name}, Stepper.step from Python", t / n * 1e9, "ns/call", target, strict=True)
        for (name, _, _, target), t in zip(runs, best, strict=True)
    ]


def _row(name, value, unit, target=None, *, strict=False):
    if target is None:
        return {"name": name, "value": float(value), "unit": unit, "target": None, "ok": None}
    ok = value < target if strict else value <= target
    sign = "<" if strict else "<="
    return {
        "name": name,
        "value": float(value),
        "unit": unit,
        "target": f"{sign} {target:g}",
        "ok": bool(ok),
    }


def _piecewise_linear(turning: np.ndarray, n: int) -> np.ndarray:
    knots = np.linspace(0.0, 1.0, turning.size)
    return np.interp(np.linspace(0.0, 1.0, n), knots, turning)


def _best(func, repeat: int = REPEAT) -> float:
    func()  # compile and warm up
    best = np.inf
    for _ in range(repeat):
        start = time.perf_counter()
        func()
        best = min(best, time.perf_counter() - start)
    return best


def _per_sample(packed: np.ndarray, u: np.ndarray) -> float:
    out = np.empty_like(u)

    def call():
        pk.preisach_run(packed.copy(), u, out)

    return _best(call) / u.size * 1e9


def _final_depth(packed: np.ndarray, u: np.ndarray) -> int:
    p = packed.copy()
    pk.preisach_run(p, u, np.empty_like(u))
    return int(p[pk.state_start(p) + pk.ST_TOP]) + 1


@numba.njit(cache=True)
def _naive_run(p, u, out):
    """Eqs. (3)-(4) with the closed pairs summed over the whole memory at every sample."""
    s = pk.state_start(p)
    e = s + pk.N_STATE
    for k in range(u.size):
        pk.preisach_apply(p, u[k])
        top = int(p[s + pk.ST_TOP])
        acc = 0.0
        for j in range(1, top + 1):
            if j % 2 == 1:
                acc += pk.everett(p, p[e + j], p[e + j - 1])
            else:
                acc -= pk.everett(p, p[e + j - 1], p[e + j])
        out[k] = acc
    return out


def _per_sample_naive(model, u: np.ndarray) -> float:
    packed = model._packed()
    out = np.empty_like(u)
    return _best(lambda: _naive_run(packed.copy(), u, out)) / u.size * 1e9


def main() -> None:
    rows = run()
    width = max(len(r["name"]) for r in rows)
    for r in rows:
        verdict = "" if r["ok"] is None else ("ok" if r["ok"] else "MISSED")
        target = r["target"] or ""
        print(f"{r['name']:<{width}}  {r['value']:10.4g} {r['unit']:<10} {target:<10} {verdict}")


if __name__ == "__main__":
    main()
