"""``hystcomp calibrate``: the simulated axis's calibration figures against the paper."""

from __future__ import annotations

import click

from hystcomp.cli import command


@command("calibrate")
@click.option("--refit", is_flag=True)
def calibrate(refit: bool) -> None:
    """``hystcomp calibrate``: the report of :mod:`hystcomp.experiment.calibration`."""
    from hystcomp.experiment.calibration import calibration_report, fit_twin_hysteresis

    params = fit_twin_hysteresis() if refit else None
    if refit:
        click.echo(params)
    click.echo(calibration_report(params))
