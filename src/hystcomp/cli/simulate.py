"""``hystcomp simulate``: a model's displacement for a voltage input."""

from __future__ import annotations

import click

from hystcomp.cli import main
from hystcomp.cli._options import (
    check_data_output,
    columns_option,
    fs_option,
    output_option,
    progress,
    quiet_option,
    read_options,
)
from hystcomp.errors import ModelFileError
from hystcomp.io.models import load_model
from hystcomp.io.records import read_table, write_table


@main.command("simulate")
@click.argument("model_file", metavar="MODEL.json")
@click.argument("input_file", metavar="INPUT")
@output_option(what="result: t, v, x")
@columns_option
@fs_option
@quiet_option
def simulate(model_file, input_file, output, columns, sample_rate, quiet):
    """Run the model in MODEL.json on the voltage in INPUT (columns t, v).

    Writes t (s), v (V) and the modelled displacement x (µm).
    """
    check_data_output(output, inputs=(model_file, input_file), what="result file")
    model = load_model(model_file)
    if getattr(model, "kind", None) == "dynamics":
        raise ModelFileError(
            f"{str(model_file)!r} holds linear dynamics, not a hysteresis model; simulate "
            "runs a PI, MPI or Preisach model file on a voltage (the dynamics act on a "
            "displacement: LinearDynamics.simulate in Python)."
        )
    table = read_table(
        input_file,
        ("v",),
        **read_options(columns, sample_rate, None, quiet, input_file, reads=("v",)),
    )
    v = table["v"]
    lo, hi = getattr(model, "voltage_range_", (-float("inf"), float("inf")))
    if v.min() < lo or v.max() > hi:
        click.echo(
            f"hystcomp: warning: the input ({v.min():.4g} .. {v.max():.4g} V) leaves the "
            f"model's voltage range ({lo:.4g} .. {hi:.4g} V); the model extrapolates there.",
            err=True,
        )
    with progress("simulating", quiet).ticking():
        x = model.simulate(v)
    written = progress(f"writing {output}", quiet)
    write_table(output, {"t": table["t"], "v": v, "x": x}, progress=written)
    click.echo(f"wrote {output}: {x.size} samples, x from {x.min():.4g} to {x.max():.4g} µm")
