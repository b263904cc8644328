"""N-axis data files: records ``t, v1..vN, x1..xN``, inputs ``t, v1..vN``, references
``t, x1..xN``.

The columns are found by their names, in any case (``V1``, ``x2``), numbered from 1 without
gaps; ``columns={"v1": 2, "x1": 5, "v2": 3, "x2": 6}`` (1-based numbers or names, or that
text parsed by :func:`parse_axis_columns`) maps others. Everything
else is as for one axis (:mod:`hystcomp.io.records`): the same formats, the same checks of
every column (finite, bounded, a time column that increases or a sample rate), units rows
and ``x_unit`` for the displacements. A file is an N-axis file when a column is named
``v1`` or ``x1`` (or ``columns`` names one).
"""

from __future__ import annotations

import re
import zipfile
from pathlib import Path

import numpy as np

from hystcomp._notice import Notice
from hystcomp._validation import as_path, check_real
from hystcomp.errors import DataFileError, InvalidParameterError
from hystcomp.io._formats import read_raw
from hystcomp.io.records import (
    MEANINGS,
    X_UNITS,
    _as_column,
    _find,
    _Raw,
    _time,
    _units,
    check_columns_read,
    parse_columns,
    read_table,
)

__all__ = [
    "axis_key",
    "is_multiaxis",
    "parse_any_columns",
    "parse_axis_columns",
    "read_axes",
    "read_columns",
]

_KEY = re.compile(r"^([vx])([1-9][0-9]*)$", re.IGNORECASE)
#: Most axes of a file.
MAX_AXES = 64
#: Bytes of a text file's start read to find its header.
PEEK_BYTES = 65_536


def axis_key(name) -> tuple[str, int] | None:
    """``("v", 2)`` for a column named ``v2`` (any case), else None.

    >>> axis_key("X12"), axis_key("x"), axis_key("v0")
    (('x', 12), None, None)

    Parameters
    ----------
    name : str
        A column name.

    Returns
    -------
    tuple of (str, int) or None
        The key (``"v"`` or ``"x"``) and the axis number (from 1), or None for any other name.
    """
    match = _KEY.match(str(name).strip())
    if match is None:
        return None
    return match.group(1).lower(), int(match.group(2))


def parse_axis_columns(text: str) -> dict[str, int | str]:
    """Parse the column mapping of an N-axis file as text, such as ``t=1,v1=2,v2=3,x1=4,x2=5``.

    Parameters
    ----------
    text : str
        ``key=column`` pairs separated by commas.

    Returns
    -------
    dict
        Each key (``t``, ``v1``, ``x2``, ...) with its 1-based column number or its column name.

    Examples
    --------
    >>> parse_axis_columns("v1=2, x1=volts")
    {'v1': 2, 'x1': 'volts'}
    """
    mapping: dict[str, int | str] = {}
    for item in str(text).split(","):
        key, sep, value = (part.strip() for part in item.partition("="))
        key = key.lower()
        if not sep or not value or key in mapping or not (key == "t" or axis_key(key)):
            raise InvalidParameterError(
                "The 'columns' option of an N-axis file must look like t=1,v1=2,v2=3,x1=4,x2=5 "
                "(1-based column numbers or header names), each key once. Got "
                f"{text!r} instead."
            )
        mapping[key] = int(value) if value.isascii() and value.isdigit() else value
    return mapping


def _header_names(path: Path) -> list[str]:
    """The names a file's columns may have, read cheaply: a text file's first lines, an
    NPZ file's keys, a MAT file's variables (parsed as for reading it)."""
    suffix = path.suffix.lower()
    try:
        if suffix == ".npz":
            with zipfile.ZipFile(path) as archive:
                return [Path(n).stem for n in archive.namelist()]
        if suffix == ".mat":
            try:
                return [str(name) for name in read_raw(path, None)[0] or []]
            except DataFileError:
                return []  # the reader says what is wrong with it
        with path.open("rb") as f:
            head = f.read(PEEK_BYTES).decode("utf-8", errors="replace")
    except (OSError, zipfile.BadZipFile):
        return []
    names: list[str] = []
    for line in head.splitlines()[:50]:
        names += re.split(r"[,;\t ]+", line.strip().lstrip("#%").strip())
    return names


def is_multiaxis(path, columns: dict | None = None) -> bool:
    """Whether ``path`` is an N-axis file: a column named ``v1`` or ``x1`` (any case), or
    ``columns`` naming one.

    Parameters
    ----------
    path : str or os.PathLike
        A data file.
    columns : dict, optional
        The column mapping the user gave.

    Returns
    -------
    bool
        True for an N-axis file.
    """
    if columns and any(axis_key(key) for key in columns):
        return True
    try:
        path = Path(path)
    except TypeError:
        return False
    if not path.is_file():
        return False
    return any((key := axis_key(name)) is not None and key[1] == 1 for name in _header_names(path))


def read_axes(
    path, keys=("v", "x"), *, columns=None, sample_rate=None, x_unit=None, progress=None
) -> dict[str, np.ndarray]:
    """Read an N-axis file: time and the columns ``keys`` of every axis.

    Parameters
    ----------
    path : str or path-like
        The file (CSV, NPZ, MAT or a text table, as :func:`hystcomp.io.records.read_table`).
    keys : sequence of {'v', 'x'}
        What each axis needs: ``("v", "x")`` for a record, ``("v",)`` for an input,
        ``("x",)`` for a reference.
    columns : dict, optional
        ``{"v1": 2, "x1": "disp_x", ...}``: 1-based numbers or names; the rest by name.
    sample_rate : float, optional
        Hz, for a file without a time column.
    x_unit : {'m', 'mm', 'um', 'nm'}, optional
        The displacements' unit, converted to µm.
    progress : callable, optional
        Called with the fraction read.

    Returns
    -------
    dict
        ``"t"`` (n,), and each key's (n, N) array, axis ``i`` in column ``i - 1``.

    Raises
    ------
    DataFileError
        Naming the file, the column, the problem and the fix.
    """
    path = as_path(path, "path", "read_axes")
    columns = {str(k).lower(): v for k, v in (columns or {}).items()}
    if sample_rate is not None:
        sample_rate = check_real(sample_rate, "sample_rate", "read_axes", positive=True)
    if x_unit is not None and x_unit not in X_UNITS:
        raise InvalidParameterError(
            f"The 'x_unit' parameter of read_axes must be one of {', '.join(X_UNITS)}. Got "
            f"{x_unit!r} instead."
        )
    try:
        names, arrays, positional, units = read_raw(path, progress)
    finally:
        if progress is not None:
            progress(1.0)
    where = f"Data file {str(path)!r}"
    found: dict[str, dict[int, int]] = {key: {} for key in keys}
    for index, name in enumerate(names or []):
        named = axis_key(name)
        if named is not None and named[0] in found:
            found[named[0]][named[1]] = index
    for spec_key, spec in columns.items():
        axis = axis_key(spec_key)
        if axis is None or axis[0] not in found:
            continue
        if isinstance(spec, int):
            if not positional or spec > len(arrays):
                raise DataFileError(
                    f"{where} has no column {spec} for {spec_key!r}: it has {len(arrays)} "
                    "numbered columns."
                )
            found[axis[0]][axis[1]] = spec - 1
        else:
            picked = _find(path, names or [], spec)
            if picked is None:
                raise DataFileError(
                    f"{where} has no column {spec!r} for {spec_key!r}; its columns are "
                    f"{', '.join(map(str, names or []))}."
                )
            found[axis[0]][axis[1]] = picked
    counts = {key: len(idx) for key, idx in found.items()}
    n_axes = max(counts.values(), default=0)
    if n_axes == 0:
        raise DataFileError(
            Notice(
                "{where} has no N-axis columns ({wanted}, ...); its columns are {found}. Name "
                "them, or map them with {axis_columns}",
                where=where,
                wanted=", ".join(k + "1" for k in keys),
                found=", ".join(map(str, names or [])) or "unnamed",
            )
        )
    if n_axes > MAX_AXES:
        raise DataFileError(f"{where} has {n_axes} axes, more than {MAX_AXES}.")
    for key, idx in found.items():
        missing = [i for i in range(1, n_axes + 1) if i not in idx]
        if missing or len(idx) != n_axes:
            label = f"{key}{missing[0]}" if missing else f"{key}{max(idx)}"
            raise DataFileError(
                f"{where} has no column {label!r} ({MEANINGS[key]} of axis "
                f"{label[1:]}), but {n_axes} axes elsewhere: every axis needs its "
                f"{' and '.join(keys)}, numbered 1..{n_axes} without gaps."
            )
    out: dict[str, np.ndarray] = {}
    raw_units = _Raw(names, [], positional, units)
    for key, idx in found.items():
        cols = []
        for number in range(1, n_axes + 1):
            index = idx[number]
            label = f"column {names[index]!r}" if names else f"column {index + 1}"
            arr = _as_column(arrays[index], path, key, label)
            factor = _units(path, raw_units, key, index, x_unit)
            if factor != 1.0:
                arr = _as_column(arr * factor, path, key, label)
            cols.append(arr)
        lengths = {a.size for a in cols}
        if len(lengths) > 1:
            raise DataFileError(f"{where} has columns of different lengths ({sorted(lengths)}).")
        out[key] = np.column_stack(cols)
    n = next(iter(out.values())).shape[0]
    if n < 2:
        raise DataFileError(f"{where} has {n} sample; at least 2 are needed.")
    t_index = columns.get("t")
    t = None
    if isinstance(t_index, int):
        t = _as_column(arrays[t_index - 1], path, "t", f"column {t_index}")
    elif names:
        t_at = _find(path, names, t_index or "t")
        if t_at is not None:
            t = _as_column(arrays[t_at], path, "t", f"column {names[t_at]!r}")
    out["t"] = _time(path, t, n, sample_rate)
    for arr in out.values():
        arr.setflags(write=False)
    return out


def axis_table(t, **signals) -> dict:
    """The columns of a data file: ``t`` and each signal, as ``v`` or, for a signal with one
    column per axis, as ``v1..vN`` (``x_ref``: ``x1_ref..xN_ref``).

    Parameters
    ----------
    t : ndarray
        Time in s.
    **signals : ndarray
        Each signal by its column name: 1-D, or 2-D with one column per axis.

    Returns
    -------
    dict
        Column name to 1-D array, ``t`` first.

    Examples
    --------
    >>> import numpy as np
    >>> list(axis_table(np.arange(2.0), v=np.ones((2, 2)), x_ref=np.zeros((2, 2))))
    ['t', 'v1', 'v2', 'x1_ref', 'x2_ref']
    """
    out = {"t": t}
    for name, s in signals.items():
        if s.ndim == 1:
            out[name] = s
        else:
            out.update({f"{name[0]}{i + 1}{name[1:]}": s[:, i] for i in range(s.shape[1])})
    return out


def parse_any_columns(text: str | None) -> dict[str, int | str] | None:
    """Parse a column mapping of one axis (``v=1,x=5``) or of N axes (``v1=2,x1=4,...``).

    Parameters
    ----------
    text : str or None
        The mapping as a user writes it, for one axis or for N; None when there is none.

    Returns
    -------
    dict or None
        As :func:`hystcomp.io.records.parse_columns` returns it, or, where its first key
        names an axis (a digit in it), as :func:`parse_axis_columns` does.

    Raises
    ------
    InvalidParameterError
        The one-axis reason, or the N-axis one where the first key names an axis.

    Examples
    --------
    >>> parse_any_columns("v=1,x=5"), parse_any_columns("v1=2,x1=volts")
    ({'v': 1, 'x': 5}, {'v1': 2, 'x1': 'volts'})
    """
    try:
        return parse_columns(text)
    except InvalidParameterError:
        if text is None or not any(c.isdigit() for c in str(text).split("=")[0]):
            raise
    return parse_axis_columns(text)


def read_columns(path, keys=("v", "x"), *, axes: bool = False, optional=(), **options) -> dict:
    """The columns t and ``keys`` of a data file, of every axis if ``axes``.

    One axis: :func:`~hystcomp.io.records.read_table`, with the ``optional`` columns the
    file has, and a column mapping that names another column refused
    (:func:`~hystcomp.io.records.check_columns_read`). N axes: :func:`read_axes`.

    Parameters
    ----------
    path : str or path-like
        The data file.
    keys : sequence of {'v', 'x'}, default ('v', 'x')
        The columns needed (of each axis).
    axes : bool, default False
        The file has N axes (columns v1..vN, x1..xN).
    optional : sequence of str, optional
        Columns read if the file has them (one axis).
    **options
        ``columns``, ``sample_rate``, ``x_unit`` and ``progress``, as
        :func:`~hystcomp.io.records.read_table` takes them.

    Returns
    -------
    dict of str to ndarray
        ``t`` and each column read (of shape (n, N) with N axes).
    """
    if axes:
        return read_axes(path, keys, **options)
    check_columns_read(options.get("columns"), (*keys, *optional))
    return read_table(path, keys, optional=optional, **options)
