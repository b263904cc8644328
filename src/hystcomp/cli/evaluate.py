"""``hystcomp evaluate``: how a measured run tracked its reference."""

from __future__ import annotations

import json

import click

from hystcomp.cli import main, report
from hystcomp.cli._options import (
    check_plot,
    columns_option,
    fs_option,
    nonnegative,
    quiet_option,
    read_options,
    warn_x_unit,
    x_unit_option,
)


@main.command("evaluate")
@click.argument("reference", metavar="REFERENCE")
@click.argument("measured", metavar="MEASURED")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of text.")
@click.option(
    "--plot",
    default=None,
    metavar="FILE",
    help="Figure of the error against time and of x against x_ref (.png/.pdf/.svg).",
)
@click.option(
    "--skip",
    type=float,
    default=0.0,
    metavar="S",
    callback=nonnegative("s"),
    help="Leave out the first S seconds of the run (a start-up transient, the first period) [0].",
)
@columns_option
@fs_option
@x_unit_option
@quiet_option
def evaluate(reference, measured, as_json, plot, skip, columns, sample_rate, x_unit, quiet):
    """How well MEASURED (columns t, x; v too if there) tracked REFERENCE (columns t, x).

    The two are matched by time (the reference interpolated at the measured instants).
    Prints the rms and largest tracking error x - x_ref in µm, the hysteresis of x against
    x_ref in % of the range (whole loop and top quarter, as the paper's Table I and Fig. 9)
    and the error over time in ten spans. --columns, --fs and --x-unit apply to MEASURED.
    """
    from hystcomp.workflows.evaluate import evaluate as run_evaluation

    if plot is not None:
        check_plot(plot, inputs=(reference, measured))
    result = run_evaluation(
        reference,
        measured,
        skip=skip,
        **read_options(columns, sample_rate, x_unit, quiet, measured, reads=("v", "x")),
    )
    warn_x_unit(result.x, measured, quiet, x_unit)
    report(result, lines=False)
    if plot is not None:
        from hystcomp.experiment.fig_evaluate import plot_evaluation

        plot_evaluation(result, plot)
    if as_json:
        out = result.to_dict()
        click.echo(json.dumps(out if plot is None else {**out, "plot": str(plot)}))
        return
    report(result, warnings=False)
    if plot is not None:
        click.echo(f"  wrote {plot}")
