"""Accuracy of the compensators on actuators of none of the model families (benchmarks/panel.py).

For each tuning actuator of the panel (:data:`benchmarks.panel.ACTUATORS`; the held-out
ones of :data:`benchmarks.panel.HELD_OUT` with ``--held-out``) and each identification
excitation (the paper's triangles ``pi``, the paper's sinusoids ``preisach``, random turning
points ``random``, and ``hystcomp excite rich``, all scaled to the actuator's range and
sampled at its rate), identify PI, MPI and Preisach with the library's defaults and track a
1 Hz triangle (from the actuator's remanence at the low end of its range to 90 % of its
stroke, see :class:`benchmarks.panel.Bench`); each cell is the tracking rms over the
uncompensated rms (the straight line through the rest point, :class:`benchmarks.panel.RestLine`,
gain from the triangle record).
Targets per cell: PI < 0.5, MPI < 0.2, Preisach < 0.25, none above 0.6. The Preisach model
is fitted by least squares from any record, so every cell has a figure.

It also compares the Preisach fits on the same cells (:func:`preisach_table`, which chose the
defaults of :class:`hystcomp.Preisach`): least squares with the cubic Everett polynomial of
eq. (5) or with tables of several grid sizes, from every excitation, and the paper's fit (eq.
5 to the reversal curves, Section III-A) and a table fitted to them, from the sinusoids.

It also checks the hyperparameter criterion (:mod:`hystcomp.identify.compensation`): over
the candidate MPI fits of each cell (regularization 0, 1e-4 .. 1e-1, physical constraints)
and the two PI fits (physical, paper), the Spearman rank correlation between the measured
tracking error and each of: the criterion ``regularization="auto"`` minimises (held-out
errors of a cross-validation over reversal segments), the inverse's estimate on the whole
record (the former criterion) and the fit error; and the regret of choosing the MPI
regularisation by each (measured ratio of the one it ranks first minus the best).

Run alone with ``python benchmarks/bench_accuracy.py`` (half a minute; prints the table).
``--paper`` prints the same table for the paper's fits (constraints="paper", regularization
0, the Preisach cubic from reversal curves, which only the sinusoids have: ``n/a``
elsewhere); ``--preisach`` prints the comparison of the Preisach fits; ``--rho`` the rank
correlations; ``--limit`` the best MPI tracking of any size and regularisation on the
quasi-static hysteresis of the twin and the Bouc-Wen stage (:func:`family_limit`);
``--coverage`` the estimated and measured tracking from records that lack what a reference
does, with the coverage warning of ``hystcomp identify`` (:func:`coverage`). ``--held-out``
runs all of these on the held-out actuators instead (``--limit`` on all of them): they are
checked last, after every default is chosen on the tuning ones.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import itertools

from benchmarks.panel import ACTUATORS, EXCITATIONS, HELD_OUT, V_MAX, Bench, excitation

from hystcomp import ModifiedPrandtlIshlinskii, PrandtlIshlinskii, Preisach
from hystcomp.errors import NotInvertibleError
from hystcomp.identify.mpi import REGULARIZATION_GRID

TARGETS = {"PI": 0.5, "MPI": 0.2, "Preisach": 0.25}
CEILING = 0.6


#: The paper's Preisach fit: eq. (5) by least squares on the reversal curves (Section III-A).
PAPER_PREISACH = {"fit_method": "reversal-curves", "everett": "polynomial", "degree": 3}
#: The Preisach fits compared by :func:`preisach_table`; "paper" and "reversal-curves table"
#: need the reversal curves of the sinusoids (excitation ``preisach``).
PREISACH_FITS = {
    "paper": PAPER_PREISACH,
    "reversal-curves table 25": {"fit_method": "reversal-curves", "everett": "table"},
    "least-squares cubic": {"fit_method": "least-squares", "everett": "polynomial"},
    **{
        f"least-squares table {n}": {
            "fit_method": "least-squares",
            "everett": "table",
            "grid_size": n,
        }
        for n in (13, 17, 25, 33)
    },
}
REVERSAL_CURVE_FITS = ("paper", "reversal-curves table 25")


def estimators(paper: bool = False) -> dict:
    if paper:
        return {
            "PI": PrandtlIshlinskii(constraints="paper"),
            "MPI": ModifiedPrandtlIshlinskii(constraints="paper", regularization=0.0),
            "Preisach": Preisach(**PAPER_PREISACH),
        }
    return {"PI": PrandtlIshlinskii(), "MPI": ModifiedPrandtlIshlinskii(), "Preisach": Preisach()}


def ratio_table(actuators=ACTUATORS, excitations=EXCITATIONS, *, paper=False, sample_rate=None):
    """``{(actuator, excitation): {method: ratio}}`` with the default fits (``paper``: the
    paper's fits, NaN where the paper's Preisach fit has no reversal curves to fit), each
    actuator at its own sample rate unless ``sample_rate`` (Hz) is given."""
    table = {}
    for name in actuators:
        bench = Bench(name, sample_rate=sample_rate)
        for exc in excitations:
            v, x = bench.record(exc)
            cells = {}
            for method, est in estimators(paper).items():
                if paper and method == "Preisach" and exc != "preisach":
                    cells[method] = float("nan")
                    continue
                cells[method] = _ratio(bench, est, v, x)
            table[name, exc] = cells
    return table


def _ratio(bench, estimator, v, x) -> float:
    """``bench.ratio`` of ``estimator`` fitted on ``(v, x)``; NaN (``n/a``) where the fit
    has no compensator: a Preisach fit to reversal curves whose branch turns back (the
    paper's cubic, and the reversal-curve table, on the Preisach and
    Krasnosel'skii-Pokrovskii stages)."""
    try:
        return bench.ratio(estimator.fit(v, x))
    except NotInvertibleError:
        return float("nan")


def preisach_table(actuators=ACTUATORS, excitations=EXCITATIONS, fits=PREISACH_FITS):
    """``{(actuator, excitation): {fit: ratio}}`` for the Preisach fits of ``fits`` (the
    reversal-curve fits from the sinusoids only)."""
    table = {}
    for name in actuators:
        bench = Bench(name)
        for exc in excitations:
            v, x = bench.record(exc)
            table[name, exc] = {
                fit: _ratio(bench, Preisach(**options), v, x)
                for fit, options in fits.items()
                if exc == "preisach" or fit not in REVERSAL_CURVE_FITS
            }
    return table


CRITERIA = ("criterion", "estimate", "fit error")


def criterion_rank_correlation(actuators=ACTUATORS, excitations=EXCITATIONS) -> dict:
    """How well each way of ranking candidate fits ranks them as measured tracking does.

    Over the candidates of each cell (the two PI fits, physical and paper, and the MPI fits
    of :data:`~hystcomp.identify.mpi.REGULARIZATION_GRID`), for ``"criterion"`` (the one
    ``regularization="auto"`` minimises: the geometric mean of the held-out forward error
    and the inverse's estimate, :func:`hystcomp.identify.compensation.tracking_scorer`),
    ``"estimate"`` (the inverse's estimate alone, the former criterion) and
    ``"fit error"``: ``{name: (rhos, regrets)}``, the Spearman rho against the measured
    tracking in each cell, and the regret of choosing the MPI regularisation by it (the
    measured ratio of the MPI fit it ranks first minus the best of the grid).
    """
    from scipy.stats import spearmanr

    keys = {"criterion": "criterion_um", "estimate": "tracking_rms_um"}
    keys["fit error"] = "rms_error_um"
    out: dict = {name: ([], []) for name in CRITERIA}
    for name in actuators:
        bench = Bench(name)
        for exc in excitations:
            v, x = bench.record(exc)
            candidates = [PrandtlIshlinskii(), PrandtlIshlinskii(constraints="paper")]
            candidates += [ModifiedPrandtlIshlinskii(regularization=r) for r in REGULARIZATION_GRID]
            models = [est.fit(v, x) for est in candidates]
            measured = np.array([bench.ratio(model) for model in models])
            for crit, key in keys.items():
                values = np.array([model.fit_report_[key] for model in models])
                out[crit][0].append(float(spearmanr(values, measured)[0]))
                mpi = slice(2, None)
                out[crit][1].append(
                    float(measured[mpi][np.argmin(values[mpi])] - measured[mpi].min())
                )
    return out


def thin_record(kind: str, sample_rate: float, voltage_range=(0.0, V_MAX)) -> np.ndarray:
    """Records that may lack what a reference does (:func:`coverage`): ``walk``, a random
    walk (Brownian, 30 s, its steps held 0.1 s, seeded) scaled to the range; ``drift``, the
    same walk on a descent three times its span, so that it crosses the range once; ``loop``, one
    2 s triangle over the range; ``stairs``, a staircase up and down in 10 % steps."""
    fs = sample_rate
    lo, hi = voltage_range
    return lo + (hi - lo) / V_MAX * _thin_record(kind, fs)


def _thin_record(kind: str, fs: float) -> np.ndarray:
    """:func:`thin_record` on 0..120 V."""
    if kind in ("walk", "drift"):
        hold = round(0.1 * fs)
        steps = np.repeat(np.random.default_rng(5).normal(0.0, 1.0, 300), hold)
        walk = np.cumsum(steps) / hold
        if kind == "drift":  # the same walk on a descent over the range: it crosses once
            walk += np.linspace(3.0 * np.ptp(walk), 0.0, walk.size)
        return V_MAX * (walk - walk.min()) / np.ptp(walk)
    if kind == "loop":
        up = np.linspace(0.0, V_MAX, round(fs))
        return np.r_[up, up[::-1]]
    if kind == "stairs":
        levels = np.r_[np.linspace(0.0, 1.0, 11), np.linspace(1.0, 0.0, 11)[1:]]
        return np.repeat(V_MAX * levels, round(0.5 * fs))
    raise ValueError(f"unknown record {kind!r}")


def coverage(actuators=ACTUATORS, sample_rate=5e3) -> list[tuple]:
    """``[(actuator, record, method, estimated, measured, warned)]``: the tracking that
    ``hystcomp identify`` estimates from the record (its ratio to the straight line's),
    the one measured (``Bench.ratio``), and whether the record draws the coverage warning
    (:func:`hystcomp.identify.scoring.coverage_warning`), for the panel's excitations and
    the records of :func:`thin_record`."""
    from hystcomp.identify.compensation import compensation_error
    from hystcomp.identify.scoring import coverage_warning, transient_end

    rows = []
    for name in actuators:
        bench = Bench(name, sample_rate=sample_rate)
        for kind in (*EXCITATIONS, "walk", "drift", "loop", "stairs"):
            if kind in EXCITATIONS:
                v, x = bench.record(kind)
            else:
                v = thin_record(kind, bench.act.sample_rate, bench.act.voltage_range)
                x = bench.act.run(v)
            start = transient_end(v)
            warned = coverage_warning(v, start) is not None
            for method, est in estimators().items():
                model = est.fit(v[start:], x[start:]) if method == "Preisach" else est.fit(v, x)
                estimate = compensation_error(model, v, x, start=start)["ratio"]
                rows.append((name, kind, method, estimate, bench.ratio(model), warned))
    return rows


def family_limit(actuators=("twin", "boucwen"), grid=(0.0, 1e-3, 1e-2, 1e-1, 1.0)) -> dict:
    """Best MPI tracking on an actuator's quasi-static hysteresis, for the MPI family's limit.

    Without creep, resonance or noise (:meth:`benchmarks.panel.Actuator.hysteresis`, the
    twin's too), from the paper's triangles and from a triangle over the whole range (the
    loop that is tracked), the MPI fits of 16 and 32 plays and dead-zones with every
    ``regularization`` of ``grid``: ``{(actuator, record): (best ratio, operators,
    regularization)}``, the tracking error of the reference through the same quasi-static
    hysteresis over the bench's uncompensated error. If the best is above the 0.2 target,
    no choice of hyperparameters of the family reaches it on that actuator and record.
    """
    out = {}
    for name in actuators:
        bench = Bench(name)
        static = bench.act.hysteresis
        lo, hi = bench.act.voltage_range
        ramp = np.linspace(lo, hi, 20001)
        records = {"pi": excitation("pi", bench.act.sample_rate, (lo, hi))}
        records[f"{lo:g}..{hi:g} V loop"] = np.tile(np.r_[ramp, ramp[::-1][1:-1]], 3)
        window = slice(bench.period, None)
        for label, v in records.items():
            x = static(v)
            best = (np.inf, 0, 0.0)
            for n in (16, 32):
                for value in grid:
                    model = ModifiedPrandtlIshlinskii(
                        n_operators=n, n_deadzones=n, regularization=value
                    ).fit(v, x)
                    e = static(model.inverse().simulate(bench.x_ref)) - bench.x_ref
                    ratio = float(np.sqrt(np.mean(e[window] ** 2))) / bench.baseline_rms
                    best = min(best, (ratio, n, value))
            out[name, label] = best
    return out


def format_table(table, columns=("PI", "MPI", "Preisach")) -> str:
    """The table as text, one row per cell, ``n/a`` where a fit has no figure."""
    width = max(9, *(len(c) for c in columns))
    lines = [f"{'actuator':<9} {'excitation':<10} " + " ".join(f"{c:>{width}}" for c in columns)]
    for (name, exc), cells in table.items():
        text = [
            f"{cells[c]:.3f}" if c in cells and not np.isnan(cells[c]) else "n/a" for c in columns
        ]
        lines.append(f"{name:<9} {exc:<10} " + " ".join(f"{t:>{width}}" for t in text))
    worst = []
    for c in columns:
        values = [(cells[c], key) for key, cells in table.items() if c in cells]
        values = [(v, key) for v, key in values if not np.isnan(v)]
        if values:
            v, (name, exc) = max(values)
            worst.append(f"{c} {v:.3f} ({name}, {exc})")
    lines.append("worst: " + "; ".join(worst))
    return "\n".join(lines)


#: Auto's targets over the panel: the worst cell, and the share of cells within 1.2x of the
#: best family; the estimate's: the share of cells within 1.5x of the measured tracking.
AUTO_WORST, AUTO_NEAR, ESTIMATE_WITHIN = 0.15, 0.9, 0.9
#: The inner turns of :func:`turning_reference`, as shares of the triangle's span.
TURNS = (0.0, 1.0, 0.35, 0.75, 0.15, 0.6, 0.45, 0.9, 0.0, 0.5, 0.3, 1.0, 0.0)


def turning_reference(bench: Bench) -> tuple[np.ndarray, int]:
    """A reference over the bench triangle's span that turns inside it (:data:`TURNS`), at
    the triangle's slope; and the first sample scored (after its first visit to the top,
    when the memory no longer depends on the start)."""
    fs = bench.act.sample_rate
    lo, hi = bench.x_low, float(bench.x_ref.max())
    points = lo + (hi - lo) * np.asarray(TURNS)
    slope = 2.0 * (hi - lo)  # µm/s, a 1 Hz triangle's
    parts = [
        np.linspace(a, b, max(2, int(abs(b - a) / slope * fs)))[1:]
        for a, b in itertools.pairwise(points)
    ]
    ref = np.r_[points[0], np.concatenate(parts)]
    return ref, int(np.argmax(ref >= hi - 1e-9))


def estimate_table(actuators=ACTUATORS, excitations=EXCITATIONS) -> list[dict]:
    """Every family of every cell identified as ``hystcomp identify --model auto`` does
    (:func:`hystcomp.workflows.auto.identify_best`), with its estimates and what it
    measures: ``[{stage, record, family, chosen, estimate, held_out, triangle, turning,
    baseline, warned}]`` (µm; ``triangle`` the bench's 1 Hz triangle, ``turning`` the
    reference of :func:`turning_reference`, ``warned`` whether ``identify`` warned)."""
    from hystcomp.io.records import Record
    from hystcomp.workflows.auto import identify_best

    out = []
    for name in actuators:
        bench = Bench(name)
        turning, skip = turning_reference(bench)
        for exc in excitations:
            v, x = bench.record(exc)
            record = Record(np.arange(v.size) / bench.act.sample_rate, v, x, source=exc)
            chosen = identify_best(record)
            for kind, result in chosen.results.items():
                model = result.model
                v_turn = model.inverse().simulate(turning)
                e_turn = bench.act.run(v_turn)[skip:] - turning[skip:]
                out.append(
                    {
                        "stage": name,
                        "record": exc,
                        "family": kind,
                        "chosen": kind == chosen.best.kind,
                        "estimate": result.tracking["tracking_rms_um"],
                        "held_out": result.tracking["held_out_rms_um"],
                        "triangle": bench.ratio(model) * bench.baseline_rms,
                        "turning": float(np.sqrt(np.mean(e_turn**2))),
                        "baseline": bench.baseline_rms,
                        "warned": bool(result.warnings),
                    }
                )
    return out


def auto_table(rows: list[dict]) -> dict:
    """``{(stage, record): {PI, MPI, Preisach, auto: ratio}}`` from :func:`estimate_table`:
    each family's 1 Hz tracking over the uncompensated, and that of the family auto chose."""
    names = {"pi": "PI", "mpi": "MPI", "preisach": "Preisach"}
    table: dict = {}
    for r in rows:
        cells = table.setdefault((r["stage"], r["record"]), {})
        cells[names[r["family"]]] = r["triangle"] / r["baseline"]
        if r["chosen"]:
            cells["auto"] = r["triangle"] / r["baseline"]
    return table


def estimate_summary(rows: list[dict]) -> dict:
    """Auto's worst cell and its share within 1.2x of the best family; the estimate's share
    within 1.5x of the measured triangle, and its cells more than 2x optimistic (and
    whether each was warned about); the held-out error's share within 1.5x of the turning
    reference."""
    cells: dict = {}
    for row in rows:
        cells.setdefault((row["stage"], row["record"]), []).append(row)
    regrets, auto = [], []
    for group in cells.values():
        best = min(r["triangle"] for r in group)
        pick = next(r for r in group if r["chosen"])
        regrets.append(pick["triangle"] / best)
        auto.append((pick["triangle"] / pick["baseline"], pick["stage"], pick["record"]))
    ratio = np.array([r["estimate"] / r["triangle"] for r in rows])
    held = np.array([r["held_out"] / r["turning"] for r in rows if np.isfinite(r["held_out"])])
    optimistic = [r for r in rows if r["estimate"] < 0.5 * r["triangle"]]
    return {
        "auto_worst": max(auto),
        "auto_near": float(np.mean(np.array(regrets) <= 1.2)),
        "auto_regret_worst": float(max(regrets)),
        "estimate_within": float(np.mean((ratio <= 1.5) & (ratio >= 1.0 / 1.5))),
        "estimate_range": (float(ratio.min()), float(ratio.max())),
        "optimistic": len(optimistic),
        "optimistic_unwarned": sum(not r["warned"] for r in optimistic),
        "held_out_within": float(np.mean((held <= 1.5) & (held >= 1.0 / 1.5))),
    }


def draw_estimates(rows: list[dict], path) -> None:
    """Predicted against measured tracking, every cell, both estimates (docs/)."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(9.0, 4.2))
    marks = {"pi": "s", "mpi": "o", "preisach": "^"}
    panels = (
        ("estimate", "triangle", "over the range: a 1 Hz triangle"),
        ("held_out", "turning", "turning inside the range"),
    )
    for ax, (predicted, measured, title) in zip(axes, panels, strict=True):
        for kind, mark in marks.items():
            mine = [r for r in rows if r["family"] == kind and np.isfinite(r[predicted])]
            ax.loglog(
                [r[measured] for r in mine],
                [r[predicted] for r in mine],
                mark,
                ms=4,
                alpha=0.7,
                label={"pi": "PI", "mpi": "MPI", "preisach": "Preisach"}[kind],
            )
        lims = np.array([0.01, 3.0])
        ax.plot(lims, lims, "k-", lw=0.8, label="estimate = measured")
        ax.plot(lims, 1.5 * lims, "k:", lw=0.8, label="1.5x either way")
        ax.plot(lims, lims / 1.5, "k:", lw=0.8)
        ax.set_xlim(*lims)
        ax.set_ylim(*lims)
        ax.set_xlabel(f"measured tracking rms, {title} (µm)")
        ax.set_ylabel("estimated by hystcomp identify (µm)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def estimate_rows(rows: list[dict]) -> list[dict]:
    """Rows for benchmarks/run.py from :func:`estimate_summary`."""
    s = estimate_summary(rows)
    worst, stage, record = s["auto_worst"]
    return [
        {
            "name": f"auto: worst cell of the panel ({stage}, {record}), 1 Hz tracking / "
            "uncompensated",
            "value": worst,
            "unit": "x",
            "target": f"<= {AUTO_WORST:g}",
            "ok": worst <= AUTO_WORST,
        },
        {
            "name": "auto: share of cells within 1.2x of the best family",
            "value": s["auto_near"],
            "unit": "",
            "target": f">= {AUTO_NEAR:g}",
            "ok": s["auto_near"] >= AUTO_NEAR,
        },
        {
            "name": "estimate: share of cells within 1.5x of the measured tracking",
            "value": s["estimate_within"],
            "unit": "",
            "target": f">= {ESTIMATE_WITHIN:g}",
            "ok": s["estimate_within"] >= ESTIMATE_WITHIN,
        },
        {
            "name": "estimate: cells more than 2x optimistic without a warning",
            "value": float(s["optimistic_unwarned"]),
            "unit": "",
            "target": "0",
            "ok": s["optimistic_unwarned"] == 0,
        },
    ]


def run() -> list[dict]:
    """Rows for benchmarks/run.py: the worst cell per method and excitation, the worst and
    median cell of each Preisach fit, and the criterion."""
    table = ratio_table()
    rows = []
    for exc in EXCITATIONS:
        for method, target in TARGETS.items():
            values = [table[name, exc][method] for name in ACTUATORS]
            worst = max(values)
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
    fits = preisach_table()
    for fit in PREISACH_FITS:
        values = [cells[fit] for cells in fits.values() if fit in cells]
        values = [value for value in values if not np.isnan(value)]  # refused: no compensator
        for what, value in (("worst", max(values)), ("median", float(np.median(values)))):
            rows.append(
                {
                    "name": f"Preisach {fit}, {what} cell of the panel",
                    "value": value,
                    "unit": "x",
                    "target": None,
                    "ok": None,
                }
            )
    rows += estimate_rows(estimate_table())
    ranks = criterion_rank_correlation()
    for crit, (rhos, regrets) in ranks.items():
        rows.append(
            {
                "name": f"{crit} vs measured tracking, median Spearman rho over the cells",
                "value": float(np.median(rhos)),
                "unit": "",
                "target": "> fit error" if crit == "criterion" else None,
                "ok": float(np.median(rhos)) > float(np.median(ranks["fit error"][0]))
                if crit == "criterion"
                else None,
            }
        )
        rows.append(
            {
                "name": f"{crit}: worst regret of the MPI regularisation it chooses",
                "value": max(regrets),
                "unit": "x",
                "target": None,
                "ok": None,
            }
        )
    return rows


if __name__ == "__main__":
    # the held-out actuators are run only to check a choice made on the tuning ones
    stages = HELD_OUT if "--held-out" in sys.argv else ACTUATORS
    print(format_table(ratio_table(stages, paper="--paper" in sys.argv)))
    if "--preisach" in sys.argv:
        print(format_table(preisach_table(stages), columns=tuple(PREISACH_FITS)))
    if "--limit" in sys.argv:
        limited = HELD_OUT if "--held-out" in sys.argv else ("twin", "boucwen")
        for (name, label), (ratio, n, value) in family_limit(limited).items():
            print(
                f"{name} quasi-static, from {label}: best MPI {ratio:.3f} ({n} operators, "
                f"regularization {value:g})"
            )
    if "--estimate" in sys.argv or "--figure" in sys.argv:
        found = estimate_table(stages)
        for r in found:
            print(
                f"{r['stage']:<9} {r['record']:<9} {r['family']:<9} "
                f"{'chosen' if r['chosen'] else '':<6} estimate {r['estimate']:.3f} "
                f"measured {r['triangle']:.3f} | held out {r['held_out']:.3f} turning "
                f"{r['turning']:.3f}{' (warned)' if r['warned'] else ''}"
            )
        print(format_table(auto_table(found), columns=("PI", "MPI", "Preisach", "auto")))
        print(estimate_summary(found))
        if "--figure" in sys.argv:
            draw_estimates(found, sys.argv[sys.argv.index("--figure") + 1])
    if "--coverage" in sys.argv:
        rows = coverage(stages)
        for row in rows:
            print("{} {} {}: estimated {:.3f}, measured {:.3f}, warned {}".format(*row))
        for warned in (True, False):
            over = np.array([m / e for *_, e, m, w in rows if w == warned])
            print(
                f"{'warned' if warned else 'not warned'}: measured / estimated, median "
                f"{np.median(over):.2f}, {over.min():.2f} .. {over.max():.2f}, above 2 in "
                f"{np.sum(over > 2)} of {over.size} cells"
            )
    if "--rho" in sys.argv:
        for crit, (rhos, regrets) in criterion_rank_correlation(stages).items():
            print(f"{crit:>9}: rho per cell", " ".join(f"{r:.2f}" for r in rhos))
            print(
                f"{crit:>9}: rho median {np.median(rhos):.3f}, mean {np.mean(rhos):.3f}, "
                f"min {np.min(rhos):.2f}; regret worst {max(regrets):.3f}, "
                f"mean {np.mean(regrets):.4f}"
            )
