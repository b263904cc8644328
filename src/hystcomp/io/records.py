"""Records (data files): measured records ``(t, v, x)``, inputs ``(t, v)`` and references ``(t, x)``.

Formats, chosen by the file's suffix:

* ``.npz`` (NumPy) and ``.mat`` (MATLAB, read with :func:`scipy.io.loadmat`): the names
  ``t``, ``v``, ``x`` as keys or variables, or one matrix whose columns are numbered;
* anything else (``.csv``, ``.dat``, ``.txt``, ...): a text table, with a header row
  naming the columns (``t`` in s, ``v`` in V, ``x`` in µm; any case; extra columns are
  ignored) or none. Separators, decimal commas, comment lines, ``# t,v,x`` headers and a
  units row are recognised by the rules of :mod:`hystcomp.io._text`.

Columns can be named explicitly: ``{"v": 1, "x": 5}`` (1-based column numbers, for text
files and one-matrix files) or ``{"v": "volts", "x": "disp"}`` (header names or keys), or as
text, ``"v=1,x=5"``. A file without a time column needs the sample rate. Displacements in
other units are converted with ``x_unit``. A record has at
most :data:`hystcomp.io._formats.MAX_SAMPLES` samples (``HYSTCOMP_MAX_SAMPLES``), checked
before a large array is loaded. CSV is written in chunks with every value as its
``repr``; writes go through :func:`hystcomp.io.atomic.atomic_path`: a failing write never
truncates an existing file. See ``docs/data-files.md``.

Files are untrusted input: every problem (not a regular file, not text, a corrupt archive,
text or complex numbers in a column, NaN or inf, a value beyond
:data:`~hystcomp._validation.MAX_MAGNITUDE`, a time column that does not increase) is a
:class:`~hystcomp.errors.DataFileError` naming the file, the column and the fix. NPZ files
are read without pickle. MAT files are parsed in a separate process, because scipy's MAT
reader is not hardened against corrupt files (it can crash the interpreter); a crash there
is reported as a corrupt file.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from io import BytesIO
from pathlib import Path
from typing import Any

import numpy as np

from hystcomp._notice import Notice
from hystcomp._validation import MAX_MAGNITUDE, as_path, as_signal, check_int, check_real
from hystcomp.errors import (
    DataFileError,
    InvalidParameterError,
    InvalidSignalError,
    OutputPathError,
)
from hystcomp.io._formats import read_raw
from hystcomp.io._text import UNITS, write_csv
from hystcomp.io.atomic import atomic_path, check_output_path

#: What each column holds, for messages.
MEANINGS = {"t": "time in s", "v": "voltage in V", "x": "displacement in µm"}
WRITABLE = (".csv", ".npz", ".mat")
#: Largest relative disagreement between a time column and a given sample rate.
RATE_TOLERANCE = 0.01
#: Displacement units of ``x_unit``, converted to µm.
X_UNITS = ("m", "mm", "um", "nm")
#: Displacement spans (µm) below or above which :func:`x_unit_warning` suspects m or nm.
SPAN_METRES = 0.01
SPAN_NANOMETRES = 5000.0


@dataclass(frozen=True, eq=False)
class Record:
    """A measured record: time (s), input voltage (V) and displacement (µm).

    Attributes
    ----------
    t, v, x : ndarray
        Read-only, finite, equally long; ``t`` strictly increasing.
    source : str
        Where it came from (a file name), for messages.

    Examples
    --------
    >>> rec = Record(np.arange(4) / 200.0, np.array([0.0, 1, 2, 1]), np.array([0.0, 2, 4, 3]))
    >>> rec.sample_rate, len(rec)
    (200.0, 4)
    """

    t: np.ndarray
    v: np.ndarray
    x: np.ndarray
    source: str = "record"

    def __post_init__(self):
        arrays = {}
        for key in ("t", "v", "x"):
            try:
                arr = as_signal(getattr(self, key), key, min_samples=1)
            except InvalidSignalError as exc:
                raise InvalidSignalError(f"Record {key!r}: {exc}") from None
            arr = np.array(arr)  # an own, read-only copy
            arr.setflags(write=False)
            arrays[key] = arr
        if len({arr.size for arr in arrays.values()}) > 1:
            raise InvalidSignalError(
                "Record: 't', 'v' and 'x' must have one sample each per instant. Got "
                f"{', '.join(f'{k}: {a.size}' for k, a in arrays.items())} samples."
            )
        if not np.all(np.diff(arrays["t"]) > 0):
            raise InvalidSignalError("Record: the time 't' must be strictly increasing.")
        for key, arr in arrays.items():
            object.__setattr__(self, key, arr)

    @classmethod
    def _checked(cls, t, v, x, source: str) -> Record:
        """A record of arrays that :func:`read_table` checked (finite, equally long, ``t``
        increasing) and made read-only, taken as they are: a copy of a long record would
        double the memory its reading needs."""
        if t.size and max(-float(t[0]), float(t[-1])) > MAX_MAGNITUDE:  # (t increases)
            return cls(t, v, x, source)  # refused there, as a Record of such times is
        rec = object.__new__(cls)
        for key, arr in (("t", t), ("v", v), ("x", x)):
            if not arr.flags.c_contiguous:  # a column of a matrix file: an own copy
                arr = np.ascontiguousarray(arr)
            arr.setflags(write=False)
            object.__setattr__(rec, key, arr)
        object.__setattr__(rec, "source", source)
        return rec

    def __len__(self) -> int:
        return int(self.t.size)

    @property
    def sample_rate(self) -> float:
        """Samples per second (from the median time step), Hz."""
        return rate_of(self.t)

    def to_frame(self):
        """The record as a ``pandas.DataFrame`` with columns ``t`` (s), ``v`` (V), ``x`` (µm).

        The frame holds copies, and its columns go back into ``fit``, ``simulate`` or
        ``score`` as they are.

        Returns
        -------
        pandas.DataFrame
            Columns ``t`` (s), ``v`` (V) and ``x`` (µm), one row per sample.
        """
        import pandas as pd  # a dependency, loaded when used

        frame = pd.DataFrame({"t": self.t.copy(), "v": self.v.copy(), "x": self.x.copy()})
        frame.attrs["source"] = self.source
        return frame


def rate_of(t) -> float:
    """Sample rate in Hz of strictly increasing times ``t`` (s), from the median step.

    Parameters
    ----------
    t : array_like
        Strictly increasing times, s.

    Returns
    -------
    float
        The sample rate, Hz.
    """
    t = as_signal(t, "t", min_samples=2)
    with np.errstate(over="ignore", divide="ignore"):
        return float(1.0 / np.median(np.diff(t)))


def parse_columns(text: str | None) -> dict[str, int | str] | None:
    """Parse a column mapping such as ``"v=1,x=5"`` or ``"v=volts,x=disp"``.

    Numbers are 1-based column numbers; anything else is a column name.

    Parameters
    ----------
    text : str or None
        ``key=column`` pairs separated by commas (None for no mapping).

    Returns
    -------
    dict or None
        Each key with its 1-based column number or its column name; None if ``text`` is None.

    Examples
    --------
    >>> parse_columns("v=1, x=5")
    {'v': 1, 'x': 5}
    >>> parse_columns("t=time,v=volts")
    {'t': 'time', 'v': 'volts'}
    """
    if text is None:
        return None
    if not isinstance(text, str):
        raise InvalidParameterError(
            f"The 'columns' option must be text such as v=1,x=5. Got {type(text).__name__}."
        )
    mapping: dict[str, int | str] = {}
    for item in text.split(","):
        key, sep, value = (part.strip() for part in item.partition("="))
        if not sep or key not in ("t", "v", "x") or not value or key in mapping:
            raise InvalidParameterError(
                "The 'columns' option must look like v=1,x=5 (1-based column numbers) or "
                "v=volts,x=disp (header names), each of t, v, x at most once. "
                f"Got {text!r} instead."
            )
        if value.isascii() and value.isdigit():
            if int(value) < 1:
                raise InvalidParameterError(
                    f"Column numbers in 'columns' start at 1. Got {key}={value} in {text!r}."
                )
            mapping[key] = int(value)
        else:
            mapping[key] = value
    _distinct(mapping, f"The 'columns' option {text!r}")
    return mapping


def _distinct(mapping: dict, what: str) -> None:
    """Refuse one column named for two of t, v, x (``v=1,x=1``)."""
    seen: dict = {}
    for key, spec in mapping.items():
        ident = spec.casefold() if isinstance(spec, str) else spec
        if ident in seen:
            raise InvalidParameterError(
                f"{what} names column {spec!r} for both {seen[ident]!r} and {key!r}; each of "
                "t, v, x needs its own column."
            )
        seen[ident] = key


def _check_columns(columns, owner: str = "read_table") -> dict:
    """A column mapping {key: 1-based number or name}, keys among t, v, x; the command
    line's text (``"t=2,v=4,x=3"``, :func:`parse_columns`) is taken too."""
    if isinstance(columns, str):
        columns = parse_columns(columns)
    if columns is not None and not isinstance(columns, dict):
        raise InvalidParameterError(
            f"The 'columns' parameter of {owner} must be a dict such as {{'v': 1, 'x': 5}} or "
            f"text such as 'v=1,x=5'. Got {type(columns).__name__}."
        )
    columns = dict(columns or {})
    for key, spec in columns.items():
        number = isinstance(spec, int) and not isinstance(spec, bool) and spec >= 1
        if key not in MEANINGS or not (number or (isinstance(spec, str) and spec)):
            raise InvalidParameterError(
                f"The 'columns' parameter of {owner} must map 't', 'v' or 'x' to a "
                f"1-based column number or a column name. Got {key!r}: {spec!r}."
            )
    _distinct(columns, f"The 'columns' parameter of {owner}")
    return columns


def _find(path: Path, names, label: str) -> int | None:
    """The index of the column named ``label``: exactly, else in any case; None if absent."""
    exact = [i for i, name in enumerate(names) if name == label]
    if len(exact) == 1:
        return exact[0]
    folded = [i for i, name in enumerate(names) if str(name).casefold() == label.casefold()]
    if len(exact) > 1 or len(folded) > 1:
        found = ", ".join(repr(names[i]) for i in (exact if len(exact) > 1 else folded))
        raise _file_error(
            path,
            "Data file {path} has {count} columns named like {label} ({found}), so which "
            "one is meant is unclear. Rename them apart in the file, or name the right one "
            "by number, e.g. {columns_eg}.",
            count=len(exact) or len(folded),
            label=repr(label),
            found=found,
            eg="x=3",
        )
    return folded[0] if folded else None


def _file_error(path, template: str, **data) -> DataFileError:
    """A :class:`DataFileError` about the file at ``path``: ``template`` names it ``{path}``
    and its remedies by :class:`~hystcomp._notice.Notice` keys."""
    return DataFileError(Notice(template, path=repr(str(path)), **data))


def _pick(path: Path, raw: _Raw, key: str, spec, required: bool):
    """The column for ``key`` (``None`` if absent and not required) and its label."""
    where = f"Data file {str(path)!r}"
    names, arrays = raw.names, raw.arrays
    if isinstance(spec, int):
        if not raw.positional:
            raise DataFileError(
                f"{where} has named arrays ({', '.join(names or []) or 'none'}), not numbered "
                f"columns: name the array for {key!r} instead of {spec} (for example "
                f"{key}={names[0] if names else 'NAME'})."
            )
        if spec > len(arrays):
            raise DataFileError(
                f"{where} has {len(arrays)} columns; column {spec} for {key!r} does not exist."
            )
        return spec - 1, f"column {spec}"
    if names is None:
        if spec is None and not required:
            return None, ""
        raise DataFileError(
            Notice(
                "{where} {nameless}, so its columns have no names: say which column holds "
                "{key} ({meaning}), e.g. {columns_eg} (1-based).",
                where=where,
                nameless=raw.nameless,
                key=repr(key),
                meaning=MEANINGS[key],
                eg=raw.example,
            )
        )
    label = spec if spec is not None else key
    index = _find(path, names, label)
    if index is None:
        if not required and spec is None:
            return None, ""
        if not names:
            raise DataFileError(f"{where} holds no columns (no named arrays or variables).")
        raise DataFileError(
            Notice(
                "{where} has no column {label} for {key} ({meaning}); its columns are "
                "{names}. Name the right one, e.g. {columns_eg}.",
                where=where,
                label=repr(label),
                key=repr(key),
                meaning=MEANINGS[key],
                names=", ".join(map(str, names)),
                eg=f"{key}=NAME",
            )
        )
    return index, f"column {names[index]!r}"


@dataclass
class _Raw:
    """What a file holds: column names (None: numbered only), arrays, units (None: unknown)."""

    names: list | None
    arrays: list
    positional: bool
    units: list | None
    nameless: str = "has no header row"
    example: str = "v=1,x=2"


def _raw(path: Path, columns: dict, keys, progress) -> _Raw:
    """Read the file; a NPZ/MAT file of one matrix becomes numbered columns."""
    names, arrays, positional, units = read_raw(path, progress)
    raw = _Raw(names, arrays, positional, units)
    if positional and names is not None:
        folded = [str(name).casefold() for name in names]
        twice = sorted({name for name in names if folded.count(str(name).casefold()) > 1})
        if twice:
            raise DataFileError(
                f"Data file {str(path)!r} names more than one column {' and '.join(twice)} in "
                "its header row, so which one is meant is unclear. Give each column its own "
                "name."
            )
    matrices = [
        (name, arr)
        for name, arr in zip(names or (), arrays, strict=False)
        if arr.dtype.kind in "iuf" and arr.ndim == 2 and min(arr.shape) >= 2
    ]
    named = {str(name).casefold() for name in names or ()} & {"t", *keys}
    numbered = any(isinstance(spec, int) for spec in columns.values())
    if not positional and len(matrices) == 1 and (numbered or not named):
        name, matrix = matrices[0]
        if matrix.shape[0] < matrix.shape[1]:
            matrix = matrix.T  # samples along the longer side
        raw = _Raw(None, list(np.asarray(matrix).T), True, None)
        raw.nameless = f"holds one matrix {name!r} ({matrix.shape[0]} x {matrix.shape[1]})"
        raw.example = ",".join(f"{k}={i}" for i, k in enumerate(("t", *keys), 1))
    return raw


def _units(path: Path, raw: _Raw, key: str, index: int | None, x_unit) -> float:
    """The factor to s, V or µm of column ``index`` for ``key``, from its units row or
    ``x_unit``."""
    given = None if raw.units is None or index is None else raw.units[index]
    if key == "x" and x_unit is not None:
        if given and UNITS["x"].get(given.lower()) not in (None, UNITS["x"][x_unit]):
            raise _file_error(
                path,
                "The units row of {path} says the displacement is in {given}, but {x_unit} "
                "says {unit}. {drop_x_unit}, or correct the units row.",
                given=given,
                unit=x_unit,
            )
        return UNITS["x"][x_unit]
    if not given:
        return 1.0
    factor = UNITS[key].get(given.lower())
    if factor is None:
        raise _file_error(
            path,
            "The units row of {path} gives {given} for {key} ({meaning}); known units "
            "are {known}. Convert the column, or correct the unit in the file"
            + (", or give {x_unit}." if key == "x" else "."),
            given=repr(given),
            key=repr(key),
            meaning=MEANINGS[key],
            known=", ".join(UNITS[key]),
        )
    return factor


def _as_column(arr, path: Path, key: str, label: str) -> np.ndarray:
    what = f"The {label} of {str(path)!r} ({key!r}, {MEANINGS[key]})"
    arr = np.asarray(arr)
    if arr.dtype.kind == "c":
        raise DataFileError(f"{what} holds complex numbers; save the real part only.")
    if arr.dtype.kind not in "iuf":
        raise DataFileError(f"{what} does not hold numbers (it holds {arr.dtype} values).")
    out = np.asarray(arr, dtype=np.float64)
    if out.ndim > 1 and sorted(out.shape)[-2] == 1:
        out = out.reshape(-1)
    if out.ndim != 1:
        raise DataFileError(
            f"{what} has shape {out.shape}; expected one value per sample (a vector)."
        )
    if not out.size:
        return out
    lo, hi = float(out.min()), float(out.max())  # two passes, no copy (NaN propagates)
    if not (np.isfinite(lo) and np.isfinite(hi)):
        bad = np.flatnonzero(~np.isfinite(out))
        raise DataFileError(
            f"{what} has a non-finite value ({float(out[bad[0]])!r}) in data row "
            f"{bad[0] + 1}: remove or interpolate that row."
        )
    if key != "t" and (hi > MAX_MAGNITUDE or lo < -MAX_MAGNITUDE):
        big = np.flatnonzero(np.abs(out) > MAX_MAGNITUDE)
        raise DataFileError(
            f"{what} has the value {float(out[big[0]]):.6g} in data row {big[0] + 1}, "
            f"beyond {MAX_MAGNITUDE:g}: check the units and the column."
        )
    return out


def read_table(
    path,
    keys=("v", "x"),
    *,
    columns=None,
    sample_rate=None,
    min_samples=2,
    x_unit=None,
    progress=None,
    optional=(),
):
    """Read time and the columns ``keys`` from a data file, validated.

    Parameters
    ----------
    path : str or path-like
        The data file (``.csv``, ``.npz``, ``.mat`` or a text table; see the module's notes
        and :mod:`hystcomp.io._text` for the text layouts understood).
    keys : sequence of str
        The columns needed besides time, among ``"v"`` and ``"x"``.
    columns : dict or str, optional
        Which column holds which key: 1-based numbers (text files, or the columns of the one
        matrix of an NPZ/MAT file) or names, as a dict (``{"v": 1, "x": 5}``) or as text
        (``"v=1,x=5"``). By default each key is the
        column of the same name, in any case (``T``, ``V``, ``X`` do).
    sample_rate : float, optional
        Samples per second (Hz). Needed when the file has no time column ``t``; if both are
        given they must agree within 1 %.
    min_samples : int, default 2
        Fewest samples accepted.
    x_unit : {"m", "mm", "um", "nm"}, optional
        The unit of the displacement in the file; it is converted to µm. By default that of
        the file's units row, else µm.
    progress : callable, optional
        Called with the fraction read so far (0..1), for a progress line.
    optional : sequence of str
        Columns read too when the file has them (by name, or named in ``columns``), among
        ``"v"`` and ``"x"`` and not in ``keys``.

    Returns
    -------
    dict of str to ndarray
        ``"t"``, each of ``keys`` and each of ``optional`` that the file has: read-only,
        finite, equally long; ``t`` strictly increasing.

    Raises
    ------
    DataFileError
        Naming the file, the column, the problem and the fix.
    """
    return _read_table(
        path, keys, columns, sample_rate, min_samples, x_unit, progress, optional, "read_table"
    )


def _read_table(path, keys, columns, sample_rate, min_samples, x_unit, progress, optional, owner):
    """:func:`read_table`, its messages naming ``owner`` (the public function called)."""
    path = as_path(path, "path", owner)
    keys = tuple(keys) if not isinstance(keys, str) else (keys,)
    optional = tuple(optional) if not isinstance(optional, str) else (optional,)
    both = keys + optional
    if not keys or any(key not in ("v", "x") for key in both) or len(set(both)) < len(both):
        raise InvalidParameterError(
            f"The 'keys' and 'optional' parameters of read_table must name 'v' and/or 'x' "
            f"once each, 'keys' at least one. Got keys={keys!r}, optional={optional!r}."
        )
    min_samples = check_int(min_samples, "min_samples", owner, minimum=1)
    columns = _check_columns(columns, owner)
    if sample_rate is not None:
        sample_rate = check_real(sample_rate, "sample_rate", owner, positive=True)
    if x_unit is not None and x_unit not in X_UNITS:
        raise InvalidParameterError(
            f"The 'x_unit' parameter of {owner} must be one of {', '.join(X_UNITS)}. "
            f"Got {x_unit!r} instead."
        )
    try:
        raw = _raw(path, columns, both, progress)
    finally:
        if progress is not None:
            progress(1.0)  # done, or failed: either way the progress line goes
    out = {}
    taken: dict[int, str] = {}
    for key in ("t", *both):
        index, label = _pick(path, raw, key, columns.get(key), key in keys)
        if index is not None and index in taken:
            raise _file_error(
                path,
                "Data file {path}: {label} would be read both as {first} ({first_meaning}) "
                "and as {key} ({meaning}). Name another column for one of them "
                "({columns_eg}...).",
                label=label,
                first=repr(taken[index]),
                first_meaning=MEANINGS[taken[index]],
                key=repr(key),
                meaning=MEANINGS[key],
                eg=f"{key}=",
            )
        if index is not None:
            taken[index] = key
            arr = _as_column(raw.arrays[index], path, key, label)
            factor = _units(path, raw, key, index, x_unit)
            if factor != 1.0:
                arr = _as_column(arr * factor, path, key, f"{label} (in {MEANINGS[key]})")
            out[key] = arr
    if len(raw.arrays) > len(out):  # keep the columns read only, not the whole table
        out = {key: np.array(arr) for key, arr in out.items()}
    del raw  # the other columns are no longer needed
    lengths = {key: arr.size for key, arr in out.items()}
    if len(set(lengths.values())) > 1:
        raise DataFileError(
            f"Data file {str(path)!r} has columns of different lengths ({lengths}); "
            "every column must hold one value per sample."
        )
    n = next(iter(lengths.values()))
    if n < min_samples:
        raise DataFileError(
            f"Data file {str(path)!r} has {n} sample{'' if n == 1 else 's'}; at least "
            f"{min_samples} are needed."
        )
    out["t"] = _time(path, out.get("t"), n, sample_rate)
    for arr in out.values():
        arr.setflags(write=False)
    return {"t": out["t"], **{key: out[key] for key in both if key in out}}


def x_unit_warning(x, source: str, given: str | None = None) -> str | None:
    """A warning if the span of displacements ``x`` (µm) looks like metres or nanometres.

    A piezo actuator's stroke is between about 0.01 µm and a few mm: a span below
    :data:`SPAN_METRES` µm is likely metres, one above :data:`SPAN_NANOMETRES` µm likely
    nanometres (the message names the command line's ``--x-unit``). ``given``, the unit the user gave, if any:
    then the message asks to check it. Returns the message, or None if the span is plausible.

    Parameters
    ----------
    x : array_like
        The displacements as read, µm.
    source : str
        How the message names the file.
    given : str, optional
        The unit the user gave (the ``x_unit`` of :func:`read_record`).

    Returns
    -------
    str or None
        The warning's text, or None if the span is plausible in µm.

    Examples
    --------
    >>> x_unit_warning([0.0, 2e-5], "rec.csv")[:52]
    'the displacement in rec.csv spans 2e-05 µm, which lo'
    >>> x_unit_warning([0.0, 20.0], "rec.csv") is None
    True
    """
    span = float(np.ptp(np.asarray(x, dtype=np.float64)))
    for unit, looks in (("m", 0 < span < SPAN_METRES), ("nm", span > SPAN_NANOMETRES)):
        if looks and given not in (None, "um", "µm"):
            return (
                f"the displacement in {source}, read in {given} as --x-unit says, spans "
                f"{span:.4g} µm, which is no piezo stroke; check --x-unit (the unit the "
                "file's displacement is in)."
            )
        if looks:
            name = {"m": "metres", "nm": "nanometres"}[unit]
            return (
                f"the displacement in {source} spans {span:.4g} µm, which looks like {name} "
                f"read as µm; if it is, give --x-unit {unit}."
            )
    return None


def uneven_sampling(t, what: str) -> str | None:
    """Why ``t`` (s, increasing) is not evenly sampled, or None.

    A step more than half a median step away from it (a dropped sample, a restart of the
    acquisition, a merged file) breaks a discrete-time model of the dynamics, which takes
    every sample as one period after the last; rounding of a written time column stays
    well inside that.

    Parameters
    ----------
    t : array_like
        Increasing times, s.
    what : str
        How the message names the record.

    Returns
    -------
    str or None
        The reason (how many steps differ from the median, the first of them), or None if
        the sampling is even.
    """
    steps = np.diff(np.asarray(t, dtype=np.float64))
    if steps.size == 0:
        return None
    median = float(np.median(steps))
    bad = np.flatnonzero(np.abs(steps - median) > 0.5 * median)
    if not bad.size:
        return None
    k = int(bad[0])
    return (
        f"The time column of {what} is not evenly sampled: {bad.size} "
        f"{'steps differ' if bad.size > 1 else 'step differs'} from the median step "
        f"({median:.6g} s) by more than half of it, the first from t = {float(t[k])!r} to "
        f"{float(t[k + 1])!r} s (data row {k + 2}). The linear dynamics are discrete-time: "
        "resample the record onto an even grid, or record it again without gaps."
    )


def _time(path: Path, t, n: int, sample_rate):
    if t is None:
        if sample_rate is None:
            raise _file_error(
                path,
                "Data file {path} has no time column 't': give the sample rate, {fs_hz}.",
            )
        with np.errstate(over="ignore"):
            t = np.arange(n) / sample_rate
        if not t[-1] <= MAX_MAGNITUDE:  # inf, or times that no reader here takes back
            raise InvalidParameterError(
                Notice(
                    "The sample rate {rate:g} Hz ({rate_name}) makes the time of the last of "
                    "the {n} samples of {path} {last:g} s, beyond the {most:g} s a time column "
                    "may hold. Give the sample rate in Hz.",
                    rate=sample_rate,
                    n=n,
                    path=repr(str(path)),
                    last=float(t[-1]),
                    most=MAX_MAGNITUDE,
                )
            )
        return t
    with np.errstate(over="ignore", invalid="ignore"):
        span = t[-1] - t[0]
        rising = t[1:] > t[:-1]  # (one byte a sample, not a copy of the steps; NaN fails)
    if not rising.all():
        k = int(np.flatnonzero(~rising)[0]) + 1
        raise _file_error(
            path,
            "The time column 't' of {path} is not strictly increasing: data row {row} has "
            "t = {t!r} s after t = {before!r} s. Sort the rows and remove duplicates, or "
            "drop the time column and {give_fs}.",
            row=k + 1,
            t=float(t[k]),
            before=float(t[k - 1]),
        )
    # the rate for these checks: the median step, of at most 100 000 steps spread over the
    # record (the same to the checks' 1 % on a long record; Record.sample_rate is exact)
    stride = max(1, (t.size - 1) // 100_000)
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        sample = t[1::stride] - t[:-1:stride]
        rate = float(1.0 / np.median(sample)) if sample.size else np.inf
    if not (np.isfinite(span) and 0.0 < rate < np.inf):
        raise _file_error(
            path,
            "The time column 't' of {path} spans {first!r} to {last!r} s, which gives no "
            "usable sample rate. Check the units of the time column, or drop it and "
            "{give_fs}.",
            first=float(t[0]),
            last=float(t[-1]),
        )
    if sample_rate is not None and abs(rate - sample_rate) > RATE_TOLERANCE * sample_rate:
        raise DataFileError(
            f"The time column 't' of {str(path)!r} says {rate:.6g} Hz but the sample rate "
            f"given is {sample_rate:.6g} Hz. Give one of them, not both."
        )
    return t


def read_record(path, *, columns=None, sample_rate=None, x_unit=None, progress=None) -> Record:
    """Read an identification record ``(t, v, x)`` and check that its input varies.

    Parameters are those of :func:`read_table`; ``columns`` may be the command line's
    text (``"t=2,v=4,x=3"``).

    Parameters
    ----------
    path : str or os.PathLike
        The data file (``.csv``, ``.npz``, ``.mat`` or a text table).
    columns : dict or str, optional
        Which column holds ``t``, ``v`` and ``x`` (numbers from 1, or names), as a dict or as
        ``"t=2,v=4,x=3"``.
    sample_rate : float, optional
        Samples per second, Hz; needed when the file has no time column.
    x_unit : {"m", "mm", "um", "nm"}, optional
        The unit of the displacement in the file, converted to µm.
    progress : callable, optional
        Called with the fraction read so far (0..1).

    Returns
    -------
    Record
    """
    table = _read_table(
        path, ("v", "x"), columns, sample_rate, 2, x_unit, progress, (), "read_record"
    )
    v = table["v"]
    if v.max() <= v.min():
        raise _file_error(
            path,
            "The voltage column 'v' of {path} is constant ({v!r} V): an identification "
            "record needs an input that sweeps the actuator's range (see {excite_any}). "
            "Check that the right column is named.",
            v=float(v[0]),
        )
    return Record._checked(table["t"], v, table["x"], str(path))


def _columns(table, owner: str) -> dict[str, np.ndarray]:
    """Column name (an ASCII identifier) to a 1-D float64 array, validated."""
    if not isinstance(table, dict) or not table:
        raise InvalidParameterError(
            f"The 'table' parameter of {owner} must be a non-empty dict of column name to "
            f"values. Got {type(table).__name__}."
        )
    cols = {}
    for name, values in table.items():
        if not (isinstance(name, str) and name.isidentifier() and name.isascii()):
            raise InvalidParameterError(
                f"Column names of {owner} must be ASCII identifiers such as 'x_ref'. Got {name!r}."
            )
        try:
            cols[name] = np.asarray(values, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError, OverflowError):
            raise InvalidParameterError(
                f"Column {name!r} of {owner} does not hold numbers."
            ) from None
    return cols


def format_csv(table: dict) -> str:
    """A table of equally long columns as CSV text with a header row (shortest round-trip).

    Parameters
    ----------
    table : dict of str to array_like
        Column name -> values, all equally long, in the order of the header.

    Returns
    -------
    str
        The CSV text, a header row then one row per sample.
    """
    cols = _columns(table, "format_csv")
    if len({c.size for c in cols.values()}) != 1:
        raise InvalidParameterError("The columns given to format_csv have different lengths.")
    buffer = BytesIO()
    write_csv(buffer, cols)
    return buffer.getvalue().decode()


def check_writable(path) -> Path:
    """``path`` as a Path if :func:`write_table` can write its format, else raise.

    Parameters
    ----------
    path : str or os.PathLike
        The output file.

    Returns
    -------
    pathlib.Path
        ``path``, checked.

    Raises
    ------
    DataFileError
        If the suffix is not one of ``.csv``, ``.npz``, ``.mat``.
    """
    path = as_path(path, "path", "write_table")
    suffix = path.suffix.lower()
    if suffix not in WRITABLE:
        raise DataFileError(
            f"Cannot write {str(path)!r}: unknown format {suffix or '(no suffix)'!r}. "
            f"Use a name ending in {', '.join(WRITABLE)}."
        )
    return path


def write_table(path, table: dict, *, progress=None) -> None:
    """Write equally long columns to ``path`` as CSV, NPZ or MAT (by suffix), atomically.

    CSV is written in chunks of rows, each value as its shortest round-trip text
    (``repr``), so memory stays bounded whatever the length and the file reads back
    bit for bit.

    Parameters
    ----------
    path : str or path-like
        Output file ending in ``.csv``, ``.npz`` or ``.mat``.
    table : dict of str to array_like
        Column name to values, e.g. ``{"t": t, "v": v, "x": x}``.
    progress : callable, optional
        Called with the fraction written so far (0..1), for a progress line (CSV).
    """
    path = check_writable(path)
    suffix = path.suffix.lower()
    cols = _columns(table, "write_table")
    lengths = {k: v.size for k, v in cols.items()}
    if len(set(lengths.values())) != 1:
        raise DataFileError(
            f"Cannot write {str(path)!r}: the columns have different lengths ({lengths})."
        )
    with atomic_path(path) as tmp, tmp.open("wb") as file:
        if suffix == ".csv":
            try:
                write_csv(file, cols, progress)
            finally:
                if progress is not None:
                    progress(1.0)
        elif suffix == ".npz":
            arrays: dict[str, Any] = cols  # (savez types its **kwds as bool, for allow_pickle)
            np.savez(file, **arrays)
        else:
            import scipy.io  # only MAT output needs it

            scipy.io.savemat(file, {k: v.reshape(-1, 1) for k, v in cols.items()})


def check_data_output(path, *, inputs=(), what: str = "output") -> Path:
    """Refuse, before any work, a data output that :func:`write_table` cannot write or that
    would overwrite an input.

    Parameters
    ----------
    path : str or os.PathLike
        The output file.
    inputs : sequence of str or os.PathLike
        Files the same command reads (:func:`hystcomp.io.atomic.check_output_path`).
    what : str
        What the file is, for messages (e.g. ``"voltage file"``).

    Returns
    -------
    pathlib.Path
        ``path``, checked.
    """
    check_output_path(path, inputs=inputs, what=what)
    return check_writable(path)


def check_columns_read(columns, reads: tuple[str, ...] = ("v", "x")) -> None:
    """Refuse a column mapping that names a column of one not read (t and ``reads`` are).

    Such an entry would be ignored, and was most likely meant for a column that is read.

    Parameters
    ----------
    columns : dict or None
        The column mapping (:func:`hystcomp.io.multiaxis.parse_any_columns`), such as
        ``{'v': 2}``.
    reads : tuple of str, default ('v', 'x')
        The columns read besides t.

    Returns
    -------
    None

    Raises
    ------
    InvalidParameterError
        An entry for another column than t and ``reads``.

    Examples
    --------
    >>> check_columns_read({"x": 2}, ("x",))
    >>> check_columns_read({"v": 2}, ("x",))
    Traceback (most recent call last):
    ...
    hystcomp.errors.InvalidParameterError: The 'columns' argument of check_columns_read, v=2 \
names a column of voltage, which is not read (it reads t and x); name the column of \
displacement instead, e.g. columns='x=2'.
    """
    unused = [key for key in columns or {} if key not in ("t", *reads)]
    if unused:
        key, spec = unused[0], columns[unused[0]]
        meant = next((k for k in reads if k not in columns), reads[0])
        raise InvalidParameterError(
            Notice(
                "The 'columns' argument of check_columns_read, {key}={spec} names a column "
                f"of {MEANINGS[key].split(' in ')[0]}, {{not_read}} (it reads t and "
                f"{' and '.join(reads)}); name the column of "
                f"{MEANINGS[meant].split(' in ')[0]} instead, e.g. {{columns_eg}}.",
                key=key,
                spec=spec,
                eg=f"{meant}={spec}",
            )
        )


def print_table(table: dict, stream=None) -> None:
    """Print a table as CSV (:func:`format_csv`) on ``stream``, standard output by default.

    Parameters
    ----------
    table : dict of str to ndarray
        Equally long columns.
    stream : file-like, optional
        Where to write [``sys.stdout``, as it is when called].

    Returns
    -------
    None

    Raises
    ------
    OutputPathError
        The stream refuses the text (a full disk, a closed file); a reader that went away
        (``| head``) raises BrokenPipeError as it is.
    """
    out = sys.stdout if stream is None else stream
    try:
        out.write(format_csv(table))
        out.flush()
    except BrokenPipeError:
        raise  # the reader went away (| head): not an error
    except OSError as exc:
        raise OutputPathError(
            Notice(
                "Cannot write the signal to standard output: {why}. {to_file}, or check "
                "where standard output goes.",
                why=exc.strerror or exc,
            )
        ) from None
