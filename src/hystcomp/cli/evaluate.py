"""``hystcomp evaluate``: how a measured run tracked its reference."""

from __future__ import annotations

import json
from pathlib import Path

import click

from hystcomp.cli import main
from hystcomp.cli._options import (
    columns_option,
    fs_option,
    nonnegative,
    quiet_option,
    read_options,
    warn_x_unit,
    x_unit_option,
)
from hystcomp.io.atomic import check_output_path


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
    from hystcomp.workflows.evaluate import OUTSIDE_WARNING
    from hystcomp.workflows.evaluate import evaluate as run_evaluation

    if plot is not None:
        from hystcomp.experiment.fig_identification import FORMATS

        if Path(plot).suffix.lower() not in FORMATS:
            raise click.BadParameter(f"must end in {', '.join(FORMATS)}.", param_hint="--plot")
        check_output_path(plot, inputs=(reference, measured), what="figure")
    result = run_evaluation(
        reference,
        measured,
        skip=skip,
        **read_options(columns, sample_rate, x_unit, quiet, measured, reads=("v", "x")),
    )
    warn_x_unit(result.x, measured, quiet, x_unit)
    if result.outside_share > OUTSIDE_WARNING:
        click.echo(
            f"hystcomp: warning: {result.outside} samples ({100 * result.outside_share:.3g} %) "
            f"of {measured} lie outside the time span of {reference} and are left out; check "
            "that the two belong together and that their time columns start alike.",
            err=True,
        )
    if plot is not None:
        from hystcomp.experiment.fig_evaluate import plot_evaluation

        plot_evaluation(result, plot)
    if as_json:
        out = result.to_dict()
        if plot is not None:
            out["plot"] = str(plot)
        click.echo(json.dumps(out))
        return
    for line in describe(result):
        click.echo(line)
    if plot is not None:
        click.echo(f"  wrote {plot}")


def describe(result) -> list[str]:
    """The lines that word an :class:`~hystcomp.workflows.evaluate.Evaluation`."""
    span = result.range_um
    share = f" ({100 * result.rms_um / span:.3g} % of the {span:.4g} µm range)" if span else ""
    matched = (
        "interpolated at the measured instants" if result.interpolated else "the same instants"
    )
    lines = [
        f"tracking of {result.measured} against {result.reference}",
        f"  matched:    {result.samples} samples, t {result.t[0]:.6g} .. {result.t[-1]:.6g} s "
        f"(reference {matched}"
        + (f"; the first {result.skip_s:g} s left out" if result.skip_s else "")
        + (f"; {result.outside} outside the reference's time span" if result.outside else "")
        + ")",
        (
            f"  error:      rms {result.rms_um:.4g} µm{share}, max {result.max_um:.4g} µm, "
            f"mean {result.mean_um:.4g} µm"
        ),
    ]
    if result.hysteresis_pct is None:
        lines.append("  hysteresis: - (the reference does not rise and fall)")
    else:
        lines.append(
            f"  hysteresis: {result.hysteresis_pct:.3g} % of the range (top quarter, the "
            f"saturation zone: {result.saturation_zone_pct:.3g} %)"
        )
    lines.append("  error over time:")
    lines.append(f"    {'t (s)':>21}  {'rms (µm)':>9}  {'max (µm)':>9}")
    for part in result.spans:
        when = f"{part.t_start:.4g} .. {part.t_end:.4g}"
        lines.append(f"    {when:>21}  {part.rms_um:9.4g}  {part.max_um:9.4g}")
    return lines
