"""``hystcomp identify``: a model from a measured record, with an optional hold-out test."""

from __future__ import annotations

import click

from hystcomp._hyperparameters import EVERETT_KINDS, MAX_DEGREE
from hystcomp.cli import _options as opts
from hystcomp.cli import command
from hystcomp.identify.preisach import FIT_METHODS
from hystcomp.identify.preisach_lsq import MAX_LSQ_GRID
from hystcomp.io.atomic import check_output_path
from hystcomp.io.multiaxis import is_multiaxis
from hystcomp.io.records import read_record
from hystcomp.workflows.identify import LABELS
from hystcomp.workflows.record import check_identification, identify_model


@command("identify")
@click.argument("data", metavar="DATA")
@click.option(
    "--model", "kind", type=click.Choice(["auto", *LABELS]), default="auto", show_default=True
)
@click.option("--operators", "--n-operators", cls=opts.Alias, type=int, callback=opts.count)
@click.option("--deadzones", "--n-deadzones", cls=opts.Alias, type=int, callback=opts.count)
@click.option("--degree", type=click.IntRange(1, MAX_DEGREE))
@click.option("--fit", "--fit-method", cls=opts.Alias, type=click.Choice(FIT_METHODS))
@click.option("--everett", type=click.Choice(EVERETT_KINDS))
@click.option("--grid", type=click.IntRange(2, MAX_LSQ_GRID))
@click.option("--regularization", metavar="LAMBDA|auto")
@click.option("--constraints", type=click.Choice(["physical", "paper"]))
@click.option("--initial-memory", type=click.Choice(["auto", "virgin", "descended"]))
@opts.reading
@click.option("--transient", type=float, metavar="SECONDS", callback=opts.positive("s", False))
@click.option("--voltage-range", **opts.RANGE)
@click.option("--allow-extrapolation", is_flag=True)
@click.option("--holdout", type=float, metavar="FRACTION", callback=opts.fraction)
@click.option("--dynamics-record", metavar="DYN")
@click.option("--jobs", "n_jobs", type=int)
@click.option("--plot", metavar="FILE")
@click.option("-o", "--output", required=True, metavar="MODEL.json")
def identify(data, kind, output, plot, dynamics_record, holdout, **o):
    """Parse, run :func:`hystcomp.workflows.record.identify_model` (N axes:
    :func:`hystcomp.workflows.multiaxis.identify_axes`), print, write."""
    inputs = (data,) if dynamics_record is None else (data, dynamics_record)
    check_output_path(output, inputs=inputs, what="model file")
    multi = is_multiaxis(data, o["columns"])
    given = {"holdout": holdout, "dynamics_record": dynamics_record, "plot": plot, **o}
    fitting = check_identification(kind, axes=multi, **given)  # before any record is read
    if plot is not None:  # refused before any work
        from hystcomp.experiment.fig_identification import check_figure_output, plot_identified

        check_figure_output(plot, inputs=inputs, output=output)
    fitting.update({k: o[k] for k in ("voltage_range", "allow_extrapolation", "transient")})
    fitting.update(unit_check=False, holdout=holdout)  # the unit checked here, before the fit
    ticking = lambda what: opts.progress(f"identifying {what}", o["quiet"]).ticking()
    if multi:
        from hystcomp.workflows.multiaxis import identify_axes

        t, v, x = (opts.read_input(data, ("v", "x"), o, multi=True)[k] for k in "tvx")
        with ticking(f"{v.shape[1]} axes"):
            axes = identify_axes(t, v, x, kind=kind, n_jobs=o["n_jobs"], source=data, **fitting)
        opts.report(axes)
        return opts.write_model(axes.model, output)
    plain = opts.read_options({**o, "x_unit": None, "quiet": True})  # a dynamics record
    rec = read_record(data, **(plain if kind == "dynamics" else opts.read_options(o, data)))
    if kind != "dynamics":
        opts.warn_x_unit(rec.x, data, o)
    dyn = None if dynamics_record is None else read_record(dynamics_record, **plain)
    progress = lambda k: ticking(f"the {LABELS[k]} model")
    found = identify_model(rec, kind, dynamics_record=dyn, progress=progress, **fitting)
    opts.report(found)  # a figure of the fit and the hold-out as predicted, or a Bode plot
    opts.write_model(found.model, output, plot, lambda path: plot_identified(rec, found, path))
