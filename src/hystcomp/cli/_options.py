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
from hystcomp.io.records import X_UNITS  # light: the readers load compiled code only on use

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


def narrowed(model, narrow_range) -> dict:
    """``{"voltage_range": narrow_range}`` for ``model.inverse``, or ``{}`` if not given;
    a range reaching beyond the model's is refused as the option's error."""
    if narrow_range is None:
        return {}
    (lo, hi), (low, high) = model.voltage_range_, narrow_range
    if low < lo or high > hi:
        raise click.BadParameter(
            f"may only narrow the model's voltage range {lo:g} .. {hi:g} V: the model was "
            f"identified inside it and would command voltages it never saw. Got {low:g} "
            f"{high:g}; choose limits within it, or identify over a wider range.",
            param_hint="'--voltage-range'",
        )
    return {"voltage_range": narrow_range}


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
    reads: tuple[str, ...] = ("v", "x"),
) -> dict:
    """Keyword arguments for :func:`hystcomp.io.records.read_table` from the shared options.

    ``reads`` are the columns the command reads besides t: a ``--columns`` entry for
    another one is refused (it would be ignored, and was most likely meant for one read).
    """
    from hystcomp.io.records import MEANINGS

    named = columns or {}
    unused = [key for key in named if key not in ("t", *reads)]
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


def method_options(model, model_file, method) -> dict:
    """``model.inverse``'s ``method`` for ``--method``, refused for a model without one."""
    if method is None:
        return {}
    if model.kind != "preisach":
        raise click.BadParameter(
            f"applies to Preisach models only; the model in {model_file} is "
            f"{model.kind.upper()}, whose inverse is analytic (eqs. 23-26). Drop --method.",
            param_hint="'--method'",
        )
    return {"method": method}


#: A step of the reference's time column shorter than this share of its median step is a
#: fault of the column, not jitter: at its rate the slew-rate limit would all but hold the
#: voltage still on every sample.
SHORTEST_STEP = 1e-3


def slew_sample_rate(t, path) -> float:
    """The rate (Hz) of the shortest step of ``t``, at which the slew-rate limit holds on
    every step; refused, naming the row, if that step is a fault of the time column."""
    import numpy as np

    from hystcomp.errors import InvalidSignalError

    steps = np.diff(t)
    k = int(np.argmin(steps))
    shortest, median = float(steps[k]), float(np.median(steps))
    if not shortest >= SHORTEST_STEP * median or not 1.0 / shortest <= MAX_MAGNITUDE:
        raise InvalidSignalError(
            f"--slew-rate limits the voltage's change per sample at the reference's shortest "
            f"time step, but the time column 't' of {str(path)!r} steps by only "
            f"{shortest:.3g} s from t = {float(t[k])!r} to {float(t[k + 1])!r} s (data row "
            f"{k + 2}), against a median step of {median:.3g} s: the limit would hold the "
            "voltage nearly still. Correct the time column there, or drop it and give --fs."
        )
    return 1.0 / shortest
