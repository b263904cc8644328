"""Parsing data files into columns, treating every file as untrusted input.

Text tables (:mod:`hystcomp.io._text`: layout rules, pandas' C reader in chunks), NPZ
(``np.load`` without pickle) and MAT files. A MAT file is parsed by scipy in a child
process: scipy's MAT reader is not hardened against corrupt files (a wrong type code in a
numeric element crashes the interpreter), so a crash there becomes a
:class:`~hystcomp.errors.DataFileError` instead of the end of the caller's process.
:mod:`hystcomp.io.records` picks and checks the columns.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np

from hystcomp.errors import DataFileError
from hystcomp.io._text import read_rows, sniff

#: Longest time a MAT file may take to parse (s).
MAT_TIMEOUT = 120.0
#: The most samples (rows) a record may have, unless ``HYSTCOMP_MAX_SAMPLES`` says otherwise.
#: Arrays are checked against it before they are loaded: NPZ members by their .npy header,
#: MAT variables by :func:`scipy.io.whosmat`, text tables as they are read (the reading stops
#: at the limit; the array they are read into is sized from the file's size).
MAX_SAMPLES = 100_000_000
#: The most columns of a matrix in an NPZ or MAT file (its shorter side).
MAX_MATRIX_COLUMNS = 64


def utf16(path: Path) -> bool:
    """Whether ``path`` starts with a UTF-16 byte-order mark (Windows' "Unicode" text)."""
    try:
        with path.open("rb") as f:
            return f.read(2) in (b"\xff\xfe", b"\xfe\xff")
    except OSError:
        return False


def max_samples() -> int:
    """The most samples a record may have: ``HYSTCOMP_MAX_SAMPLES`` if set, else
    :data:`MAX_SAMPLES`."""
    text = os.environ.get("HYSTCOMP_MAX_SAMPLES", "").strip()
    if not text:
        return MAX_SAMPLES
    try:
        value = int(float(text))
    except (ValueError, OverflowError):
        value = 0
    if value < 1:
        raise DataFileError(
            f"HYSTCOMP_MAX_SAMPLES must be a whole number >= 1 (samples); got {text!r}. "
            "Unset it for the default limit."
        )
    return value


def _too_large(path: Path, name: str, shape: tuple, limit: int) -> DataFileError:
    rows = max((int(n) for n in shape if isinstance(n, int)), default=0)
    if 0 < rows <= limit:  # the samples fit: too many columns
        return DataFileError(
            f"Data file {str(path)!r} declares an array {name!r} of shape {shape}: "
            f"{int(np.prod(shape, dtype=object)) // rows} columns, more than the "
            f"{MAX_MATRIX_COLUMNS} a matrix of a record may have. Save only the signals' "
            "columns (t, v, x), or each as a variable of its own."
        )
    return DataFileError(
        f"Data file {str(path)!r} declares an array {name!r} of shape {shape}, more than "
        f"{limit} samples, the most a record may have (HYSTCOMP_MAX_SAMPLES raises the "
        "limit); it is corrupt or too large. Split the record or lower its sample rate."
    )


def check_shape(path: Path, name: str, shape: tuple, limit: int) -> None:
    """Refuse an array of more than ``limit`` samples: a vector's length or a matrix's
    longer side, with at most :data:`MAX_MATRIX_COLUMNS` on the other side."""
    shape = tuple(int(n) for n in shape)
    size = int(np.prod(shape, dtype=object))
    rows = max(shape, default=1)
    if rows > limit or size // max(rows, 1) > MAX_MATRIX_COLUMNS:
        raise _too_large(path, name, shape, limit)


def _check_npz_headers(path: Path, file, limit: int) -> None:
    """Read each member's .npy header (shape and dtype, not the data) and refuse one too large."""
    try:
        archive = zipfile.ZipFile(file)
    except (zipfile.BadZipFile, OSError, ValueError, EOFError):
        file.seek(0)  # the search for a zip directory moved it: np.load reads from the start
        return  # not a zip: np.load says what it is
    with archive:
        for info in archive.infolist():
            try:
                with archive.open(info) as member:
                    version = np.lib.format.read_magic(member)
                    read = (
                        np.lib.format.read_array_header_1_0
                        if version == (1, 0)
                        else np.lib.format.read_array_header_2_0
                    )
                    shape, _, _ = read(member, max_header_size=10_000)
            except Exception:  # noqa: BLE001, S112 - np.load reports a broken member
                continue
            check_shape(path, info.filename.removesuffix(".npy"), shape, limit)
    file.seek(0)


def _read_text(path: Path, progress=None):
    """Header names (or None), units (or None) and the columns of a text table."""
    layout = sniff(path)
    columns = read_rows(path, layout, max_samples(), progress)
    if not columns or columns[0].size == 0:
        raise DataFileError(f"Data file {str(path)!r} has a header but no data rows.")
    return layout.names, columns, layout.units


def _read_npz(path: Path):
    """Names and arrays of an NPZ file (never unpickling)."""
    try:
        with path.open("rb") as file:  # our handle: closed whatever numpy does
            if file.read(4) not in (b"PK\x03\x04", b"PK\x05\x06"):  # a zip, maybe empty
                file.seek(0)
                what = (
                    "holds a single .npy array, not named arrays"
                    if file.read(6) == b"\x93NUMPY"
                    else "is not a zip archive, which an .npz file is"
                )
                raise DataFileError(
                    f"Data file {str(path)!r} is not a NumPy .npz file: it {what}. Write it "
                    "with numpy.savez (named arrays t, v, x)."
                )
            file.seek(0)
            _check_npz_headers(path, file, max_samples())
            with np.load(file, allow_pickle=False) as npz:
                arrays = {name: npz[name] for name in npz.files}
    except (MemoryError, DataFileError):
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
    limit, columns = int(sys.argv[3]), int(sys.argv[4])
    for name, shape, _ in scipy.io.whosmat(sys.argv[1]):
        rows = max(shape, default=1)
        if rows > limit or int(np.prod(shape, dtype=object)) // max(rows, 1) > columns:
            sys.stdout.write(json.dumps([name, list(shape)]))
            sys.exit(5)
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
    limit = max_samples()
    with tempfile.TemporaryDirectory(prefix="hystcomp-mat-") as folder:
        out = Path(folder) / "variables.npz"
        try:
            child = subprocess.run(
                # -P: the working folder is not on the child's path (no module of it shadows
                # numpy or scipy), while PYTHONPATH still applies
                [
                    *(sys.executable, "-P", "-c", _MAT_CHILD, str(path.resolve()), str(out)),
                    *(str(limit), str(MAX_MATRIX_COLUMNS)),
                ],
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
        if child.returncode == 5:
            try:
                name, shape = json.loads(child.stdout)
            except (ValueError, TypeError):
                name, shape = "?", "?"
            raise _too_large(path, str(name), tuple(shape), limit)
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


def read_raw(path: Path, progress=None):
    """Names (or None), columns, whether columns are numbered, and units (or None).

    ``progress``, if given, is called with the fraction read so far (text tables).

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
            return (*_read_npz(path), False, None)
        if suffix == ".mat":
            return (*_read_mat(path), False, None)
        names, columns, units = _read_text(path, progress)
        return names, columns, True, units
    except UnicodeDecodeError:
        raise DataFileError(
            f"Data file {str(path)!r} is "
            + (
                "UTF-16 text; save it as UTF-8."
                if utf16(path)
                else "not text; use .csv, .npz, .mat or a text table."
            )
        ) from None
    except MemoryError:
        raise DataFileError(
            f"Data file {str(path)!r} is too large for this computer's memory (or corrupt)."
        ) from None
    except OSError as exc:
        raise DataFileError(
            f"Cannot read data file {str(path)!r}: {exc.strerror or exc}."
        ) from None
