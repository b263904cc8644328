"""``hystcomp evaluate``: how a measured run tracked its reference."""

from __future__ import annotations

import json

import click

from hystcomp.cli import _options as opts
from hystcomp.cli import command


@command("evaluate")
@click.argument("reference", metavar="REFERENCE")
@click.argument("measured", metavar="MEASURED")
@click.option("--json", "as_json", is_flag=True)
@click.option("--plot", metavar="FILE")
@click.option("--skip", type=float, default=0.0, metavar="S", callback=opts.positive("s", False))
@opts.reading
def evaluate(reference, measured, as_json, plot, skip, **o):
    """Parse, run :func:`hystcomp.workflows.evaluate.evaluate` (its result words itself), print."""
    from hystcomp.workflows.evaluate import evaluate as run_evaluation

    if plot is not None:  # refused before any work
        from hystcomp.experiment.fig_evaluate import plot_evaluation
        from hystcomp.experiment.fig_identification import check_figure_output

        check_figure_output(plot, inputs=(reference, measured))
    result = run_evaluation(reference, measured, skip=skip, **opts.read_options(o, measured))
    opts.warn_x_unit(result.x, measured, o)
    opts.report(result, lines=False)
    if plot is not None:
        plot_evaluation(result, plot)
    if as_json:
        out = result.to_dict()
        return click.echo(json.dumps(out if plot is None else {**out, "plot": str(plot)}))
    opts.report(result, warnings=False)
    if plot is not None:
        click.echo(f"  wrote {plot}")
