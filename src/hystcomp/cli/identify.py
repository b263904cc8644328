"""``hystcomp identify``: a model from a measured record, with an optional hold-out test.

The work is :func:`hystcomp.identify.workflow.identify_record`; this module parses the
options, prints the result and writes the files.
"""

from __future__ import annotations

from pathlib import Path

import click

from hystcomp._hyperparameters import EVERETT_KINDS, MAX_DEGREE
from hystcomp._validation import MAX_MAGNITUDE
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
from hystcomp.identify.preisach import FIT_METHODS
from hystcomp.identify.preisach_lsq import MAX_LSQ_GRID
from hystcomp.identify.workflow import (
    LABELS,
    SIZE_OPTIONS,
    build_estimator,
    extrapolation_error,
    fit_samples,
    identify_record,
)
from hystcomp.io.atomic import atomic_paths, check_output_path
from hystcomp.io.models import model_text
from hystcomp.io.records import read_record

#: Largest --grid (the least-squares table fit has about grid^2 / 2 unknowns).
MAX_GRID = MAX_LSQ_GRID


def _check_options(kind: str, given: dict) -> None:
    """Refuse, in the command's words, an option that --model (or --everett) does not take."""
    for name, value in given.items():
        if value is not None and kind != "auto" and name not in SIZE_OPTIONS[kind]:
            option = name.replace("_", "-")
            raise click.UsageError(f"--{option} does not apply to --model {kind}.")
    if given["everett"] == "table" and given["degree"] is not None:
        raise click.UsageError("--degree applies to --everett polynomial; a table has --grid.")
    if given["grid"] is not None and given["everett"] == "polynomial":
        raise click.UsageError("--grid applies to --everett table.")
    if given["grid"] is not None and given["degree"] is not None:
        raise click.UsageError(
            "--grid and --degree exclude each other: --degree fits the polynomial of eq. 5, "
            "--grid a table; give one of them."
        )


def _regularization(ctx, param, value):
    """``--regularization``: ``auto`` or a number >= 0."""
    if value is None or value == "auto":
        return value
    try:
        number = float(value)
    except ValueError:
        number = float("nan")
    if not 0 <= number <= MAX_MAGNITUDE:
        raise click.BadParameter(
            f"must be 'auto' or a number from 0 to {MAX_MAGNITUDE:g}; got {value!r}.", param=param
        )
    return number


@main.command("identify")
@click.argument("data", metavar="DATA")
@click.option(
    "--model",
    "kind",
    type=click.Choice(["auto", *LABELS]),
    default="auto",
    show_default=True,
    help="Model family; auto fits PI, MPI and Preisach and keeps the one whose compensator "
    "is predicted to track best (the ranking is printed); dynamics: the linear dynamics "
    "alone.",
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
    "preisach`), with --everett polynomial and --constraints paper the paper's fit of eq. 5 "
    "(Section III-A); auto takes "
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
    "thresholds span half the input range, where plays can move (pi: and every part of the "
    "input range weighs the same in the fit); 'paper': eq. 16's thresholds, eq. 12 / eq. 19 "
    "with only the invertibility constraints (every partial sum of the weights positive). "
    "preisach: 'physical' [default] holds X(v, v) = 0, as eq. 2 implies; 'paper' fits eq. 5's "
    "coefficients free (with --fit reversal-curves --everett polynomial).",
)
@click.option(
    "--initial-memory",
    type=click.Choice(["auto", "virgin", "descended"]),
    default=None,
    help="mpi: where the plays start, for the fit and the compensator [auto: the better "
    "predicted tracking on the record]. 'descended' is a stage at rest after it has been "
    "driven, as most are when a reference starts; 'virgin' is eq. 18. The record cannot "
    "say how the stage will start: give it when you know.",
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
    "saw. --allow-extrapolation accepts it. A Preisach model's plane covers the record's "
    "whole input: narrow its clamp with compensate's --voltage-range.",
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
@click.option(
    "--dynamics-record",
    default=None,
    metavar="DYN",
    help="Also identify the linear dynamics (creep, resonance), from this answer to "
    "'hystcomp excite dynamics' (same --columns and --fs), as one pair with the hysteresis "
    "model: D behind H, H in front of D, alternated. Writes the pair; compensate and "
    "export-c then invert both (beyond the paper).",
)
@click.option(
    "--jobs",
    "n_jobs",
    type=int,
    default=None,
    help="N-axis records: axes identified in parallel by joblib (-1: every core) [1].",
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
    initial_memory,
    columns,
    sample_rate,
    x_unit,
    quiet,
    transient,
    voltage_range,
    allow_extrapolation,
    holdout,
    dynamics_record,
    n_jobs,
    plot,
    output,
):
    """Identify a hysteresis model from DATA (columns t, v, x) and write it as JSON.

    A DATA with columns v1..vN, x1..xN (N coupled axes) gives an N-axis model: each axis's
    model (--model and its options apply to every axis) and the coupling between them.

    PI and MPI: constrained least squares (eqs. 16-19) with invertible weights; the
    start-up transient, the input range (bipolar too) and a displacement offset are handled.
    Preisach: least squares over any record with a tabulated Everett function by default;
    --fit reversal-curves --everett polynomial --constraints paper is the paper's fit (Section
    III-A, eq. 5). dynamics (beyond the paper): creep and first resonance (and a second mode
    when the record shows one) from the answer to 'hystcomp excite dynamics', for
    compensate/export-c --dynamics; --plot draws its Bode plot.
    By default the play weights beyond the first are non-negative (--constraints physical);
    --constraints paper --regularization 0 is eq. 19 as printed.

    Besides the fit error, prints an estimate of the compensator's tracking error in µm
    rms (the model's error on the record's swings and its inverse's on its own model) beside
    a straight line's, and the error on reversal branches a cross-validation left out; warns
    when the compensator is predicted to do no better than the line, when the latter is
    more than twice the former, or when a hold-out leaves the fitted range.
    """
    inputs = (data,) if dynamics_record is None else (data, dynamics_record)
    check_output_path(output, inputs=inputs, what="model file")
    from hystcomp.io.multiaxis import is_multiaxis

    if is_multiaxis(data, columns):  # t, v1..vN, x1..xN: N coupled axes
        from hystcomp.cli._multiaxis import identify_multiaxis, refuse

        why = "an N-axis record"
        refuse("--model dynamics", kind == "dynamics" or None, why)
        for name, value in (("--holdout", holdout), ("--dynamics-record", dynamics_record)):
            refuse(name, value, why)
        refuse("--plot", plot, why)
        options = {"operators": operators, "deadzones": deadzones, "degree": degree}
        options.update(fit=fit, everett=everett, grid=grid, regularization=regularization)
        options.update(constraints=constraints, initial_memory=initial_memory)
        _check_options(kind, options)
        identify_multiaxis(
            data,
            output,
            kind=kind,
            options=options,
            columns=columns,
            sample_rate=sample_rate,
            x_unit=x_unit,
            quiet=quiet,
            transient=transient,
            voltage_range=voltage_range,
            allow_extrapolation=allow_extrapolation,
            n_jobs=n_jobs,
        )
        return
    if n_jobs is not None:
        raise click.UsageError("--jobs applies to N-axis records (columns v1..vN, x1..xN).")
    if plot is not None:  # matplotlib is imported only when a figure is asked for
        from hystcomp.experiment.fig_identification import FORMATS, plot_identification_result

        if Path(plot).suffix.lower() not in FORMATS:
            raise click.BadParameter(f"must end in {', '.join(FORMATS)}.", param_hint="--plot")
        check_output_path(plot, inputs=inputs, what="figure")
        if Path(plot).resolve() == Path(output).resolve():
            raise click.BadParameter("names the same file as -o.", param_hint="--plot")
    if kind == "dynamics":  # linear dynamics: a record of 'hystcomp excite dynamics'
        from hystcomp.cli._dynamics import identify_dynamics

        given = {"--operators": operators, "--deadzones": deadzones, "--degree": degree}
        given.update({"--regularization": regularization, "--transient": transient})
        given.update({"--voltage-range": voltage_range, "--holdout": holdout})
        given["--initial-memory"] = initial_memory
        given["--dynamics-record"] = dynamics_record
        for name, value in given.items():
            if value is not None:
                raise click.UsageError(f"{name} does not apply to --model dynamics.")
        identify_dynamics(read_record(data, **read_options(columns, sample_rate)), output, plot)
        return
    options = {"operators": operators, "deadzones": deadzones}
    options.update(regularization=regularization, degree=degree, fit=fit, everett=everett)
    options.update(grid=grid, constraints=constraints, initial_memory=initial_memory)
    _check_options(kind, options)
    if kind != "auto":
        model = build_estimator(kind, voltage_range=voltage_range, **options)
    rec = read_record(data, **read_options(columns, sample_rate, x_unit, quiet, data))
    warn_x_unit(rec.x, data, quiet, x_unit)
    n = len(rec)
    n_fit = fit_samples(n, holdout)
    if holdout is not None and not 2 <= n_fit < n:
        raise IdentificationError(
            f"--holdout {holdout} leaves {n_fit} of {n} samples to fit on; choose a fraction "
            "that keeps samples on both sides."
        )
    why = None if voltage_range is None else extrapolation_error(voltage_range, rec.v[:n_fit])
    if why is not None and not allow_extrapolation:
        raise click.BadParameter(
            f"{why}: the compensator would command voltages the model never saw. Give a "
            "range within the record, record over the whole range, or pass "
            "--allow-extrapolation.",
            param_hint="'--voltage-range'",
        )
    fitting = {
        "allow_extrapolation": allow_extrapolation,
        "transient": transient,
        "unit_check": False,  # checked above, before the fit, and silenced by --quiet
    }
    if dynamics_record is not None and holdout is not None:
        raise click.UsageError(
            "--holdout does not apply with --dynamics-record: the pair's tracking is "
            "estimated on the dynamics record's triangles. Hold out without it."
        )
    lines: list[str] = []
    fitted = None  # the hysteresis model's identification, where auto made it
    if kind == "auto":
        from hystcomp.workflows.auto import identify_best

        chosen = identify_best(
            rec,
            voltage_range=voltage_range,
            holdout=holdout,
            progress=lambda k: progress(f"identifying the {LABELS[k]} model", quiet).ticking(),
            **{k: v for k, v in options.items() if v is not None},
            **fitting,
        )
        lines += chosen.lines
        fitted = chosen.best
    else:
        fitting["progress"] = progress(f"identifying the {LABELS[kind]} model", quiet).ticking()
    if dynamics_record is None:
        result = fitted or identify_record(rec, model, holdout=holdout, **fitting)
        lines, warnings, written = lines + result.lines, result.warnings, result.model
    else:
        from hystcomp.workflows.pair import identify_pair_record

        dyn = read_record(dynamics_record, **read_options(columns, sample_rate))
        if fitted is not None:
            paired = identify_pair_record(rec, dyn, fitted.model, hysteresis=fitted)
        else:
            paired = identify_pair_record(rec, dyn, model, **fitting)
        result = paired.hysteresis
        lines = lines + result.lines + paired.lines
        warnings = result.warnings + paired.warnings
        written = paired.model
    for line in lines:
        click.echo(line)
    for warning in warnings:
        click.echo(f"hystcomp: warning: {warning}", err=True)
    # Everything is computed; now write all outputs at once (a failure writes none of them).
    text = model_text(written)
    outputs = [output] if plot is None else [output, plot]
    with atomic_paths(*outputs) as (tmp_model, *tmp_plot):
        tmp_model.write_text(text, encoding="utf-8")
        if plot is not None:  # the fitted part, and the hold-out as the model predicts it
            plot_identification_result(rec, result, tmp_plot[0])
    for path in outputs[::-1]:
        click.echo(f"  wrote {path}")
