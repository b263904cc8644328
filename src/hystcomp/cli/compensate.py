"""``hystcomp compensate``: the feedforward voltage for a reference displacement."""

from __future__ import annotations

import click

from hystcomp.cli import _options as opts
from hystcomp.cli import command
from hystcomp.io.multiaxis import axis_table
from hystcomp.io.records import check_data_output
from hystcomp.models.multiaxis import MultiAxisModel
from hystcomp.workflows.compensate import compensate_reference, load_compensation, voltage_summary


@command("compensate")
@click.argument("model_file", metavar="MODEL.json")
@click.argument("reference_file", metavar="REFERENCE")
@click.option("-o", "--output", required=True, metavar="FILE")
@opts.reading
@click.option("--slew-rate", type=float, metavar="V/S", callback=opts.positive("V/s"))
@click.option("--voltage-range", **opts.RANGE)
@opts.method_option
@click.option("--dynamics", "dynamics_file", metavar="DYN.json")
@click.option("--strict", is_flag=True)
def compensate(model_file, reference_file, output, dynamics_file, **o):
    """Parse, run :func:`hystcomp.workflows.compensate.compensate_reference`, print, write."""
    inputs = (model_file, reference_file) + ((dynamics_file,) if dynamics_file else ())
    check_data_output(output, inputs=inputs, what="voltage file")
    model, dynamics = load_compensation(model_file, dynamics_file)
    multi = isinstance(model, MultiAxisModel)  # t, x1..xN -> t, v1..vN, x1_ref..xN_ref
    table = opts.read_input(reference_file, ("x",), o, multi=multi)
    given = {k: o[k] for k in ("voltage_range", "method", "slew_rate", "strict")}
    given.update(source=str(model_file), reference=str(reference_file), dynamics=dynamics)
    ticking = opts.progress("computing the voltage" + "s" * multi, o["quiet"]).ticking()
    result = compensate_reference(model, table["t"], table["x"], progress=ticking, **given)
    opts.report(result)
    out = axis_table(table["t"], v=result.v, x_ref=table["x"])
    opts.write_signal(out, output, o["quiet"], voltage_summary(result))
    if result.preview is not None:
        click.echo(
            f"  with the inverse of the dynamics of {dynamics_file or model_file}: "
            f"{result.preview} samples of look-ahead in the reference"
        )
