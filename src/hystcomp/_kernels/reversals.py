"""Turning points of a record, as a compiled kernel, for identification.

The Preisach fit (:mod:`hystcomp.identify.preisach`) keeps a long record's reversals and a
grid between them; this finds the reversals, ignoring those smaller than a tolerance (the
sensor noise). It trusts its input.
"""

from __future__ import annotations

from hystcomp._kernels._jit import kernel


@kernel
def turning_points(v, delta, out):
    """Indices of the alternating extrema of ``v``, ignoring reversals smaller than ``delta``.

    A maximum is confirmed once the signal falls more than ``delta`` below it, a minimum once
    it rises more than ``delta`` above it (the last index of a plateau is the turning point).
    ``out`` receives the indices, the last one being the running extremum at the end of the
    data (not confirmed). Returns ``(count, first_is_max)``; ``count`` is 0 if ``v`` never
    moves by more than ``delta``.
    """
    n = v.size
    i_hi = 0
    i_lo = 0
    k = 1
    direction = 0
    while k < n:
        if v[k] >= v[i_hi]:
            i_hi = k
        if v[k] <= v[i_lo]:
            i_lo = k
        if v[k] - v[i_lo] > delta:
            direction = 1
            break
        if v[i_hi] - v[k] > delta:
            direction = -1
            break
        k += 1
    if direction == 0:
        return 0, False
    count = 1
    first_is_max = direction == -1
    out[0] = i_hi if first_is_max else i_lo
    candidate = k
    for k in range(candidate + 1, n):
        if direction == 1:
            if v[k] >= v[candidate]:
                candidate = k
            elif v[candidate] - v[k] > delta:
                out[count] = candidate
                count += 1
                direction = -1
                candidate = k
        else:
            if v[k] <= v[candidate]:
                candidate = k
            elif v[k] - v[candidate] > delta:
                out[count] = candidate
                count += 1
                direction = 1
                candidate = k
    out[count] = candidate
    return count + 1, first_is_max
