"""Slow, obviously-correct references for the kernels, written independently of them."""

from __future__ import annotations

import numpy as np


def play(v, r, y0=0.0):
    """One play operator, eq. (11), sample by sample."""
    y, out = float(y0), []
    for vk in v:
        if vk - y > r:
            y = vk - r
        elif y - vk > r:
            y = vk + r
        out.append(y)
    return np.array(out)


def deadzone(z, r):
    """One-sided dead-zone, eq. (13)."""
    z = np.asarray(z, dtype=float)
    return z.copy() if r == 0 else np.where(z > r, z - r, 0.0)


def pi_model(v, r, w, y0=None, v0=0.0, x0=0.0):
    """Eq. (12) as a plain sum of independent plays."""
    y0 = np.zeros(len(r)) if y0 is None else y0
    u = np.asarray(v, dtype=float) - v0
    return x0 + sum(wi * play(u, ri, yi) for ri, wi, yi in zip(r, w, y0, strict=True))


def saturation(z, r, w):
    """Eq. (14)."""
    return sum(wj * deadzone(z, rj) for rj, wj in zip(r, w, strict=True))


def mpi_model(v, r, w, rs, ws, y0=None, v0=0.0, x0=0.0):
    """Eq. (15): dead-zones after plays."""
    return x0 + saturation(pi_model(v, r, w, y0, v0), rs, ws)


def invert_monotone(f, y, lo, hi, iters=200):
    """Bisection inverse of an increasing scalar function on [lo, hi]."""
    for _ in range(iters):
        mid = 0.5 * (lo + hi)
        if f(mid) < y:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def partial_sum_lsq(design, target, blocks):
    """Least squares with every partial sum of each block ``(first, stop, bound)`` >= bound.

    Written with scipy's bounded solver on the partial sums themselves (w = diff of s), not
    with the normal equations: an independent route to the same optimum.
    """
    from scipy.optimize import lsq_linear

    p = design.shape[1]
    to_weights = np.eye(p)
    lower = np.full(p, -np.inf)
    for first, stop, bound in blocks:
        for i in range(first + 1, stop):
            to_weights[i, i - 1] = -1.0
        lower[first:stop] = bound
    result = lsq_linear(design @ to_weights, target, bounds=(lower, np.inf), method="bvls")
    return to_weights @ result.x
