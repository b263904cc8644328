"""``hystcomp identify``: a model from a measured record, with an optional hold-out test."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from hystcomp import paper
from hystcomp._hyperparameters import EVERETT_KINDS, MAX_DEGREE
from hystcomp.cli import main
from hystcomp.cli._options import (
    columns_option,
    count,
    fraction,
    fs_option,
    nonnegative,
    progress,
    quiet_option,
    read_options,
    voltage_range,
    warn_x_unit,
    x_unit_option,
)
from hystcomp.errors import IdentificationError
from hystcomp.identify.compensation import compensation_error
from hystcomp.identify.preisach import FIT_METHODS
from hystcomp.identify.preisach_lsq import MAX_LSQ_GRID
from hystcomp.identify.scoring import error_report, holdout_report, straight_line, transient_end
from hystcomp.io.atomic import atomic_paths, check_output_path
from hystcomp.io.models import MODEL_KINDS, model_text
from hystcomp.io.records import read_record

DEFAULT_OPERATORS = paper.N_OPERATORS

#: What each --model builds, and which size options it takes.
LABELS = {"pi": "PI", "mpi": "MPI", "preisach": "Preisach", "dynamics": "dynamics"}
SIZE_OPTIONS = {
    "pi": ("operators", "constraints"),
    "mpi": ("operators", "deadzones", "regularization", "constraints"),
    "preisach": ("degree", "fit", "everett", "grid"),
    "dynamics": (),
}
#: Largest --grid (the least-squares table fit has about grid^2 / 2 unknowns).
MAX_GRID = MAX_LSQ_GRID


def build_estimator(
    kind: str,
    *,
    operators,
    deadzones,
    voltage_range,
    regularization=None,
    degree=None,
    fit=None,
    everett=None,
    grid=None,
    constraints=None,
):
    """An unfitted model of ``kind`` from the registry :data:`hystcomp.io.models.MODEL_KINDS`."""
    cls = MODEL_KINDS.get(kind)
    if cls is None:
        raise IdentificationError(
            f"The {LABELS[kind]} model is not available in this version of hystcomp; "
            f"choose --model {' or '.join(k for k in LABELS if k in MODEL_KINDS)}."
        )
    given = {
        "operators": operators,
        "deadzones": deadzones,
        "regularization": regularization,
        "degree": degree,
        "fit": fit,
        "everett": everett,
        "grid": grid,
        "constraints": constraints,
    }
    for name, value in given.items():
        if value is not None and name not in SIZE_OPTIONS[kind]:
            raise click.UsageError(f"--{name} does not apply to --model {kind}.")
    params = {"voltage_range": voltage_range}
    if "operators" in SIZE_OPTIONS[kind]:
        params["n_operators"] = DEFAULT_OPERATORS if operators is None else operators
    if "deadzones" in SIZE_OPTIONS[kind]:
        params["n_deadzones"] = DEFAULT_OPERATORS if deadzones is None else deadzones
    if regularization is not None:
        params["regularization"] = regularization
    if degree is not None:
        params["degree"] = degree
    if kind == "preisach":
        params.update(_everett_params(fit, everett, degree, grid))
    if constraints is not None:
        params["constraints"] = constraints
    return cls(**params)


def _everett_params(fit, everett, degree, grid) -> dict:
    """The Preisach estimator's ``fit_method``, ``everett`` and ``grid_size`` from the options."""
    if everett == "table" and degree is not None:
        raise click.UsageError("--degree applies to --everett polynomial; a table has --grid.")
    if grid is not None and everett == "polynomial":
        raise click.UsageError("--grid applies to --everett table.")
    if degree is not None and everett is None:
        everett = "polynomial"  # a degree names the polynomial of eq. 5, not the default table
    params = {}
    if fit is not None:
        params["fit_method"] = fit
    if everett is not None:
        params["everett"] = everett
    if grid is not None:
        params["grid_size"] = grid
    return params


def _regularization(ctx, param, value):
    """``--regularization``: ``auto`` or a number >= 0."""
    if value is None or value == "auto":
        return value
    try:
        number = float(value)
    except ValueError:
        number = float("nan")
    if not number >= 0 or number == float("inf"):
        raise click.BadParameter(f"must be 'auto' or a number >= 0; got {value!r}.", param=param)
    return number


def _refuse_extrapolation(voltage_range, v) -> None:
    """Refuse a --voltage-range that reaches beyond the input the model is fitted on."""
    lo, hi = voltage_range
    v_lo, v_hi = float(v.min()), float(v.max())
    slack = 1e-9 * (v_hi - v_lo)
    if lo < v_lo - slack or hi > v_hi + slack:
        raise click.BadParameter(
            f"{lo:g} {hi:g} V reaches beyond the record's input ({v_lo:.6g} .. {v_hi:.6g} V): "
            "the compensator would command voltages the model never saw. Give a range "
            "within the record, record over the whole range, or pass --allow-extrapolation.",
            param_hint="'--voltage-range'",
        )


def _verdict(improvement: float) -> str:
    """``line rms / model rms`` in words: "2.5x better", or "1.14x worse" below 1."""
    if improvement >= 1.0:
        return f"{improvement:.3g}x better"
    if improvement > 0.0:
        return f"{1.0 / improvement:.3g}x worse"
    return "no better (the line fits the held-out part exactly)"


def _sizes(model) -> str:
    parts = []
    if hasattr(model, "n_operators"):
        parts.append(f"{model.n_operators} plays")
    if hasattr(model, "n_deadzones"):
        parts.append(f"{model.n_deadzones} dead-zones")
    return f" ({', '.join(parts)})" if parts else ""


@main.command("identify")
@click.argument("data", metavar="DATA")
@click.option(
    "--model", "kind", type=click.Choice(list(LABELS)), required=True, help="Model family."
)
@click.option(
    "--operators", type=int, default=None, callback=count, help="Number of plays n+1 [16]."
)
@click.option(
    "--deadzones",
    type=int,
    default=None,
    callback=count,
    help="Number of dead-zones m+1, mpi [16].",
)
@click.option(
    "--degree",
    type=click.IntRange(1, MAX_DEGREE),
    default=None,
    help="Degree of the Everett polynomial of a preisach model; implies --everett polynomial "
    "[3, eq. 5].",
)
@click.option(
    "--fit",
    type=click.Choice(FIT_METHODS),
    default=None,
    help="How the preisach model is fitted [least-squares]: least-squares fits the model's "
    "output over any record that sweeps the range, with a non-negative Preisach density; "
    "reversal-curves fits X to first-order descending curves (the record of `hystcomp excite "
    "preisach`), with --everett polynomial the paper's fit of eq. 5 (Section III-A); auto takes "
    "the reversal curves when the record has them from 8 or more maxima, else least squares.",
)
@click.option(
    "--everett",
    type=click.Choice(EVERETT_KINDS),
    default=None,
    help="Everett function of the preisach model: a table interpolated bilinearly (--grid) "
    "[table: it tracks better than the cubic on every actuator of benchmarks/bench_accuracy.py] "
    "or the polynomial of eq. 5 (--degree).",
)
@click.option(
    "--grid",
    type=click.IntRange(2, MAX_GRID),
    default=None,
    help="Nodes per axis of a preisach --everett table [25].",
)
@click.option(
    "--regularization",
    default=None,
    metavar="LAMBDA|auto",
    callback=_regularization,
    help="Penalty on the inverse dead-zone weights, mpi [auto: the value of 0, 1e-4 .. 1e-1 "
    "whose compensator is predicted to track best; 0 is eq. 19 as printed].",
)
@click.option(
    "--constraints",
    type=click.Choice(["physical", "paper"]),
    default=None,
    help="pi, mpi: 'physical' [default]: play weights beyond the first are non-negative, so "
    "the loops widen with amplitude and the inverse has no steep slopes, and the play "
    "thresholds span half the input range, where plays can move; 'paper': eq. 16's "
    "thresholds and only the partial-sum constraints of eq. 12 / eq. 19 as printed.",
)
@columns_option
@fs_option
@x_unit_option
@quiet_option
@click.option(
    "--transient",
    type=float,
    default=None,
    metavar="SECONDS",
    callback=nonnegative("s"),
    help="Start of the record left out of the fit [until the input first reaches an end "
    "of its range].",
)
@click.option(
    "--voltage-range",
    nargs=2,
    type=float,
    default=None,
    metavar="LO HI",
    callback=voltage_range,
    help="Amplifier range in V, the compensator's clamp [the record's range]. A range "
    "reaching beyond the record's input is refused, not capped (a cap would quietly give "
    "another range than asked): the compensator would command voltages the model never "
    "saw. --allow-extrapolation accepts it.",
)
@click.option(
    "--allow-extrapolation",
    is_flag=True,
    help="Accept a --voltage-range wider than the record's input; the model then "
    "extrapolates there.",
)
@click.option(
    "--holdout",
    type=float,
    default=None,
    metavar="FRACTION",
    callback=fraction,
    help="Fit on the first part only and report how well the model predicts this last "
    "fraction of the record, against a straight line.",
)
@click.option("--plot", default=None, metavar="FILE", help="Fig. 8-style figure (.png/.pdf/.svg).")
@click.option("-o", "--output", required=True, metavar="MODEL.json", help="Model file to write.")
def identify(
    data,
    kind,
    operators,
    deadzones,
    degree,
    fit,
    everett,
    grid,
    regularization,
    constraints,
    columns,
    sample_rate,
    x_unit,
    quiet,
    transient,
    voltage_range,
    allow_extrapolation,
    holdout,
    plot,
    output,
):
    """Identify a hysteresis model from DATA (columns t, v, x) and write it as JSON.

    PI and MPI: constrained least squares (eqs. 16-19) with invertible weights; the
    start-up transient, the input range (bipolar too) and a displacement offset are handled.
    Preisach: least squares over any record with a tabulated Everett function by default;
    --fit reversal-curves --everett polynomial is the paper's fit (Section III-A, eq. 5). dynamics (beyond the paper): creep and first resonance from the answer to
    'hystcomp excite dynamics', for compensate/export-c --dynamics; --plot draws its Bode plot.
    By default the play weights beyond the first are non-negative (--constraints physical);
    --constraints paper --regularization 0 is eq. 19 as printed.

    Besides the fit error, prints an estimate of the compensator's tracking error in µm
    rms (the inverse run on the measured displacement, its voltage error times the record's
    gain) beside the same estimate for a straight line, and warns when the compensator is
    predicted to do no better than the line, or when a hold-out leaves the fitted range.
    """
    check_output_path(output, inputs=(data,), what="model file")
    if plot is not None:  # matplotlib is imported only when a figure is asked for
        from hystcomp.experiment.fig_identification import FORMATS, plot_identification

        if Path(plot).suffix.lower() not in FORMATS:
            raise click.BadParameter(f"must end in {', '.join(FORMATS)}.", param_hint="--plot")
        check_output_path(plot, inputs=(data,), what="figure")
        if Path(plot).resolve() == Path(output).resolve():
            raise click.BadParameter("names the same file as -o.", param_hint="--plot")
    if kind == "dynamics":  # linear dynamics: a record of 'hystcomp excite dynamics'
        from hystcomp.cli._dynamics import identify_dynamics

        given = {"--operators": operators, "--deadzones": deadzones, "--degree": degree}
        given.update({"--regularization": regularization, "--transient": transient})
        given.update({"--voltage-range": voltage_range, "--holdout": holdout})
        for name, value in given.items():
            if value is not None:
                raise click.UsageError(f"{name} does not apply to --model dynamics.")
        identify_dynamics(read_record(data, **read_options(columns, sample_rate)), output, plot)
        return
    model = build_estimator(
        kind,
        operators=operators,
        deadzones=deadzones,
        voltage_range=voltage_range,
        regularization=regularization,
        degree=degree,
        fit=fit,
        everett=everett,
        grid=grid,
        constraints=constraints,
    )
    rec = read_record(data, **read_options(columns, sample_rate, x_unit, quiet, data))
    warn_x_unit(rec.x, data, quiet)
    n = len(rec)
    n_fit = n if holdout is None else n - round(holdout * n)
    if holdout is not None and not 2 <= n_fit < n:
        raise IdentificationError(
            f"--holdout {holdout} leaves {n_fit} of {n} samples to fit on; choose a fraction "
            "that keeps samples on both sides."
        )
    v, x = rec.v[:n_fit], rec.x[:n_fit]
    if voltage_range is not None and not allow_extrapolation:
        _refuse_extrapolation(voltage_range, v)
    if transient is None:
        start = transient_end(v)
    else:
        start = int(np.searchsorted(rec.t - rec.t[0], transient, side="left"))
    with progress(f"identifying the {LABELS[kind]} model", quiet).ticking():
        if "transient" in model.get_params():
            if transient is not None:
                model.transient = start
            model.fit(v, x)
        else:  # a model without its own transient option is fitted on the settled part only
            model.fit(v[start:], x[start:])
    x_model = model.simulate(v)
    report = error_report(x, x_model, start)

    label = LABELS[kind]
    click.echo(f"{label} model{_sizes(model)} from {rec.source}")
    click.echo(
        f"  record:    {n} samples at {rec.sample_rate:.6g} Hz ({rec.t[-1] - rec.t[0]:.4g} s), "
        f"v {rec.v.min():.4g} .. {rec.v.max():.4g} V, x {rec.x.min():.4g} .. {rec.x.max():.4g} µm"
    )
    skipped = f" (first {start} left out: start-up transient)" if start else ""
    click.echo(f"  fitted on: samples {start + 1}..{n_fit}{skipped}")
    if model.get_params().get("regularization") == "auto":
        chosen = model.fit_report_["regularization"]
        click.echo(
            f"  regularization: {chosen:g} (auto: the best predicted tracking of 0, 1e-4 .. 1e-1)"
        )
    if kind == "preisach":
        click.echo(f"  Everett fit: {_preisach_fit_line(model)}")
    click.echo(
        f"  fit error: rms {report['rms_error_um']:.4g} µm "
        f"({report['rms_error_percent']:.3g} % of {report['displacement_range_um']:.4g} µm), "
        f"max {report['max_error_um']:.4g} µm ({report['max_error_percent']:.3g} %)"
    )
    est = compensation_error(model, v, x, start=start)
    click.echo(
        f"  compensation (estimated): tracking rms {est['tracking_rms_um']:.4g} µm, straight "
        f"line v = x/k_lin {est['baseline_rms_um']:.4g} µm ({est['ratio']:.2g}x)"
    )
    if not est["ratio"] < 1.0:
        click.echo(
            f"hystcomp: warning: the {label} compensator is predicted to track no better than "
            f"a straight line ({est['tracking_rms_um']:.3g} vs {est['baseline_rms_um']:.3g} µm "
            "rms); record a signal with turning points across the range (hystcomp excite "
            "rich) or try another model.",
            err=True,
        )
    if holdout is not None:
        held = holdout_report(model, rec.v, rec.x, n_fit, start)
        click.echo(
            f"  hold-out:  last {held['n_holdout']} samples ({100 * holdout:g} %): model rms "
            f"{held['model_rms_um']:.4g} µm, straight line rms {held['line_rms_um']:.4g} µm: "
            f"{_verdict(held['improvement'])}"
        )
        lo, hi = float(v.min()), float(v.max())
        held_v = rec.v[n_fit:]
        if held_v.min() < lo or held_v.max() > hi:
            click.echo(
                f"hystcomp: warning: the hold-out drives {held_v.min():.4g} .. "
                f"{held_v.max():.4g} V, beyond the fitted range {lo:.4g} .. {hi:.4g} V; the "
                "model extrapolates there. Hold out a part that stays inside the range.",
                err=True,
            )
    # Everything is computed; now write all outputs at once (a failure writes none of them).
    text = model_text(model)
    outputs = [output] if plot is None else [output, plot]
    with atomic_paths(*outputs) as (tmp_model, *tmp_plot):
        tmp_model.write_text(text, encoding="utf-8")
        if plot is not None:
            a, b = straight_line(v[start:], x[start:])
            line = a * v[start:] + b
            plot_identification(
                v[start:], x[start:], line, x_model[start:], tmp_plot[0], model_name=label
            )
    for path in outputs[::-1]:
        click.echo(f"  wrote {path}")


def _preisach_fit_line(model) -> str:
    """How a Preisach model was fitted, in a few words."""
    report = model.fit_report_
    what = (
        f"{model.grid_size} x {model.grid_size} table"
        if model.everett == "table"
        else f"degree-{model.degree} polynomial"
    )
    if report["fit"] == "reversal-curves":
        how = f"reversal curves from {report['n_curves']} maxima"
        if model.everett == "polynomial":
            how += " (paper, Section III-A)"
    else:
        how = "least squares over the record, non-negative density"
    why = ""
    if model.fit_method == "auto":
        why = (
            " (auto: first-order descending curves from 8 or more maxima)"
            if report["fit"] == "reversal-curves"
            else " (auto: the record has too few first-order descending curves)"
        )
    return f"{what}, {how}{why}"
