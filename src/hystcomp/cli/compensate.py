"""``hystcomp compensate``: the feedforward voltage for a reference displacement."""

from __future__ import annotations

import click

from hystcomp.cli import main
from hystcomp.cli._options import columns_option, fs_option, output_option, read_options
from hystcomp.data import rate_of, read_table, write_table
from hystcomp.io import load_model


@main.command("compensate")
@click.argument("model_file", metavar="MODEL.json")
@click.argument("reference_file", metavar="REFERENCE")
@output_option(what="voltage: t, v, x_ref")
@columns_option
@fs_option
@click.option(
    "--slew-rate",
    type=float,
    default=None,
    metavar="V/S",
    help="Largest voltage slew rate of the output (none by default).",
)
def compensate(model_file, reference_file, output, columns, sample_rate, slew_rate):
    """Voltage that makes the actuator of MODEL.json follow REFERENCE (columns t, x).

    Uses the model's inverse (eqs. 23-26 for PI/MPI), clamped to the model's voltage range.
    Writes t (s), v (V) and x_ref (µm).
    """
    model = load_model(model_file)
    table = read_table(reference_file, ("x",), **read_options(columns, sample_rate))
    options = {}
    if slew_rate is not None:
        options = {"slew_rate": slew_rate, "sample_rate": rate_of(table["t"])}
    v = model.inverse(**options).simulate(table["x"])
    write_table(output, {"t": table["t"], "v": v, "x_ref": table["x"]})
    click.echo(f"wrote {output}: {v.size} samples, v from {v.min():.4g} to {v.max():.4g} V")
