"""``hystcomp identify``: a model from a measured record, with an optional hold-out test."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

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
from hystcomp.data import read_record
from hystcomp.errors import IdentificationError
from hystcomp.identify.preisach import MAX_DEGREE
from hystcomp.identify.scoring import error_report, holdout_report, straight_line, transient_end
from hystcomp.io import MODEL_KINDS, atomic_paths, check_output_path, model_text

DEFAULT_OPERATORS = 16

#: What each --model builds, and which size options it takes.
LABELS = {"pi": "PI", "mpi": "MPI", "preisach": "Preisach"}
SIZE_OPTIONS = {
    "pi": ("operators",),
    "mpi": ("operators", "deadzones", "regularization"),
    "preisach": ("degree",),
}


def build_estimator(
    kind: str, *, operators, deadzones, voltage_range, regularization=None, degree=None
):
    """An unfitted model of ``kind`` from the registry :data:`hystcomp.io.MODEL_KINDS`."""
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
    return cls(**params)


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
    help="Degree of the Everett polynomial, preisach [3, eq. 5].",
)
@click.option(
    "--regularization",
    default=None,
    metavar="LAMBDA|auto",
    callback=_regularization,
    help="Penalty on the inverse dead-zone weights, mpi [auto: the value of 0, 1e-4 .. 1e-1 "
    "whose model best reproduces the record; 0 is eq. 19 as printed].",
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
    help="Amplifier range in V, the compensator's clamp [the record's range].",
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
    regularization,
    columns,
    sample_rate,
    x_unit,
    quiet,
    transient,
    voltage_range,
    holdout,
    plot,
    output,
):
    """Identify a hysteresis model from DATA (columns t, v, x) and write it as JSON.

    PI and MPI: constrained least squares (eqs. 16-19) with invertible weights; the
    start-up transient, the input range (bipolar too) and a displacement offset are handled.
    """
    check_output_path(output, inputs=(data,), what="model file")
    if plot is not None:  # matplotlib is imported only when a figure is asked for
        from hystcomp.experiment.fig_identification import FORMATS, plot_identification

        if Path(plot).suffix.lower() not in FORMATS:
            raise click.BadParameter(f"must end in {', '.join(FORMATS)}.", param_hint="--plot")
        check_output_path(plot, inputs=(data,), what="figure")
        if Path(plot).resolve() == Path(output).resolve():
            raise click.BadParameter("names the same file as -o.", param_hint="--plot")
    model = build_estimator(
        kind,
        operators=operators,
        deadzones=deadzones,
        voltage_range=voltage_range,
        regularization=regularization,
        degree=degree,
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
            f"  regularization: {chosen:g} (auto: the smallest fit error of 0, 1e-4 .. 1e-1)"
        )
    click.echo(
        f"  fit error: rms {report['rms_error_um']:.4g} µm "
        f"({report['rms_error_percent']:.3g} % of {report['displacement_range_um']:.4g} µm), "
        f"max {report['max_error_um']:.4g} µm ({report['max_error_percent']:.3g} %)"
    )
    if holdout is not None:
        held = holdout_report(model, rec.v, rec.x, n_fit, start)
        click.echo(
            f"  hold-out:  last {held['n_holdout']} samples ({100 * holdout:g} %): model rms "
            f"{held['model_rms_um']:.4g} µm, straight line rms {held['line_rms_um']:.4g} µm: "
            f"{held['improvement']:.3g}x better"
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
