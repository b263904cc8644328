"""Accuracy of the compensators on actuators of none of the model families (benchmarks/panel.py).

For each actuator of the panel and each identification excitation (the paper's triangles
``pi``, the paper's sinusoids ``preisach``, random turning points ``random``, and
``hystcomp excite rich``), identify PI, MPI and Preisach with the library's defaults and
track a 1 Hz triangle; each cell is the tracking rms over the uncompensated rms (the
linear baseline of :mod:`hystcomp.experiment.baseline`, gain from the triangle record).
Targets per cell: PI < 0.5, MPI < 0.2, Preisach < 0.25, none above 0.6. A Preisach fit
that refuses a record is reported as ``refused`` (NaN).

It also checks the hyperparameter criterion (:mod:`hystcomp.identify.compensation`): over
the candidate MPI fits of each cell (regularization 0, 1e-4 .. 1e-1, physical constraints)
and the two PI fits (physical, paper), the Spearman rank correlation between the estimated
and the measured tracking error.

Run alone with ``python benchmarks/bench_accuracy.py`` (about two minutes; prints the table).
``--paper`` prints the same table for the paper's fits (constraints="paper", regularization 0).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.panel import ACTUATORS, EXCITATIONS, Bench

from hystcomp import ModifiedPrandtlIshlinskii, PrandtlIshlinskii, Preisach
from hystcomp.identify.compensation import compensation_error
from hystcomp.identify.mpi import REGULARIZATION_GRID
from hystcomp.identify.scoring import transient_end

TARGETS = {"PI": 0.5, "MPI": 0.2, "Preisach": 0.25}
CEILING = 0.6


def estimators(paper: bool = False) -> dict:
    if paper:
        return {
            "PI": PrandtlIshlinskii(constraints="paper"),
            "MPI": ModifiedPrandtlIshlinskii(constraints="paper", regularization=0.0),
            "Preisach": Preisach(),
        }
    return {"PI": PrandtlIshlinskii(), "MPI": ModifiedPrandtlIshlinskii(), "Preisach": Preisach()}


def ratio_table(actuators=ACTUATORS, excitations=EXCITATIONS, *, paper=False, sample_rate=20e3):
    """``{(actuator, excitation): {method: ratio or nan}}`` with the default fits."""
    table = {}
    for name in actuators:
        bench = Bench(name, sample_rate=sample_rate)
        for exc in excitations:
            v, x = bench.record(exc)
            cells = {}
            for method, est in estimators(paper).items():
                try:
                    model = est.fit(v, x)
                except ValueError:
                    cells[method] = float("nan")
                    continue
                cells[method] = bench.ratio(model)
            table[name, exc] = cells
    return table


def criterion_rank_correlation(
    actuators=ACTUATORS, excitations=EXCITATIONS
) -> tuple[list[float], list[float]]:
    """Spearman rho against the measured tracking over the candidates of each cell: of the
    estimate of :mod:`hystcomp.identify.compensation`, and of the fit error (the former
    criterion of ``regularization="auto"``)."""
    from scipy.stats import spearmanr

    rhos, fit_rhos = [], []
    for name in actuators:
        bench = Bench(name)
        for exc in excitations:
            v, x = bench.record(exc)
            start = transient_end(v)
            candidates = [PrandtlIshlinskii(), PrandtlIshlinskii(constraints="paper")]
            candidates += [ModifiedPrandtlIshlinskii(regularization=r) for r in REGULARIZATION_GRID]
            estimated, fitted, measured = [], [], []
            for est in candidates:
                model = est.fit(v, x)
                estimated.append(compensation_error(model, v, x, start=start)["tracking_rms_um"])
                fitted.append(model.fit_report_["rms_error_um"])
                measured.append(bench.ratio(model) * bench.baseline_rms)
            rhos.append(float(spearmanr(estimated, measured)[0]))
            fit_rhos.append(float(spearmanr(fitted, measured)[0]))
    return rhos, fit_rhos


def format_table(table) -> str:
    lines = [f"{'actuator':<9} {'excitation':<10} {'PI':>7} {'MPI':>7} {'Preisach':>9}"]
    for (name, exc), cells in table.items():
        text = [
            "refused" if np.isnan(cells[m]) else f"{cells[m]:.2f}"
            for m in ("PI", "MPI", "Preisach")
        ]
        lines.append(f"{name:<9} {exc:<10} {text[0]:>7} {text[1]:>7} {text[2]:>9}")
    return "\n".join(lines)


def run() -> list[dict]:
    """Rows for benchmarks/run.py: the worst cell per method and excitation, and the criterion."""
    table = ratio_table()
    rows = []
    for exc in EXCITATIONS:
        for method, target in TARGETS.items():
            values = [table[name, exc][method] for name in ACTUATORS]
            finite = [v for v in values if not np.isnan(v)]
            if not finite:
                rows.append(
                    {
                        "name": f"{method} from '{exc}': refused on every actuator",
                        "value": float("nan"),
                        "unit": "x",
                        "target": f"< {target:g}",
                        "ok": None,
                    }
                )
                continue
            worst = max(finite)
            where = ACTUATORS[values.index(worst)]
            rows.append(
                {
                    "name": f"{method} from '{exc}', worst of the panel ({where}), 1 Hz tracking "
                    "/ uncompensated",
                    "value": worst,
                    "unit": "x",
                    "target": f"< {target:g}",
                    "ok": worst < target,
                }
            )
    rhos, fit_rhos = criterion_rank_correlation()
    rows.append(
        {
            "name": "fit error vs measured tracking, median Spearman rho (the former criterion)",
            "value": float(np.median(fit_rhos)),
            "unit": "",
            "target": None,
            "ok": None,
        }
    )
    rows.append(
        {
            "name": "criterion vs measured tracking, median Spearman rho over the cells",
            "value": float(np.median(rhos)),
            "unit": "",
            "target": "> 0.5",
            "ok": float(np.median(rhos)) > 0.5,
        }
    )
    return rows


if __name__ == "__main__":
    print(format_table(ratio_table(paper="--paper" in sys.argv)))
    if "--rho" in sys.argv:
        rhos, fit_rhos = criterion_rank_correlation()
        print("Spearman rho per cell, estimate:", " ".join(f"{r:.2f}" for r in rhos))
        print("Spearman rho per cell, fit error:", " ".join(f"{r:.2f}" for r in fit_rhos))
        print(f"median: estimate {np.median(rhos):.2f}, fit error {np.median(fit_rhos):.2f}")
