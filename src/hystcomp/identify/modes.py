"""A second resonance mode in the frequency response: found, fitted, and kept or not.

Beyond the paper. :func:`hystcomp.identify.dynamics.fit_dynamics` fits one resonance to the
multisine's lines; a stage with a second mode in its band (a stack and its flexure, a
mount) then gets a resonance between the two, too lightly damped, and a latency that takes
up the second mode's phase (docs/dynamics.md, "A second mode", gives the figures on the
two-mode stage of ``benchmarks/dynamics_panel.py``). So, after the one-mode fit, two modes in parallel
are fitted to the same lines (:func:`fit_modes`), each a second-order section of unit
static gain, ``R = (1 - g) R1 + g R2``, the latency free with them, and
:func:`keeps_second_mode` decides.

The fit, on the lines from the fit's lowest frequency up (relative complex error, the
complex factor of the hysteresis eliminated as in the one-mode fit):

1. start: the first mode as the one-mode fit found it; for the second, a grid of
   frequencies above the first (from :data:`SEPARATION` times it to the highest line) and
   damping ratios, at the latencies near the one-mode fit's and at 0, each with the two
   modes' complex factors by linear least squares; the best of the grid;
2. ``scipy.optimize.least_squares`` of the first and second mode, the second's share
   ``g`` and the latency (a fraction of a sample too) from there; the one-mode model is
   refitted the same way (the same error, the same freedom in the latency), so that the
   two costs compare.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from hystcomp._lti import resonance_response, resonance_zoh

#: The second mode lies at least this multiple of the first's frequency above it.
SEPARATION = 1.15
#: Keep two modes when their residual (rms of the relative complex error on the lines) is at
#: most this share of one mode's: about the geometric middle of the gap between the ratios
#: measured on two-mode and on single-mode stages (docs/dynamics.md, "A second mode").
RESIDUAL_RATIO = 0.25
#: A second mode is kept only if it is a resonance (damped less than this) and holds at
#: least :data:`MIN_SHARE` of the static gain.
MAX_SECOND_DAMPING = 0.5
MIN_SHARE = 0.005
#: The grid of the start: second-mode frequencies (log-spaced) and damping ratios.
GRID_POINTS = 40
GRID_DAMPING = (0.01, 0.03, 0.1, 0.3)


class ModalFit(NamedTuple):
    """A fit of :func:`fit_modes`: ``modes`` as ``((hz, zeta, share), ...)``, the latency
    ``tau`` (samples beyond the sample-and-hold's, a fraction too) and the residual (rms of
    the relative complex error over the lines)."""

    modes: tuple[tuple[float, float, float], ...]
    tau: float
    residual: float


def _sections(fs, z1, modes):
    return [resonance_response(*resonance_zoh(hz, zeta, fs), z1) for hz, zeta, _ in modes]


def _relative_error(m, g):
    """``(c m - g) / |g|`` with the complex factor ``c`` that minimises it."""
    w = 1.0 / np.abs(g)
    mw, gw = m * w, g * w
    c = np.vdot(mw, gw) / np.vdot(mw, mw)
    return c * mw - gw


def _two_columns(a, b, y):
    """Least squares of ``y`` on the columns ``a`` and ``b[k]`` for every row ``k`` of ``b``
    (complex): the residual norms and the coefficients ``(k, 2)``."""
    aa = np.vdot(a, a).real
    bb = np.einsum("kn,kn->k", b.conj(), b).real
    ab = b @ a.conj()  # conj(a) . b[k]
    ay = np.vdot(a, y)
    by = b.conj() @ y
    det = aa * bb - np.abs(ab) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        ca = (bb * ay - ab * by) / det
        cb = (aa * by - ab.conj() * ay) / det
    residual = y[None, :] - ca[:, None] * a[None, :] - cb[:, None] * b
    cost = np.linalg.norm(residual, axis=1)
    return np.where(np.isfinite(cost), cost, np.inf), np.column_stack([ca, cb])


def fit_modes(f, g, fs, creep, first, tau, *, delay_range, max_damping) -> tuple[ModalFit, ...]:
    """One mode, then two, fitted to the lines ``g`` at ``f`` (Hz).

    Parameters
    ----------
    f, g : ndarray
        The lines (Hz) and the measured response there, latency in (complex).
    fs : float
        Hz.
    creep : ndarray
        The creep bank's response at the lines (complex), held fixed.
    first : (float, float)
        The one-mode fit's resonance (Hz) and damping ratio, the start.
    tau : float
        The one-mode fit's latency in samples, the start.
    delay_range : (int, int)
        The latencies a model may have (samples).
    max_damping : float
        The largest damping ratio of either mode.

    Returns
    -------
    (ModalFit, ModalFit)
        The one-mode and the two-mode fit; the second mode above the first, below
        ``0.45 fs``.
    """
    from scipy.optimize import least_squares

    z1 = np.exp(-2j * np.pi * f / fs)
    low_tau, high_tau = delay_range[0] - 0.5, delay_range[1] + 0.5

    def model(theta, two):
        fn, zeta = np.exp(theta[:2])
        modes = [(fn, zeta, 1.0)]
        if two:
            share = theta[4]
            modes = [(fn, zeta, 1.0 - share), (fn * np.exp(theta[2]), np.exp(theta[3]), share)]
        r = sum(s * m for (_, _, s), m in zip(modes, _sections(fs, z1, modes), strict=True))
        return creep * r * np.exp(-2j * np.pi * f * theta[-1] / fs), modes

    def residual(theta, two):
        e = _relative_error(model(theta, two)[0], g)
        return np.r_[e.real, e.imag]

    def solve(start, low, high, two):
        start = np.clip(start, low + 1e-9, high - 1e-9)
        theta = least_squares(residual, start, args=(two,), bounds=(low, high)).x
        e = residual(theta, two)
        return ModalFit(
            tuple((float(a), float(b), float(c)) for a, b, c in model(theta, two)[1]),
            float(theta[-1]),
            float(np.sqrt(np.mean(e**2) * 2.0)),
        )

    fn_bounds = (np.log(1.0), np.log(0.45 * fs))
    zeta_bounds = (np.log(1e-4), np.log(max_damping))
    one = solve(
        np.r_[np.log(first), tau],
        np.r_[fn_bounds[0], zeta_bounds[0], max(tau - 1.0, low_tau)],
        np.r_[fn_bounds[1], zeta_bounds[1], min(tau + 1.0, high_tau)],
        False,
    )
    # the start of two modes: the first as found, the second on a grid above it, the two
    # modes' complex factors by linear least squares
    fn1, zeta1, _ = one.modes[0]
    top = min(f.max(), 0.45 * fs)
    if top <= SEPARATION * fn1:
        return one, one._replace(residual=np.inf)  # no room above the first in the band
    w = 1.0 / np.abs(g)
    first_r = _sections(fs, z1, [(fn1, zeta1, 1.0)])[0]
    grid = [
        (hz, zeta)
        for hz in np.geomspace(SEPARATION * fn1, top, GRID_POINTS)
        for zeta in GRID_DAMPING
    ]
    second_r = np.array(_sections(fs, z1, [(hz, zeta, 1.0) for hz, zeta in grid]))
    best = (np.inf, fn1, zeta1, 0.0, 0.0)
    delays = {round(tau) - 1.0, float(round(tau)), round(tau) + 1.0, 0.0}
    for d in sorted(x for x in delays if low_tau <= x <= high_tau):
        shift = creep * np.exp(-2j * np.pi * f * d / fs) * w
        cost, coef = _two_columns(first_r * shift, second_r * shift, g * w)
        k = int(np.argmin(cost))
        if cost[k] < best[0]:
            share = float(np.real(coef[k, 1] / (coef[k, 0] + coef[k, 1])))
            best = (float(cost[k]), *grid[k], share, d)
    _, hz, zeta, share, d = best
    low = np.r_[fn_bounds[0], zeta_bounds[0], np.log(SEPARATION), zeta_bounds[0], 1e-4]
    high = np.r_[fn_bounds[1], zeta_bounds[1], np.log(0.45 * fs / fn1), zeta_bounds[1], 0.999]
    two = solve(
        np.r_[np.log([fn1, zeta1, hz / fn1, zeta]), np.clip(share, 0.01, 0.9), d],
        np.r_[low, max(d - 1.0, low_tau)],
        np.r_[high, min(d + 1.0, high_tau)],
        True,
    )
    return one, two


def keeps_second_mode(one: ModalFit, two: ModalFit, top_hz: float) -> bool:
    """Whether the two-mode fit explains the lines clearly better than one mode.

    Its residual is at most :data:`RESIDUAL_RATIO` of one mode's, its second mode is a
    resonance (damping ratio below :data:`MAX_SECOND_DAMPING`) within the lines' band (at
    most ``top_hz``) with at least :data:`MIN_SHARE` of the static gain.

    Parameters
    ----------
    one : ModalFit
        The fit of one mode.
    two : ModalFit
        The fit of two modes.
    top_hz : float
        The highest frequency of the lines, Hz.

    Returns
    -------
    bool
        True if the second mode is kept.
    """
    if len(two.modes) < 2:
        return False
    hz, zeta, share = two.modes[1]
    return bool(
        two.residual <= RESIDUAL_RATIO * one.residual
        and zeta < MAX_SECOND_DAMPING
        and hz <= top_hz
        and MIN_SHARE <= share
    )
