"""Float64 to text as Python's ``repr`` writes it, for whole arrays (numba kernels).

``repr`` gives the shortest decimal that reads back as the same float64; it is exact but
costs about a microsecond a value in the interpreter. :func:`format_rows` does the same
work in compiled loops, by the classic method (Steele & White; Grisu and Ryu refine it):

1. The float ``a = M * 2**E`` rounds back from every decimal strictly inside its rounding
   interval ``(a - lo, a + hi)`` (half the gap to each neighbouring float).
2. The interval's ends and ``a`` are scaled by ``10**k`` so that they are about ``1e17``;
   the products are computed in double-double arithmetic (an exact product by Dekker's
   split plus a 106-bit power of ten), which is exact whenever ``10**k`` is a float
   (``0 <= k <= 22``, all values between 1e-5 and 1e17) and otherwise accurate to about
   1e-13 of a unit.
3. Trailing digits are removed while the interval still holds a shorter number, and of the
   shortest numbers the one closest to ``a`` is kept (ties: the even one).
4. The digits are laid out as ``repr`` does (scientific below 1e-4 and from 1e16 on).

Any value where step 2's error could change a decision (an end or a tie within 1e-9 of a
unit, which the exact cases never need), and non-finite, zero-sign, subnormal or extreme
values, are marked and formatted by ``repr`` itself. The ends of the interval belong to it when
the mantissa is even (they read back as ``a`` by round-half-even), as in ``repr``.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numba
import numpy as np

from hystcomp._kernels._jit import caching

#: Bytes kept per formatted value (the longest repr of a float64 has 24 characters).
WIDTH = 32
_KMIN, _KMAX = -280, 280


def _powers() -> tuple[np.ndarray, np.ndarray]:
    """10**k for k in [_KMIN, _KMAX] as double-double pairs (hi, lo), from exact fractions."""
    hi = np.empty(_KMAX - _KMIN + 1)
    lo = np.empty_like(hi)
    for i, k in enumerate(range(_KMIN, _KMAX + 1)):
        exact = Fraction(10) ** k
        hi[i] = float(exact)
        lo[i] = float(exact - Fraction(hi[i]))
    return hi, lo


_P_HI, _P_LO = _powers()
_POW10 = np.array([10**i for i in range(19)], dtype=np.int64)
_SPLIT = 134217729.0  # 2**27 + 1, Dekker's splitter
_EPS = 1e-9


def _kernel(func):
    # No fastmath: the error-free transformations need IEEE arithmetic as written.
    return numba.njit(cache=caching(), nogil=True)(func)  # off where nowhere is writable


@_kernel
def _two_prod(a, b):
    p = a * b
    t = _SPLIT * a
    ah = t - (t - a)
    al = a - ah
    t = _SPLIT * b
    bh = t - (t - b)
    bl = b - bh
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


@_kernel
def _scaled(p, e, a, d, ph, pl):
    """(a + d) * (ph + pl) as an int64 and a fraction in [0, 1), given ``p + e = a * ph``
    exactly; ``d`` is a power of two (or 0), so ``d * ph`` is exact."""
    t = e + d * ph
    t += a * pl + d * pl
    whole = math.floor(t)
    return np.int64(p) + np.int64(whole), t - whole


@_kernel
def _digits(a, dst):
    """Write the repr of ``a`` (finite, > 0) into ``dst``; its length, or -1 to fall back."""
    m, ex = math.frexp(a)
    if ex < -870 or ex > 900:  # keep the power of ten and Dekker's split in range
        return -1
    mant = np.int64(m * 9007199254740992.0)  # 2**53
    e2 = ex - 53
    half = math.ldexp(1.0, e2 - 1)
    lower = math.ldexp(1.0, e2 - 2) if mant == 4503599627370496 else half
    # 10**k brings a into [1e17, 1e18): floor(log10(a)) is one of two values given ex
    k = 16 - math.floor((ex - 1) * 0.30102999566398120)
    if k < _KMIN or k + 1 > _KMAX:
        return -1
    if a * _P_HI[k - _KMIN] < 1e17:
        k += 1
    ph = _P_HI[k - _KMIN]
    pl = _P_LO[k - _KMIN]
    exact = pl == 0.0
    p, e = _two_prod(a, ph)
    c_int, c_fr = _scaled(p, e, a, 0.0, ph, pl)
    u_int, u_fr = _scaled(p, e, a, half, ph, pl)
    l_int, l_fr = _scaled(p, e, a, -lower, ph, pl)
    if not exact and (
        min(u_fr, 1.0 - u_fr) < _EPS or min(l_fr, 1.0 - l_fr) < _EPS or c_fr > 1.0 - _EPS
    ):
        return -1
    # the integers inside the interval; its ends belong to it if the mantissa is even (ties
    # to even read back as a), which only an exact computation can tell
    closed = exact and mant % 2 == 0
    lo = l_int if closed and l_fr == 0.0 else l_int + 1
    hi = u_int if u_fr > 0.0 or closed else u_int - 1
    if lo > hi:
        return -1
    # remove digits while the interval still holds a multiple of ten; every integer here is
    # positive, and unsigned division by a constant compiles to a multiply and a shift
    j = 0
    q_lo, q_hi = np.uint64(lo), np.uint64(hi)
    ten = np.uint64(10)
    while True:
        up, down = (q_lo + np.uint64(9)) // ten, q_hi // ten
        if up > down:
            break
        q_lo, q_hi = up, down
        j += 1
    div = _POW10[j]
    q = np.int64(np.uint64(c_int) // np.uint64(div))
    rem = float(c_int - q * div) + c_fr
    half_div = 0.5 * float(div)
    if rem > half_div or (rem == half_div and q % 2 == 1):
        q += 1
    if not exact and abs(rem - half_div) < _EPS * float(div):
        return -1
    q = min(max(q, np.int64(q_lo)), np.int64(q_hi))
    n = 1
    while n < 19 and q >= _POW10[n]:
        n += 1
    point = n + j - k  # a = 0.d1 d2 ... * 10**point
    if -4 < point <= 16:
        if point <= 0:  # 0.000ddd
            dst[0] = 48
            dst[1] = 46
            for i in range(-point):
                dst[2 + i] = 48
            return _put(dst, 2 - point, q, n, -1)
        if point >= n:  # ddd000.0
            pos = _put(dst, 0, q, n, -1)
            for _ in range(point - n):
                dst[pos] = 48
                pos += 1
            dst[pos] = 46
            dst[pos + 1] = 48
            return pos + 2
        return _put(dst, 0, q, n, point)  # dd.ddd
    pos = _put(dst, 0, q, n, 1)  # d.ddde-05
    dst[pos] = 101
    exp = point - 1
    dst[pos + 1] = 45 if exp < 0 else 43
    pos += 2
    exp = abs(exp)
    if exp >= 100:
        dst[pos] = 48 + exp // 100
        pos += 1
    dst[pos] = 48 + (exp // 10) % 10
    dst[pos + 1] = 48 + exp % 10
    return pos + 2


#: "00", "01", ..., "99": the digits are written two at a time.
_PAIRS = np.frombuffer("".join(f"{i:02d}" for i in range(100)).encode(), dtype=np.uint8).copy()


@_kernel
def _fill(dst, end, u, count):
    """The last ``count`` digits of ``u`` (uint64) into ``dst[end - count:end]``."""
    pos = end
    while count >= 2:
        r = u % np.uint64(100)
        u //= np.uint64(100)
        pos -= 2
        dst[pos] = _PAIRS[2 * r]
        dst[pos + 1] = _PAIRS[2 * r + 1]
        count -= 2
    if count:
        dst[pos - 1] = 48 + u % np.uint64(10)


@_kernel
def _put(dst, start, q, n, dot):
    """The ``n`` digits of ``q`` at ``dst[start:]``, a point before digit ``dot`` if
    ``0 < dot < n``; the end position."""
    u = np.uint64(q)
    if 0 < dot < n:
        low = n - dot
        div = np.uint64(_POW10[low])
        end = start + n + 1
        _fill(dst, end, u % div, low)
        dst[end - low - 1] = 46
        _fill(dst, end - low - 1, u // div, dot)
        return end
    _fill(dst, start + n, u, n)
    return start + n


@_kernel
def _format_values(values, out, lengths):
    """repr of each value into ``out`` rows; length -1 where ``repr`` must do it."""
    for i in range(values.size):
        v = values[i]
        if not math.isfinite(v) or v == 0.0:
            lengths[i] = -1
            continue
        start = 0
        if v < 0.0:
            out[i, 0] = 45
            start = 1
        n = _digits(abs(v), out[i, start:])
        lengths[i] = -1 if n < 0 else n + start


@_kernel
def _write_rows(table, buffer):
    """All rows of ``table`` as CSV into ``buffer``; the end, or -1 if a value needs repr."""
    pos = 0
    rows, columns = table.shape
    for i in range(rows):
        for c in range(columns):
            v = table[i, c]
            if v == 0.0:
                if math.copysign(1.0, v) < 0.0:
                    buffer[pos] = 45
                    pos += 1
                buffer[pos] = 48
                buffer[pos + 1] = 46
                buffer[pos + 2] = 48
                pos += 3
            else:
                if v < 0.0:
                    buffer[pos] = 45
                    pos += 1
                n = _digits(abs(v), buffer[pos:])
                if n < 0:
                    return -1
                pos += n
            buffer[pos] = 44 if c < columns - 1 else 10
            pos += 1
    return pos


@_kernel
def _join(out, lengths, n_columns, buffer):
    """Values row after row, ``,`` between columns and a newline after each row."""
    pos = 0
    for i in range(lengths.size):
        for b in range(lengths[i]):
            buffer[pos] = out[i, b]
            pos += 1
        buffer[pos] = 10 if (i + 1) % n_columns == 0 else 44
        pos += 1
    return pos


def format_rows(table: np.ndarray) -> bytes:
    """The CSV text (bytes) of the rows of a 2-D float64 array, each value as ``repr``.

    Examples
    --------
    >>> format_rows(np.array([[0.1, -2.0], [1e-05, 1e16]]))
    b'0.1,-2.0\\n1e-05,1e+16\\n'
    """
    table = np.ascontiguousarray(table, dtype=np.float64)
    if table.ndim == 1:
        table = table.reshape(-1, 1)
    buffer = np.empty(table.size * (WIDTH - 6), dtype=np.uint8)  # 24 characters and 1 separator
    end = _write_rows(table, buffer)
    if end >= 0:
        return buffer[:end].tobytes()
    # some value is non-finite or outside the fast method's range: repr formats those
    values = table.reshape(-1)
    out = np.empty((values.size, WIDTH), dtype=np.uint8)
    lengths = np.empty(values.size, dtype=np.int64)
    _format_values(values, out, lengths)
    for i in np.flatnonzero(lengths < 0):
        text = repr(float(values[i])).encode()
        out[i, : len(text)] = np.frombuffer(text, dtype=np.uint8)
        lengths[i] = len(text)
    buffer = np.empty(int(lengths.sum()) + values.size, dtype=np.uint8)
    end = _join(out, lengths, table.shape[1], buffer)
    return buffer[:end].tobytes()
