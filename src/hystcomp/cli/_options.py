"""Options shared by several subcommands, the checks every option value goes through, and the
steps every command shares: read a file, show progress, write the outputs.

Every value is checked when click parses it (a callback), so that a bad option is refused
before any file is read or any work is done, with one line naming the option and the fix.
hystcomp.io.records's readers, hystcomp.io.models and the models are imported where used: a
command that needs no kernel (``excite``) then loads neither numba nor SciPy's sparse solvers.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import click

from hystcomp._hyperparameters import MAX_OPERATORS
from hystcomp._progress import Progress
from hystcomp._validation import MAX_MAGNITUDE
from hystcomp.cli import TEXT
from hystcomp.errors import InvalidParameterError, OutputPathError
from hystcomp.io.records import X_UNITS, format_csv  # light: no compiled code until used


def _finite(value: float, param) -> float:
    if not (math.isfinite(value) and abs(value) <= MAX_MAGNITUDE):
        raise click.BadParameter(
            f"must be a finite number of size at most {MAX_MAGNITUDE:g}; got {value!r}.",
            param=param,
        )
    return value


def positive(unit: str, strict: bool = True):
    """A callback: the value, if given, must be a finite number > 0 (>= 0 unless ``strict``)
    in ``unit``."""

    def check(ctx, param, value):
        if value is not None and not (_finite(value, param) > 0 or (not strict and value == 0)):
            sign = ">" if strict else ">="
            raise click.BadParameter(
                f"must be a number {sign} 0 ({unit}); got {value!r}.", param=param
            )
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
    """A callback: an operator count between 1 and ``MAX_OPERATORS``."""
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


def columns(ctx, param, value):
    """A callback: a column mapping such as ``v=1,x=5``, or ``v1=2,...`` of an N-axis file."""
    from hystcomp.io.multiaxis import parse_axis_columns
    from hystcomp.io.records import parse_columns

    try:
        return parse_columns(value)
    except InvalidParameterError as exc:
        try:
            if value is None or not any(c.isdigit() for c in value.split("=")[0]):
                raise exc from None
            return parse_axis_columns(value)
        except InvalidParameterError as error:
            raise click.BadParameter(str(error), param=param) from None


def _shared(*decls: str, **attrs):
    flag = next(d for d in decls if d.startswith("--"))[2:]
    return click.option(*decls, help=TEXT["options"][flag], **attrs)


#: ``--voltage-range LO HI`` of compensate and export-c: a clamp inside the model's range.
narrow_range = _shared(
    "--voltage-range", "narrow_range", nargs=2, type=float, metavar="LO HI", callback=voltage_range
)


def method_option(f):
    """``--method``: the Preisach inverse's method (its choices from the Preisach model)."""
    from hystcomp.models.preisach import INVERSE_METHODS

    return _shared("--method", type=click.Choice(INVERSE_METHODS))(f)


def reading(f):
    """The options of a command that reads a data file: --columns, --fs, --x-unit, --quiet."""
    for decorate in reversed(
        [
            _shared("--columns", metavar="SPEC", callback=columns),
            _shared("--fs", "sample_rate", type=float, metavar="HZ", callback=positive("Hz")),
            _shared("--x-unit", type=click.Choice(X_UNITS)),
            _shared("--quiet", "-q", is_flag=True),
        ]
    ):
        f = decorate(f)
    return f


def read_options(given: dict, path="", *, reads: tuple[str, ...] | None = ("v", "x")) -> dict:
    """Keyword arguments for :func:`hystcomp.io.records.read_table` from the shared options.

    ``reads`` are the columns the command reads besides t: a ``--columns`` entry for
    another one is refused (it would be ignored, and was most likely meant for one read).
    None (an N-axis file) checks nothing.
    """
    from hystcomp.io.records import MEANINGS

    named = given.get("columns") or {}
    unused = [key for key in named if reads is not None and key not in ("t", *reads)]
    if reads is not None and unused:
        key, spec = unused[0], named[unused[0]]
        meant = next((k for k in reads if k not in named), reads[0])
        raise click.BadParameter(
            f"{key}={spec} names a column of {MEANINGS[key].split(' in ')[0]}, which this "
            f"command does not read (it reads t and {' and '.join(reads)}); name the column "
            f"of {MEANINGS[meant].split(' in ')[0]} instead, e.g. --columns {meant}={spec}.",
            param_hint="'--columns'",
        )
    options = {k: given.get(k) for k in ("columns", "sample_rate", "x_unit")}
    if not given.get("quiet"):
        options["progress"] = Progress(f"reading {click.format_filename(str(path))}")
    return options


def progress(label: str, quiet: bool):
    """A progress line for a step (see :mod:`hystcomp._progress`); silent with --quiet."""
    return Progress(label, enabled=False if quiet else None)


def warn_x_unit(x, source, given: dict) -> None:
    """The one-line warning of :func:`hystcomp.io.records.x_unit_warning`, unless --quiet."""
    from hystcomp.io.records import x_unit_warning

    message = x_unit_warning(x, str(source), given.get("x_unit"))
    if message and not given.get("quiet"):
        click.echo(f"hystcomp: warning: {message}", err=True)


def check_data_output(path, *, inputs=(), what: str = "output"):
    """Refuse, before any work, a data output that cannot be written or would overwrite an input."""
    from hystcomp.io.atomic import check_output_path
    from hystcomp.io.records import check_writable

    check_output_path(path, inputs=inputs, what=what)
    return check_writable(path)


def check_plot(plot, *, inputs=(), output=None) -> None:
    """Refuse, before any work, a figure of an unknown format, or one that would overwrite
    an input or the command's other output."""
    from hystcomp.experiment.fig_identification import FORMATS  # no matplotlib yet
    from hystcomp.io.atomic import check_output_path

    if Path(plot).suffix.lower() not in FORMATS:
        raise click.BadParameter(f"must end in {', '.join(FORMATS)}.", param_hint="--plot")
    check_output_path(plot, inputs=inputs, what="figure")
    if output is not None and Path(plot).resolve() == Path(output).resolve():
        raise click.BadParameter("names the same file as -o.", param_hint="--plot")


def write_files(writers: dict, *, reverse: bool = False) -> None:
    """Write every output at once (a failure writes none of them), then say so.

    ``writers`` maps each path to a function that writes a temporary file given to it.
    """
    from hystcomp.io.atomic import atomic_paths

    with atomic_paths(*writers) as temporaries:
        for write, tmp in zip(writers.values(), temporaries, strict=True):
            write(tmp)
    for path in list(writers)[:: -1 if reverse else 1]:
        click.echo(f"  wrote {path}")


def write_model(model, output, plot=None, draw=None) -> None:
    """Write ``model`` to ``output`` and, with ``plot``, the figure ``draw(path)`` makes."""
    from hystcomp.io.models import model_text

    text = model_text(model)
    writers = {output: lambda tmp: tmp.write_text(text, encoding="utf-8")}
    write_files(writers if plot is None else {**writers, plot: draw}, reverse=True)


def write_signal(table: dict, output, quiet: bool, summary: str) -> None:
    """Write ``table`` to ``output`` and say ``summary``, or print it as CSV without one."""
    from hystcomp.io.records import write_table

    if output is not None:
        write_table(output, table, progress=progress(f"writing {output}", quiet))
        return click.echo(f"wrote {output}: {summary}")
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
