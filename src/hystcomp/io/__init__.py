"""Files: records (CSV, NPZ, MAT, .dat), model files (JSON) and atomic outputs.

* :mod:`hystcomp.io.records`: measured records ``(t, v, x)``, inputs and references
  (:class:`~hystcomp.io.records.Record`, :func:`~hystcomp.io.records.read_record`,
  :func:`~hystcomp.io.records.read_table`, :func:`~hystcomp.io.records.write_table`);
* :mod:`hystcomp.io.models`: model files (:func:`~hystcomp.io.models.load_model`,
  :func:`~hystcomp.io.models.save_model`, the registry ``MODEL_KINDS``);
* :mod:`hystcomp.io.atomic`: output-path checks and writes that never leave a broken file
  (a leaf: it imports no model and no record reader).

Every public name of the three is available here too. The atomic outputs are imported
with the package; records and model files load when first used, so that a command that
only writes a file (or only reads a record) does not import every model class.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from hystcomp.io.atomic import (
    atomic_path,
    atomic_paths,
    check_output_path,
    discard_temporary,
    forget_folder,
    new_temporary_folder,
    refusal,
    remove_pending,
    replace_all,
    staging_folder,
    track_new_folder,
    write_all,
    write_target,
)

if TYPE_CHECKING:
    from hystcomp.io.models import (
        MAX_MODEL_FILE_BYTES,
        MODEL_FORMAT,
        MODEL_KINDS,
        MODEL_VERSION,
        load_model,
        model_from_dict,
        model_text,
        model_to_dict,
        save_model,
    )
    from hystcomp.io.records import (
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

#: Names loaded on first use, by the module that defines them.
_LAZY = {
    **dict.fromkeys(
        (
            "MAX_MODEL_FILE_BYTES",
            "MODEL_FORMAT",
            "MODEL_KINDS",
            "MODEL_VERSION",
            "load_model",
            "model_from_dict",
            "model_text",
            "model_to_dict",
            "save_model",
        ),
        "hystcomp.io.models",
    ),
    **dict.fromkeys(
        (
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
        ),
        "hystcomp.io.records",
    ),
}

__all__ = [  # written out for static tools; the package's tests check it against _LAZY
    "MAX_MODEL_FILE_BYTES",
    "MODEL_FORMAT",
    "MODEL_KINDS",
    "MODEL_VERSION",
    "X_UNITS",
    "Record",
    "atomic_path",
    "atomic_paths",
    "check_output_path",
    "check_writable",
    "discard_temporary",
    "forget_folder",
    "format_csv",
    "load_model",
    "model_from_dict",
    "model_text",
    "model_to_dict",
    "new_temporary_folder",
    "parse_columns",
    "rate_of",
    "read_record",
    "read_table",
    "refusal",
    "remove_pending",
    "replace_all",
    "save_model",
    "staging_folder",
    "track_new_folder",
    "write_all",
    "write_table",
    "write_target",
    "x_unit_warning",
]


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'hystcomp.io' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})
