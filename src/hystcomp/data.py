"""Data files: measured records ``(t, v, x)``, inputs ``(t, v)`` and references ``(t, x)``.

Formats, chosen by the file's suffix:

* ``.csv``: comma-separated, a header row naming the columns (``t`` in s, ``v`` in V,
  ``x`` in µm; extra columns are ignored);
* ``.npz`` (NumPy) and ``.mat`` (MATLAB, read with :func:`scipy.io.loadmat`): the same names
  as keys or variables;
* anything else (``.dat``, ``.txt``, ...): whitespace-separated numbers, with or without a
  header row, as many lab programs write them.

Columns can be named explicitly: ``{"v": 1, "x": 5}`` (1-based column numbers, for text
files) or ``{"v": "volts", "x": "disp"}`` (header names or keys); on the command line
``--columns v=1,x=5``. A file without a time column needs the sample rate. Writes go through
:func:`hystcomp.io.atomic_path`: a failing write never truncates an existing file.
"""

from __future__ import annotations

import io as _io
import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.io

from hystcomp._validation import check_real
from hystcomp.errors import DataFileError, InvalidParameterError
from hystcomp.io import atomic_path

#: What each column holds, for messages.
MEANINGS = {"t": "time in s", "v": "voltage in V", "x": "displacement in µm"}
WRITABLE = (".csv", ".npz", ".mat")
#: Largest relative disagreement between a time column and a given sample rate.
RATE_TOLERANCE = 0.01


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

    def __len__(self) -> int:
        return int(self.t.size)

    @property
    def sample_rate(self) -> float:
        """Samples per second (from the median time step), Hz."""
        return rate_of(self.t)


def rate_of(t) -> float:
    """Sample rate in Hz of strictly increasing times ``t`` (s), from the median step."""
    return float(1.0 / np.median(np.diff(t)))


def parse_columns(text: str | None) -> dict[str, int | str] | None:
    """Parse a column mapping such as ``"v=1,x=5"`` or ``"v=volts,x=disp"``.

    Numbers are 1-based column numbers; anything else is a column name.

    Examples
    --------
    >>> parse_columns("v=1, x=5")
    {'v': 1, 'x': 5}
    >>> parse_columns("t=time,v=volts")
    {'t': 'time', 'v': 'volts'}
    """
    if text is None:
        return None
    mapping: dict[str, int | str] = {}
    for item in text.split(","):
        key, sep, value = (part.strip() for part in item.partition("="))
        if not sep or key not in ("t", "v", "x") or not value or key in mapping:
            raise InvalidParameterError(
                "The 'columns' option must look like v=1,x=5 (1-based column numbers) or "
                "v=volts,x=disp (header names), each of t, v, x at most once. "
                f"Got {text!r} instead."
            )
        if value.isdigit():
            if int(value) < 1:
                raise InvalidParameterError(
                    f"Column numbers in 'columns' start at 1. Got {key}={value} in {text!r}."
                )
            mapping[key] = int(value)
        else:
            mapping[key] = value
    return mapping


def _check_columns(columns) -> dict:
    """A column mapping {key: 1-based number or name}, keys among t, v, x."""
    columns = dict(columns or {})
    for key, spec in columns.items():
        number = isinstance(spec, int) and not isinstance(spec, bool) and spec >= 1
        if key not in MEANINGS or not (number or (isinstance(spec, str) and spec)):
            raise InvalidParameterError(
                "The 'columns' parameter of read_table must map 't', 'v' or 'x' to a "
                f"1-based column number or a column name. Got {key!r}: {spec!r}."
            )
    return columns


def _is_header(tokens: list[str]) -> bool:
    try:
        [float(tok) for tok in tokens]
    except ValueError:
        return True
    return False


def _first_line(path: Path) -> str:
    with path.open(encoding="utf-8-sig") as f:
        for line in f:
            if line.strip() and not line.lstrip().startswith("#"):
                return line
    raise DataFileError(f"Data file {str(path)!r} is empty: it has no data rows.")


def _read_text(path: Path, delimiter: str | None):
    """Header names (or None) and the columns of a text table (``None``: by whitespace)."""
    first = _first_line(path)
    if delimiter is None and "," in first:
        delimiter = ","
    tokens = [tok.strip() for tok in (first.split(delimiter) if delimiter else first.split())]
    names = tokens if _is_header(tokens) else None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # "input contained no data"
            table = np.loadtxt(
                path,
                delimiter=delimiter,
                skiprows=1 if names else 0,
                comments="#",
                ndmin=2,
                encoding="utf-8-sig",
            )
    except ValueError as exc:
        raise DataFileError(
            f"Data file {str(path)!r} is not a table of numbers ({exc}). Every row after the "
            "header must hold the same number of numeric columns."
        ) from None
    if table.shape[0] == 0:
        raise DataFileError(f"Data file {str(path)!r} has a header but no data rows.")
    if names is not None and len(names) != table.shape[1]:
        raise DataFileError(
            f"Data file {str(path)!r} has {len(names)} names in its header row but "
            f"{table.shape[1]} columns of data. Make them agree."
        )
    return names, list(table.T)


def _read_arrays(path: Path, suffix: str):
    """Names and arrays of an NPZ or MAT file."""
    try:
        if suffix == ".npz":
            with np.load(path, allow_pickle=False) as npz:
                arrays = {name: npz[name] for name in npz.files}
        else:
            arrays = {k: v for k, v in scipy.io.loadmat(path).items() if not k.startswith("__")}
    except NotImplementedError:
        raise DataFileError(
            f"Data file {str(path)!r} is a MATLAB v7.3 (HDF5) file, which scipy cannot read. "
            "Save it from MATLAB with save(..., '-v7')."
        ) from None
    except (ValueError, OSError, TypeError) as exc:
        kind = "NumPy .npz" if suffix == ".npz" else "MATLAB .mat"
        raise DataFileError(
            f"Data file {str(path)!r} is not a readable {kind} file ({exc})."
        ) from None
    return list(arrays), list(arrays.values())


def _read_raw(path: Path):
    if not path.exists():
        raise DataFileError(f"Data file {str(path)!r} does not exist; check the path.")
    if path.is_dir():
        raise DataFileError(f"{str(path)!r} is a folder, not a data file.")
    suffix = path.suffix.lower()
    try:
        if suffix in (".npz", ".mat"):
            return (*_read_arrays(path, suffix), False)
        return (*_read_text(path, "," if suffix == ".csv" else None), True)
    except UnicodeDecodeError:
        raise DataFileError(
            f"Data file {str(path)!r} is not text; use .csv, .npz, .mat or a text table."
        ) from None


def _pick(path: Path, names, arrays, positional, key: str, spec, required: bool):
    """The column for ``key`` (``None`` if absent and not required)."""
    where = f"Data file {str(path)!r}"
    if isinstance(spec, int):
        if not positional:
            raise DataFileError(
                f"{where} has named arrays ({', '.join(names)}), not numbered columns: "
                f"name the array for {key!r} instead of {spec} (for example {key}={names[0]})."
            )
        if spec > len(arrays):
            raise DataFileError(
                f"{where} has {len(arrays)} columns; column {spec} for {key!r} does not exist."
            )
        return arrays[spec - 1], f"column {spec}"
    if names is None:
        if spec is None and not required:
            return None, ""
        raise DataFileError(
            f"{where} has no header row, so its columns have no names: say which column "
            f"holds {key!r} ({MEANINGS[key]}), e.g. --columns v=1,x=2 on the command line "
            "(columns={'v': 1, 'x': 2} in Python; 1-based)."
        )
    label = spec if spec is not None else key
    if label not in names:
        if not required and spec is None:
            return None, ""
        raise DataFileError(
            f"{where} has no column {label!r} for {key!r} ({MEANINGS[key]}); its columns "
            f"are {', '.join(map(str, names))}. Name the right one, e.g. --columns {key}=NAME."
        )
    return arrays[names.index(label)], f"column {label!r}"


def _as_column(arr, path: Path, key: str, label: str) -> np.ndarray:
    what = f"The {label} of {str(path)!r} ({key!r}, {MEANINGS[key]})"
    try:
        out = np.asarray(arr, dtype=np.float64)
    except (TypeError, ValueError):
        raise DataFileError(f"{what} does not hold numbers.") from None
    if out.ndim > 1 and sorted(out.shape)[-2] == 1:
        out = out.reshape(-1)
    if out.ndim != 1:
        raise DataFileError(
            f"{what} has shape {out.shape}; expected one value per sample (a vector)."
        )
    bad = np.flatnonzero(~np.isfinite(out))
    if bad.size:
        raise DataFileError(
            f"{what} has a non-finite value ({float(out[bad[0]])!r}) in data row "
            f"{bad[0] + 1}: remove or interpolate that row."
        )
    return out


def read_table(path, keys=("v", "x"), *, columns=None, sample_rate=None, min_samples=2):
    """Read time and the columns ``keys`` from a data file, validated.

    Parameters
    ----------
    path : str or path-like
        The data file (``.csv``, ``.npz``, ``.mat`` or a whitespace-separated text table).
    keys : sequence of str
        The columns needed besides time, among ``"v"`` and ``"x"``.
    columns : dict, optional
        Which column holds which key: 1-based numbers (text files) or names. By default each
        key is the column of the same name.
    sample_rate : float, optional
        Samples per second (Hz). Needed when the file has no time column ``t``; if both are
        given they must agree within 1 %.
    min_samples : int, default 2
        Fewest samples accepted.

    Returns
    -------
    dict of str to ndarray
        ``"t"`` and each of ``keys``: read-only, finite, equally long; ``t`` strictly
        increasing.

    Raises
    ------
    DataFileError
        Naming the file, the column, the problem and the fix.
    """
    path = Path(os.fspath(path))
    columns = _check_columns(columns)
    names, arrays, positional = _read_raw(path)
    out = {}
    for key in ("t", *keys):
        arr, label = _pick(path, names, arrays, positional, key, columns.get(key), key != "t")
        if arr is not None:
            out[key] = _as_column(arr, path, key, label)
    lengths = {key: arr.size for key, arr in out.items()}
    if len(set(lengths.values())) > 1:
        raise DataFileError(
            f"Data file {str(path)!r} has columns of different lengths ({lengths}); "
            "every column must hold one value per sample."
        )
    n = next(iter(lengths.values()))
    if n < min_samples:
        raise DataFileError(
            f"Data file {str(path)!r} has {n} samples; at least {min_samples} are needed."
        )
    if sample_rate is not None:
        sample_rate = check_real(sample_rate, "sample_rate", "read_table", positive=True)
    out["t"] = _time(path, out.get("t"), n, sample_rate)
    for arr in out.values():
        arr.setflags(write=False)
    return {"t": out["t"], **{key: out[key] for key in keys}}


def _time(path: Path, t, n: int, sample_rate):
    if t is None:
        if sample_rate is None:
            raise DataFileError(
                f"Data file {str(path)!r} has no time column 't': give the sample rate, "
                "--fs HZ on the command line (sample_rate=HZ in Python)."
            )
        return np.arange(n) / sample_rate
    steps = np.diff(t)
    bad = np.flatnonzero(~(steps > 0))
    if bad.size:
        k = int(bad[0]) + 1
        raise DataFileError(
            f"The time column 't' of {str(path)!r} is not strictly increasing: data row "
            f"{k + 1} has t = {float(t[k])!r} s after t = {float(t[k - 1])!r} s. Sort the "
            "rows and remove duplicates, or drop the time column and give the sample rate "
            "(--fs)."
        )
    if sample_rate is not None:
        rate = rate_of(t)
        if abs(rate - sample_rate) > RATE_TOLERANCE * sample_rate:
            raise DataFileError(
                f"The time column 't' of {str(path)!r} says {rate:.6g} Hz but the sample rate "
                f"given is {sample_rate:.6g} Hz. Give one of them, not both."
            )
    return t


def read_record(path, *, columns=None, sample_rate=None) -> Record:
    """Read an identification record ``(t, v, x)`` and check that its input varies.

    Parameters are those of :func:`read_table`.

    Returns
    -------
    Record
    """
    table = read_table(path, ("v", "x"), columns=columns, sample_rate=sample_rate)
    v = table["v"]
    if np.ptp(v) <= 0:
        raise DataFileError(
            f"The voltage column 'v' of {str(path)!r} is constant ({float(v[0])!r} V): an "
            "identification record needs an input that sweeps the actuator's range "
            "(see 'hystcomp excite'). Check that the right column is named."
        )
    return Record(table["t"], v, table["x"], source=str(path))


def format_csv(table: dict) -> str:
    """A table of equally long columns as CSV text with a header row (shortest round-trip)."""
    keys = list(table)
    rows = np.column_stack([np.asarray(table[k], dtype=np.float64) for k in keys]).tolist()
    lines = [",".join(keys), *(",".join(map(repr, row)) for row in rows)]
    return "\n".join(lines) + "\n"


def write_table(path, table: dict) -> None:
    """Write equally long columns to ``path`` as CSV, NPZ or MAT (by suffix), atomically.

    Parameters
    ----------
    path : str or path-like
        Output file ending in ``.csv``, ``.npz`` or ``.mat``.
    table : dict of str to array_like
        Column name to values, e.g. ``{"t": t, "v": v, "x": x}``.
    """
    path = Path(os.fspath(path))
    suffix = path.suffix.lower()
    if suffix not in WRITABLE:
        raise DataFileError(
            f"Cannot write {str(path)!r}: unknown format {suffix or '(no suffix)'!r}. "
            f"Use a name ending in {', '.join(WRITABLE)}."
        )
    cols = {k: np.asarray(v, dtype=np.float64).reshape(-1) for k, v in table.items()}
    lengths = {k: v.size for k, v in cols.items()}
    if len(set(lengths.values())) != 1:
        raise DataFileError(
            f"Cannot write {str(path)!r}: the columns have different lengths ({lengths})."
        )
    with atomic_path(path) as tmp:
        if suffix == ".csv":
            tmp.write_text(format_csv(cols), encoding="utf-8")
            return
        buffer = _io.BytesIO()
        if suffix == ".npz":
            np.savez(buffer, **cols)
        else:
            scipy.io.savemat(buffer, {k: v.reshape(-1, 1) for k, v in cols.items()})
        tmp.write_bytes(buffer.getvalue())
