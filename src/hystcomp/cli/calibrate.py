"""``hystcomp calibrate``: the simulated axis's calibration figures against the paper."""

from __future__ import annotations

import click

from hystcomp.cli import main


@main.command("calibrate")
@click.option(
    "--refit",
    is_flag=True,
    help="Fit the twin's hysteresis parameters to the paper's Preisach loops again first "
    "(a few seconds), print them, and report the refitted twin.",
)
def calibrate(refit: bool) -> None:
    """Print how the simulated axis (the twin) compares with the paper's figures.

    Stroke at 120 V, major-loop hysteresis (whole and in the saturation zone), the rms
    difference to the loops of eq. 6 (Fig. 5), the resonance of D(s), and the
    uncompensated tracking errors of Table I with several linear gains. Units: µm, V, Hz.
    See hystcomp.experiment.calibration.
    """
    from hystcomp.experiment.calibration import calibration_report, fit_twin_hysteresis

    params = None
    if refit:
        params = fit_twin_hysteresis()
        click.echo(params)
    click.echo(calibration_report(params))
