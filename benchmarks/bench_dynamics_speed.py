"""Speed of the inverse of the linear dynamics (``python benchmarks/run.py dynamics_speed``).

The stage: a 630 Hz resonance (zeta 0.1, the compare twin's) and 3 % creep in four modes
(4 ms to 2 s) at 20 kHz, behind the paper's MPI model as one pair (``HammersteinModel``);
the inverse filter has 17 taps and four creep modes.

* Batch: the inverse filter's kernel (:func:`hystcomp._kernels.dynamics.inverse_run`) over a
  million samples, against a C99 version of the same algorithm with a circular delay line
  (``benchmarks/c/inverse_dynamics.c``: fixed sizes, parameters and state in a struct)
  compiled here with the compiler licences that numba has (``-O3 -march=native`` and the
  fast-math subset of the kernels, :data:`bench_realtime.C_MATCHED`), one thread. The C runs
  the taps over the circular line in the three ways an engineer writes it (the line held
  twice over and one loop, the kernel's way; two contiguous runs; one loop whose index
  wraps); the fastest of the three in this run is the reference (target: the kernel within
  1.5x of its time). The outputs must agree to 1e-9 µm and the clamp counts exactly. For
  information: the whole compensator with dynamics in blocks (``stepper().step_block``)
  and as ``hystcomp export-c`` writes it, built with the same flags.
* Streaming: one ``step`` of the compensator with dynamics (the filter, then the MPI
  compensator) from a Python loop (target < 200 ns), beside the empty compiled call bound
  the same way (a kernel that returns its input, over two packed arrays, behind the same
  type test of the sample): the floor of any call from Python, measured in the same rounds.
  The MPI compensator's own ``step`` is given beside them, for information.

The reference is a 100 Hz triangle from 5 % below to 5 % above the filter's output range
(the clamp cuts a few samples at each turn). A reference held beyond an end of the range for
seconds is a slower case for any implementation: the creep lags then decay towards the
end's value, and where that is 0 they pass through subnormal numbers, which the processor
computes far more slowly (the C as much as the kernel: about 200 ns a sample for both
here, held at 5 % below the range after the triangle's first turns).

Times are the best of several interleaved runs; ratios come from the same run.
"""

from __future__ import annotations

import ctypes
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numba
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.bench_realtime import C_MATCHED, ExportedC, best_of, row

import hystcomp
from hystcomp._kernels import dynamics as dk
from hystcomp._kernels.chain import CLAMP_TOLERANCE
from hystcomp.models.hammerstein import HammersteinModel

HERE = Path(__file__).resolve().parent
CC = shutil.which("cc")
N_SAMPLES = 1_000_000
STEP_SAMPLES = 20_000
REPEAT = 11
FS = 20_000.0
BATCH_TARGET = 1.5  # kernel time / the fastest C time
STEP_TARGET_NS = 200.0


def compensator():
    """The paper's MPI model and the compare twin's linear part, as one pair, inverted."""
    dynamics = hystcomp.LinearDynamics.from_parameters(
        sample_rate=FS,
        resonance_hz=630.0,
        damping_ratio=0.1,
        creep_time_constants=[0.004, 0.04, 0.4, 2.0],
        creep_weights=[0.0075] * 4,
    )
    return HammersteinModel(hystcomp.presets.paper_mpi(), dynamics).inverse()


def reference(inverse, n: int) -> np.ndarray:
    """A 100 Hz triangle (µm) from 5 % below to 5 % above the filter's output range."""
    low, high = inverse.output_range
    phase = (np.arange(n) * 100.0 / FS) % 1.0
    return low - 0.05 * (high - low) + 1.1 * (high - low) * (1.0 - np.abs(2.0 * phase - 1.0))


def run() -> list[dict]:
    comp = compensator()
    x = reference(comp.dynamics_inverse, N_SAMPLES)
    with tempfile.TemporaryDirectory() as tmp:
        rows = batch_rows(comp, x, Path(tmp))
    return rows + step_rows(comp, x[:STEP_SAMPLES])


# ----------------------------------------------------------------------------- batch


class ReferenceC:
    """``benchmarks/c/inverse_dynamics.c`` built for the filter's sizes, loaded with its
    parameters; ``run(variant, x, out)`` runs ``ref_run_<variant>`` from rest."""

    VARIANTS = ("twice", "split", "wrap")

    def __init__(self, inverse, tmp: Path):
        p = inverse.packed
        n, m = int(p[dk.N_FIR]), int(p[dk.N_CREEP])
        lib = tmp / "inverse_dynamics.so"
        sizes = [f"-DN_FIR={n}", f"-DN_CREEP={m}"]
        cmd = [CC, "-std=c99", *C_MATCHED, *sizes, "-shared", "-fPIC", "-o", str(lib)]
        subprocess.run([*cmd, str(HERE / "c" / "inverse_dynamics.c")], check=True)
        self._lib = ctypes.CDLL(str(lib))
        taps, line, creep = (
            (ctypes.c_double * n),
            (ctypes.c_double * (2 * n)),
            (ctypes.c_double * m),
        )
        scalars = ("scale", "direct", "low", "high", "bias", "tol")
        fields = [("h", taps), ("a", creep), ("c", creep)]
        fields += [(name, ctypes.c_double) for name in scalars]
        fields += [("line", line), ("lag", creep), ("head", ctypes.c_long)]
        fields += [("clamped", ctypes.c_double)]
        state_type = type("ref_filter", (ctypes.Structure,), {"_fields_": fields})
        a0 = dk.HEADER + n
        low, high = p[dk.LOW], p[dk.HIGH]
        self._initial = state_type(
            taps(*p[dk.HEADER : a0]),
            creep(*p[a0 : a0 + m]),
            creep(*p[a0 + m : a0 + 2 * m]),
            p[dk.SCALE],
            p[dk.DIRECT],
            low,
            high,
            p[dk.BIAS],
            CLAMP_TOLERANCE * (high - low),
            line(*[inverse.rest] * (2 * n)),
            creep(*[inverse.rest] * m),
            0,
            0.0,
        )
        self._state = state_type()

    def run(self, variant: str, x: np.ndarray, out: np.ndarray) -> None:
        func = getattr(self._lib, f"ref_run_{variant}")
        ctypes.pointer(self._state)[0] = self._initial
        args = (x.ctypes.data, out.ctypes.data)
        func(ctypes.byref(self._state), *map(ctypes.c_void_p, args), ctypes.c_long(x.size))

    @property
    def clamped(self) -> int:
        """The count of clamped outputs of the last run."""
        return int(self._state.clamped)


def batch_rows(comp, x: np.ndarray, tmp: Path) -> list[dict]:
    inverse = comp.dynamics_inverse
    out = {name: np.empty_like(x) for name in ("numba", "pair", "export", *ReferenceC.VARIANTS)}
    state = inverse.packed.copy()

    def kernel():
        state[:] = inverse.packed
        dk.inverse_run(state, x, out["numba"])

    def pair():
        out["pair"] = comp.stepper().step_block(x)

    kernel()  # compile, or load from the cache
    pair()
    funcs = {"numba": kernel, "pair": pair}
    if CC is not None:
        c = ReferenceC(inverse, tmp)
        for variant in ReferenceC.VARIANTS:
            funcs[variant] = lambda v=variant: c.run(v, x, out[v])
        funcs["export"] = lambda: exported.run(x, out["export"])
        exported = ExportedC(comp, tmp, C_MATCHED)
    t = best_of(funcs, REPEAT)
    ns = {name: seconds * 1e9 / x.size for name, seconds in t.items()}
    taps = int(inverse.packed[dk.N_FIR])
    rows = [
        row(f"inverse filter batch ({taps} taps), inverse_run (numba)", ns["numba"], "ns/sample"),
        row(
            "compensator with dynamics, stepper().step_block, for information",
            ns["pair"],
            "ns/sample",
        ),
    ]
    if CC is None:
        return [*rows, row("C reference: skipped, no C compiler 'cc'", np.nan, "")]
    fastest = min(ReferenceC.VARIANTS, key=t.__getitem__)
    ratio = t["numba"] / t[fastest]
    diff = max(float(np.abs(out["numba"] - out[v]).max()) for v in ReferenceC.VARIANTS)
    counted = int(state[dk.clamped_slot(state)])
    dv = float(np.abs(out["pair"] - out["export"]).max())
    return [
        row("C, circular line held twice over, one loop (the kernel's)", ns["twice"], "ns/sample"),
        row("C, circular line, taps in two runs", ns["split"], "ns/sample"),
        row("C, circular line, one loop with a wrapping index", ns["wrap"], "ns/sample"),
        *rows,
        row(
            f"inverse_run time / the fastest C time ({fastest})",
            ratio,
            "x",
            f"<= {BATCH_TARGET:g}",
            ratio <= BATCH_TARGET,
        ),
        row("max |output| difference, inverse_run vs C", diff, "um", "<= 1e-9", diff <= 1e-9),
        row(
            f"clamped outputs, inverse_run - C (of {counted})",
            counted - c.clamped,
            "",
            "== 0",
            counted == c.clamped,
        ),
        row(
            "for information: exported C of the compensator with dynamics, same flags",
            ns["export"],
            "ns/sample",
        ),
        row("max |v| difference, step_block vs export", dv, "V", "<= 1e-9", dv <= 1e-9),
    ]


# ----------------------------------------------------------------------------- streaming


@numba.njit(cache=True, _nrt=False)
def _empty(p, q, u):  # pragma: no cover - compiled
    return u


def step_rows(comp, x: np.ndarray) -> list[dict]:
    samples = x.tolist()
    stepper = comp.stepper()
    alone = comp.hysteresis.stepper()
    floor = _bound(_empty.compile((numba.float64[::1],) * 2 + (numba.float64,)))
    funcs = {}
    for name, step in (("step", stepper.step), ("alone", alone.step), ("empty", floor)):
        step(samples[0])

        def loop(step=step):
            for xk in samples:
                step(xk)

        funcs[name] = loop
    t = best_of(funcs, 3 * REPEAT)
    ns = {name: seconds * 1e9 / len(samples) for name, seconds in t.items()}
    return [
        row(
            "step() of the compensator with dynamics, one call in a Python loop",
            ns["step"],
            "ns",
            f"< {STEP_TARGET_NS:g}",
            ns["step"] < STEP_TARGET_NS,
        ),
        row("the empty compiled call, bound as step is (the floor of a call)", ns["empty"], "ns"),
        row("step() of the MPI compensator alone, for information", ns["alone"], "ns"),
        row("step() with dynamics / the empty compiled call", t["step"] / t["empty"], "x"),
    ]


def _bound(kernel):
    """``kernel`` over two packed arrays behind the type test of a stepper's ``step``."""
    p, q = np.zeros(1), np.zeros(1)

    def step(u):
        if u.__class__ is float:
            return kernel(p, q, u)
        raise TypeError(u)

    return step


if __name__ == "__main__":
    for r in run():
        print(f"{r['name']}: {r['value']:.4g} {r['unit']} (target {r['target']})")
