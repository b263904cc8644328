"""``hystcomp identify``: a model from a measured record, with an optional hold-out test.

The work is :mod:`hystcomp.workflows` (:func:`~hystcomp.workflows.identify.identify_record`,
``auto``, ``pair``, ``multiaxis``); this module parses the options, prints the result and
writes the files.
"""

from __future__ import annotations

import functools

import click

from hystcomp._hyperparameters import EVERETT_KINDS, MAX_DEGREE
from hystcomp._validation import MAX_MAGNITUDE
from hystcomp.cli import _options as opts
from hystcomp.cli import command, refuse, report
from hystcomp.cli import option as cli_option
from hystcomp.identify.preisach import FIT_METHODS
from hystcomp.identify.preisach_lsq import MAX_LSQ_GRID
from hystcomp.io.atomic import check_output_path
from hystcomp.io.multiaxis import is_multiaxis
from hystcomp.io.records import read_record
from hystcomp.workflows.identify import LABELS, SIZE_OPTIONS
from hystcomp.workflows.record import identify_model

option = functools.partial(cli_option, "identify")
#: The options that size or shape the hysteresis model, of every family.
FAMILY = list(dict.fromkeys(name for names in SIZE_OPTIONS.values() for name in names))


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
    try:
        number = float(value) if value not in (None, "auto") else 0.0
    except ValueError:
        number = float("nan")
    if not 0 <= number <= MAX_MAGNITUDE:
        raise click.BadParameter(
            f"must be 'auto' or a number from 0 to {MAX_MAGNITUDE:g}; got {value!r}.", param=param
        )
    return value if value in (None, "auto") else number


@command("identify")
@click.argument("data", metavar="DATA")
@option("--model", "kind", type=click.Choice(["auto", *LABELS]), default="auto", show_default=True)
@option("--operators", type=int, callback=opts.count)
@option("--deadzones", type=int, callback=opts.count)
@option("--degree", type=click.IntRange(1, MAX_DEGREE))
@option("--fit", type=click.Choice(FIT_METHODS))
@option("--everett", type=click.Choice(EVERETT_KINDS))
@option("--grid", type=click.IntRange(2, MAX_LSQ_GRID))
@option("--regularization", metavar="LAMBDA|auto", callback=_regularization)
@option("--constraints", type=click.Choice(["physical", "paper"]))
@option("--initial-memory", type=click.Choice(["auto", "virgin", "descended"]))
@opts.reading
@option("--transient", type=float, metavar="SECONDS", callback=opts.positive("s", strict=False))
@option("--voltage-range", nargs=2, type=float, metavar="LO HI", callback=opts.voltage_range)
@option("--allow-extrapolation", is_flag=True)
@option("--holdout", type=float, metavar="FRACTION", callback=opts.fraction)
@option("--dynamics-record", metavar="DYN")
@option("--jobs", "n_jobs", type=int)
@option("--plot", metavar="FILE")
@option("-o", "--output", required=True, metavar="MODEL.json")
def identify(data, kind, output, plot, dynamics_record, holdout, voltage_range, **o):
    """``hystcomp identify``: parse, identify (:mod:`hystcomp.workflows`), print, write."""
    inputs = (data,) if dynamics_record is None else (data, dynamics_record)
    check_output_path(output, inputs=inputs, what="model file")
    options = {name: o[name] for name in FAMILY}
    multi = is_multiaxis(data, o["columns"])
    if multi:  # N coupled axes: each axis's model and the coupling
        given = {"--model dynamics": kind == "dynamics" or None, "--holdout": holdout}
        refuse({**given, "--dynamics-record": dynamics_record, "--plot": plot}, "an N-axis record")
    elif kind == "dynamics":  # linear dynamics: a record of 'hystcomp excite dynamics'
        given = {f"--{k.replace('_', '-')}": v for k, v in options.items()}
        given.update({"--transient": o["transient"], "--voltage-range": voltage_range})
        given.update({"--holdout": holdout, "--dynamics-record": dynamics_record})
        refuse(given, "--model dynamics")
    elif o["n_jobs"] is not None:
        raise click.UsageError("--jobs applies to N-axis records (columns v1..vN, x1..xN).")
    _check_options(kind, options)
    if plot is not None:
        opts.check_plot(plot, inputs=inputs, output=output)
    given = {k: v for k, v in options.items() if v is not None}
    fitting = {"allow_extrapolation": o["allow_extrapolation"], "transient": o["transient"]}
    fitting["unit_check"] = False  # checked here before the fit, and silenced by --quiet
    reading = opts.read_options(o, data, reads=None if multi else ("v", "x"))

    def ticking(what: str):
        return opts.progress(f"identifying {what}", o["quiet"]).ticking()

    if multi:
        from hystcomp.io.multiaxis import read_axes
        from hystcomp.workflows.multiaxis import identify_axes

        table = read_axes(data, ("v", "x"), **reading)
        with ticking(f"{table['v'].shape[1]} axes"):
            axes = identify_axes(
                table["t"],
                table["v"],
                table["x"],
                kind=kind,
                n_jobs=o["n_jobs"],
                source=str(data),
                voltage_range=voltage_range,
                **fitting,
                **given,
            )
        report(axes)
        return opts.write_model(axes.model, output)
    plain = opts.read_options({**o, "x_unit": None, "quiet": True})  # a dynamics record
    rec = read_record(data, **(plain if kind == "dynamics" else reading))
    if kind != "dynamics":
        opts.warn_x_unit(rec.x, data, o)
    dyn = None if dynamics_record is None else read_record(dynamics_record, **plain)
    found = identify_model(
        rec,
        kind,
        dynamics_record=dyn,
        holdout=holdout,
        progress=lambda k: ticking(f"the {LABELS[k]} model"),
        **({} if kind == "dynamics" else {"voltage_range": voltage_range, **fitting, **given}),
    )
    report(found)

    def draw(path):  # the fitted part and the hold-out as the model predicts it, or a Bode plot
        from hystcomp.experiment.fig_dynamics import plot_bode
        from hystcomp.experiment.fig_identification import plot_identification_result

        if found.hysteresis is None:
            return plot_bode(found.model, path)
        plot_identification_result(rec, found.hysteresis, path)

    opts.write_model(found.model, output, plot, draw)
