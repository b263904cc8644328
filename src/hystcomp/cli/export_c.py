"""``hystcomp export-c``: a model file's compensator as C99 code for an embedded controller."""

from __future__ import annotations

import warnings
from pathlib import Path

import click

from hystcomp import paper
from hystcomp.cli import main
from hystcomp.cli._dynamics import load_dynamics, refuse_dynamics_as_model
from hystcomp.cli._options import (
    method_option,
    method_options,
    narrow_range_option,
    narrowed,
    positive,
)
from hystcomp.codegen import DEFAULT_PREFIX, check_prefix, export_c
from hystcomp.errors import HystcompWarning, ModelFileError
from hystcomp.io.atomic import check_output_path
from hystcomp.io.models import load_model
from hystcomp.models.dynamics import APART
from hystcomp.models.hammerstein import HammersteinModel


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
    if getattr(model, "kind", None) == "multiaxis":  # one state struct for all axes
        from hystcomp.cli._multiaxis import export_multiaxis, refuse

        refuse("--dynamics", dynamics_file, "a multi-axis model")
        export_multiaxis(model, model_file, directory, prefix, slew_rate, sample_rate, method)
        return
    refuse_dynamics_as_model(model, model_file)
    options = {"slew_rate": slew_rate, "sample_rate": sample_rate, **narrowed(model, narrow_range)}
    pair = isinstance(model, HammersteinModel)
    if pair and dynamics_file is not None:
        raise ModelFileError(
            f"{str(model_file)!r} holds a hysteresis model and its dynamics, identified as "
            "one pair; its inverse inverts both. Drop --dynamics."
        )
    dynamics = model.dynamics if pair else None
    if dynamics_file is not None:
        dynamics = options["dynamics"] = load_dynamics(dynamics_file)
    if dynamics is not None and abs(dynamics.sample_rate_ - sample_rate) > 1e-6 * sample_rate:
        raise click.BadParameter(
            f"is {sample_rate:g} Hz but {dynamics_file or model_file} was identified at "
            f"{dynamics.sample_rate_:g} Hz; the code must run at the dynamics' rate.",
            param_hint="'--fs'",
        )
    chosen = method_options(model.hysteresis if pair else model, model_file, method)
    if pair:
        options.pop("sample_rate")  # the pair's own
    elif dynamics_file is not None:
        click.echo(f"hystcomp: warning: {APART}", err=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", HystcompWarning)  # said above, in the command's words
        compensator = model.inverse(**options, **chosen)
    header, source = export_c(
        compensator,
        directory,
        prefix=prefix,
        source=str(model_file),
        sample_rate=sample_rate,
        inputs=(model_file,),
    )
    click.echo(f"wrote {header} and {source}")
