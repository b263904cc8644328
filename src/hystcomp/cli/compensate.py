"""``hystcomp compensate``: the feedforward voltage for a reference displacement."""

from __future__ import annotations

import warnings
from typing import Any

import click
import numpy as np

from hystcomp.cli import main
from hystcomp.cli._dynamics import dynamics_for, load_dynamics, refuse_dynamics_as_model
from hystcomp.cli._options import (
    check_data_output,
    columns_option,
    fs_option,
    method_option,
    method_options,
    narrow_range_option,
    narrowed,
    output_option,
    positive,
    progress,
    quiet_option,
    read_options,
    slew_sample_rate,
    warn_x_unit,
    x_unit_option,
)
from hystcomp.errors import HystcompWarning, InvalidSignalError, ModelFileError
from hystcomp.io.models import load_model
from hystcomp.io.records import read_table, write_table
from hystcomp.models.dynamics import APART
from hystcomp.models.hammerstein import HammersteinModel
from hystcomp.models.multiaxis import MultiAxisModel
from hystcomp.workflows.pair import predicted_worse


def inverse_options(model, table, *, slew_rate, narrow_range, path="the reference") -> dict:
    """Keyword arguments of ``model.inverse`` for the command's options.

    The slew-rate limit is per sample, so it needs the reference's own sample rate. With
    uneven sampling the shortest interval is taken: the limit then holds on every interval.
    """
    options: dict[str, Any] = {}
    if slew_rate is not None:
        options.update(slew_rate=slew_rate, sample_rate=slew_sample_rate(table["t"], path))
    options.update(narrowed(model, narrow_range))
    return options


@main.command("compensate")
@click.argument("model_file", metavar="MODEL.json")
@click.argument("reference_file", metavar="REFERENCE")
@output_option(what="voltage: t, v, x_ref")
@columns_option
@fs_option
@x_unit_option
@quiet_option
@click.option(
    "--slew-rate",
    type=float,
    default=None,
    metavar="V/S",
    callback=positive("V/s"),
    help="Largest voltage slew rate of the output, in V/s, at the reference's own sample "
    "rate (none by default).",
)
@narrow_range_option
@method_option
@click.option(
    "--dynamics",
    "dynamics_file",
    default=None,
    metavar="DYN.json",
    help="Also invert the linear dynamics of this file (hystcomp identify --model "
    "dynamics): v = H^-1[D^-1[x_ref]], looking ahead in the reference (beyond the paper). "
    "Identified apart from the model, they are matched at 1 Hz, with a warning; a model "
    "identified with --dynamics-record holds its dynamics as one pair, used without this.",
)
@click.option(
    "--strict",
    is_flag=True,
    help="Refuse (exit 2, nothing written) a reference that the clamp cuts anywhere, "
    "a pair predicted to track it worse than its hysteresis model alone, or dynamics "
    "identified apart from the model, instead of warning.",
)
def compensate(
    model_file,
    reference_file,
    output,
    columns,
    sample_rate,
    x_unit,
    quiet,
    slew_rate,
    narrow_range,
    method,
    dynamics_file,
    strict,
):
    """Voltage that makes the actuator of MODEL.json follow REFERENCE (columns t, x).

    With an N-axis model: REFERENCE has t, x1..xN and the output t, v1..vN, x1_ref..xN_ref,
    each axis clamped to its own range and warned about on its own.

    Uses the model's inverse (eqs. 23-26 for PI/MPI; for Preisach eq. 10 or, with
    --method exact, the exact inverse), clamped to the model's voltage range (or a narrower
    --voltage-range). Writes t (s), v (V) and x_ref (µm). Samples whose reference lies out
    of the actuator's reach are clamped and counted: a warning says how many (exit 0), or
    with --strict the command refuses (exit 2) and writes nothing.
    """
    inputs = (model_file, reference_file) + ((dynamics_file,) if dynamics_file else ())
    check_data_output(output, inputs=inputs, what="voltage file")
    model = load_model(model_file)
    if isinstance(model, MultiAxisModel):  # N coupled axes: t, x1..xN -> t, v1..vN, x1_ref..
        from hystcomp.cli._multiaxis import compensate_multiaxis, refuse

        refuse("--dynamics", dynamics_file, "a multi-axis model")
        compensate_multiaxis(
            model,
            model_file,
            reference_file,
            output,
            columns=columns,
            sample_rate=sample_rate,
            x_unit=x_unit,
            quiet=quiet,
            slew_rate=slew_rate,
            narrow_range=narrow_range,
            method=method,
            strict=strict,
        )
        return
    refuse_dynamics_as_model(model, model_file)
    pair = isinstance(model, HammersteinModel)
    if pair and dynamics_file is not None:
        raise ModelFileError(
            f"{model_file!r} holds a hysteresis model and its dynamics, identified as one "
            "pair; its inverse inverts both. Drop --dynamics."
        )
    chosen = method_options(model.hysteresis if pair else model, model_file, method)
    options = read_options(columns, sample_rate, x_unit, quiet, reference_file, reads=("x",))
    table = read_table(reference_file, ("x",), **options)
    warn_x_unit(table["x"], reference_file, quiet, x_unit)
    options = inverse_options(
        model, table, slew_rate=slew_rate, narrow_range=narrow_range, path=reference_file
    )
    if pair:
        dynamics_for(model.dynamics, table)  # it runs at the dynamics' rate only
        options.pop("sample_rate", None)
        worse = predicted_worse(model, table["x"], model.sample_rate)
        if worse is not None:
            rate, alone, paired = worse
            what = (
                f"the pair in {model_file} is predicted to track this reference (about "
                f"{rate:.3g} Hz) at {paired:.3g} µm rms, worse than its hysteresis model "
                f"alone ({alone:.3g} µm; estimated when it was identified)"
            )
            if strict:
                raise InvalidSignalError(
                    f"{what}. Nothing written (--strict); compensate with the hysteresis "
                    "model alone (hystcomp identify without --dynamics-record), or drop "
                    "--strict."
                )
            click.echo(f"hystcomp: warning: {what}.", err=True)
    elif dynamics_file is not None:
        options["dynamics"] = dynamics_for(load_dynamics(dynamics_file), table)
        if strict:
            raise ModelFileError(
                f"{model_file} and {dynamics_file} were identified apart, so whether their "
                "inverse tracks better than the hysteresis model's alone cannot be "
                "predicted. Nothing written (--strict); identify them as one pair (hystcomp "
                "identify DATA --model KIND --dynamics-record DYN.csv), or drop --strict."
            )
        click.echo(f"hystcomp: warning: {APART}", err=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", HystcompWarning)  # said above, in the command's words
        compensator = model.inverse(**options, **chosen)
    with progress("computing the voltage", quiet).ticking():
        result = compensator.run(table["x"])
    v = result.v
    lo, hi = compensator.voltage_range
    if result.clamped:
        reach, (d_lo, d_hi) = _reach(model.hysteresis if pair else model, lo, hi)
        x = table["x"]
        what = (
            f"{result.clamped} of {v.size} samples ({100 * result.clamped_share:.3g} %) are "
            f"out of reach and clamped to {lo:.4g} .. {hi:.4g} V: the reference spans "
            f"{x.min():.4g} .. {x.max():.4g} µm, {reach}"
        )
        if strict:
            raise InvalidSignalError(
                f"{what}. Nothing written (--strict); shift or scale the reference into "
                f"{d_lo:.4g} .. {d_hi:.4g} µm, or drop --strict to accept the clamp."
            )
        click.echo(f"hystcomp: warning: {what}.", err=True)
    beyond = _beyond_record(model.hysteresis if pair else model, v)
    if beyond is not None:
        click.echo(f"hystcomp: warning: {beyond}", err=True)
    if getattr(getattr(compensator, "hysteresis", compensator), "method", None) == "multiplicative":
        spikes = _own_turns(v, table["x"], hi - lo)
        if spikes is not None:
            n, size, k = spikes
            click.echo(
                "hystcomp: warning: the paper's multiplicative structure (eq. 10) turns the "
                f"voltage back where the reference does not, {n} time{'s' if n > 1 else ''} "
                f"(the largest by {size:.3g} V, at t = {table['t'][k]:.6g} s"
                + (", where the reference steps from the model's rest" if k <= 2 else "")
                + "): it overshoots where the model is steeper than its gain rho, on a "
                "fast step or sample after sample, and each turn leaves the stage in a minor "
                "loop that the model did not follow. --method exact inverts the model "
                "without it.",
                err=True,
            )
    written = progress(f"writing {output}", quiet)
    write_table(output, {"t": table["t"], "v": v, "x_ref": table["x"]}, progress=written)
    click.echo(
        f"wrote {output}: {v.size} samples, v from {v.min():.4g} to {v.max():.4g} V "
        f"(range {lo:.4g} .. {hi:.4g} V, {result.clamped} clamped)"
    )
    if dynamics_file is not None or pair:
        click.echo(
            f"  with the inverse of the dynamics of {dynamics_file or model_file}: "
            f"{compensator.preview} samples of look-ahead in the reference"
        )


#: A turn of the voltage larger than this fraction of the range, where the reference does
#: not turn, is eq. 10 overshooting: its recursion corrects with the constant gain rho, and
#: where the model is steeper (a step, or a slope beyond 2 rho) it overshoots, or chatters.
OWN_TURN = 0.01


def _own_turns(v, x, span: float):
    """``(count, largest in V, index)`` of the samples where ``v`` turns back by more than
    :data:`OWN_TURN` of ``span`` (both its steps, in and out) and ``x`` does not turn
    within a sample, or None."""
    import numpy as np

    dv, dx = np.diff(v), np.diff(x)
    size = np.minimum(np.abs(dv[:-1]), np.abs(dv[1:]))
    turns = dx[:-1] * dx[1:] < 0
    near = turns | np.r_[False, turns[:-1]] | np.r_[turns[1:], False]  # eq. 10 a sample late
    own = (dv[:-1] * dv[1:] < 0) & ~near & (size > OWN_TURN * span)
    if not own.any():
        return None
    largest = int(np.argmax(np.where(own, size, 0.0)))
    return int(np.count_nonzero(own)), float(size[largest]), largest + 1


def _beyond_record(model, v) -> str | None:
    """Words for the samples of ``v`` beyond the input range the model's record covered
    (:meth:`~hystcomp.models.base.HysteresisModel.covered_range`), or None: the model's
    range was given wider than its record, and the model extrapolates there."""
    covered = model.covered_range()
    if covered is None:
        return None
    lo, hi = covered
    slack = 1e-9 * (hi - lo)
    beyond = int(np.count_nonzero((v < lo - slack) | (v > hi + slack)))
    if not beyond:
        return None
    return (
        f"{beyond} of {v.size} samples command voltages beyond {lo:.4g} .. {hi:.4g} V, the "
        f"range that the model's record covered (v from {v.min():.4g} to {v.max():.4g} V; "
        f"the model's range {model.voltage_range_[0]:.4g} .. {model.voltage_range_[1]:.4g} V "
        "was given wider): the model extrapolates there. Check the tracking there, narrow "
        f"the output with --voltage-range {lo:.6g} {hi:.6g}, or identify from a record "
        "that covers the range."
    )


def _reach(model, lo: float, hi: float) -> tuple[str, tuple[float, float]]:
    """What the model reaches with ``lo .. hi`` V, in words, and the displacements at the
    ends once it has swung over the whole range (where a model whose loops do not close at
    the ends no longer reaches its initial extremes)."""
    x_lo, x_hi = model.reachable_range(voltage_range=(lo, hi))
    swung = model.simulate(np.array([lo, hi, lo, hi]))
    d_lo, d_hi = float(swung[2]), float(swung[3])
    text = f"the model reaches {x_lo:.4g} .. {x_hi:.4g} µm"
    if f"{d_lo:.4g} {d_hi:.4g}" != f"{x_lo:.4g} {x_hi:.4g}":
        text += (
            f", but after a swing over the whole range only {d_lo:.4g} .. {d_hi:.4g} µm "
            "(it starts from a state off its major loop, which a swing leaves for good)"
        )
    return text, (d_lo, d_hi)
