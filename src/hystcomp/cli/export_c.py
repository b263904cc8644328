"""``hystcomp export-c``: a model file's compensator as C99 code for an embedded controller."""

from __future__ import annotations

from pathlib import Path

import click

from hystcomp import paper
from hystcomp.cli import main, report
from hystcomp.cli._options import method_option, narrow_range_option, positive
from hystcomp.codegen import DEFAULT_PREFIX, check_prefix
from hystcomp.io.atomic import check_output_path
from hystcomp.io.models import load_model
from hystcomp.workflows.compensate import (
    export_compensator,
    load_dynamics,
    refuse_dynamics_as_model,
)


@main.command("export-c")
@click.argument("model_file", type=click.Path(path_type=Path))
@click.option(
    "-o",
    "--output",
    "directory",
    required=True,
    type=click.Path(path_type=Path),
    help="Folder for NAME.h and NAME.c (made if its parent exists).",
)
@click.option(
    "--prefix",
    default=DEFAULT_PREFIX,
    show_default=True,
    help="NAME: names the files, the state type NAME_state and the functions (a C identifier).",
)
@click.option(
    "--slew-rate",
    type=float,
    default=None,
    metavar="V_PER_S",
    callback=positive("V/s"),
    help="Largest output slew rate in V/s, baked into the code (none by default).",
)
@click.option(
    "--fs",
    "sample_rate",
    type=float,
    default=paper.SAMPLE_RATE,
    show_default=True,
    metavar="HZ",
    callback=positive("Hz, the rate at which NAME_step is called"),
    help="Sample rate at which NAME_step is called; sets the slew step per sample.",
)
@narrow_range_option
@method_option
@click.option(
    "--dynamics",
    "dynamics_file",
    default=None,
    metavar="DYN.json",
    help="Also invert the linear dynamics of this file (beyond the paper); NAME_step then "
    "takes the reference a fixed number of samples ahead (see the header).",
)
def export_c_command(
    model_file, directory, prefix, slew_rate, sample_rate, narrow_range, method, dynamics_file
):
    """Write MODEL_FILE's compensator as C99 code: NAME.h and NAME.c in folder -o.

    The code has the identified parameters baked in, clamps its output to the model's
    voltage range (or a narrower --voltage-range) and holds the last output when the
    reference is not finite:

    \b
      void   NAME_init(NAME_state *s);
      void   NAME_reset(NAME_state *s);
      double NAME_step(NAME_state *s, double x_ref);   /* um in, V out */
    """
    check_prefix(prefix)
    for suffix in (".h", ".c") if directory.is_dir() else ():  # never overwrite the model
        check_output_path(directory / f"{prefix}{suffix}", inputs=(model_file,))
    model = load_model(model_file)
    refuse_dynamics_as_model(model, model_file)
    result = export_compensator(
        model,
        directory,
        prefix=prefix,
        source=str(model_file),
        sample_rate=sample_rate,
        slew_rate=slew_rate,
        voltage_range=narrow_range,
        method=method,
        dynamics=None if dynamics_file is None else load_dynamics(dynamics_file),
        inputs=(model_file,),
    )
    report(result)
    paths = [str(p) for p in result.paths]
    click.echo(f"wrote {' and '.join(paths) if len(paths) == 2 else ', '.join(paths)}")
