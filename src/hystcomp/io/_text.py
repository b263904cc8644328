"""Text tables as labs write them: how the layout is recognised, and chunked reading/writing.

The layout is decided from the first data row and the lines above it, by these rules (no
guessing from statistics, unlike :class:`csv.Sniffer`):

1. The text is UTF-8 (a byte-order mark is dropped), or else Windows-1252 (a header
   with ``µm`` written by Windows software). Blank lines are skipped everywhere.
2. The **first data row** is the first line, not starting with ``#``, whose fields are all
   numbers. Its **separator** is ``;`` if the line holds one, else a tab if it holds one,
   else ``,`` if it holds one, else runs of spaces; but a line whose fields are split by
   spaces and hold decimal commas (``0,5 1,25``) is split by spaces.
3. With a separator other than ``,``, a ``,`` inside the data rows is a **decimal comma**
   (``0,5;1,25``): every ``,`` of the data is read as ``.``. A table without a header whose
   rows are two whole numbers split by a comma (``0,046``) is one column with decimal commas
   when a second field starts with ``0`` (``046``, which no integer column writes), or when
   the header names one column; two columns when the header names two; otherwise it is
   refused, as the two readings differ.
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
   its empty last field ignored in every row (and in the header and units row). A separator
   at the start of the first data row (``,0,-1.617,0``, as some acquisition scripts write)
   is a **leading separator**: the empty first column keeps its number (``columns="t=2"``
   is the first number) and is never read.

The data rows are parsed by pandas' C reader (:func:`pandas.read_csv`, the separator, the
decimal comma, quotes and comments given from the layout above, never guessed) in one pass,
its column arrays taken from the reader's engine as they are, without the DataFrame that
would copy them: a read needs about 1.4 times the memory of the values (8 bytes each),
against 4 times for ``pandas.read_csv``. A file that may hold more rows than the limit of
samples (:func:`hystcomp.io._formats.max_samples`) by its size has its lines counted first,
and is refused before it is read. Where pandas stops (text in a row, a row of more fields) or fills a gap with
NaN (a row of fewer fields), the data rows are parsed again by :func:`numpy.loadtxt`, which
words the error with the data row and the column.
"""

from __future__ import annotations

import functools
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from hystcomp.errors import DataFileError

#: Bytes of data rows worded at once when a row is wrong (and written at once).
CHUNK_BYTES = 1 << 21
#: Values up to which CSV is formatted by ``repr`` in the interpreter, in one piece: loading
#: the compiled formatter costs about as much as formatting this many values so.
SMALL_TABLE = 200_000
#: Bytes read to recognise the layout; the header and first data row must lie within them.
HEAD_BYTES = 1 << 16
#: The longest first line read to find it whole (a line of many columns).
MAX_LINE_BYTES = 1 << 20
#: Units understood in a units row or ``x_unit``, per column, as factors to s, V, µm.
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
    leading: bool = False  # a separator starts each row: an empty first column, never read
    data_line: int = 0  # lines (blank ones too) above the first data row
    line_above: bool = False  # the line right above the data has as many fields (a header)


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

    The layout is read from the first :data:`HEAD_BYTES` of the file; where they hold no
    complete data row (a header of many columns), from four times as many, up to
    :data:`MAX_LINE_BYTES` per line.

    Raises
    ------
    DataFileError
        If the file has no data row, or its header or units row does not fit the data.
    """
    size = HEAD_BYTES
    while True:
        with path.open("rb") as f:
            head = f.read(size)
        whole = len(head) < size
        if not whole and not (b"\n" in head or b"\r" in head) and size >= MAX_LINE_BYTES:
            raise DataFileError(
                f"Data file {str(path)!r} has a first line of more than {size} bytes: a table "
                "of that many columns, or samples written along a line. A record holds one "
                "sample per line (columns t, v, x): transpose the table."
            )
        layout = _layout(path, head, whole)
        if layout is not None:
            return layout
        size *= 4  # a partial head without a data row: read more of the file


def _layout(path: Path, head: bytes, whole: bool) -> Layout | None:
    """The layout from ``head``, the file's first bytes (all of it if ``whole``); None if a
    partial head holds no data row (and none of the errors of a header without data)."""
    if not whole:  # cut at the last complete line (ended by "\r" alone on old Macs)
        head = head[: max(head.rfind(b"\n"), head.rfind(b"\r")) + 1]
        if len(head) * 2 < HEAD_BYTES:  # a first line of many columns, cut: read more
            return None
    encoding = _encoding(head)
    text = head.decode(encoding)
    bom = 3 if head.startswith(b"\xef\xbb\xbf") else 0
    text = text[1:] if bom else text
    offset, chars = bom, 0
    above: list[tuple[bool, str]] = []  # (is a comment, text) of the lines above the data
    previous = ""  # the line above, blank or not
    for line in text.splitlines(keepends=True):
        stripped, before = line.strip(), previous
        previous = stripped
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
        if delimiter == "," and not _numbers(tokens, False) and _numbers(stripped.split(), True):
            # spaces between the fields, decimal commas in them: "0,5 1,25" (rule 2)
            delimiter, decimal_comma, tokens = None, True, stripped.split()
        # (a tab ending the line is gone from the stripped line: look at the line itself)
        trailing = delimiter is not None and line.rstrip("\r\n ").endswith(delimiter)
        if trailing and len(tokens) > 1 and tokens[-1] == "":
            tokens = tokens[:-1]
        leading = delimiter is not None and len(tokens) > 1 and tokens[0] == ""
        if _numbers(tokens[1:] if leading else tokens, decimal_comma):
            pairs = delimiter == "," and _comma_pairs(tokens, text[first:])
            if pairs and _one_column(path, above, text[first:]):  # "0,046": decimal commas
                delimiter, decimal_comma, tokens = None, True, [stripped]
            names, units = _header(path, above, delimiter, len(tokens))
            n = len(tokens)
            line_number = len(_LINE_END.findall(head[:start]))
            # a line of as many fields right above the data (the header, a units row), which
            # pandas' reader may take as its header: it reads faster so than skipping it
            fields = len(_split(before, delimiter)) - (1 if trailing else 0)
            named = bool(before) and not before.startswith("#") and fields == n
            return Layout(
                names,
                units,
                delimiter,
                decimal_comma,
                n,
                start,
                trailing,
                encoding,
                leading,
                line_number,
                named,
            )
        above.append((False, stripped))
    if not above and not text.strip():
        raise DataFileError(f"Data file {str(path)!r} is empty: it has no data rows.")
    if not whole and len(head) < MAX_LINE_BYTES:  # a long header: read more
        return None
    raise DataFileError(
        f"Data file {str(path)!r} has a header but no data rows"
        + ("" if whole else f" in its first {len(head)} bytes")
        + ": a data row is a line of numbers only, separated by ',', ';', tabs or spaces."
    )


_LINE_END = re.compile(rb"\r\n|\r|\n")
_PAIR = re.compile(r"[+-]?\d+,\d+")


def _comma_pairs(tokens: list[str], text: str) -> bool:
    """Whether the first data row and every data row in ``text`` are two whole numbers split
    by a comma (``0,046``), which reads as one column with decimal commas or as two columns
    of integers."""
    if len(tokens) != 2:
        return False
    rows = [line.strip() for line in text.splitlines()]
    return all(_PAIR.fullmatch(row) for row in rows if row and not row.startswith("#"))


def _one_column(path: Path, above, text: str) -> bool:
    """For a table of comma pairs (:func:`_comma_pairs`) in ``text``: True if it is one
    column with decimal commas, False if two columns; raises if the file does not say (rule
    3): by its header's count of names, else by a second field with a leading zero."""
    plain = [line for comment, line in above if not comment]
    header = [row for row in plain[-2:] if not _is_units(_split(row, ","))]
    if header:
        return len(_split(header[-1], ",")) == 1
    rows = [line.strip() for line in text.splitlines()]
    seconds = [row.split(",")[1] for row in rows if row and not row.startswith("#")]
    if any(len(field) > 1 and field.startswith("0") for field in seconds):
        return True
    raise DataFileError(
        f"Data file {str(path)!r} has no header, and its rows are two whole numbers split by "
        "a comma (such as 0,5): one column with decimal commas, or two columns of integers? "
        "The two readings differ, so it is not guessed. Give the file a header row (one "
        "name per column, e.g. x or t,x), or write the decimals with '.', or separate the "
        "columns with ';'."
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


def _marks(path: Path, offset: int, size: int = -1) -> tuple[bool, bool]:
    """Whether the bytes of ``path`` from ``offset`` on (``size`` of them; -1: all) hold a
    ``#`` (a comment) and a ``"`` (quotes)."""
    hash_mark = quote = False
    with path.open("rb") as f:
        f.seek(offset)
        left = size
        while left and (block := f.read(CHUNK_BYTES if left < 0 else min(left, CHUNK_BYTES))):
            hash_mark = hash_mark or b"#" in block
            quote = quote or b'"' in block
            left -= len(block) if left > 0 else 0
    return hash_mark, quote


def row_bound(path: Path, layout: Layout) -> int:
    """An upper bound of the data rows of ``path``: its data bytes over the shortest data
    line of the first :data:`HEAD_BYTES` (a line much shorter still, later, grows the
    array as it is read)."""
    with path.open("rb") as f:
        f.seek(layout.data_offset)
        head = f.read(HEAD_BYTES)
    lines = [line for line in head.splitlines()[:-1] if line.strip()] or [head]
    shortest = max(1, min(len(line) for line in lines))
    data = path.stat().st_size - layout.data_offset
    return int(data / (shortest + 1) * 1.25) + 8


def read_rows(path: Path, layout: Layout, limit: int, progress=None) -> list[np.ndarray]:
    """The data rows of ``path`` as columns (1-D float64 arrays), parsed by pandas.

    Raises
    ------
    DataFileError
        If a row does not hold ``layout.n_columns`` numbers, or the file holds more than
        ``limit`` rows.
    """
    where = f"Data file {str(path)!r}"
    marks = _marks(path, layout.data_offset, HEAD_BYTES)
    values, suspect, failure = _parse_rows(path, layout, limit, marks, progress)
    if suspect and marks != (True, True):  # a comment or a quote after the first lines?
        more = _marks(path, layout.data_offset)
        if more != marks:
            values, suspect, failure = _parse_rows(path, layout, limit, more, progress)
    if suspect:  # numpy reads the rows again and words what is wrong, with where
        _word(path, layout, where)
    if failure is not None:  # (numpy read them: say what pandas said)
        raise DataFileError(
            f"{where} is not a table of numbers ({failure.splitlines()[0][:160]})."
        ) from None
    return values


def _parse_rows(path: Path, layout: Layout, limit: int, marks: tuple[bool, bool], progress):
    """pandas' reading of the data rows: ``(columns, suspect, failure)``, the columns as 1-D
    float64 arrays, ``suspect`` where a row may be wrong (text, a row of fewer fields filled
    with NaN), ``failure`` the text of pandas' error, if any."""
    import pandas as pd  # loaded by a text table's reading only

    where = f"Data file {str(path)!r}"
    if row_bound(path, layout) > limit and count_rows(path, layout.data_offset, limit) > limit:
        raise DataFileError(
            f"{where} has more than {limit} rows, the most a record may have "
            "(HYSTCOMP_MAX_SAMPLES raises the limit). Split the record or lower its sample "
            "rate."
        )
    first = 1 if layout.leading else 0  # an empty first column: never read, NaN
    options = _read_options(layout, *marks)
    if progress is not None:
        progress(0.0)
    try:
        raw = _read_columns(pd, path, options)
    except (ValueError, pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        if isinstance(exc, pd.errors.EmptyDataError):  # no rows: said by the caller
            return [np.empty(0) for _ in range(layout.n_columns)], False, None
        return [], True, str(exc).strip() or type(exc).__name__
    suspect, numbers, columns = len(raw) != layout.n_columns, True, []
    for j, column in enumerate(raw):
        if column.dtype.kind not in "iuf":  # text among the numbers
            numbers = numbers and j < first
            suspect = True
            column = np.full(column.size, np.nan)
        column = np.asarray(column, dtype=np.float64)  # (integers converted; floats as they are)
        # a row of fewer fields is filled with NaN (min propagates it): worded later
        suspect = suspect or (j >= first and column.size > 0 and bool(np.isnan(column.min())))
        columns.append(column)
    if columns and columns[0].size > limit:
        raise DataFileError(
            f"{where} has more than {limit} rows, the most a record may have "
            "(HYSTCOMP_MAX_SAMPLES raises the limit). Split the record or lower its sample "
            "rate."
        )
    failure = "text among the numbers" if suspect and not numbers else None
    return columns, suspect, failure


def _read_columns(pd, path: Path, options: dict) -> list[np.ndarray]:
    """The columns of the data rows, read by pandas' C reader in one pass.

    Through the reader's engine where pandas has it (the arrays its parser makes, about the
    memory of the values); a DataFrame (four times the values, at the peak) only where not.
    """
    with pd.read_csv(path, iterator=True, **options) as reader:
        read = getattr(getattr(reader, "_engine", None), "read", None)
        result = read() if read is not None else None
        if isinstance(result, tuple) and len(result) == 3 and isinstance(result[2], dict):
            _, names, data = result
            return [np.asarray(data[name]) for name in names]
        frame = reader.read()
    return [frame.iloc[:, j].to_numpy() for j in range(frame.shape[1])]


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
    return rows + (last != b"\n")


@functools.cache
def _pandas_major() -> int:
    import pandas as pd

    return int(pd.__version__.split(".")[0])


def _read_options(layout: Layout, comments: bool, quotes: bool) -> dict:
    """The options of :func:`pandas.read_csv` for the data rows of ``layout``: nothing
    guessed (separator, decimal comma and columns from the layout), and its defaults where
    they do (comments and quotes are looked for only where the data hold ``#`` or ``"``:
    either makes pandas' reader two to three times slower). The file is given by its path,
    the lines above the data skipped: a file object would be decoded twice."""
    options: dict[str, object] = {
        "sep": r"\s+" if layout.delimiter is None else layout.delimiter,
        "decimal": "," if layout.decimal_comma else ".",
        # the line above as pandas' header (its names unused), else no header
        "header": 0 if layout.line_above else None,
        "skiprows": layout.data_line - 1 if layout.line_above else layout.data_line,
        "encoding": layout.encoding,
        "engine": "c",
    }
    if layout.trailing:  # the empty field after the last separator: not a column
        options["usecols"] = list(range(layout.n_columns))
    if _pandas_major() < 3:  # pandas 2 rounds a few values a unit off unless told to round-trip
        options["float_precision"] = "round_trip"
    if comments:
        options["comment"] = "#"
    if quotes:
        options["skipinitialspace"] = True  # a quoted number after a space: read as a number
    return options


def _word(path: Path, layout: Layout, where: str) -> None:
    """Parse the data rows again with :func:`numpy.loadtxt`, chunk by chunk, to word what is
    wrong (a row of other length, text) with its data row; returns if numpy reads them all
    (NaN or inf written as such: the caller's checks refuse them in the columns it reads)."""
    before = 0
    with path.open("rb") as f:
        f.seek(layout.data_offset)
        rest = b""
        while True:
            block = f.read(CHUNK_BYTES)
            chunk = rest + block
            cut = max(chunk.rfind(b"\n"), chunk.rfind(b"\r")) + 1 if block else len(chunk)
            chunk, rest = chunk[:cut], chunk[cut:]
            if chunk and not chunk.isspace():
                before += _parse(chunk.decode(layout.encoding), layout, where, before).shape[0]
            if not block:
                return


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
                converters=_empty if layout.leading else None,
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


def _empty(text: str) -> float:
    """A field of a table with a leading separator: NaN for the empty first column."""
    return float(text) if text.strip() else np.nan


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
