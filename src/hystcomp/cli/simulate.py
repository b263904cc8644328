"""``hystcomp simulate``: a model's displacement for a voltage input.

The work is :func:`hystcomp.workflows.simulate.simulate_voltage`.
"""

from __future__ import annotations

import click

from hystcomp.cli import _options as opts
from hystcomp.cli import command, option, report
from hystcomp.io.models import load_model
from hystcomp.io.multiaxis import axis_table, read_axes
from hystcomp.io.records import read_table
from hystcomp.models.multiaxis import MultiAxisModel
from hystcomp.workflows.simulate import simulate_voltage


@command("simulate")
@click.argument("model_file", metavar="MODEL.json")
@click.argument("input_file", metavar="INPUT")
@option("simulate", "-o", "--output", required=True, metavar="FILE")
@opts.reading
def simulate(model_file, input_file, output, **o):
    """``hystcomp simulate``: parse, simulate (:mod:`hystcomp.workflows`), print, write."""
    opts.check_data_output(output, inputs=(model_file, input_file), what="result file")
    model = load_model(model_file)
    multi = isinstance(model, MultiAxisModel)  # N coupled axes: t, v1..vN -> x1..xN
    reading = opts.read_options(o, input_file, reads=None if multi else ("v", "x"))
    if multi:
        table = read_axes(input_file, ("v",), **reading)
    else:
        table = read_table(input_file, ("v",), optional=("x",), **reading)
        if "x" in table:  # a measured displacement to validate against: in µm, like the model
            opts.warn_x_unit(table["x"], input_file, o)
    result = simulate_voltage(
        model,
        table["t"],
        table["v"],
        measured=table.get("x"),
        source=str(model_file),
        data=str(input_file),
        progress=opts.progress("simulating", o["quiet"]).ticking(),
    )
    report(result, lines=False)
    x = result.x
    if multi:
        summary = f"{x.shape[0]} samples of {x.shape[1]} axes"
    else:
        summary = f"{x.size} samples, x from {x.min():.4g} to {x.max():.4g} µm"
    opts.write_signal(axis_table(table["t"], v=table["v"], x=x), output, o["quiet"], summary)
    report(result, warnings=False)
