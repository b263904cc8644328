"""``hystcomp simulate``: a model's displacement for a voltage input."""

from __future__ import annotations

import click

from hystcomp.cli import _options as opts
from hystcomp.cli import command
from hystcomp.io.models import load_model
from hystcomp.io.multiaxis import axis_table
from hystcomp.io.records import check_data_output
from hystcomp.models.multiaxis import MultiAxisModel
from hystcomp.workflows.simulate import simulate_voltage


@command("simulate")
@click.argument("model_file", metavar="MODEL.json")
@click.argument("input_file", metavar="INPUT")
@click.option("-o", "--output", required=True, metavar="FILE")
@opts.reading
def simulate(model_file, input_file, output, **o):
    """Parse, run :func:`hystcomp.workflows.simulate.simulate_voltage`, print, write."""
    check_data_output(output, inputs=(model_file, input_file), what="result file")
    model = load_model(model_file)
    multi = isinstance(model, MultiAxisModel)  # N coupled axes: t, v1..vN -> x1..xN
    optional = () if multi else ("x",)  # a measured displacement to validate against
    table = opts.read_input(input_file, ("v",), o, multi=multi, optional=optional)
    ticking = opts.progress("simulating", o["quiet"]).ticking()
    t, v, measured = table["t"], table["v"], table.get("x")
    names = {"source": str(model_file), "data": str(input_file)}
    result = simulate_voltage(model, t, v, measured=measured, progress=ticking, **names)
    opts.report(result, lines=False)
    x = result.x
    if multi:
        summary = f"{x.shape[0]} samples of {x.shape[1]} axes"
    else:
        summary = f"{x.size} samples, x from {x.min():.4g} to {x.max():.4g} µm"
    opts.write_signal(axis_table(t, v=v, x=x), output, o["quiet"], summary)
    opts.report(result, warnings=False)
