"""Run every speed benchmark of hystcomp and print one table.

Usage (from the repository root)::

    python benchmarks/run.py            # all benchmarks/bench_*.py modules
    python benchmarks/run.py realtime   # only those whose name contains "realtime"
    python benchmarks/run.py --check    # exit 1 if a target is missed

Each ``benchmarks/bench_*.py`` module has a ``run() -> list[dict]``; each dict is a row with
the keys ``name`` (str), ``value`` (float), ``unit`` (str), ``target`` (str such as
``"<= 0.5"``, or None for a figure given for information) and ``ok`` (bool, or None without
a target). Speed is measured here, in one run with its ratios, and never asserted in the
tests: timings depend on the machine.
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import sys
import time
import traceback
from pathlib import Path

HERE = Path(__file__).resolve().parent
COLUMNS = ("benchmark", "name", "value", "unit", "target", "ok")


def discover(folder: Path = HERE, pattern: str = "") -> list[Path]:
    """The benchmark modules of ``folder`` whose name contains ``pattern``, in name order."""
    return [p for p in sorted(Path(folder).glob("bench_*.py")) if pattern in p.stem]


def load(path: Path):
    """Import a benchmark module from its file (the folder is not a package)."""
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[path.stem] = module
    spec.loader.exec_module(module)
    return module


def run_module(path: Path) -> list[dict]:
    """The rows of one module; a module that fails gives one failed row with the error."""
    try:
        rows = list(load(path).run())
    except Exception as exc:  # noqa: BLE001 - report and go on with the other modules
        traceback.print_exc(file=sys.stderr)
        return [
            {"name": f"failed: {type(exc).__name__}: {exc}", "value": float("nan"), "unit": ""}
            | {"target": "runs", "ok": False}
        ]
    for row in rows:
        missing = {"name", "value", "unit", "target", "ok"} - set(row)
        if missing:
            row.update(name=f"{row.get('name', '?')} (row lacks {sorted(missing)})", ok=False)
            row.setdefault("target", "well-formed")
    return rows


def format_value(value) -> str:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return str(value)
    if math.isnan(value):
        return "-"
    if value == 0 or 1e-3 <= abs(value) < 1e6:
        return f"{value:.4g}"
    return f"{value:.3e}"


def format_table(results: list[tuple[str, dict]]) -> str:
    """One aligned text table; ``ok`` shows as yes / NO / (blank for information)."""
    lines = []
    for bench, row in results:
        ok = {True: "yes", False: "NO", None: ""}.get(row.get("ok"), str(row.get("ok")))
        target = "" if row.get("target") is None else str(row["target"])
        lines.append((bench, str(row["name"]), format_value(row["value"]), row["unit"], target, ok))
    widths = [max(len(c), *(len(line[i]) for line in lines)) for i, c in enumerate(COLUMNS)]
    rule = "  ".join("-" * w for w in widths)
    out = ["  ".join(c.ljust(w) for c, w in zip(COLUMNS, widths, strict=True)), rule]
    for line in lines:
        cells = [
            cell.rjust(w) if i == 2 else cell.ljust(w)
            for i, (cell, w) in enumerate(zip(line, widths, strict=True))
        ]
        out.append("  ".join(cells).rstrip())
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("pattern", nargs="?", default="", help="run only matching modules")
    parser.add_argument(
        "--check", action="store_true", help="exit with status 1 if any target is missed"
    )
    parser.add_argument("--dir", type=Path, default=HERE, help="folder of bench_*.py modules")
    args = parser.parse_args(argv)
    modules = discover(args.dir, args.pattern)
    if not modules:
        print(f"no benchmarks/bench_*.py module matches {args.pattern!r}", file=sys.stderr)
        return 2
    results = []
    start = time.perf_counter()
    for path in modules:
        bench = path.stem.removeprefix("bench_")
        print(f"running {bench} ...", file=sys.stderr, flush=True)
        results += [(bench, row) for row in run_module(path)]
    print(format_table(results))
    missed = [row["name"] for _, row in results if row.get("ok") is False]
    print(
        f"\n{len(results)} figures from {len(modules)} modules in "
        f"{time.perf_counter() - start:.0f} s; {len(missed)} targets missed"
        + (": " + "; ".join(missed) if missed else "")
    )
    return 1 if args.check and missed else 0


if __name__ == "__main__":
    sys.exit(main())
