"""Deprecated: the records API moved to :mod:`hystcomp.io.records`.

This module re-exports the same objects (``hystcomp.data.Record is
hystcomp.io.records.Record``), so code written for it keeps working; importing it warns
with a :class:`DeprecationWarning`. New code imports from :mod:`hystcomp.io` (or uses
``hystcomp.Record`` and ``hystcomp.read_record``).
"""

from __future__ import annotations

import warnings

from hystcomp.io.records import (
    MEANINGS,
    RATE_TOLERANCE,
    SPAN_METRES,
    SPAN_NANOMETRES,
    WRITABLE,
    X_UNITS,
    Record,
    check_writable,
    format_csv,
    parse_columns,
    rate_of,
    read_record,
    read_table,
    write_table,
    x_unit_warning,
)

__all__ = [
    "MEANINGS",
    "RATE_TOLERANCE",
    "SPAN_METRES",
    "SPAN_NANOMETRES",
    "WRITABLE",
    "X_UNITS",
    "Record",
    "check_writable",
    "format_csv",
    "parse_columns",
    "rate_of",
    "read_record",
    "read_table",
    "write_table",
    "x_unit_warning",
]

warnings.warn(
    "hystcomp.data is deprecated; import from hystcomp.io (hystcomp.io.records) instead, "
    "e.g. 'from hystcomp.io import read_record'.",
    DeprecationWarning,
    stacklevel=2,
)
