"""Linear time-invariant helpers of the dynamics model: discretisation, responses, output.

Below both the model (:mod:`hystcomp.models.dynamics`) and its identification
(:mod:`hystcomp.identify.dynamics`), which share them: NumPy and the filter kernels of
:mod:`hystcomp._kernels.dynamics`. ``scipy.signal`` is not imported: its import alone (about
1 s of CPU) cost ten times the identification itself.
"""

from __future__ import annotations

import cmath
import math

import numpy as np

from hystcomp._kernels import dynamics as dk


def resonance_zoh(
    resonance_hz: float, damping_ratio: float, sample_rate: float
) -> tuple[np.ndarray, np.ndarray]:
    """``(b, a)`` of the zero-order-hold discretisation of ``wn^2 / (s^2 + 2 zeta wn s + wn^2)``.

    ``R(z) = (b[0] z + b[1]) / (z^2 + a[1] z + a[2])``, ``a[0] = 1``, with unit gain at
    ``z = 1``. The output at sample ``k`` is the position before the input of sample ``k``
    acts, as on a sampled rig (and in the twin).

    Examples
    --------
    >>> b, a = resonance_zoh(630.0, 0.1, 20_000.0)
    >>> round(float(sum(b) / sum(a)), 12)
    1.0
    """
    ad, bd = zoh_matrices(resonance_hz, damping_ratio, sample_rate)
    b = np.array([bd[0], ad[0, 1] * bd[1] - ad[1, 1] * bd[0]])
    a = np.array([1.0, -np.trace(ad), np.linalg.det(ad)])
    return b, a


def zoh_matrices(resonance_hz: float, damping_ratio: float, sample_rate: float):
    """``(Ad, Bd)`` of the exact zero-order-hold discretisation of the resonance.

    The states are position (µm) and velocity (µm/s) of ``x'' = -wn^2 x - 2 zeta wn x' +
    wn^2 u``; the position is the output and the steady-state gain is 1. ``Ad = exp(M Ts)``
    of the 2x2 matrix ``M`` in closed form, ``e^(s Ts) (cosh(q Ts) I + sinh(q Ts)/q (M -
    s I))`` with ``s = -zeta wn`` and ``q = sqrt(s^2 - wn^2)`` (complex below critical
    damping, 0 at it), and ``Bd = M^-1 (Ad - I) (0, wn^2)``.
    """
    wn = 2.0 * math.pi * resonance_hz
    ts = 1.0 / sample_rate
    m = np.array([[0.0, 1.0], [-(wn**2), -2.0 * damping_ratio * wn]])
    shift = -damping_ratio * wn
    q = cmath.sqrt(shift**2 - wn**2)
    sinhc = ts if abs(q * ts) < 1e-12 else cmath.sinh(q * ts) / q
    ad = np.real(
        math.exp(shift * ts) * (cmath.cosh(q * ts) * np.eye(2) + sinhc * (m - shift * np.eye(2)))
    )
    bd = np.linalg.solve(m, (ad - np.eye(2)) @ np.array([0.0, wn**2]))
    return ad, bd


def creep_response(lags, weights, z1) -> np.ndarray:
    """``C`` at ``z^-1 = z1`` (complex array)."""
    out = np.ones_like(z1)
    for a, c in zip(lags, weights, strict=True):
        out = out + c * (1.0 - a) / (1.0 - a * z1)
    return out / (1.0 + float(np.sum(weights)))


def resonance_response(b, a, z1) -> np.ndarray:
    """``R`` at ``z^-1 = z1``: ``(b0 z^-1 + b1 z^-2) / (1 + a1 z^-1 + a2 z^-2)`` (and alike
    for the higher orders of :func:`modal_tf`: ``b[k]`` multiplies ``z^-(k + 1)``)."""
    if len(a) == 3:  # one mode
        return (b[0] * z1 + b[1] * z1**2) / (a[0] + a[1] * z1 + a[2] * z1**2)
    num = np.zeros_like(z1)
    for bk in b[::-1]:  # Horner in z^-1
        num = (num + bk) * z1
    den = np.zeros_like(z1)
    for ak in a[::-1]:
        den = den * z1 + ak
    return num / den


def creep_lags(time_constants, sample_rate: float) -> np.ndarray:
    """``a_i = exp(-Ts / tau_i)``, the creep poles in discrete time."""
    return np.exp(-1.0 / (sample_rate * np.asarray(time_constants, dtype=np.float64)))


def modal_tf(modes, sample_rate: float):
    """``(b, a)`` of the modes in parallel, ``R(z) = sum_i g_i R_i(z)``, as one transfer function.

    ``modes`` are ``(resonance_hz, damping_ratio, share)`` triples, each ``R_i`` of
    :func:`resonance_zoh`; ``b`` is the numerator in powers of ``z`` (one degree below
    ``a``, strictly proper as each section is), ``a`` the product of the sections'
    denominators (``a[0] = 1``). One mode of share 1 is :func:`resonance_zoh` itself.

    Examples
    --------
    >>> b, a = modal_tf([(1200.0, 0.05, 0.92), (3100.0, 0.03, 0.08)], 20_000.0)
    >>> b.size, a.size, round(float(np.polyval(b, 1.0) / np.polyval(a, 1.0)), 12)
    (4, 5, 1.0)
    """
    sections = [(share, *resonance_zoh(hz, zeta, sample_rate)) for hz, zeta, share in modes]
    a = np.ones(1)
    for _, _, ai in sections:
        a = np.polymul(a, ai)
    b = np.zeros(a.size - 1)
    for i, (share, bi, _) in enumerate(sections):
        term = share * bi
        for j, (_, _, aj) in enumerate(sections):
            if j != i:
                term = np.polymul(term, aj)
        b[b.size - term.size :] += term
    return b, a


def modal_response(modes, sample_rate: float, z1) -> np.ndarray:
    """``R = sum_i g_i R_i`` at ``z^-1 = z1`` (``modes`` as in :func:`modal_tf`)."""
    out = np.zeros_like(z1)
    for hz, zeta, share in modes:
        b, a = resonance_zoh(hz, zeta, sample_rate)
        out = out + share * resonance_response(b, a, z1)
    return out


def frequency_response(frequencies, sample_rate, modes, lags, weights, delay: int = 0):
    """``D(exp(j 2 pi f Ts))`` of the model (see :mod:`hystcomp.models.dynamics`): the
    ``modes`` in parallel (as in :func:`modal_tf`), with ``delay`` samples of latency
    beyond the sample-and-hold's one."""
    f = np.asarray(frequencies, dtype=np.float64)
    z1 = np.exp(-2j * np.pi * f / sample_rate)  # z^-1
    return creep_response(lags, weights, z1) * modal_response(modes, sample_rate, z1) * z1**delay


def output(u, rest, sample_rate, modes, lags, weights, delay: int = 0) -> np.ndarray:
    """``D[u]`` from rest at ``rest``: the creep bank, then the modes in parallel (as in
    :func:`modal_tf`), ``delay`` samples late (-1: a sample early, the sample-and-hold's
    own delay taken off)."""
    q = np.ascontiguousarray(u, dtype=np.float64) - rest
    if delay < 0:  # the answer to u[k + 1] is known at k: hold the input one sample more
        q = np.r_[q, q[-1:]]
    creep = q.copy()
    for a, c in zip(lags, weights, strict=True):
        creep += c * lag(a, q)
    creep /= 1.0 + float(np.sum(weights))
    out = modal(modes, sample_rate, creep)
    if delay < 0:
        out = out[1:]
    elif delay > 0:
        out = np.r_[np.zeros(min(delay, out.size)), out[: max(out.size - delay, 0)]]
    return rest + out


def modal(modes, sample_rate: float, u) -> np.ndarray:
    """``R[u]`` from rest at 0 for the modes in parallel (as in :func:`modal_tf`): each
    section run on its own and the outputs summed (better conditioned than the product
    form of :func:`modal_tf`)."""
    out = np.zeros(np.shape(u))
    for hz, zeta, share in modes:
        out += share * resonance(resonance_zoh(hz, zeta, sample_rate), u)
    return out


def lag(a: float, u) -> np.ndarray:
    """One creep mode from rest at 0: ``y[k] = a y[k-1] + (1 - a) u[k]``."""
    u = np.ascontiguousarray(u, dtype=np.float64)
    out = np.empty_like(u)
    dk.lag_run(float(a), u, out)
    return out


def resonance(ba, u) -> np.ndarray:
    """``R[u]`` from rest at 0, ``ba = (b, a)`` of :func:`resonance_zoh`."""
    b, a = (np.ascontiguousarray(c, dtype=np.float64) for c in ba)
    u = np.ascontiguousarray(u, dtype=np.float64)
    out = np.empty_like(u)
    dk.resonance_run(b, a, u, out)
    return out


def creep_fraction(seconds, time_constants, weights) -> float:
    """How far a step response still has to rise after ``seconds``, as a fraction of its end."""
    weights = np.asarray(weights, dtype=np.float64)
    tail = np.exp(-seconds / np.asarray(time_constants, dtype=np.float64))
    return float((weights * tail).sum() / (1.0 + weights.sum()))
