"""Deprecated: the records API moved to :mod:`hystcomp.io.records`.

Every name this module had is still here and is the same object
(``hystcomp.data.Record is hystcomp.io.records.Record``), so code written for it keeps
working; using one warns with a :class:`DeprecationWarning`. New code imports from
:mod:`hystcomp.io` (or uses ``hystcomp.Record`` and ``hystcomp.read_record``).
"""

from __future__ import annotations

import importlib
import warnings
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
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


def __getattr__(name: str) -> Any:
    if name not in __all__:
        raise AttributeError(f"module 'hystcomp.data' has no attribute {name!r}")
    warnings.warn(
        f"hystcomp.data is deprecated; use hystcomp.io.{name} "
        f"(e.g. 'from hystcomp.io import {name}').",
        DeprecationWarning,
        stacklevel=2,
    )
    return getattr(importlib.import_module("hystcomp.io.records"), name)


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
