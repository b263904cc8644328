"""``hystcomp compensate``: the feedforward voltage for a reference displacement.

The work is :func:`hystcomp.workflows.compensate.compensate_reference`; this module parses
the options, reads the reference, prints the warnings and writes the voltage.
"""

from __future__ import annotations

import click

from hystcomp.cli import main, report
from hystcomp.cli._options import (
    check_data_output,
    columns_option,
    fs_option,
    method_option,
    narrow_range_option,
    output_option,
    positive,
    progress,
    quiet_option,
    read_options,
    warn_x_unit,
    x_unit_option,
)
from hystcomp.io.models import load_model
from hystcomp.io.multiaxis import read_axes
from hystcomp.io.records import read_table, write_table
from hystcomp.models.multiaxis import MultiAxisModel
from hystcomp.workflows.compensate import (
    compensate_reference,
    load_dynamics,
    refuse_dynamics_as_model,
)


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
    refuse_dynamics_as_model(model, model_file)
    multi = isinstance(model, MultiAxisModel)  # t, x1..xN -> t, v1..vN, x1_ref..xN_ref
    if multi and dynamics_file is not None:
        raise click.UsageError("--dynamics does not apply to a multi-axis model.")
    dynamics = None if dynamics_file is None else load_dynamics(dynamics_file)
    reads = None if multi else ("x",)
    options = read_options(columns, sample_rate, x_unit, quiet, reference_file, reads=reads)
    table = (read_axes if multi else read_table)(reference_file, ("x",), **options)
    if not multi:
        warn_x_unit(table["x"], reference_file, quiet, x_unit)
    result = compensate_reference(
        model,
        table["t"],
        table["x"],
        source=str(model_file),
        reference=str(reference_file),
        voltage_range=narrow_range,
        method=method,
        slew_rate=slew_rate,
        dynamics=dynamics,
        strict=strict,
        progress=progress(f"computing the voltage{'s' if multi else ''}", quiet).ticking(),
    )
    report(result)
    v, x = result.v, table["x"]
    if multi:
        n = model.n_axes
        out = {"t": table["t"], **{f"v{i + 1}": v[:, i] for i in range(n)}}
        out.update({f"x{i + 1}_ref": x[:, i] for i in range(n)})
    else:
        out = {"t": table["t"], "v": v, "x_ref": x}
    write_table(output, out, progress=progress(f"writing {output}", quiet))
    if multi:
        ranges = ", ".join(
            f"v{i + 1} {v[:, i].min():.4g} .. {v[:, i].max():.4g} V" for i in range(n)
        )
        summary = f"{v.shape[0]} samples of {n} axes ({ranges}; {sum(result.clamped)} clamped)"
    else:
        lo, hi = result.compensator.voltage_range
        summary = (
            f"{v.size} samples, v from {v.min():.4g} to {v.max():.4g} V (range {lo:.4g} .. "
            f"{hi:.4g} V, {result.clamped} clamped)"
        )
    click.echo(f"wrote {output}: {summary}")
    if result.preview is not None:
        click.echo(
            f"  with the inverse of the dynamics of {dynamics_file or model_file}: "
            f"{result.preview} samples of look-ahead in the reference"
        )
