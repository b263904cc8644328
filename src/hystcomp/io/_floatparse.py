"""Text tables of numbers to float64 as Python's ``float`` reads them (numba kernels).

:func:`numpy.loadtxt` reads a table at about 300 ns a value; :func:`parse_rows` reads the
common case, plain decimal numbers between separators, in compiled loops, and says when it
cannot (then the caller reads that part with ``loadtxt``, which also words the errors):

1. Each number is read as ``(-1)**s * M * 10**e`` with the first 18 significant digits in the
   integer ``M`` (a digit beyond them that is not zero gives up).
2. ``M < 2**53`` and ``|e| <= 22``: ``M`` and ``10**|e|`` are floats, and one product or
   quotient rounds once, correctly (Clinger's fast path; most numbers that labs write).
3. Otherwise ``M * 10**e`` in double-double arithmetic (Dekker's exact product, with the
   106-bit powers of ten of :mod:`hystcomp.io._floattext`), accurate to about 2**-100 of the
   value: its leading double is the correctly rounded value unless the exact value could be
   within that error of a tie between two doubles, a power of two, or out of the normal
   range, where it gives up.
4. It gives up too on what it does not read: quotes, comments, ``nan`` and ``inf``, a lone
   carriage return, a non-ASCII byte, a row with another number of fields.
"""

from __future__ import annotations

import math

import numpy as np

from hystcomp.io._floattext import _KMAX, _KMIN, _P_HI, _P_LO, _kernel, _two_prod

#: Significant digits kept in the integer mantissa (10**18 < 2**63).
_DIGITS = 18
_EXACT = np.array([10.0**i for i in range(23)])  # exact floats
_TIE = 2.0**-40  # a remainder this close (in half-ulps) to a tie gives up


@_kernel
def _value(negative, mantissa, exp10):
    """The float nearest ``(-1)**negative * mantissa * 10**exp10``; NaN if step 3 cannot
    tell which it is."""
    if mantissa == 0:
        return -0.0 if negative else 0.0
    if mantissa < 9007199254740992 and -22 <= exp10 <= 22:  # 2**53
        x = float(mantissa)
        x = x * _EXACT[exp10] if exp10 >= 0 else x / _EXACT[-exp10]
        return -x if negative else x
    if exp10 < _KMIN or exp10 > _KMAX:
        return math.nan
    m_hi = float(mantissa)
    m_lo = float(mantissa - np.int64(m_hi))  # exact: below 2**10
    ph = _P_HI[exp10 - _KMIN]
    pl = _P_LO[exp10 - _KMIN]
    p, err = _two_prod(m_hi, ph)
    rest = err + m_hi * pl + m_lo * ph
    s = p + rest
    s_lo = rest - (s - p)  # exact: |p| >= |rest|
    if not 2.3e-308 < s < 1.7e308:
        return math.nan
    fraction, exponent = math.frexp(s)
    if fraction == 0.5:  # a power of two: the ulp below is half the ulp above
        return math.nan
    half_ulp = math.ldexp(1.0, exponent - 54)
    if abs(abs(s_lo) - half_ulp) <= _TIE * half_ulp:
        return math.nan
    return -s if negative else s


@_kernel
def _number(buf, i, comma):
    """The number starting at ``buf[i]``: (value, end); value NaN if it gives up."""
    n = buf.size
    negative = False
    if i < n and (buf[i] == 43 or buf[i] == 45):  # + -
        negative = buf[i] == 45
        i += 1
    mantissa = np.int64(0)
    digits = 0
    exp10 = 0
    seen = False
    while i < n and 48 <= buf[i] <= 57:
        d = buf[i] - 48
        seen = True
        if mantissa != 0 or d != 0:
            if digits < _DIGITS:
                mantissa = mantissa * 10 + d
                digits += 1
            else:
                exp10 += 1
                if d != 0:
                    return math.nan, i
        i += 1
    if i < n and (buf[i] == 46 or (comma and buf[i] == 44)):  # . or a decimal comma
        i += 1
        while i < n and 48 <= buf[i] <= 57:
            d = buf[i] - 48
            seen = True
            if mantissa == 0 and d == 0:
                exp10 -= 1
            elif digits < _DIGITS:
                mantissa = mantissa * 10 + d
                digits += 1
                exp10 -= 1
            elif d != 0:
                return math.nan, i
            i += 1
    if not seen:
        return math.nan, i
    if i < n and (buf[i] == 101 or buf[i] == 69):  # e E
        i += 1
        negative_exp = False
        if i < n and (buf[i] == 43 or buf[i] == 45):
            negative_exp = buf[i] == 45
            i += 1
        if not (i < n and 48 <= buf[i] <= 57):
            return math.nan, i
        e = 0
        while i < n and 48 <= buf[i] <= 57:
            if e < 100_000:
                e = e * 10 + (buf[i] - 48)
            i += 1
        exp10 += -e if negative_exp else e
    return _value(negative, mantissa, exp10), i


@_kernel
def _blank(buf, i, delimiter):
    """The first position from ``i`` that is not a space (nor a tab, unless tabs separate)."""
    while i < buf.size and (buf[i] == 32 or (buf[i] == 9 and delimiter != 9)):
        i += 1
    return i


@_kernel
def _line_end(buf, i):
    """The position after the line end at ``buf[i]`` (or the buffer's end); -1 if none is
    there."""
    if i >= buf.size:
        return i
    if buf[i] == 10:
        return i + 1
    if buf[i] == 13 and i + 1 < buf.size and buf[i + 1] == 10:
        return i + 2
    return -1


@_kernel
def parse_rows(buf, delimiter, comma, trailing, out, start):
    """Read the rows of the text ``buf`` (uint8) into ``out[:, start:]``, a row per column.

    ``delimiter`` is the separator's byte, or 0 for runs of spaces and tabs; ``comma``: a
    ``,`` inside a number is its decimal point; ``trailing``: a separator may end a row.
    Empty lines are skipped (as numpy does: with a separator, a line of spaces is a row).
    Returns the number of rows read, or -1 where the caller must read ``buf`` another way
    (``out[:, start:]`` may have been written then).
    """
    n_columns, room = out.shape
    row = start
    i = 0
    while i < buf.size:
        end = _line_end(buf, _blank(buf, i, delimiter) if delimiter == 0 else i)
        if end >= 0:  # an empty line (with spaces only, if spaces separate)
            i = end
            continue
        i = _blank(buf, i, delimiter)
        if row >= room:
            return -1
        column = 0
        while True:
            value, i = _number(buf, i, comma)
            if math.isnan(value) or column == n_columns:
                return -1
            out[column, row] = value
            column += 1
            after = i
            i = _blank(buf, i, delimiter)
            end = _line_end(buf, i)
            if end >= 0:
                i = end
                break
            if delimiter == 0:
                if i == after:  # no space after the number
                    return -1
                continue
            if buf[i] != delimiter:
                return -1
            i = _blank(buf, i + 1, delimiter)
            if trailing and column == n_columns:
                end = _line_end(buf, i)
                if end < 0:
                    return -1
                i = end
                break
        if column != n_columns:
            return -1
        row += 1
    return row - start


def parse_text(
    text: bytes, n_columns: int, delimiter: str | None = ",", *, comma=False, trailing=False
) -> np.ndarray | None:
    """The table in ``text`` as an array (columns, rows), or None where ``loadtxt`` must read it.

    Examples
    --------
    >>> parse_text(b"0.1,2\\n-3e-05,4\\n", 2).tolist()
    [[0.1, -3e-05], [2.0, 4.0]]
    >>> parse_text(b'"0.1",2\\n', 2) is None
    True
    """
    buf = np.frombuffer(text, dtype=np.uint8)
    out = np.empty((n_columns, text.count(b"\n") + 1))
    code = 0 if delimiter is None else ord(delimiter)
    rows = parse_rows(buf, code, comma, trailing, out, 0)
    return None if rows < 0 else out[:, :rows]
