"""An AFM raster on coupled scanners (``python benchmarks/run.py raster``).

The measurement of ``hystcomp raster`` (:mod:`hystcomp.experiment.raster`) on the two- and
three-axis stages of :func:`hystcomp.plant.scanner.raster_scanner` (Bouc-Wen X, relay
Preisach Y with output saturation, Krasnosel'skii-Pokrovskii Z; couplings of 2 to 8 %; each
axis its own mode): identified from ``excite multiaxis`` with ``--model auto``, then a
raster (the fast axis a 10 Hz triangle over 10-80 % of its stroke, the slow axis a ramp over
10-80 %), measured on the second frame. Targets: every axis within 0.15x its uncompensated
rms with the coupled model, and the axes' summed rms at most 0.5x that of per-axis
compensators that ignore the coupling. Prints the table of each stage. About a minute.
"""

from __future__ import annotations

from hystcomp.experiment.raster import raster_experiment

AXIS_TARGET = 0.15
SUM_TARGET = 0.5


def row(name, value, unit, target=None, ok=None) -> dict:
    return {"name": name, "value": float(value), "unit": unit, "target": target, "ok": ok}


def run() -> list[dict]:
    rows = []
    for n_axes in (2, 3):
        result = raster_experiment(n_axes=n_axes)
        print(f"{n_axes}-axis stage (kinds: {', '.join(result.kinds)})")
        for line in result.table():
            print("  " + line)
        for i, ratio in enumerate(result.ratio("coupled")):
            rows.append(
                row(
                    f"{n_axes} axes, {'XYZ'[i]}: coupled rms / uncompensated rms",
                    ratio,
                    "x",
                    f"<= {AXIS_TARGET:g}",
                    ratio <= AXIS_TARGET,
                )
            )
            rows.append(
                row(
                    f"{n_axes} axes, {'XYZ'[i]}: per-axis rms / uncompensated rms",
                    result.ratio("per-axis")[i],
                    "x",
                )
            )
        rows.append(
            row(
                f"{n_axes} axes: summed rms, coupled / per-axis",
                result.summed_ratio,
                "x",
                f"<= {SUM_TARGET:g}",
                result.summed_ratio <= SUM_TARGET,
            )
        )
    return rows


if __name__ == "__main__":
    for r in run():
        print(f"{r['name']:<60} {r['value']:8.3f} {r['unit']}  {r['target'] or ''}")
