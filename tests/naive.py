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


def everett_polynomial(theta, v_min=0.0):
    """X(alpha, beta) of eq. (5), generalised: degree by degree, from beta^k to alpha^k."""
    terms, k = [], 1
    while len(terms) < len(theta):
        terms += [(k - j, j) for j in range(k + 1)]
        k += 1

    def everett(alpha, beta):
        a, b = alpha - v_min, beta - v_min
        return sum(c * b**i * a**j for c, (i, j) in zip(theta, terms, strict=True))

    return everett


def everett_table(lower, v_min, v_max):
    """Bilinear interpolation of X on a grid; above the diagonal X(a, b) = -X(b, a)."""
    from scipy.interpolate import RegularGridInterpolator

    lower = np.tril(np.asarray(lower, dtype=float))
    full = lower - np.tril(lower, -1).T
    nodes = np.linspace(v_min, v_max, lower.shape[0])
    interp = RegularGridInterpolator((nodes, nodes), full)

    def everett(alpha, beta):
        return float(interp([[alpha, beta]])[0])

    return everett


def preisach_extrema(v, everett, v_min, v_max):
    """Eqs. (3)-(4) with the alternating dominant extrema of the whole history found anew
    at every sample (the last index of a repeated extremum counts, which is the wipe-out)."""
    u = np.clip(np.asarray(v, dtype=float), v_min, v_max)
    out = []
    for k in range(u.size):
        hist = np.concatenate([[v_min], u[: k + 1]])
        alphas, betas = [], [v_min]
        pos, want_max = 0, True
        while True:
            seg = hist[pos + 1 :]
            target = seg.max() if want_max else seg.min()
            pos = pos + 1 + int(np.flatnonzero(seg == target)[-1])
            if pos == hist.size - 1:
                break
            (alphas if want_max else betas).append(target)
            want_max = not want_max
        x = sum(
            everett(a, b0) - everett(a, b1)
            for a, b0, b1 in zip(alphas, betas, betas[1:], strict=False)
        )
        if want_max:  # rising from betas[-1]
            x += everett(u[k], betas[-1])
        else:  # falling from alphas[-1]
            x += everett(alphas[-1], betas[-1]) - everett(alphas[-1], u[k])
        out.append(x)
    return np.array(out)


def preisach_relays(v_index, everett, nodes):
    """Eq. (1) literally: 0/1 relays on a grid, for inputs on the grid nodes.

    Relay (i, j) switches on at ``nodes[i]`` and off at ``nodes[j]`` (j < i); its weight is
    the Preisach density integrated over its cell of the limiting triangle, from the Everett
    function (an Everett function must vanish on the diagonal for this to hold).
    """
    n = len(nodes)
    up, down, weight = [], [], []
    for i in range(1, n):
        for j in range(i):
            if j + 1 <= i - 1:
                w = (
                    everett(nodes[i], nodes[j])
                    - everett(nodes[i - 1], nodes[j])
                    - everett(nodes[i], nodes[j + 1])
                    + everett(nodes[i - 1], nodes[j + 1])
                )
            else:
                w = everett(nodes[i], nodes[j])
            up.append(i)
            down.append(j)
            weight.append(w)
    up, down, weight = np.array(up), np.array(down), np.array(weight)
    state = np.zeros(up.size, dtype=bool)
    out = []
    for idx in v_index:
        state[up <= idx] = True
        state[down >= idx] = False
        out.append(float(weight @ state))
    return np.array(out)


def _overlap(lo1, hi1, lo2, hi2):
    """Length of the intersection of the intervals [lo1, hi1] and [lo2, hi2]."""
    return max(0.0, min(hi1, hi2) - max(lo1, lo2))


def everett_basis_polynomial(exponents, v_min, v_max):
    """X_m(alpha, beta) = b^i a^j - b^(i+j) on the unit square, one function per (i, j)."""
    span = v_max - v_min

    def element(i, j):
        def everett(alpha, beta):
            a, b = (alpha - v_min) / span, (beta - v_min) / span
            return b**i * a**j - b ** (i + j)

        return everett

    return [element(i, j) for i, j in exponents]


def everett_basis_cells(n_seg, v_min, v_max):
    """Everett functions of unit masses on a grid: X(alpha, beta) is the part of the mass in
    {beta <= beta' <= alpha' <= alpha}. Diagonal segments first (a mass spread along the
    segment), then the cells (s_a, s_b), s_b < s_a, in the order (1, 0), (2, 0), (2, 1), ..."""
    h = (v_max - v_min) / n_seg
    g = v_min + h * np.arange(n_seg + 1)

    def segment(s):
        return lambda alpha, beta: _overlap(g[s], g[s + 1], beta, alpha) / h

    def cell(sa, sb):
        # the cell lies below the diagonal, so beta' <= alpha' holds inside it
        def everett(alpha, beta):
            on_alpha = _overlap(g[sa], g[sa + 1], -np.inf, alpha) / h
            on_beta = _overlap(g[sb], g[sb + 1], beta, np.inf) / h
            return on_alpha * on_beta

        return everett

    funcs = [segment(s) for s in range(n_seg)]
    funcs += [cell(sa, sb) for sa in range(1, n_seg) for sb in range(sa)]
    return funcs


def preisach_regressors(v, basis, v_min, v_max):
    """Eqs. (3)-(4) with each basis Everett function alone: one column per element."""
    return np.column_stack([preisach_extrema(v, f, v_min, v_max) for f in basis])


def dynamics_inverse(x, taps, lags, weights, *, rest, bias, low, high, tolerance):
    """The inverse filter of the linear dynamics from rest, sample by sample: the FIR over a
    list of past samples (newest first, all at ``rest`` before the first), then the creep
    bank's equation ``(q + sum_i c_i lag_i) / (1 + sum_i c_i) = w`` solved for ``q`` with
    ``lag_i = a_i lag_i[k-1] + (1 - a_i) q``, clamped to ``[low, high]``.

    Returns the outputs (NaN where held: a non-finite sample, which leaves the state alone,
    or an overflow) and the count of outputs that the clamp moved by more than ``tolerance``.
    """
    past = [float(rest)] * len(taps)
    state = [float(rest)] * len(lags)
    out, clamped = [], 0
    for xk in x:
        if not np.isfinite(xk):
            out.append(np.nan)
            continue
        past = [float(xk), *past[:-1]]
        w = bias + sum(h * u for h, u in zip(taps, past, strict=True))
        # q + sum_i c_i (a_i lag_i + (1 - a_i) q) = w (1 + sum_i c_i)
        known = sum(c * a * s for c, a, s in zip(weights, lags, state, strict=True))
        direct = 1.0 + sum(c * (1.0 - a) for c, a in zip(weights, lags, strict=True))
        q = (w * (1.0 + sum(weights)) - known) / direct  # Python floats: inf, no error
        if not np.isfinite(q):
            out.append(np.nan)
            continue
        if q > high + tolerance or q < low - tolerance:
            clamped += 1
        q = min(max(q, low), high)
        state = [a * s + (1.0 - a) * q for a, s in zip(lags, state, strict=True)]
        out.append(q)
    return np.array(out), clamped
