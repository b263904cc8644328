"""Parsing data files into columns, treating every file as untrusted input.

Text tables (``np.loadtxt``), NPZ (``np.load`` without pickle) and MAT files. A MAT file is
parsed by scipy in a child process: scipy's MAT reader is not hardened against corrupt files
(a wrong type code in a numeric element crashes the interpreter), so a crash there becomes a
:class:`~hystcomp.errors.DataFileError` instead of the end of the caller's process.
:mod:`hystcomp.data` picks and checks the columns.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

from hystcomp.errors import DataFileError

#: Longest time a MAT file may take to parse (s).
MAT_TIMEOUT = 120.0


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
    except (ValueError, IndexError, OverflowError) as exc:
        raise DataFileError(
            f"Data file {str(path)!r} is not a table of numbers ({_reason(exc)}). Every row "
            "after the header must hold the same number of numeric columns."
        ) from None
    if table.shape[0] == 0:
        raise DataFileError(f"Data file {str(path)!r} has a header but no data rows.")
    if names is not None and len(names) != table.shape[1]:
        raise DataFileError(
            f"Data file {str(path)!r} has {len(names)} names in its header row but "
            f"{table.shape[1]} columns of data. Make them agree."
        )
    return names, list(table.T)


def _read_npz(path: Path):
    """Names and arrays of an NPZ file (never unpickling)."""
    try:
        with path.open("rb") as file:  # our handle: closed whatever numpy does
            loaded = np.load(file, allow_pickle=False)
            if not isinstance(loaded, np.lib.npyio.NpzFile):
                raise TypeError("it holds a single .npy array, not named arrays")
            with loaded as npz:
                arrays = {name: npz[name] for name in npz.files}
    except MemoryError:
        raise
    except Exception as exc:  # noqa: BLE001 - any failure to parse foreign bytes
        raise DataFileError(
            f"Data file {str(path)!r} is not a readable NumPy .npz file ({_reason(exc)}). "
            "Write it with numpy.savez (named arrays t, v, x)."
        ) from None
    return list(arrays), list(arrays.values())


_MAT_CHILD = """
import json, sys
import numpy as np
import scipy.io
try:
    variables = scipy.io.loadmat(sys.argv[1])
except NotImplementedError:
    sys.exit(4)
except Exception as exc:
    sys.stderr.write(f"{type(exc).__name__}: {exc}"[:300])
    sys.exit(3)
numeric, other = {}, []
for name, value in variables.items():
    if name.startswith("__"):
        continue
    if isinstance(value, np.ndarray) and value.dtype.kind in "iufc":
        numeric[name] = value
    else:
        other.append(name)
np.savez(sys.argv[2], **numeric)
sys.stdout.write(json.dumps(other))
"""


def _read_mat(path: Path):
    """Names and arrays of a MAT file, parsed by scipy in a child process.

    The child writes the numeric variables to an NPZ file, read here without pickle; the
    names of other variables (text, cells, structs) are kept, with a value that is refused
    as "does not hold numbers".
    """
    where = f"Data file {str(path)!r}"
    with tempfile.TemporaryDirectory(prefix="hystcomp-mat-") as folder:
        out = Path(folder) / "variables.npz"
        try:
            child = subprocess.run(
                # -P: the working folder is not on the child's path (no module of it shadows
                # numpy or scipy), while PYTHONPATH still applies
                [sys.executable, "-P", "-c", _MAT_CHILD, str(path.resolve()), str(out)],
                capture_output=True,
                text=True,
                timeout=MAT_TIMEOUT,
                check=False,
            )
        except OSError as exc:
            raise DataFileError(
                f"{where} is a MATLAB .mat file, which is read by a Python child process, and "
                f"{sys.executable!r} could not be started ({exc.strerror or exc}). Save the "
                "columns as .csv or .npz instead."
            ) from None
        except subprocess.TimeoutExpired:
            raise DataFileError(
                f"{where} took more than {MAT_TIMEOUT:g} s to read as a MATLAB .mat file; it "
                "is corrupt or too large. Save the columns as .csv or .npz instead."
            ) from None
        if child.returncode == 4:
            raise DataFileError(
                f"{where} is a MATLAB v7.3 (HDF5) file, which scipy cannot read. "
                "Save it from MATLAB with save(..., '-v7')."
            )
        if child.returncode != 0:
            reason = (
                child.stderr.strip().splitlines()[-1][:200]
                if child.returncode == 3 and child.stderr.strip()
                else f"the reader stopped with status {child.returncode}"
            )
            raise DataFileError(
                f"{where} is not a readable MATLAB .mat file ({reason}); the file is corrupt. "
                "Save it again from MATLAB (save(..., '-v7')) or as .csv."
            )
        names, arrays = _read_npz(out)
        try:
            other = [str(name) for name in json.loads(child.stdout)]
        except (ValueError, TypeError):
            other = []
    return [*names, *other], [*arrays, *([np.array(["(not numbers)"])] * len(other))]


def _reason(exc: Exception) -> str:
    text = str(exc).strip().splitlines()[0][:160] if str(exc).strip() else ""
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def read_raw(path: Path):
    """Names (or None) and columns of a data file, and whether columns are numbered.

    Raises
    ------
    DataFileError
        For any file that cannot be read as a table, naming the file and the fix.
    """
    if not path.exists():
        raise DataFileError(f"Data file {str(path)!r} does not exist; check the path.")
    if path.is_dir():
        raise DataFileError(f"{str(path)!r} is a folder, not a data file.")
    if not path.is_file():
        raise DataFileError(
            f"{str(path)!r} is not a regular file (a device or a pipe?); save the data to a "
            "file first."
        )
    suffix = path.suffix.lower()
    try:
        if suffix == ".npz":
            return (*_read_npz(path), False)
        if suffix == ".mat":
            return (*_read_mat(path), False)
        return (*_read_text(path, "," if suffix == ".csv" else None), True)
    except UnicodeDecodeError:
        raise DataFileError(
            f"Data file {str(path)!r} is not text; use .csv, .npz, .mat or a text table."
        ) from None
    except MemoryError:
        raise DataFileError(
            f"Data file {str(path)!r} is too large for this computer's memory (or corrupt)."
        ) from None
    except OSError as exc:
        raise DataFileError(
            f"Cannot read data file {str(path)!r}: {exc.strerror or exc}."
        ) from None
