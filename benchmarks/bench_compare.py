"""Speed of the main job: ``hystcomp compare``, the paper's whole experiment on the twin.

Target: under 20 s with the kernels already compiled (warm: the on-disk cache filled by a
first run) on 2 cores. The first run of this benchmark fills the cache if it is empty, so
the first row is the cold figure only on a fresh checkout. Each run is a fresh process,
as a user would start it; the output folder is a temporary one.

Run alone with ``python benchmarks/bench_compare.py``.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time

TARGET_S = 20.0


def _run_compare() -> float:
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "hystcomp", "compare", "--out", folder],
            check=True,
            capture_output=True,
        )
        return time.perf_counter() - start


def run() -> list[dict]:
    """Measure and return one row per figure: name, value, unit, target, ok."""
    first = _run_compare()
    warm = _run_compare()
    return [
        {
            "name": "hystcomp compare, first run (cold if the kernel cache was empty)",
            "value": first,
            "unit": "s",
            "target": None,
            "ok": None,
        },
        {
            "name": "hystcomp compare, warm kernel cache",
            "value": warm,
            "unit": "s",
            "target": f"< {TARGET_S:g}",
            "ok": warm < TARGET_S,
        },
    ]


if __name__ == "__main__":
    for row in run():
        print(f"{row['name']}: {row['value']:.4g} {row['unit']}")
