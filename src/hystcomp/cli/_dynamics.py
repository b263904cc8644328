"""The command-line side of the linear dynamics: identify, report, plot, load for compensation."""

from __future__ import annotations

import click

from hystcomp.errors import DataFileError, ModelFileError
from hystcomp.io.atomic import atomic_paths
from hystcomp.io.models import load_model, model_text
from hystcomp.io.records import uneven_sampling
from hystcomp.models.dynamics import LinearDynamics


def identify_dynamics(rec, output: str, plot: str | None) -> None:
    """Fit :class:`LinearDynamics` to ``rec``, print the fit, write the model (and figure)."""
    from hystcomp.workflows.pair import identify_dynamics_record

    result = identify_dynamics_record(rec)
    for line in result.lines:
        click.echo(line)
    for warning in result.warnings:
        click.echo(f"hystcomp: warning: {warning}", err=True)
    model = result.model
    text = model_text(model)
    outputs = [output] if plot is None else [output, plot]
    with atomic_paths(*outputs) as (tmp_model, *tmp_plot):
        tmp_model.write_text(text, encoding="utf-8")
        if plot is not None:
            from hystcomp.experiment.fig_dynamics import plot_bode

            plot_bode(model, tmp_plot[0])
    for path in outputs[::-1]:
        click.echo(f"  wrote {path}")


def load_dynamics(path) -> LinearDynamics:
    """A dynamics model file, or a one-line error naming the option."""
    model = load_model(path)
    if not isinstance(model, LinearDynamics):
        raise ModelFileError(
            f"--dynamics {str(path)!r} holds a {model.kind!r} model, not linear dynamics; "
            "give the file written by 'hystcomp identify DATA --model dynamics'."
        )
    return model


def refuse_dynamics_as_model(model, path) -> None:
    """A dynamics file given where a hysteresis model belongs: one line saying so."""
    if isinstance(model, LinearDynamics):
        raise ModelFileError(
            f"{str(path)!r} holds linear dynamics, not a hysteresis model; give a PI, MPI or "
            "Preisach model file and pass this one as --dynamics."
        )


#: How far (relative) a reference's sample rate may be from the dynamics' rate.
RATE_MATCH = 1e-3


def dynamics_for(dynamics: LinearDynamics, table) -> LinearDynamics:
    """``dynamics``, checked against the reference's sample rate (it is discrete-time)."""
    import numpy as np

    steps = np.diff(table["t"])
    fs = 1.0 / float(np.median(steps)) if steps.size else dynamics.sample_rate_
    # 0.1 %: a time column's jitter or rounding moves its median step, a wrong rate by far more
    if abs(fs - dynamics.sample_rate_) > RATE_MATCH * dynamics.sample_rate_:
        raise ModelFileError(
            f"The dynamics model was identified at {dynamics.sample_rate_:g} Hz but the "
            f"reference is sampled at {fs:.6g} Hz; resample the reference or identify the "
            "dynamics at the reference's rate."
        )
    uneven = uneven_sampling(table["t"], "the reference")
    if uneven:
        raise DataFileError(uneven)
    return dynamics
