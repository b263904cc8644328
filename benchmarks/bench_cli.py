"""Start-up of the command line: ``hystcomp --help``, against Python's own start-up.

Target: ``hystcomp --help`` answers in at most 0.3 s (median of 7 fresh processes). The
package imports a subcommand's module, numba and SciPy only when a command needs them, so
``--help`` costs Python and click. The references, measured in the same run and
interleaved with it so that machine load hits all alike: ``python -c pass`` (the floor) and
``python -c "import click"`` (what a click program cannot avoid). ``hystcomp excite pi``
(no kernel either) and ``hystcomp identify --help`` (which loads the models and numba) are
given for information.

Run alone with ``python benchmarks/bench_cli.py``.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import time

TARGET_S = 0.3
REPEATS = 7

COMMANDS = {
    "python -c pass": [sys.executable, "-c", "pass"],
    "python -c 'import click'": [sys.executable, "-c", "import click"],
    "hystcomp --help": [sys.executable, "-m", "hystcomp", "--help"],
    "hystcomp excite pi": [sys.executable, "-m", "hystcomp", "excite", "pi"],
    "hystcomp identify --help": [sys.executable, "-m", "hystcomp", "identify", "--help"],
}


def _once(argv: list[str]) -> float:
    start = time.perf_counter()
    subprocess.run(argv, check=True, capture_output=True)
    return time.perf_counter() - start


def measure(repeats: int = REPEATS) -> dict[str, float]:
    """Median wall time in s of each command, over ``repeats`` interleaved rounds."""
    for argv in COMMANDS.values():  # warm the file cache (and numba's on-disk cache)
        _once(argv)
    times = {name: [] for name in COMMANDS}
    for _ in range(repeats):
        for name, argv in COMMANDS.items():
            times[name].append(_once(argv))
    return {name: statistics.median(values) for name, values in times.items()}


def run() -> list[dict]:
    """Measure and return one row per figure: name, value, unit, target, ok."""
    medians = measure()
    floor = medians["python -c 'import click'"]
    rows = [
        {
            "name": f"{name} (median of {REPEATS})",
            "value": value,
            "unit": "s",
            "target": None,
            "ok": None,
        }
        for name, value in medians.items()
    ]
    helped = medians["hystcomp --help"]
    rows[2].update(target=f"<= {TARGET_S:g}", ok=helped <= TARGET_S)
    rows.append(
        {
            "name": "hystcomp --help / python -c 'import click'",
            "value": helped / floor,
            "unit": "x",
            "target": None,
            "ok": None,
        }
    )
    return rows


if __name__ == "__main__":
    for row in run():
        print(f"{row['name']:<55} {row['value']:8.3f} {row['unit']:<2} {row['target'] or ''}")
