"""``hystcomp export-c``: a model file's compensator as C99 code for an embedded controller."""

from __future__ import annotations

from pathlib import Path

import click

from hystcomp import paper
from hystcomp.cli import _options as opts
from hystcomp.cli import command
from hystcomp.codegen import DEFAULT_PREFIX, check_prefix
from hystcomp.io.atomic import check_output_path
from hystcomp.workflows.compensate import export_compensator, load_compensation

STEP_HZ = {**opts.HZ, "callback": opts.positive("Hz, the rate at which NAME_step is called")}


@command("export-c")
@click.argument("model_file", type=click.Path(path_type=Path))
@click.option("-o", "--output", "directory", required=True, type=click.Path(path_type=Path))
@click.option("--prefix", default=DEFAULT_PREFIX, show_default=True)
@click.option("--slew-rate", type=float, metavar="V_PER_S", callback=opts.positive("V/s"))
@click.option("--fs", "sample_rate", default=paper.SAMPLE_RATE, show_default=True, **STEP_HZ)
@click.option("--voltage-range", **opts.RANGE)
@opts.method_option
@click.option("--dynamics", "dynamics_file", metavar="DYN.json")
def export_c_command(model_file, directory, prefix, dynamics_file, **o):
    """Parse, run :func:`hystcomp.workflows.compensate.export_compensator`, print."""
    check_prefix(prefix)
    for suffix in (".h", ".c") if directory.is_dir() else ():  # never overwrite the model
        check_output_path(directory / f"{prefix}{suffix}", inputs=(model_file,))
    model, dynamics = load_compensation(model_file, dynamics_file)
    given = dict(o, prefix=prefix, source=str(model_file), dynamics=dynamics)
    result = export_compensator(model, directory, inputs=(model_file,), **given)
    opts.report(result)
    paths = [str(p) for p in result.paths]
    click.echo(f"wrote {' and '.join(paths) if len(paths) == 2 else ', '.join(paths)}")
