"""``hystcomp simulate``: a model's displacement for a voltage input."""

from __future__ import annotations

import click
import numpy as np

from hystcomp.cli import main
from hystcomp.cli._dynamics import dynamics_for
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
from hystcomp.errors import ModelFileError
from hystcomp.io.models import load_model
from hystcomp.io.records import read_table, write_table
from hystcomp.models.hammerstein import HammersteinModel


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
    if getattr(model, "kind", None) == "multiaxis":  # N coupled axes: t, v1..vN -> x1..xN
        from hystcomp.cli._multiaxis import simulate_multiaxis

        simulate_multiaxis(
            model,
            model_file,
            input_file,
            output,
            columns=columns,
            sample_rate=sample_rate,
            x_unit=x_unit,
            quiet=quiet,
        )
        return
    if getattr(model, "kind", None) == "dynamics":
        raise ModelFileError(
            f"{str(model_file)!r} holds linear dynamics, not a hysteresis model; simulate "
            "runs a PI, MPI or Preisach model file on a voltage (the dynamics act on a "
            "displacement: LinearDynamics.simulate in Python)."
        )
    table = read_table(
        input_file,
        ("v",),
        optional=("x",),
        **read_options(columns, sample_rate, x_unit, quiet, input_file, reads=("v", "x")),
    )
    if "x" in table:  # a measured displacement to validate against: in µm, like the model
        warn_x_unit(table["x"], input_file, quiet, x_unit)
    if isinstance(model, HammersteinModel):  # discrete-time dynamics: at their rate only
        dynamics_for(model.dynamics, table)
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
    if "x" in table:
        click.echo(_validation(v, table["x"], x, input_file))


def _validation(v, measured, x, source) -> str:
    """One line: the model's error against the measured displacement of ``source``, after
    its start-up transient (where the model's memory and the stage's may differ), beside
    a straight line fitted to that record."""
    from hystcomp.identify.scoring import error_report, straight_line, transient_end

    start = transient_end(v)
    if v.size - start < max(10, v.size // 10):  # too little left after it: score it all
        start = 0
    model = error_report(measured, x, start)
    a, b = straight_line(v[start:], measured[start:])
    line = float(np.sqrt(np.mean((a * v[start:] + b - measured[start:]) ** 2)))
    after = f" from sample {start + 1} (after the start-up transient)" if start else ""
    return (
        f"  against the measured x of {source}{after}: model rms {model['rms_error_um']:.4g} "
        f"µm, max {model['max_error_um']:.4g} µm; a straight line fitted to it: rms "
        f"{line:.4g} µm"
    )
