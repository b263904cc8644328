"""Speed of the main job: ``hystcomp compare``, the paper's whole experiment on the twin.

Two runs, each a fresh process as a user would start it, writing into a temporary folder:

* cold: an empty numba kernel cache, in a new temporary folder (``NUMBA_CACHE_DIR``), so
  every kernel the command needs is compiled (a first run after installing);
* warm: the same command again, the kernels loaded from the cache the first run filled;
  the median of :data:`WARM_RUNS` runs (a shared machine's load moves one run by up to
  1.5x), with the slowest beside it.

Targets: under 8 s cold and 3 s warm. The machine's load counts in these wall-clock
figures, so the process's own CPU time is given beside each.

Run alone with ``python benchmarks/bench_compare.py``.
"""

from __future__ import annotations

import contextlib
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TARGET_WARM_S = 3.0
TARGET_COLD_S = 8.0
WARM_RUNS = 3


def _run_compare(cache: Path) -> tuple[float, float]:
    """Wall-clock and CPU seconds of one ``hystcomp compare`` with kernel cache ``cache``."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    # Python's own bytecode cache as an installation has it: a shell that forbids writing
    # it would have every run compile hystcomp's modules from source again (0.2 s).
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    with tempfile.TemporaryDirectory() as folder:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "hystcomp", "compare", "--out", folder],
            check=True,
            capture_output=True,
            env=env,
        )
        wall = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def _settle(cache: Path, quiet_s: float = 2.0, limit_s: float = 60.0) -> None:
    """Wait until the kernel cache has stopped changing for ``quiet_s`` seconds.

    The warm runs measure loading from the full cache, not the last writes of a first
    run's processes (numba writes each file when a kernel is compiled).
    """

    def listing():
        files = []
        for path in cache.rglob("*"):
            with contextlib.suppress(OSError):  # a temporary file renamed meanwhile
                files.append((path.name, path.stat().st_size))
        return sorted(files)

    last, since, start = listing(), time.monotonic(), time.monotonic()
    while time.monotonic() - since < quiet_s and time.monotonic() - start < limit_s:
        time.sleep(0.2)
        now = listing()
        if now != last:
            last, since = now, time.monotonic()


def _row(name, value, unit, target=None):
    ok = None if target is None else value < target
    return {
        "name": name,
        "value": value,
        "unit": unit,
        "target": None if target is None else f"< {target:g}",
        "ok": ok,
    }


def run() -> list[dict]:
    """Measure and return one row per figure: name, value, unit, target, ok."""
    with tempfile.TemporaryDirectory() as cache:
        cold, cold_cpu = _run_compare(Path(cache))
        _settle(Path(cache))
        warm_runs = sorted(_run_compare(Path(cache)) for _ in range(WARM_RUNS))
    warm, warm_cpu = warm_runs[len(warm_runs) // 2]
    return [
        _row(
            "hystcomp compare, empty kernel cache (fresh temporary folder)",
            cold,
            "s",
            TARGET_COLD_S,
        ),
        _row("  its CPU time (user + system), its forked processes included", cold_cpu, "s"),
        _row(
            f"hystcomp compare, warm kernel cache, median of {WARM_RUNS}", warm, "s", TARGET_WARM_S
        ),
        _row("  its CPU time (user + system)", warm_cpu, "s"),
        _row("  the slowest warm run", warm_runs[-1][0], "s"),
    ]


if __name__ == "__main__":
    for row in run():
        print(f"{row['name']}: {row['value']:.4g} {row['unit']}")
