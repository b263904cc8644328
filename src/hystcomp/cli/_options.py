"""Options shared by several subcommands, and the checks every option value goes through.

Every value is checked when click parses it (a callback), so that a bad option is refused
before any file is read or any work is done, with one line naming the option and the fix.
"""

from __future__ import annotations

import math

import click

from hystcomp._hyperparameters import MAX_OPERATORS
from hystcomp._progress import Progress
from hystcomp._validation import MAX_MAGNITUDE
from hystcomp.errors import InvalidParameterError

# light: the readers load compiled code only on use
from hystcomp.io.records import X_UNITS, format_csv

# hystcomp.io.records, hystcomp.io.models and the models are imported where used: a command that
# needs no kernel (``excite``) then loads neither numba nor SciPy's sparse solvers.


def _finite(value: float, param) -> float:
    if not (math.isfinite(value) and abs(value) <= MAX_MAGNITUDE):
        raise click.BadParameter(
            f"must be a finite number of size at most {MAX_MAGNITUDE:g}; got {value!r}.",
            param=param,
        )
    return value


def positive(unit: str):
    """A callback: the value, if given, must be a finite number > 0 (in ``unit``)."""

    def check(ctx, param, value):
        if value is None:
            return None
        if not (_finite(value, param) > 0):
            raise click.BadParameter(f"must be a number > 0 ({unit}); got {value!r}.", param=param)
        return value

    return check


def nonnegative(unit: str):
    """A callback: the value, if given, must be a finite number >= 0 (in ``unit``)."""

    def check(ctx, param, value):
        if value is None:
            return None
        if not (_finite(value, param) >= 0):
            raise click.BadParameter(f"must be a number >= 0 ({unit}); got {value!r}.", param=param)
        return value

    return check


def fraction(ctx, param, value):
    """A callback: the value, if given, must lie strictly between 0 and 1."""
    if value is not None and not 0.0 < value < 1.0:
        raise click.BadParameter(
            f"must be between 0 and 1 (exclusive); got {value!r}.", param=param
        )
    return value


def count(ctx, param, value):
    """A callback: an operator count between 1 and
    :data:`~hystcomp._hyperparameters.MAX_OPERATORS`."""
    if value is not None and not 1 <= value <= MAX_OPERATORS:
        raise click.BadParameter(
            f"must be between 1 and {MAX_OPERATORS} (the paper uses 16; the fit grows as the "
            f"cube of the count); got {value}.",
            param=param,
        )
    return value


def voltage_range(ctx, param, value):
    """A callback: ``LO HI`` in V, finite, with ``LO < HI``."""
    if value is None:
        return None
    lo, hi = (_finite(v, param) for v in value)
    if not lo < hi:
        raise click.BadParameter(f"must be LO HI with LO < HI (V); got {lo:g} {hi:g}.", param=param)
    return (lo, hi)


#: ``--voltage-range LO HI`` of compensate and export-c: a clamp inside the model's range.
narrow_range_option = click.option(
    "--voltage-range",
    "narrow_range",
    nargs=2,
    type=float,
    default=None,
    metavar="LO HI",
    callback=voltage_range,
    help="Clamp the output to this range in V, inside the model's range (it may only "
    "narrow it) [the model's range].",
)


def columns(ctx, param, value):
    """A callback: a column mapping such as ``v=1,x=5`` (see :func:`parse_columns`)."""
    from hystcomp.io.records import parse_columns

    try:
        return parse_columns(value)
    except InvalidParameterError as exc:
        if value is not None and any(c.isdigit() for c in value.split("=")[0]):
            from hystcomp.io.multiaxis import parse_axis_columns  # an N-axis file: v1=2,...

            try:
                return parse_axis_columns(value)
            except InvalidParameterError as axis_exc:
                raise click.BadParameter(str(axis_exc), param=param) from None
        raise click.BadParameter(str(exc), param=param) from None


columns_option = click.option(
    "--columns",
    metavar="SPEC",
    default=None,
    callback=columns,
    help=(
        "Which file columns hold t, v, x: 1-based numbers for text tables or the one matrix "
        "of a MAT/NPZ file (v=1,x=5), or names in any case (v=volts,x=disp). Default: "
        "columns named t, v, x. N-axis files: v1=2,v2=3,x1=4,x2=5 (default: columns named "
        "v1..vN, x1..xN)."
    ),
)
fs_option = click.option(
    "--fs",
    "sample_rate",
    type=float,
    default=None,
    metavar="HZ",
    callback=positive("Hz"),
    help="Sample rate in Hz, for files without a time column t.",
)


def output_option(required: bool = True, what: str = "output"):
    """The ``-o/--output FILE`` option (format by suffix: .csv, .npz, .mat)."""
    return click.option(
        "-o",
        "--output",
        required=required,
        metavar="FILE",
        help=f"Where to write the {what} (.csv, .npz or .mat).",
    )


x_unit_option = click.option(
    "--x-unit",
    type=click.Choice(X_UNITS),
    default=None,
    help="Unit of the displacement in the file, converted to µm [the file's units row, else um].",
)
quiet_option = click.option(
    "--quiet",
    "-q",
    is_flag=True,
    help="No progress line and no unit-guess warning. Warnings about safety (clamping, "
    "leaving the model's range) are always shown. Progress is shown only on a terminal, "
    "for steps over 2 s.",
)


def read_options(
    columns: dict | None,
    sample_rate: float | None,
    x_unit=None,
    quiet: bool = False,
    path="",
    *,
    reads: tuple[str, ...] | None = ("v", "x"),
) -> dict:
    """Keyword arguments for :func:`hystcomp.io.records.read_table` from the shared options.

    ``reads`` are the columns the command reads besides t: a ``--columns`` entry for
    another one is refused (it would be ignored, and was most likely meant for one read).
    None (an N-axis file) checks nothing.
    """
    from hystcomp.io.records import MEANINGS

    named = columns or {}
    unused = [key for key in named if reads is not None and key not in ("t", *reads)]
    if unused:
        key, spec = unused[0], named[unused[0]]
        meant = next((k for k in reads if k not in named), reads[0])
        raise click.BadParameter(
            f"{key}={spec} names a column of {MEANINGS[key].split(' in ')[0]}, which this "
            f"command does not read (it reads t and {' and '.join(reads)}); name the column "
            f"of {MEANINGS[meant].split(' in ')[0]} instead, e.g. --columns {meant}={spec}.",
            param_hint="'--columns'",
        )
    options = {"columns": columns, "sample_rate": sample_rate, "x_unit": x_unit}
    if not quiet:
        options["progress"] = Progress(f"reading {click.format_filename(str(path))}")
    return options


def progress(label: str, quiet: bool):
    """A progress line for a step (see :mod:`hystcomp._progress`); silent with --quiet."""
    return Progress(label, enabled=False if quiet else None)


def warn_x_unit(x, source, quiet: bool, x_unit: str | None = None) -> None:
    """The one-line warning of :func:`hystcomp.io.records.x_unit_warning`, unless --quiet."""
    from hystcomp.io.records import x_unit_warning

    message = x_unit_warning(x, str(source), x_unit)
    if message and not quiet:
        click.echo(f"hystcomp: warning: {message}", err=True)


def check_data_output(path, *, inputs=(), what: str = "output"):
    """Refuse, before any work, a data output that cannot be written or would overwrite an input."""
    from hystcomp.io.atomic import check_output_path
    from hystcomp.io.records import check_writable

    check_output_path(path, inputs=inputs, what=what)
    return check_writable(path)


def __getattr__(name: str):
    if name == "method_option":  # built on first use: its choices come from the Preisach model
        from hystcomp.models.preisach import INVERSE_METHODS

        return click.option(
            "--method",
            type=click.Choice(INVERSE_METHODS),
            default=None,
            help="Preisach models only: the inverse multiplicative structure (eq. 10) or the "
            "exact inverse [multiplicative; exact with --dynamics, as eq. 10's one-sample lag "
            "overshoots a fast rise, a minor loop that the dynamics cannot undo].",
        )
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def check_plot(plot, *, inputs=(), output=None) -> None:
    """Refuse, before any work, a figure path of an unknown format, or one that would
    overwrite an input or the command's other output."""
    from pathlib import Path

    from hystcomp.experiment.fig_identification import FORMATS  # matplotlib only when drawn
    from hystcomp.io.atomic import check_output_path

    if Path(plot).suffix.lower() not in FORMATS:
        raise click.BadParameter(f"must end in {', '.join(FORMATS)}.", param_hint="--plot")
    check_output_path(plot, inputs=inputs, what="figure")
    if output is not None and Path(plot).resolve() == Path(output).resolve():
        raise click.BadParameter("names the same file as -o.", param_hint="--plot")


def write_model(model, output, plot=None, draw=None) -> None:
    """Write ``model`` to ``output`` and, with ``plot``, the figure ``draw(path)`` makes; all
    at once (a failure writes none of them), then say so."""
    from hystcomp.io.atomic import atomic_paths
    from hystcomp.io.models import model_text

    text = model_text(model)
    outputs = [output] if plot is None else [output, plot]
    with atomic_paths(*outputs) as (tmp_model, *tmp_plot):
        tmp_model.write_text(text, encoding="utf-8")
        if plot is not None:
            draw(tmp_plot[0])
    for path in outputs[::-1]:
        click.echo(f"  wrote {path}")


def write_signal(table: dict, output, quiet: bool, summary: str) -> None:
    """Write ``table`` to ``output`` (``summary`` after it), or as CSV on standard output."""
    import sys

    from hystcomp.errors import OutputPathError
    from hystcomp.io.records import write_table

    if output is not None:
        write_table(output, table, progress=progress(f"writing {output}", quiet))
        click.echo(f"wrote {output}: {summary}")
        return
    try:
        click.echo(format_csv(table), nl=False)
        sys.stdout.flush()
    except BrokenPipeError:
        raise  # the reader went away (| head): not an error
    except OSError as exc:
        raise OutputPathError(
            f"Cannot write the signal to standard output: {exc.strerror or exc}. Give a "
            "file with -o, or check where standard output goes."
        ) from None
