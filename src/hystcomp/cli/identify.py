"""``hystcomp identify``: a model from a measured record, with an optional hold-out test.

The work is :mod:`hystcomp.workflows` (:func:`~hystcomp.workflows.identify.identify_record`,
``auto``, ``pair``, ``multiaxis``); this module parses the options, prints the result and
writes the files.
"""

from __future__ import annotations

import click

from hystcomp._hyperparameters import EVERETT_KINDS, MAX_DEGREE
from hystcomp._validation import MAX_MAGNITUDE
from hystcomp.cli import main, refuse, report
from hystcomp.cli._options import (
    check_plot,
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
    write_model,
    x_unit_option,
)
from hystcomp.identify.preisach import FIT_METHODS
from hystcomp.identify.preisach_lsq import MAX_LSQ_GRID
from hystcomp.io.atomic import check_output_path
from hystcomp.io.multiaxis import is_multiaxis
from hystcomp.io.records import read_record
from hystcomp.workflows.identify import LABELS, SIZE_OPTIONS, build_estimator, identify_record


def _check_options(kind: str, given: dict) -> None:
    """Refuse, in the command's words, an option that --model (or --everett) does not take."""
    for name, value in given.items():
        if value is not None and kind != "auto" and name not in SIZE_OPTIONS[kind]:
            raise click.UsageError(f"--{name.replace('_', '-')} does not apply to --model {kind}.")
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
    type=click.IntRange(2, MAX_LSQ_GRID),
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
    options = {"operators": operators, "deadzones": deadzones, "regularization": regularization}
    options.update(degree=degree, fit=fit, everett=everett, grid=grid, constraints=constraints)
    options["initial_memory"] = initial_memory
    multi = is_multiaxis(data, columns)
    if multi:  # N coupled axes: each axis's model and the coupling
        given = {"--model dynamics": kind == "dynamics" or None, "--holdout": holdout}
        refuse({**given, "--dynamics-record": dynamics_record, "--plot": plot}, "an N-axis record")
    elif kind == "dynamics":  # linear dynamics: a record of 'hystcomp excite dynamics'
        given = {f"--{k.replace('_', '-')}": v for k, v in options.items()}
        given.update({"--transient": transient, "--voltage-range": voltage_range})
        refuse(
            {**given, "--holdout": holdout, "--dynamics-record": dynamics_record},
            "--model dynamics",
        )
    elif n_jobs is not None:
        raise click.UsageError("--jobs applies to N-axis records (columns v1..vN, x1..xN).")
    if dynamics_record is not None and holdout is not None:
        raise click.UsageError(
            "--holdout does not apply with --dynamics-record: the pair's tracking is "
            "estimated on the dynamics record's triangles. Hold out without it."
        )
    _check_options(kind, options)
    if plot is not None:
        check_plot(plot, inputs=inputs, output=output)
    given = {k: v for k, v in options.items() if v is not None}
    fitting = {"allow_extrapolation": allow_extrapolation, "transient": transient}
    fitting["unit_check"] = False  # checked here before the fit, and silenced by --quiet
    reading = read_options(columns, sample_rate, x_unit, quiet, data, reads=None)
    if multi:
        from hystcomp.io.multiaxis import read_axes
        from hystcomp.workflows.multiaxis import identify_axes

        table = read_axes(data, ("v", "x"), **reading)
        with progress(f"identifying {table['v'].shape[1]} axes", quiet).ticking():
            axes = identify_axes(
                *(table[k] for k in "tvx"),
                kind=kind,
                n_jobs=n_jobs,
                source=str(data),
                voltage_range=voltage_range,
                **fitting,
                **given,
            )
        report(axes)
        return write_model(axes.model, output)
    if kind == "dynamics":
        from hystcomp.experiment.fig_dynamics import plot_bode
        from hystcomp.workflows.pair import identify_dynamics_record

        found = identify_dynamics_record(read_record(data, **read_options(columns, sample_rate)))
        report(found)
        return write_model(found.model, output, plot, lambda path: plot_bode(found.model, path))
    model = kind if kind == "auto" else build_estimator(kind, voltage_range=voltage_range, **given)
    rec = read_record(data, **reading)
    warn_x_unit(rec.x, data, quiet, x_unit)
    if kind == "auto":
        from hystcomp.workflows.auto import identify_best

        chosen = identify_best(
            rec,
            voltage_range=voltage_range,
            holdout=holdout,
            progress=lambda k: progress(f"identifying the {LABELS[k]} model", quiet).ticking(),
            **given,
            **fitting,
        )
        said, result = [chosen], chosen.best  # the results whose report is printed, in order
    else:
        fitting["progress"] = progress(f"identifying the {LABELS[kind]} model", quiet).ticking()
        said, result = [], None
    if dynamics_record is None:
        result = result or identify_record(rec, model, holdout=holdout, **fitting)
        said.append(result)
        written = result.model
    else:
        from hystcomp.workflows.pair import identify_pair_record

        dyn = read_record(dynamics_record, **read_options(columns, sample_rate))
        if result is None:
            paired = identify_pair_record(rec, dyn, model, **fitting)
        else:  # the model auto fitted, not fitted again
            paired = identify_pair_record(rec, dyn, result.model, hysteresis=result)
        result, written = paired.hysteresis, paired.model
        said += [result, paired]
    report(*said)

    def draw(path):  # the fitted part, and the hold-out as the model predicts it
        from hystcomp.experiment.fig_identification import plot_identification_result

        plot_identification_result(rec, result, path)

    write_model(written, output, plot, draw)
