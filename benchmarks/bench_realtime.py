"""Real-time speed of the compensators (``python benchmarks/run.py realtime``).

* Batch: the paper's inverse MPI (16 dead-zones, 16 plays; ``presets.paper_mpi().inverse()``)
  over a million samples, against a C99 version with the same loop structure as the kernel
  (``benchmarks/c/inverse_mpi_blocks.c``: blocks, dead-zones vectorised over samples, plays
  over operators) compiled here with the compiler licences that numba has: the fast-math subset of the package's
  kernels (:data:`hystcomp._kernels._jit.FASTMATH`: reassociation, contraction, no signed zeros,
  reciprocals; :data:`C_FASTMATH` here) and the host's instruction set (numba compiles for
  the host CPU, so ``-march=native``). That ratio says how far the kernels are from what the
  same loop can do (target: at most 1.5x its time). The same C with plain ``cc -O3`` (no
  fast-math, the generic x86-64 instruction set) is given beside it, labelled, for
  information: it is not a like-for-like reference.
* The same compensator exported with ``hystcomp export-c`` and compiled with the reference's
  flags (:data:`C_MATCHED`).
* Streaming: the cost of one ``Stepper.step`` call from a Python loop, for every model and
  compensator (target < 150 ns), and of one ``step_block`` call of 20 samples into a
  preallocated ``out`` (target < 600 ns for the inverse MPI), each beside the empty compiled
  call made the same way in the same run (a kernel that does nothing, bound as a stepper
  binds its own): what is left above it is the kernel's work and the type tests.
* First use: the cost of the first call in a fresh process, with an empty and with a warm
  on-disk kernel cache.

Times are the best of several runs; ratios come from the same run.
"""

from __future__ import annotations

import ctypes
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numba
import numpy as np

import hystcomp
from hystcomp._kernels import _jit, chain
from hystcomp.codegen import export_c
from hystcomp.models.system import checked_step, fast_block

HERE = Path(__file__).resolve().parent
N_SAMPLES = 1_000_000
REPEAT = 11
CC = shutil.which("cc")
# gcc/clang flags for the fast-math flags of the package's kernels (_jit.FASTMATH:
# reassoc, contract, nsz, arcp; not nnan/ninf, which would drop the finiteness tests).
# -fassociative-math needs -fno-signed-zeros and -fno-trapping-math to take effect.
C_FASTMATH = [
    "-ffp-contract=fast",
    "-fassociative-math",
    "-fno-signed-zeros",
    "-fno-trapping-math",
    "-freciprocal-math",
]
C_MATCHED = ["-O3", "-march=native", *C_FASTMATH]
MATCHED_TARGET = 1.5


def run() -> list[dict]:
    model = hystcomp.presets.paper_mpi()
    comp = model.inverse()
    x = reference(model, N_SAMPLES)
    with tempfile.TemporaryDirectory() as tmp:
        rows = batch_rows(comp, x, Path(tmp))
        rows += first_call_rows(Path(tmp))
    rows += stepper_rows(comp, x)
    return rows


def reference(model, n: int) -> np.ndarray:
    """A seeded random-walk reference in µm, a little beyond the reachable range."""
    x_max = float(model.simulate([0.0, model.voltage_range_[1]])[-1])
    rng = np.random.default_rng(20_000)
    walk = np.cumsum(rng.normal(scale=0.01 * x_max, size=n)) + 0.5 * x_max
    return np.clip(walk, -0.05 * x_max, 1.05 * x_max)


def best_of(funcs: dict, repeat: int = REPEAT) -> dict:
    """The shortest time in s of each of ``funcs`` (name -> callable), over ``repeat`` rounds.

    The rounds interleave the callables, so that a slow spell of a shared machine hits all
    of them alike and the ratios stay fair.
    """
    best = dict.fromkeys(funcs, np.inf)
    for _ in range(repeat):
        for name, func in funcs.items():
            start = time.perf_counter()
            func()
            best[name] = min(best[name], time.perf_counter() - start)
    return best


def row(name, value, unit, target=None, ok=None) -> dict:
    return {"name": name, "value": float(value), "unit": unit, "target": target, "ok": ok}


# ----------------------------------------------------------------------------- batch


def batch_rows(comp, x: np.ndarray, tmp: Path) -> list[dict]:
    outputs = {}

    def timed(name, run):
        out = outputs.setdefault(name, np.empty_like(x))
        return lambda: run(x, out)

    funcs = {
        "numba": timed("numba", lambda u, out: chain.chain_run(comp.packed.copy(), u, out)),
        "simulate": lambda: comp.simulate(x),
    }
    funcs["numba"]()  # compile, or load from the cache
    comp.simulate(x[:10])
    if CC is not None:
        funcs["matched"] = timed("matched", PlainC(comp, tmp, C_MATCHED, "blocks").run)
        funcs["c"] = timed("c", PlainC(comp, tmp, ["-O3"]).run)
        funcs["export"] = timed("export", ExportedC(comp, tmp, C_MATCHED).run)
    t = best_of(funcs)
    ns = {name: seconds * 1e9 / x.size for name, seconds in t.items()}
    rows = [
        row("inverse MPI batch, chain_run (numba)", ns["numba"], "ns/sample"),
        row("inverse MPI batch, Compensator.simulate", ns["simulate"], "ns/sample"),
    ]
    if CC is None:
        return [*rows, row("C reference: skipped, no C compiler 'cc'", np.nan, "")]
    dv_c = float(np.abs(outputs["numba"] - outputs["matched"]).max())
    dv_export = float(np.abs(outputs["numba"] - outputs["export"]).max())
    ratio, ratio_simulate = t["numba"] / t["matched"], t["simulate"] / t["matched"]
    target = f"<= {MATCHED_TARGET:g}"
    return [
        row(
            "inverse MPI batch, C99 in the kernel's loop structure, numba's flags (reference)",
            ns["matched"],
            "ns/sample",
        ),
        *rows,
        row("chain_run time / matched C time", ratio, "x", target, ratio <= MATCHED_TARGET),
        row(
            "simulate time / matched C time",
            ratio_simulate,
            "x",
            target,
            ratio_simulate <= MATCHED_TARGET,
        ),
        row(
            "for information: scalar C loop, plain cc -O3 (no fast-math, generic x86-64)",
            ns["c"],
            "ns/sample",
        ),
        row("for information: chain_run time / plain cc -O3 time", t["numba"] / t["c"], "x"),
        row(
            "exported C (hystcomp export-c), same flags as the reference", ns["export"], "ns/sample"
        ),
        row("max |v| difference, chain_run vs matched C", dv_c, "V", "<= 1e-9", dv_c <= 1e-9),
        row(
            "max |v| difference, chain_run vs export", dv_export, "V", "<= 1e-9", dv_export <= 1e-9
        ),
    ]


def build(sources: list[Path], lib: Path, flags: list[str]) -> ctypes.CDLL:
    cmd = [CC, "-std=c99", *flags, "-shared", "-fPIC", "-o", str(lib), *map(str, sources)]
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    return ctypes.CDLL(str(lib))


class PlainC:
    """``benchmarks/c/inverse_mpi.c`` (``_blocks.c``) loaded with the compensator's parameters."""

    N_DEADZONES = N_PLAYS = 16

    def __init__(self, comp, tmp: Path, flags: list[str], variant: str = ""):
        c = chain.unpack_chain(comp.packed)
        if (c.pre_r.size, c.play_r.size, c.post_r.size) != (self.N_DEADZONES, self.N_PLAYS, 0):
            raise ValueError("the C reference is written for 16 dead-zones then 16 plays")
        name = "inverse_mpi" + (f"_{variant}" if variant else "")
        lib = build([HERE / "c" / f"{name}.c"], tmp / f"{name}{len(flags)}.so", flags)
        self._run = lib.ref_run
        self._run.argtypes = [ctypes.c_void_p] * 3 + [ctypes.c_long]
        doubles = ctypes.c_double * 16
        fields = [(name, doubles) for name in ("dz_r", "dz_w", "play_r", "play_w")]
        scalars = ("in_offset", "out_offset", "low", "high", "max_step")
        fields += [(name, ctypes.c_double) for name in scalars]
        fields += [("y", doubles), ("last", ctypes.c_double)]
        state_type = type("ref_compensator", (ctypes.Structure,), {"_fields_": fields})
        self._initial = state_type(
            doubles(*c.pre_r),
            doubles(*c.pre_w),
            doubles(*c.play_r),
            doubles(*c.play_w),
            *(getattr(c, name) for name in scalars),
            doubles(*c.plays),
            c.state[chain.STATE_LAST],
        )
        self._state = state_type()

    def run(self, x: np.ndarray, out: np.ndarray) -> None:
        ctypes.pointer(self._state)[0] = self._initial
        self._run(ctypes.byref(self._state), x.ctypes.data, out.ctypes.data, x.size)


class ExportedC:
    """The compensator as ``hystcomp export-c`` writes it, with a loop around its step."""

    DRIVER = """#include "bench_comp.h"
void bench_run(const double *x_ref, double *v, long n)
{
    bench_comp_state s;
    long k;
    bench_comp_init(&s);
    for (k = 0; k < n; k++) {
        v[k] = bench_comp_step(&s, x_ref[k]);
    }
}
"""

    def __init__(self, comp, tmp: Path, flags: list[str]):
        _, source = export_c(comp, tmp / "export", prefix="bench_comp")
        driver = tmp / "export" / "driver.c"
        driver.write_text(self.DRIVER)
        self._run = build([source, driver], tmp / "export.so", flags).bench_run
        self._run.argtypes = [ctypes.c_void_p] * 2 + [ctypes.c_long]

    def run(self, x: np.ndarray, out: np.ndarray) -> None:
        self._run(x.ctypes.data, out.ctypes.data, x.size)


# ----------------------------------------------------------------------------- streaming


STEP_TARGET_NS = 150.0
BLOCK_TARGET_NS = 600.0
BLOCK = 20


# Compiled as the step kernels are (_jit.step_kernel) but not cached on disk: a kernel of a
# module loaded from its file would be cached under a name the next run cannot import.
_STEP_FLAGS = {"fastmath": _jit.FASTMATH, "_nrt": False}


@numba.njit(**_STEP_FLAGS)
def _empty_step(p, u):
    """The reference of a step: a compiled call that does nothing, called as a step is."""
    return u


@numba.njit(**_STEP_FLAGS)
def _empty_block(p, u, out, work):
    """The reference of a block call: a compiled block call that does nothing."""
    return 0


def _systems():
    """Every model and compensator a real-time loop steps (name -> system)."""
    mpi, pi, preisach = (
        hystcomp.presets.paper_mpi(),
        hystcomp.presets.paper_pi(),
        hystcomp.presets.paper_preisach(),
    )
    return {
        "inverse MPI": mpi.inverse(),
        "inverse PI": pi.inverse(),
        "Preisach, eq. 10": preisach.inverse(),
        "Preisach, exact inverse": preisach.inverse(method="exact"),
        "MPI model": mpi,
        "PI model": pi,
        "Preisach model": preisach,
    }


def stepper_rows(comp, x: np.ndarray) -> list[dict]:
    """``step()`` of every model and compensator, and ``step_block`` of 20 samples into a
    preallocated ``out``, beside the empty compiled call made the same way (a stepper's bound
    step and block paths around a kernel that does nothing), all in one run."""
    references = x[:20_000]
    volts = 120.0 / float(np.max(np.abs(references))) * np.abs(references)  # forward models
    out = np.empty(BLOCK)
    empty_p = np.zeros(4)
    empty_step = checked_step(_jit.step_function(_empty_step), empty_p)
    empty_block = fast_block(_empty_block, empty_p, empty_p, None)
    funcs = {
        "empty step": _step_loop(empty_step, references),
        "empty block": _block_loop(empty_block, references, out),
    }
    names = []
    for name, system in _systems().items():
        signal = volts if name.endswith("model") else references
        stepper = system.stepper()
        stepper.step(float(signal[0]))  # compile, or load from the cache
        stepper.step_block(signal[:BLOCK].copy(), np.empty(BLOCK))
        funcs[f"step {name}"] = _step_loop(stepper.step, signal)
        funcs[f"block {name}"] = _block_loop(stepper.step_block, signal, out)
        names.append(name)
    t = best_of(funcs, 3 * REPEAT)
    n_blocks = references.size // BLOCK
    step_ns = {k: v / references.size * 1e9 for k, v in t.items()}
    block_ns = {k: v / n_blocks * 1e9 for k, v in t.items()}
    empty = step_ns["empty step"]
    rows = [row("empty compiled call, bound as a stepper's step (reference)", empty, "ns")]
    for name in names:
        ns = step_ns[f"step {name}"]
        target = f"< {STEP_TARGET_NS:g}"
        rows.append(row(f"{name}: Stepper.step, one call in a Python loop", ns, "ns", target,
                        ns < STEP_TARGET_NS))  # fmt: skip
        rows.append(row(f"  {name}: step / empty compiled call", ns / empty, "x"))
    empty = block_ns["empty block"]
    rows.append(row("empty compiled block call, bound as step_block (reference)", empty, "ns"))
    for name in names:
        ns = block_ns[f"block {name}"]
        label = f"{name}: Stepper.step_block({BLOCK} samples, out=...), one call"
        if name == "inverse MPI":  # the compensator of the batch figures above
            rows.append(row(label, ns, "ns", f"< {BLOCK_TARGET_NS:g}", ns < BLOCK_TARGET_NS))
        else:
            rows.append(row(label, ns, "ns"))
    rows.append(row("  inverse MPI: step_block / empty block call",
                    block_ns["block inverse MPI"] / empty, "x"))  # fmt: skip
    return rows


def _step_loop(step, signal: np.ndarray):
    samples = signal.tolist()

    def loop():
        for xk in samples:
            step(xk)

    return loop


def _block_loop(step_block, signal: np.ndarray, out: np.ndarray):
    blocks = list(signal[: signal.size // BLOCK * BLOCK].reshape(-1, BLOCK))  # views, as a loop has

    def loop():
        for b in blocks:
            step_block(b, out)

    return loop


# ----------------------------------------------------------------------------- first use

FIRST_CALL = """
import json, time
start = time.perf_counter()
import hystcomp
imported = time.perf_counter()
comp = hystcomp.presets.paper_mpi().inverse()
comp.simulate([0.0, 1.0])
comp.stepper().step(1.0)
print(json.dumps({"import": imported - start, "first": time.perf_counter() - imported}))
"""


def first_call_rows(tmp: Path) -> list[dict]:
    """Import and first-call times in fresh processes sharing an initially empty cache."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp / "numba-cache"))
    src = str(Path(hystcomp.__file__).resolve().parents[1])  # the hystcomp measured here
    env["PYTHONPATH"] = os.pathsep.join([src, env.get("PYTHONPATH", "")])
    times = []
    for _ in range(2):  # cold, then warm
        done = subprocess.run(
            [sys.executable, "-c", FIRST_CALL], env=env, capture_output=True, text=True, check=True
        )
        times.append(json.loads(done.stdout))
    cold, warm = times
    return [
        row("import hystcomp, fresh process", warm["import"], "s"),
        row("first simulate + step, empty kernel cache", cold["first"], "s"),
        row("first simulate + step, warm kernel cache", warm["first"], "s"),
    ]
