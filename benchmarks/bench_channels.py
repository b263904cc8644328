"""Many channels at once: a 1024-actuator mirror (``python benchmarks/run.py channels``).

1024 inverse PI compensators of 16 plays each (the paper's PI model, every channel's weights
jittered by a seeded draw, so that each channel has its own inverse), run by a
:class:`hystcomp.models.channels.ChannelBank`:

* batch: ``ChannelBank.simulate`` over 4000 samples (0.2 s at 20 kHz), and the kernel alone
  (``bank_run``, what ``step_block`` calls);
* stepper: ``BankStepper.step(row)`` from a Python loop, one call per sample for all 1024
  channels (the cost of a 20 kHz loop driving the mirror);

each against ``benchmarks/c/channel_bank.c``, the same loops in C99 compiled here with the
licences numba has (-O3 -march=native and the kernels' fast-math subset), batch and one call
per sample. Target: at most 3 ns per channel-sample, batch and stepper (a 1024-channel step
within 3.1 µs: 6 % of a 20 kHz period). Times are the best of several interleaved rounds.
"""

from __future__ import annotations

import ctypes
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.bench_realtime import C_MATCHED, best_of

import hystcomp
from hystcomp._kernels import channels as ck
from hystcomp.models.channels import ChannelBank

HERE = Path(__file__).resolve().parent
CC = shutil.which("cc")
N_CHANNELS = 1024
N_SAMPLES = 4000
N_STEPS = 2000
REPEAT = 9
TARGET_NS = 3.0


def row(name, value, unit, target=None, ok=None) -> dict:
    return {"name": name, "value": float(value), "unit": unit, "target": target, "ok": ok}


def mirror(n_channels: int = N_CHANNELS, seed: int = 0) -> ChannelBank:
    """A bank of ``n_channels`` inverse PI compensators of 16 plays, weights jittered."""
    base = hystcomp.presets.paper_pi()
    rng = np.random.default_rng(seed)
    comps = []
    for _ in range(n_channels):
        weights = base.weights_ * rng.uniform(0.8, 1.2, base.weights_.size)
        model = hystcomp.PrandtlIshlinskii.from_parameters(
            thresholds=base.thresholds_, weights=weights, voltage_range=base.voltage_range_
        )
        comps.append(model.inverse())
    return ChannelBank(comps)


def references(n: int, n_channels: int = N_CHANNELS, seed: int = 1) -> np.ndarray:
    """Seeded references (µm): a sinusoid per channel, phases drawn, inside the reach."""
    rng = np.random.default_rng(seed)
    phase = rng.uniform(0.0, 2 * np.pi, n_channels)
    t = np.arange(n)[:, None] / 20_000.0
    return np.ascontiguousarray(14.0 + 12.0 * np.sin(2 * np.pi * 50.0 * t + phase[None, :]))


class CBank:
    """``channel_bank.c`` compiled with ``flags``, on the bank's parameters."""

    def __init__(self, bank: ChannelBank, tmp: Path, flags: list[str]):
        lib = tmp / "channel_bank.so"
        cmd = [CC, *flags, "-shared", "-fPIC", str(HERE / "c" / "channel_bank.c"), "-o", str(lib)]
        subprocess.run(cmd, check=True, capture_output=True, text=True)
        self._lib = ctypes.CDLL(str(lib))
        self._run = self._lib.bank_run
        self._run.argtypes = [ctypes.c_void_p] * 7 + [ctypes.c_long] * 3
        (group,) = bank._groups
        self.group = group
        self.plays = group.plays0.copy()
        self.counters = group.counters0.copy()

    def run(self, u: np.ndarray, out: np.ndarray) -> None:
        g = self.group
        self._run(
            g.play_r.ctypes.data,
            g.play_w.ctypes.data,
            g.scalars.ctypes.data,
            self.plays.ctypes.data,
            self.counters.ctypes.data,
            u.ctypes.data,
            out.ctypes.data,
            u.shape[0],
            u.shape[1],
            g.play_r.shape[0],
        )


def run() -> list[dict]:
    bank = mirror()
    x = references(N_SAMPLES)
    (group,) = bank._groups
    stepper = bank.stepper()
    out = np.empty_like(x)
    work = np.empty((2, ck.CHANNEL_BLOCK))
    plays, counters = group.plays0.copy(), group.counters0.copy()

    def kernel():
        ck.bank_run(*group.params(), group.scalars, plays, counters, x, out, work)

    def steps():
        step = stepper.step
        for k in range(N_STEPS):
            step(x[k])

    funcs = {"simulate": lambda: bank.simulate(x), "kernel": kernel, "step": steps}
    kernel()
    steps()
    rows_c = []
    with tempfile.TemporaryDirectory() as tmp:
        if CC is not None:
            c = CBank(bank, Path(tmp), C_MATCHED)
            c_out = np.empty_like(x)
            c_row = np.empty((1, N_CHANNELS))
            funcs["c batch"] = lambda: c.run(x, c_out)

            def c_steps():
                for k in range(N_STEPS):
                    c.run(x[k : k + 1], c_row)

            funcs["c step"] = c_steps
            c.run(x, c_out)
            ours = bank.simulate(x)
            rows_c.append(
                row("largest difference, kernel against C", np.abs(ours - c_out).max(), "V")
            )
        t = best_of(funcs, REPEAT)
    per = N_SAMPLES * N_CHANNELS
    ns = {
        "simulate": t["simulate"] / per * 1e9,
        "kernel": t["kernel"] / per * 1e9,
        "step": t["step"] / (N_STEPS * N_CHANNELS) * 1e9,
    }
    target = f"<= {TARGET_NS:g}"
    rows = [
        row(
            "1024 x 16-play channels, batch (ChannelBank.simulate)",
            ns["simulate"],
            "ns/channel-sample",
            target,
            ns["simulate"] <= TARGET_NS,
        ),
        row("1024 x 16-play channels, batch kernel (bank_run)", ns["kernel"], "ns/channel-sample"),
        row(
            "1024 x 16-play channels, stepper (BankStepper.step per sample)",
            ns["step"],
            "ns/channel-sample",
            target,
            ns["step"] <= TARGET_NS,
        ),
    ]
    if CC is None:
        return [*rows, row("C reference: skipped, no C compiler 'cc'", np.nan, "")]
    c_batch = t["c batch"] / per * 1e9
    c_step = t["c step"] / (N_STEPS * N_CHANNELS) * 1e9
    return [
        row(
            "C99, the kernel's loops, numba's flags: batch (reference)",
            c_batch,
            "ns/channel-sample",
        ),
        row(
            "C99, the kernel's loops: one call per sample (reference)", c_step, "ns/channel-sample"
        ),
        *rows,
        row("batch kernel time / C batch time", t["kernel"] / t["c batch"], "x"),
        row("stepper time / C per-sample time", t["step"] / t["c step"], "x"),
        *rows_c,
    ]


if __name__ == "__main__":
    for r in run():
        print(f"{r['name']:<70} {r['value']:10.4g} {r['unit']}  {r['target'] or ''}")
