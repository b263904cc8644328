"""``hystcomp simulate``: a model's displacement for a voltage input.

The work is :func:`hystcomp.workflows.simulate.simulate_voltage`.
"""

from __future__ import annotations

import click

from hystcomp.cli import main, report
from hystcomp.cli._options import (
    check_data_output,
    columns_option,
    fs_option,
    output_option,
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
from hystcomp.workflows.simulate import simulate_voltage


@main.command("simulate")
@click.argument("model_file", metavar="MODEL.json")
@click.argument("input_file", metavar="INPUT")
@output_option(what="result: t, v, x")
@columns_option
@fs_option
@x_unit_option
@quiet_option
def simulate(model_file, input_file, output, columns, sample_rate, x_unit, quiet):
    """Run the model in MODEL.json on the voltage in INPUT (columns t, v).

    With an N-axis model: INPUT has t, v1..vN and the output t, v1..vN, x1..xN.

    Writes t (s), v (V) and the modelled displacement x (µm). If INPUT also holds a
    measured displacement x (a record the model was not fitted on, say), prints how far the
    model is from it, beside a straight line fitted to that record: a validation.
    """
    check_data_output(output, inputs=(model_file, input_file), what="result file")
    model = load_model(model_file)
    multi = isinstance(model, MultiAxisModel)  # N coupled axes: t, v1..vN -> x1..xN
    reading = read_options(columns, sample_rate, x_unit, quiet, input_file, reads=None)
    if multi:
        table = read_axes(input_file, ("v",), **reading)
    else:
        reading = read_options(columns, sample_rate, x_unit, quiet, input_file)
        table = read_table(input_file, ("v",), optional=("x",), **reading)
        if "x" in table:  # a measured displacement to validate against: in µm, like the model
            warn_x_unit(table["x"], input_file, quiet, x_unit)
    v = table["v"]
    result = simulate_voltage(
        model,
        table["t"],
        v,
        measured=table.get("x"),
        source=str(model_file),
        data=str(input_file),
        progress=progress("simulating", quiet).ticking(),
    )
    report(result, lines=False)
    x = result.x
    out = {"t": table["t"]}
    if multi:
        out.update({f"v{i + 1}": v[:, i] for i in range(model.n_axes)})
        out.update({f"x{i + 1}": x[:, i] for i in range(model.n_axes)})
        summary = f"{x.shape[0]} samples of {model.n_axes} axes"
    else:
        out.update(v=v, x=x)
        summary = f"{x.size} samples, x from {x.min():.4g} to {x.max():.4g} µm"
    write_table(output, out, progress=progress(f"writing {output}", quiet))
    click.echo(f"wrote {output}: {summary}")
    report(result, warnings=False)
