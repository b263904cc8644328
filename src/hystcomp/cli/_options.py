"""Options shared by several subcommands: data columns, sample rate, output file."""

from __future__ import annotations

import click

from hystcomp.data import parse_columns

columns_option = click.option(
    "--columns",
    metavar="SPEC",
    default=None,
    help=(
        "Which file columns hold t, v, x: 1-based numbers for text tables (v=1,x=5) or "
        "names (v=volts,x=disp). Default: columns named t, v, x."
    ),
)
fs_option = click.option(
    "--fs",
    "sample_rate",
    type=float,
    default=None,
    metavar="HZ",
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


def read_options(columns: str | None, sample_rate: float | None) -> dict:
    """Keyword arguments for :func:`hystcomp.data.read_table` from the shared options."""
    return {"columns": parse_columns(columns), "sample_rate": sample_rate}
