"""What the commands share: checks on option values, made when click parses them (before any
file is read or any work done), the shared options, reading, progress and writing. Readers,
models and figures are imported where used: ``excite`` loads neither numba nor SciPy's solvers.
"""

from __future__ import annotations

import math

import click

from hystcomp._hyperparameters import MAX_OPERATORS
from hystcomp._notice import worded
from hystcomp._progress import Progress
from hystcomp._validation import MAX_MAGNITUDE
from hystcomp.cli import TEXT, _say
from hystcomp.errors import InvalidParameterError
from hystcomp.io.records import X_UNITS  # light: no compiled code until used


def check(test, words: str, finite: bool = False):
    """A callback: a value given must pass ``test(value)``, else ``words`` (formatted with it
    as ``v``) say what it must be; with ``finite``, each of its numbers must be finite first."""

    def callback(ctx, param, value):
        for number in (value if isinstance(value, tuple) else (value,)) if finite else ():
            if number is not None and not (math.isfinite(number) and abs(number) <= MAX_MAGNITUDE):
                raise click.BadParameter(
                    f"must be a finite number of size at most {MAX_MAGNITUDE:g}; got {number!r}.",
                    param=param,
                )
        if value is not None and not test(value):
            raise click.BadParameter(words.format(v=value), param=param)
        return value

    return callback


def positive(unit: str, strict: bool = True):
    """A callback: a finite number > 0 (>= 0 unless ``strict``) in ``unit``."""
    words = f"must be a number {'>' if strict else '>='} 0 ({unit}); got {{v!r}}."
    return check(lambda v: v > 0 or (not strict and v == 0), words, finite=True)


fraction = check(lambda v: 0.0 < v < 1.0, "must be between 0 and 1 (exclusive); got {v!r}.")
count = check(
    lambda v: 1 <= v <= MAX_OPERATORS,
    f"must be between 1 and {MAX_OPERATORS} (the paper uses 16; the fit grows as the cube of "
    "the count); got {v}.",
)
voltage_range = check(  # LO HI in V
    lambda v: v[0] < v[1], "must be LO HI with LO < HI (V); got {v[0]:g} {v[1]:g}.", finite=True
)


class Alias(click.Option):
    """An option with a second name (the Python face's): its errors name only the first."""

    def get_error_hint(self, ctx) -> str:
        return f"'{self.opts[0]}'"


def _columns(ctx, param, value):
    """A callback: a column mapping such as ``v=1,x=5``, or ``v1=2,...`` of an N-axis file."""
    from hystcomp.io.multiaxis import parse_any_columns

    try:
        return parse_any_columns(value)
    except InvalidParameterError as exc:
        raise click.BadParameter(str(exc), param=param) from None


#: ``--voltage-range LO HI`` (V): identify's and excite's range, compensate's and export-c's clamp.
RANGE = {"nargs": 2, "type": float, "metavar": "LO HI", "callback": voltage_range}
#: A rate in Hz (--fs, --frequency).
HZ = {"type": float, "metavar": "HZ", "callback": positive("Hz")}


def method_option(f):
    """``--method``: the Preisach inverse's method (its choices from the Preisach model)."""
    from hystcomp.models.preisach import INVERSE_METHODS

    return click.option("--method", type=click.Choice(INVERSE_METHODS))(f)


quiet = click.option("--quiet", "-q", is_flag=True)


def reading(f):
    """The options of a command that reads a data file: --columns, --fs, --x-unit, --quiet."""
    f = click.option("--x-unit", type=click.Choice(X_UNITS))(quiet(f))
    f = click.option("--fs", "sample_rate", **HZ)(f)
    return click.option("--columns", metavar="SPEC", callback=_columns)(f)


def report(*results, lines: bool = True, warnings: bool = True) -> None:
    """Print the workflow results' report lines, then their warnings on standard error."""
    for line in (x for r in results if lines for x in getattr(r, "lines", ())):
        click.echo(worded(line, TEXT["remedies"]))
    for warning in (x for r in results if warnings for x in getattr(r, "warnings", ())):
        click.echo(f"hystcomp: warning: {_say(warning)}", err=True)


def read_options(given: dict, path="", *, reads: tuple[str, ...] | None = ("v", "x")) -> dict:
    """Keyword arguments for :func:`hystcomp.io.records.read_table` from the shared options;
    a ``--columns`` entry for a column but t and ``reads`` is refused (none: N axes)."""
    from hystcomp.io.records import check_columns_read

    if reads is not None:
        check_columns_read(given.get("columns"), reads)
    options = {k: given.get(k) for k in ("columns", "sample_rate", "x_unit")}
    if not given.get("quiet"):
        options["progress"] = Progress(f"reading {click.format_filename(str(path))}")
    return options


def read_input(path, keys: tuple[str, ...], given: dict, *, multi: bool, optional=()) -> dict:
    """:func:`hystcomp.io.multiaxis.read_columns` with the shared options; a displacement
    read (one axis) is checked for its unit."""
    from hystcomp.io.multiaxis import read_columns

    options = read_options(given, path, reads=None)
    table = read_columns(path, keys, axes=multi, optional=optional, **options)
    if "x" in table and not multi:  # a displacement, in µm like the model
        warn_x_unit(table["x"], path, given)
    return table


def progress(label: str, quiet: bool):
    """A progress line for a step (see :mod:`hystcomp._progress`); silent with --quiet."""
    return Progress(label, enabled=False if quiet else None)


def warn_x_unit(x, source, given: dict) -> None:
    """The one-line warning of :func:`hystcomp.io.records.x_unit_warning`, unless --quiet."""
    from hystcomp.io.records import x_unit_warning

    message = x_unit_warning(x, str(source), given.get("x_unit"))
    if message and not given.get("quiet"):
        click.echo(f"hystcomp: warning: {message}", err=True)


def wrote(paths) -> None:
    """Say that each of ``paths`` was written."""
    for path in paths:
        click.echo(f"  wrote {path}")


def write_model(model, output, plot=None, draw=None) -> None:
    """Write ``model`` to ``output`` and, with ``plot``, the figure ``draw(path)`` makes."""
    from hystcomp.io.atomic import write_all
    from hystcomp.io.models import model_text

    text = model_text(model)
    writers = {output: lambda tmp: tmp.write_text(text, encoding="utf-8")}
    wrote(write_all(writers if plot is None else {**writers, plot: draw})[::-1])


def write_signal(table: dict, output, quiet: bool, summary: str) -> None:
    """Write ``table`` to ``output`` and say ``summary``, or print it as CSV without one."""
    from hystcomp.io.records import print_table, write_table

    if output is None:
        return print_table(table)
    write_table(output, table, progress=progress(f"writing {output}", quiet))
    click.echo(f"wrote {output}: {summary}")
