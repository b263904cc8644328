"""Text tables as labs write them: how the layout is recognised, and chunked reading/writing.

The layout is decided from the first data row and the lines above it, by these rules (no
guessing from statistics, unlike :class:`csv.Sniffer`):

1. The text is UTF-8 (a byte-order mark is dropped), or else Windows-1252 (a header
   with ``µm`` written by Windows software). Blank lines are skipped everywhere.
2. The **first data row** is the first line, not starting with ``#``, whose fields are all
   numbers. Its **separator** is ``;`` if the line holds one, else a tab if it holds one,
   else ``,`` if it holds one, else runs of spaces.
3. With a separator other than ``,``, a ``,`` inside the data rows is a **decimal comma**
   (``0,5;1,25``): every ``,`` of the data is read as ``.``.
4. The **header** is the last line above the first data row that is not a comment; if that
   line is a **units row** (every field a unit such as ``s``, ``V``, ``um``, ``[µm]``,
   ``(mV)``, or empty), the header is the line above it. Without such a line, the last
   comment line (``# t,v,x``, as ``numpy.savetxt(..., header=...)`` writes it) directly
   above the data or the units row is the header. Lines above the header (other comments,
   a preamble) are ignored. Without any of these the table has no header.
5. Header names and units lose surrounding quotes (units also brackets); a name such as
   ``x [um]`` or ``t (s)`` gives the column's name and unit when there is no units row.
   The header and the units row must have as many fields as the data rows.
6. As spreadsheets and loggers write them: a number may be quoted (``"0.5"``), and a
   separator at the end of the first data row (``0,0.5,1,``) is a **trailing separator**,
   its empty last field ignored in every row (and in the header and units row).

The data rows are parsed in chunks of :data:`CHUNK_BYTES` into one preallocated array: by the
compiled parser of :mod:`hystcomp.io._floatparse` (plain decimal numbers, read exactly as
``float`` reads them) in a table of more than :data:`SMALL_READ` values, and by
:func:`numpy.loadtxt` (its C parser) in a smaller one and wherever the compiled parser gives
up (quotes, comments, ``nan``, a row of the wrong length: numpy words the error). A read
needs about the memory of the values (8 bytes each) and no more; rows are counted first and
a file with more than the limit of samples (:func:`hystcomp.io._formats.max_samples`) is
refused before any large allocation.
"""

from __future__ import annotations

import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hystcomp.errors import DataFileError

#: Bytes of data rows parsed at once (and written at once).
CHUNK_BYTES = 1 << 21
#: Values up to which CSV is formatted by ``repr`` in the interpreter, in one piece: loading
#: the compiled formatter costs about as much as formatting this many values so.
SMALL_TABLE = 200_000
#: Values up to which a text table is read by :func:`numpy.loadtxt` alone: the first compiled
#: kernel that a process loads costs about 0.25 s, what numpy takes for this many values
#: (the compiled parser then reads 6x faster).
SMALL_READ = 800_000
#: Bytes read to recognise the layout; the header and first data row must lie within them.
HEAD_BYTES = 1 << 16
#: Units understood in a units row or ``--x-unit``, per column, as factors to s, V, µm.
UNITS = {
    "t": {"s": 1.0, "sec": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "μs": 1e-6},
    "v": {"v": 1.0, "volt": 1.0, "volts": 1.0, "mv": 1e-3, "kv": 1e3},
    "x": {"m": 1e6, "mm": 1e3, "um": 1.0, "µm": 1.0, "μm": 1.0, "micron": 1.0, "nm": 1e-3},
}
_ALL_UNITS = {u for units in UNITS.values() for u in units} | {"a.u.", "%", "°c", "c", "k", "a"}
_STRIP = " \t\"'[]()"
_NAME_UNIT = re.compile(r"\s*(.*?)\s*[\[(]([^\])]*)[\])]\s*")


@dataclass(frozen=True)
class Layout:
    """How a text table is written: where its data starts and how to split it."""

    names: list[str] | None
    units: list[str] | None
    delimiter: str | None  # None: runs of white space
    decimal_comma: bool
    n_columns: int
    data_offset: int  # byte offset of the first data row
    trailing: bool = False  # a separator ends each row: an empty last field to ignore
    encoding: str = "utf-8"


def _split(line: str, delimiter: str | None) -> list[str]:
    return [tok.strip() for tok in (line.split(delimiter) if delimiter else line.split())]


def _numbers(tokens: list[str], decimal_comma: bool) -> bool:
    try:
        for tok in tokens:
            tok = tok[1:-1] if len(tok) > 1 and tok[0] == tok[-1] == '"' else tok
            float(tok.replace(",", ".") if decimal_comma else tok)
    except ValueError:
        return False
    return True


def _delimiter(line: str) -> str | None:
    for sep in (";", "\t", ","):
        if sep in line:
            return sep
    return None


def _unknown_units(rows: list[list[str]]) -> list[str]:
    """The tokens of ``rows[1]`` that are no unit, if it reads as a units row under the
    header ``rows[0]`` (the header names more of t, v, x than the row, and the row holds a
    known unit); else []."""
    header = [tok.strip(" \t\"'").lower() for tok in rows[0]]
    below = [tok.strip(_STRIP) for tok in rows[1]]
    named = sum(tok in ("t", "v", "x") for tok in header)
    if named <= sum(tok.lower() in ("t", "v", "x") for tok in below):  # ("V" is a unit too)
        return []
    if not any(tok.lower() in _ALL_UNITS for tok in below):
        return []
    return [tok for tok in below if tok and tok.lower() not in _ALL_UNITS]


def _is_units(tokens: list[str]) -> bool:
    return all(tok.strip(_STRIP).lower() in _ALL_UNITS or not tok.strip(_STRIP) for tok in tokens)


def sniff(path: Path) -> Layout:
    """The layout of the text table ``path`` by the module's rules.

    Raises
    ------
    DataFileError
        If the file has no data row, or its header or units row does not fit the data.
    """
    with path.open("rb") as f:
        head = f.read(HEAD_BYTES)
    whole = len(head) < HEAD_BYTES
    if not whole:  # cut at the last complete line (ended by "\r" alone on old Macs)
        head = head[: max(head.rfind(b"\n"), head.rfind(b"\r")) + 1]
    encoding = _encoding(head)
    text = head.decode(encoding)
    bom = 3 if head.startswith(b"\xef\xbb\xbf") else 0
    text = text[1:] if bom else text
    offset, chars = bom, 0
    above: list[tuple[bool, str]] = []  # (is a comment, text) of the lines above the data
    for line in text.splitlines(keepends=True):
        stripped = line.strip()
        start, offset = offset, offset + len(line.encode(encoding))
        first, chars = chars, chars + len(line)
        if not stripped:
            continue
        if stripped.startswith("#"):
            above.append((True, stripped.lstrip("#").strip()))
            continue
        delimiter = _delimiter(stripped)
        decimal_comma = delimiter != "," and "," in text[first:]
        tokens = _split(stripped, delimiter)
        # (a tab ending the line is gone from the stripped line: look at the line itself)
        trailing = delimiter is not None and line.rstrip("\r\n ").endswith(delimiter)
        if trailing and len(tokens) > 1 and tokens[-1] == "":
            tokens = tokens[:-1]
        if _numbers(tokens, decimal_comma):
            names, units = _header(path, above, delimiter, len(tokens))
            n = len(tokens)
            return Layout(names, units, delimiter, decimal_comma, n, start, trailing, encoding)
        above.append((False, stripped))
    if not above and not text.strip():
        raise DataFileError(f"Data file {str(path)!r} is empty: it has no data rows.")
    raise DataFileError(
        f"Data file {str(path)!r} has a header but no data rows"
        + ("" if whole else f" in its first {HEAD_BYTES} bytes")
        + ": a data row is a line of numbers only, separated by ',', ';', tabs or spaces."
    )


def _encoding(head: bytes) -> str:
    """UTF-8, or Windows-1252 for a text that is not UTF-8 (``µm`` and ``°C`` in the header
    of a table written by Windows software); raises UnicodeDecodeError for binary data (a
    control character other than tab and line ends, or a byte that no text has)."""
    try:
        head.decode("utf-8")
        return "utf-8"
    except UnicodeDecodeError:
        if re.search(rb"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f]", head):
            raise
        head.decode("cp1252")  # raises for the five bytes that cp1252 leaves undefined
        return "cp1252"


def _header(path: Path, above, delimiter, n: int):
    """Names and units from the lines above the first data row (rules 4 and 5)."""
    plain = [line for comment, line in above if not comment]
    comments: list[str] = []
    for comment, line in reversed(above):  # the comment lines directly above the data
        if not comment:
            break
        comments.insert(0, line)
    if not plain:  # a header in comment lines: those with a name per column ("# t,v,x")
        comments = [line for line in comments if len(_split(line, delimiter)) == n]
    candidates = plain[-2:] if plain else comments[-2:]
    if not candidates:
        return None, None
    rows = [_split(line, delimiter) for line in candidates]
    # a separator ending the header or units row, as it may end every row (rule 6)
    rows = [row[:-1] if len(row) == n + 1 and row[-1] == "" else row for row in rows]
    units = None
    if len(rows) == 2 and _is_units(rows[1]) and not _is_units(rows[0]):
        units = [tok.strip(_STRIP) for tok in rows[1]]
    elif len(rows) == 2 and len(rows[0]) == n and _unknown_units(rows):
        raise DataFileError(
            f"Data file {str(path)!r} has a row below its header that looks like a units row "
            f"({', '.join(rows[1])}), but {', '.join(map(repr, _unknown_units(rows)))} is not "
            "a unit hystcomp knows. Write the units as s, V and µm (um, m, mm, nm), or "
            "remove the row."
        )
    names = [tok.strip(" \t\"'") for tok in (rows[0] if units is not None else rows[-1])]
    split = [_NAME_UNIT.fullmatch(name) for name in names]
    if any(split):  # "t [s]", "x (um)": the name and its unit
        names = [m[1] if m else name for m, name in zip(split, names, strict=True)]
        if units is None:
            units = [m[2].strip() if m else "" for m in split]
    if not plain and (len(names) != n or _numbers(names, False)):
        return None, None  # a comment that is no header
    where = f"Data file {str(path)!r}"
    if len(names) != n:
        raise DataFileError(
            f"{where} is not a table of numbers as its header says: the header row has "
            f"{len(names)} names but the first data row {n} columns (separated by "
            f"{_describe(delimiter)}). Make them agree."
        )
    if units is not None and len(units) != n:
        raise DataFileError(
            f"{where} has {len(units)} units in its units row but {n} columns of data."
        )
    return names, units


def _describe(delimiter: str | None) -> str:
    return {None: "spaces", "\t": "tabs"}.get(delimiter, repr(delimiter))


def count_rows(path: Path, offset: int, limit: int) -> int:
    """Lines from ``offset`` on (an upper bound of the data rows); counting stops past
    ``limit``."""
    rows, last = 0, b"\n"
    with path.open("rb") as f:
        f.seek(offset)
        while block := f.read(CHUNK_BYTES):
            rows += block.count(b"\n")
            last = block[-1:]
            if rows > limit:
                break
    rows += last != b"\n"
    return rows


def read_rows(path: Path, layout: Layout, limit: int, progress=None) -> np.ndarray:
    """The data rows of ``path`` as an array of shape (columns, rows), parsed in chunks.

    Raises
    ------
    DataFileError
        If a row does not hold ``layout.n_columns`` numbers, or the file holds more than
        ``limit`` rows.
    """
    where = f"Data file {str(path)!r}"
    bound = count_rows(path, layout.data_offset, limit)
    out = np.empty((layout.n_columns, min(bound, limit + 1)))
    compiled = _compiled_reader(layout, out.size)
    n, done = 0, 0
    size = max(path.stat().st_size, 1)
    with path.open("rb") as f:
        f.seek(layout.data_offset)
        rest = b""
        while True:
            block = f.read(CHUNK_BYTES)
            chunk = rest + block
            cut = chunk.rfind(b"\n") + 1 if block else len(chunk)
            chunk, rest = chunk[:cut], chunk[cut:]
            if chunk and not chunk.isspace():  # (no copy, as strip makes)
                read = compiled(chunk, out, n) if compiled is not None else -1
                if read < 0:  # numpy reads what the compiled parser does not
                    rows = _parse(chunk.decode(layout.encoding), layout, where, n)
                    read = rows.shape[0]
                    if n + read <= limit:
                        if n + read > out.shape[1]:  # lines not ended by "\n" (old Macs)
                            out = np.concatenate([out[:, :n], rows.T], axis=1)
                        else:
                            out[:, n : n + read] = rows.T
                if n + read > limit:
                    raise DataFileError(
                        f"{where} has more than {limit} rows, the most a record may have "
                        "(HYSTCOMP_MAX_SAMPLES raises the limit). Split the record or lower "
                        "its sample rate."
                    )
                n += read
            done += len(block)
            if progress is not None:
                progress(min(1.0, (layout.data_offset + done) / size))
            if not block:
                break
    return out[:, :n]


def _compiled_reader(layout: Layout, values: int):
    """``read(chunk, out, n)``: the rows of ``chunk`` (bytes) into ``out[:, n:]`` by the
    compiled parser (:mod:`hystcomp.io._floatparse`), their number or -1 where
    :func:`numpy.loadtxt` must read the chunk; None for a table too small to be worth
    loading the parser (:data:`SMALL_READ` values)."""
    if values <= SMALL_READ:
        return None
    from hystcomp.io._floatparse import parse_rows  # compiled: loaded for large tables

    code = 0 if layout.delimiter is None else ord(layout.delimiter)
    comma, trailing = layout.decimal_comma, layout.trailing

    def read(chunk: bytes, out: np.ndarray, n: int) -> int:
        return int(parse_rows(np.frombuffer(chunk, np.uint8), code, comma, trailing, out, n))

    return read


def _parse(text: str, layout: Layout, where: str, before: int) -> np.ndarray:
    if layout.decimal_comma:
        text = text.replace(",", ".")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # "input contained no data"
            rows = np.loadtxt(
                [line for line in text.splitlines() if line.strip()],  # blank: skipped
                delimiter=layout.delimiter,
                comments="#",
                quotechar='"',
                usecols=range(layout.n_columns) if layout.trailing else None,
                ndmin=2,
            )
    except (ValueError, IndexError, OverflowError) as exc:
        raise DataFileError(
            f"{where} is not a table of numbers ({_reason(exc, before)}). Every row after "
            f"the header must hold the same number of numeric columns ({layout.n_columns}, "
            f"separated by {_describe(layout.delimiter)}"
            + (", with decimal commas" if layout.decimal_comma else "")
            + ")."
        ) from None
    if rows.size and rows.shape[1] != layout.n_columns:
        raise DataFileError(
            f"{where} is not a table of numbers: its first data row has {layout.n_columns} "
            f"columns, a row after data row {before} has {rows.shape[1]}. Every row after "
            "the header must hold the same number of numeric columns."
        )
    return rows


def _reason(exc: Exception, before: int) -> str:
    """numpy's reason, its rows as the file's data rows (1-based, as the other messages
    count them); ``before`` data rows came before this chunk."""
    text = str(exc).strip().splitlines()[0][:160] if str(exc).strip() else type(exc).__name__
    # numpy counts the chunk's data rows: from 0 in a conversion error, from 1 in a change
    # of the column count (whose advice on `usecols`, a numpy argument, is dropped)
    text = re.sub(
        r"at row (\d+), column (\d+)\.?",
        lambda m: f"in data row {before + int(m[1]) + 1}, column {m[2]}",
        text,
    )
    text = re.sub(
        r"the number of columns changed from (\d+) to (\d+) at row (\d+);.*",
        lambda m: f"data row {before + int(m[3])} has {m[2]} columns, not {m[1]}",
        text,
    )
    if before:  # any other row numbers: in the chunk after ``before`` data rows
        text = re.sub(
            r"(?<!data )\b(row|line) (\d+)",
            lambda m: f"{m[1]} {m[2]} after data row {before}",
            text,
        )
    return text


def write_csv(file, columns: dict[str, np.ndarray], progress=None) -> None:
    """Write ``columns`` to the binary ``file`` as CSV with a header row, in chunks.

    Every value is written as Python's ``repr`` writes it (the shortest text that reads
    back as the same float64), by the compiled formatter of :mod:`hystcomp.io._floattext`;
    chunks of rows keep the memory bounded whatever the length.
    """
    names = list(columns)
    file.write((",".join(names) + "\n").encode())
    arrays = [columns[k] for k in names]
    n = arrays[0].size if arrays else 0
    if n * len(arrays) <= SMALL_TABLE:  # not worth loading the compiled formatter
        rows = zip(*(map(repr, a.tolist()) for a in arrays), strict=True)
        file.write("".join(",".join(row) + "\n" for row in rows).encode())
        return
    from hystcomp.io._floattext import WIDTH, format_rows  # compiled: loaded when writing

    step = max(1, CHUNK_BYTES // (WIDTH * max(len(arrays), 1)))
    for start in range(0, n, step):
        file.write(format_rows(np.column_stack([a[start : start + step] for a in arrays])))
        if progress is not None:
            progress(min(1.0, (start + step) / n))
