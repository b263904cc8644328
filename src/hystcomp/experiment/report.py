"""Tables and the written report of the comparison, beside the paper's numbers.

Files written by :func:`write_outputs` (as one set: all new, or all as they were):

* ``table1.csv``: ``frequency_hz, method, rms_um, max_um`` (the paper's Table I);
* ``hysteresis.csv``: ``method, hysteresis_pct, saturation_zone_pct`` at the lowest
  frequency (1 Hz, the paper's Fig. 9);
* the figures (:mod:`hystcomp.experiment.figures`);
* ``report.md``: our Table I beside the paper's, and a reading of the differences, every
  sentence of which is built from the numbers of this run.
"""

from __future__ import annotations

import csv
import io
import os
import tempfile
from pathlib import Path

from hystcomp import paper
from hystcomp.errors import InvalidParameterError
from hystcomp.experiment.figures import BACKGROUND_FIGURES, FIGURES, write_figures
from hystcomp.experiment.metrics import SATURATION_ZONE
from hystcomp.experiment.tracking import error_rows as table1_rows
from hystcomp.io.atomic import (
    atomic_path,
    check_output_path,
    replace_all,
    staging_folder,
    write_target,
)
from hystcomp.paper import LABELS, METHODS


def hysteresis_rows(comparison) -> list[dict]:
    """Hysteresis % at the lowest frequency, whole loop and saturation zone, per method.

    Parameters
    ----------
    comparison : Comparison
        The comparison; only its lowest frequency's results are read.

    Returns
    -------
    list of dict
        ``method``, ``hysteresis_pct`` and ``saturation_zone_pct``, a row per method.
    """
    low = min(comparison.results)
    return [
        {
            "method": m,
            "hysteresis_pct": r.hysteresis_pct,
            "saturation_zone_pct": r.saturation_zone_pct,
        }
        for m, r in comparison.results[low].items()
    ]


def _csv_text(rows: list[dict]) -> str:
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: f"{v:.6g}" if isinstance(v, float) else v for k, v in row.items()})
    return buffer.getvalue()


def _write_text(path: Path, text: str) -> None:
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def _figures(comparison, stage: Path, background) -> dict[str, str | None]:
    """The paper's figures in ``stage``: those of :data:`~hystcomp.experiment.figures.
    BACKGROUND_FIGURES` from ``background`` if it drew them, the others (or all) drawn here."""
    if background is None:
        return write_figures(comparison, stage)
    notes = write_figures(comparison, stage, [n for n in FIGURES if n not in BACKGROUND_FIGURES])
    drawn = background.collect()
    if drawn is None:
        notes.update(write_figures(comparison, stage, BACKGROUND_FIGURES))
    else:
        more, files = drawn
        for name, data in files.items():
            with atomic_path(stage / name) as tmp:
                tmp.write_bytes(data)
        notes.update(more)
    return {name: notes[name] for name in FIGURES if name in notes}


def format_table(comparison) -> str:
    """Table I as text for the terminal: our rms/max beside the paper's.

    Parameters
    ----------
    comparison : Comparison
        The comparison's results.

    Returns
    -------
    str
        The table, several lines.
    """
    lines = [
        f"{'f (Hz)':>7}  {'method':<14}{'rms (µm)':>10}{'paper':>9}{'max (µm)':>11}{'paper':>9}"
    ]
    for f, by_method in comparison.results.items():
        for m, r in by_method.items():
            ref = paper.TABLE_I.get(f, {}).get(m)
            p_rms, p_max = (f"{ref[0]:.3f}", f"{ref[1]:.3f}") if ref else ("-", "-")
            lines.append(
                f"{f:>7g}  {LABELS[m]:<14}{r.rms:>10.3f}{p_rms:>9}{r.max:>11.3f}{p_max:>9}"
            )
    if getattr(comparison, "dynamics", None) is not None:  # beyond the paper: no paper column
        lines.append("beyond the paper: with an inverse of the linear dynamics (creep, resonance)")
        for f, row in comparison.dynamics.results.items():
            for m, r in row.items():
                base, _, extra = m.partition(" + ")
                label = LABELS[base] + (f" + {extra}" if extra else "")
                lines.append(f"{f:>7g}  {label:<20}{r.rms:>10.3f}{'-':>9}{r.max:>11.3f}{'-':>9}")
    return "\n".join(lines)


def prepare_output_dir(out_dir) -> Path:
    """Create ``out_dir`` (and its parents) if needed; refuse a path that exists and is
    not a folder, and an empty path.

    Parameters
    ----------
    out_dir : str or os.PathLike
        The output folder.

    Returns
    -------
    pathlib.Path
        The folder, made if it was missing.
    """
    if not os.fspath(out_dir):
        raise InvalidParameterError(
            "The output folder is an empty path. Name a folder for the results "
            "(--out compare-out, or --out . for this folder)."
        )
    path = Path(os.fspath(out_dir))
    if path.exists() and not path.is_dir():
        raise InvalidParameterError(
            f"The output folder {str(path)!r} exists and is a file, not a folder. "
            "Choose another --out path or remove the file."
        )
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InvalidParameterError(
            f"Cannot create the output folder {str(path)!r}: {exc.strerror}. Choose another path."
        ) from None
    try:  # before the run, not after it: can files be written there?
        with tempfile.TemporaryFile(dir=path):
            pass
    except OSError as exc:
        raise InvalidParameterError(
            f"Cannot write into the output folder {str(path)!r}: {exc.strerror}. Choose "
            "another --out folder or check its permissions."
        ) from None
    return path


def write_outputs(comparison, out_dir, *, figures=None) -> list[Path]:
    """Write tables, figures and ``report.md`` into ``out_dir``; return the files written.

    Every file is first written into a hidden folder inside ``out_dir``, then all are
    renamed into place together (:func:`hystcomp.io.atomic.replace_all`): a failure or an
    interruption leaves the files of an earlier run as they were, never a mix of two runs.

    ``figures``, if given, is a :class:`~hystcomp.experiment.background.BackgroundJob`
    (:func:`~hystcomp.experiment.background.draw_in_background`) drawing :data:`~hystcomp.experiment.figures.BACKGROUND_FIGURES` with
    :func:`~hystcomp.experiment.figures.write_figures` for this comparison (from its Table
    I) while the others are drawn here; its files are written as they came, or its figures
    are drawn here too if it failed.

    Parameters
    ----------
    comparison : Comparison
        The comparison's results.
    out_dir : str or os.PathLike
        The output folder.
    figures : BackgroundJob, optional
        A job drawing some of the figures.

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    out = prepare_output_dir(out_dir)
    with staging_folder(out) as stage:
        _write_text(stage / "table1.csv", _csv_text(table1_rows(comparison)))
        _write_text(stage / "hysteresis.csv", _csv_text(hysteresis_rows(comparison)))
        dc = getattr(comparison, "dynamics", None)
        if dc is not None:  # beyond the paper; drawn first, while the figures process ends
            from hystcomp.experiment.compare_dynamics import dynamics_markdown
            from hystcomp.experiment.fig_dynamics import plot_step

            _write_text(stage / "dynamics.csv", _csv_text(table1_rows(dc)))
            t, x_ref = next(iter(dc.step.values()))[:2]
            plot_step(t, x_ref, {k: run[2] for k, run in dc.step.items()}, stage / "step_creep.png")
        notes = _figures(comparison, stage, figures)
        text = report_markdown(comparison, notes)
        names = ["table1.csv", "hysteresis.csv", *(n for n, why in notes.items() if why is None)]
        if dc is not None:
            text += "\n" + "\n".join(dynamics_markdown(dc, comparison.results))
            text += "\n![Step and hold](step_creep.png)\n"
            names += ["dynamics.csv", "step_creep.png"]
        _write_text(stage / "report.md", text)
        names.append("report.md")
        for name in names:
            check_output_path(out / name, what="output")
        try:
            replace_all([(stage / n, write_target(out / n)) for n in names])
        except OSError as exc:
            raise InvalidParameterError(
                f"Cannot write into {str(out)!r}: {exc.strerror or exc}; the files of any "
                "earlier run are unchanged. Check the permissions and the free space."
            ) from None
    return [out / n for n in names]


# ----------------------------------------------------------------------------- report text


def _ratio(ours: float, theirs: float) -> str:
    return f"{ours / theirs:.2f}x" if theirs else "-"


def _order(values: dict[str, float]) -> list[str]:
    return sorted(values, key=values.__getitem__)


def _order_text(order: list[str]) -> str:
    return " < ".join(LABELS[m] for m in order)


def report_markdown(comparison, figure_notes: dict[str, str | None]) -> str:
    """The report: set-up, Table I beside the paper's, hysteresis, a reading, the figures.

    Parameters
    ----------
    comparison : Comparison
        The comparison's results.
    figure_notes : dict
        ``{file name: None if drawn, else why not}``.

    Returns
    -------
    str
        The report, Markdown.
    """
    c = comparison
    low = min(c.results)
    parts = [
        "# The paper's experiment on the simulated axis",
        "",
        "Generated by `hystcomp compare`: the paper's identification signals were applied to the "
        "twin (the simulated piezo axis of Section II), the Preisach, PI and MPI models were "
        "identified from its answers, and each method tracked triangles at "
        + ", ".join(f"{f:g}" for f in c.results)
        + " Hz.",
        "",
        "## Set-up",
        "",
        *(f"- {line}" for line in _setup_lines(c)),
        "",
        "## Table I: rms and maximal tracking error (µm)",
        "",
        "| f (Hz) | method | rms (ours) | rms (paper) | ratio | max (ours) | max (paper) | ratio |",
        "|---:|---|---:|---:|---:|---:|---:|---:|",
    ]
    for f, by_method in c.results.items():
        for m, r in by_method.items():
            ref = paper.TABLE_I.get(f, {}).get(m)
            if ref is None:
                parts.append(f"| {f:g} | {LABELS[m]} | {r.rms:.3f} | - | - | {r.max:.3f} | - | - |")
            else:
                parts.append(
                    f"| {f:g} | {LABELS[m]} | {r.rms:.3f} | {ref[0]:.3f} | {_ratio(r.rms, ref[0])} "
                    f"| {r.max:.3f} | {ref[1]:.3f} | {_ratio(r.max, ref[1])} |"
                )
    parts += [
        "",
        f"## Hysteresis at {low:g} Hz (% of the displacement range)",
        "",
        f"Saturation zone: the top {100 * (1 - SATURATION_ZONE):.0f} % of the range.",
        "",
        "| method | whole loop (ours) | saturation zone (ours) | saturation zone (paper) |",
        "|---|---:|---:|---:|",
    ]
    for m, r in c.results[low].items():
        zone_ref = paper.SATURATION_ZONE_PCT.get(m) if low == paper.FIG9_FREQUENCY else None
        theirs = f"{zone_ref:g}" if zone_ref is not None else "-"
        parts.append(
            f"| {LABELS[m]} | {r.hysteresis_pct:.2f} | {r.saturation_zone_pct:.2f} | {theirs} |"
        )
    if c.preisach_exact:
        parts += [
            "",
            "## Preisach: inverse multiplicative structure (eq. 10) against the exact inverse",
            "",
            (
                "The exact inverse solves H(v) = x_ref on the current branch at every sample; "
                "the multiplicative structure uses the previous sample's H, so it lags by one "
                "sample."
            ),
            "",
            "| f (Hz) | rms, eq. 10 | rms, exact | max, eq. 10 | max, exact |",
            "|---:|---:|---:|---:|---:|",
        ]
        for f, exact in c.preisach_exact.items():
            mult = c.results[f]["preisach"]
            parts.append(
                f"| {f:g} | {mult.rms:.3f} | {exact.rms:.3f} | {mult.max:.3f} | {exact.max:.3f} |"
            )
    if c.paper_fit:
        low = min(c.results)
        none = c.results[low]["uncompensated"].rms
        parts += [
            "",
            "## Table I's fits against the paper's eqs. 5, 12 and 19 as printed",
            "",
            (
                "The default fit keeps the play weights beyond the first non-negative (the loop "
                "widens with amplitude, as on a piezo), spreads the play thresholds over half the "
                "input span (where plays can move), weighs every part of the input range the "
                "same (PI), and chooses the MPI regularisation and the plays' initial memory "
                "(eq. 18's virgin start, or descended, so that loops close at 0 V) by the "
                'predicted tracking error; the paper\'s fit (constraints="paper", '
                "regularization=0) only keeps every partial sum positive, so on an actuator of "
                "none of the model families its weights may alternate in sign and its inverse "
                "gets steep slopes. Table I's Preisach fit is the paper's (eq. 5 fitted to the "
                "reversal curves of the sinusoids) with X(v, v) = 0 imposed, as eq. 2 implies; "
                "fitted free, as printed, X(v, v) is not 0 and the output steps by it at every "
                "reversal."
            ),
            "",
            (
                f"| method ({low:g} Hz) | rms, Table I's fit | rms, paper's fit | "
                "ratio to uncompensated, Table I's | ratio, paper's |"
            ),
            "|---|---:|---:|---:|---:|",
        ]
        for kind, paper_run in c.paper_fit.items():
            ours = c.results[low][kind].rms
            parts.append(
                f"| {LABELS[kind]} | {ours:.3f} | {paper_run.rms:.3f} | {ours / none:.2f} | "
                f"{paper_run.rms / none:.2f} |"
            )
    parts += ["", "## Reading", ""]
    parts += [f"- {line}" for line in _reading(c)]
    parts += ["", "## Figures", ""]
    for name, why in figure_notes.items():
        parts.append(f"- `{name}`" + (f": {why}" if why else ""))
    return "\n".join(parts) + "\n"


def _setup_lines(c) -> list[str]:
    cfg = c.config
    noise_nm = 1e3 * cfg.twin.sensor_noise / cfg.twin.sensor_gain
    return [
        (
            f"Twin: seed {cfg.seed}, sensor noise {noise_nm:.1f} nm rms, resonance "
            f"{cfg.twin.resonance_hz:g} Hz (damping ratio {cfg.twin.damping_ratio:g}), creep "
            f"{100 * cfg.twin.creep_gain:g} % (not in the paper's Fig. 2; a real stage creeps, "
            "and the models identified at 1 Hz hold its faster part); largest "
            f"displacement in the identification record {c.record_pi.x.max():.2f} µm."
        ),
        (
            "Twin hysteresis: a rate-independent Bouc-Wen model calibrated on the loops of the "
            "paper's Preisach model (eq. 6); like them, its loops close at the rest position "
            "whenever the voltage returns to 0 V, which a Preisach model reproduces by "
            "structure and a PI or MPI model only with its plays started descended, not with "
            "eq. 18's virgin start."
        ),
        (
            f"Uncompensated baseline: v = x_ref / k_lin with k_lin = {c.gain:.4f} µm/V, the "
            "least-squares gain through the origin on the PI/MPI identification record."
        ),
        (
            f"References: triangles from 0 to {c.reference_amplitude:.2f} µm "
            f"({100 * cfg.reference_fraction:.0f} % of the measured stroke), {cfg.periods} "
            "periods each; errors and hysteresis are measured over the periods after the first."
        ),
        (
            f"Models: PI with {cfg.n_operators} plays, MPI with {cfg.n_operators} plays and "
            f"{cfg.n_deadzones} dead-zones, Preisach with a degree-{cfg.preisach_degree} Everett "
            f"function identified from {len(cfg.preisach_amplitudes)} sinusoids."
        ),
        _mpi_note(c.models["mpi"]),
        f"Run time of the experiment (identification and tracking): {c.seconds:.1f} s.",
    ]


def _reading(c) -> list[str]:
    """Observations computed from this run's numbers and the paper's."""
    lines = []
    common = [f for f in c.results if f in paper.TABLE_I]
    for f in common:
        ours = {m: r.rms for m, r in c.results[f].items()}
        theirs = {m: paper.TABLE_I[f][m][0] for m in ours}
        same = _order(ours) == _order(theirs)
        lines.append(
            f"At {f:g} Hz the methods rank by rms error as {_order_text(_order(ours))}"
            + (", as in the paper." if same else f"; the paper has {_order_text(_order(theirs))}.")
        )
    for f in common[:1]:
        base = c.results[f]["uncompensated"].rms
        p_base = paper.TABLE_I[f]["uncompensated"][0]
        gains = ", ".join(
            f"{LABELS[m]} {base / c.results[f][m].rms:.1f}x (paper {p_base / paper.TABLE_I[f][m][0]:.1f}x)"
            for m in METHODS[1:]
        )
        lines.append(f"Reduction of the rms error against no compensation at {f:g} Hz: {gains}.")
    if len(common) > 1:
        f0, f1 = common[0], common[-1]
        growth = ", ".join(
            f"{LABELS[m]} {c.results[f1][m].rms / c.results[f0][m].rms:.2f}x "
            f"(paper {paper.TABLE_I[f1][m][0] / paper.TABLE_I[f0][m][0]:.2f}x)"
            for m in METHODS
        )
        lines.append(f"Growth of the rms error from {f0:g} to {f1:g} Hz: {growth}.")
    lines += _baseline_reading(c, common)
    low = min(c.results)
    zone = {m: r.saturation_zone_pct for m, r in c.results[low].items()}
    compensated = {m: zone[m] for m in METHODS[1:]}
    worst = max(compensated, key=compensated.__getitem__)
    best = min(compensated, key=compensated.__getitem__)
    paper_zone = paper.SATURATION_ZONE_PCT
    p_worst = max(METHODS[1:], key=paper_zone.__getitem__)
    p_best = min(METHODS[1:], key=paper_zone.__getitem__)
    lines.append(
        f"In the saturation zone at {low:g} Hz the uncompensated loop has {zone['uncompensated']:.1f} % "
        f"of hysteresis (paper {paper_zone['uncompensated']:g} %); among the compensated methods "
        f"{LABELS[worst]} leaves the most ({compensated[worst]:.1f} %) and {LABELS[best]} the least "
        f"({compensated[best]:.1f} %); in the paper {LABELS[p_worst]} leaves the most "
        f"({paper_zone[p_worst]:g} %) and {LABELS[p_best]} the least ({paper_zone[p_best]:g} %)."
    )
    return lines


def _baseline_reading(c, common) -> list[str]:
    if not common:
        return []
    f = common[0]
    ours = c.results[f]["uncompensated"]
    sheet = c.datasheet[f]
    p_rms, p_max = paper.TABLE_I[f]["uncompensated"]
    closer = abs(sheet.rms - p_rms) < abs(ours.rms - p_rms)
    text = (
        f"The uncompensated error at {f:g} Hz is {ours.rms:.2f} µm rms and {ours.max:.2f} µm max, "
        f"{_ratio(ours.rms, p_rms)} and {_ratio(ours.max, p_max)} the paper's. With the datasheet "
        f"gain {paper.DATASHEET_GAIN} µm/V (Section II) instead of k_lin = {c.gain:.3f} µm/V the "
        f"same twin gives {sheet.rms:.2f} µm rms and {sheet.max:.2f} µm max, "
    )
    if closer:
        text += (
            "closer to the paper's column, which suggests that the paper's open-loop map used a "
            "gain near the datasheet value rather than one fitted to its data."
        )
    else:
        text += "no closer to the paper's column."
    return [text]


def _mpi_note(model) -> str:
    """How the MPI regularisation was chosen, if the model was fitted."""
    report = getattr(model, "fit_report_", {})
    value = report.get("regularization")
    if value is None:
        return "MPI model: given, not identified in this run."
    memory = report.get("initial_memory", "virgin")
    return (
        f"MPI identification: eq. 19 with non-negative play weights beyond the first and a "
        f"penalty on the inverse dead-zone weights (regularization {value:g}), the plays "
        f"starting {memory} ({_MEMORY[memory]}); of 0, 1e-4 .. 1e-1 and of both initial "
        "memories, those whose compensator is predicted to track best "
        "(hystcomp.identify.compensation). Eq. 19 as printed overfits a twin that is not an "
        "MPI system (see the section on the paper's fit below)."
    )


_MEMORY = {
    "virgin": "eq. 18's zero states",
    "descended": "as after a descent from the top, so that every loop closes at 0 V",
}
