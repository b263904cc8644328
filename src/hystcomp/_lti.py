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


def resonance_zoh(resonance_hz: float, damping_ratio: float, sample_rate: float):
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
    """``R`` at ``z^-1 = z1``: ``(b0 z^-1 + b1 z^-2) / (1 + a1 z^-1 + a2 z^-2)``."""
    return (b[0] * z1 + b[1] * z1**2) / (a[0] + a[1] * z1 + a[2] * z1**2)


def creep_lags(time_constants, sample_rate: float) -> np.ndarray:
    """``a_i = exp(-Ts / tau_i)``, the creep poles in discrete time."""
    return np.exp(-1.0 / (sample_rate * np.asarray(time_constants, dtype=np.float64)))


def frequency_response(
    frequencies, sample_rate, resonance_hz, damping_ratio, lags, weights, delay: int = 0
):
    """``D(exp(j 2 pi f Ts))`` of the model (see :mod:`hystcomp.models.dynamics`), with
    ``delay`` samples of latency beyond the sample-and-hold's one."""
    f = np.asarray(frequencies, dtype=np.float64)
    z1 = np.exp(-2j * np.pi * f / sample_rate)  # z^-1
    b, a = resonance_zoh(resonance_hz, damping_ratio, sample_rate)
    return creep_response(lags, weights, z1) * resonance_response(b, a, z1) * z1**delay


def output(
    u, rest, sample_rate, resonance_hz, damping_ratio, lags, weights, delay: int = 0
) -> np.ndarray:
    """``D[u]`` from rest at ``rest``: the creep bank, then the resonance, ``delay`` samples
    late (-1: a sample early, the sample-and-hold's own delay taken off)."""
    q = np.ascontiguousarray(u, dtype=np.float64) - rest
    if delay < 0:  # the answer to u[k + 1] is known at k: hold the input one sample more
        q = np.r_[q, q[-1:]]
    creep = q.copy()
    for a, c in zip(lags, weights, strict=True):
        creep += c * lag(a, q)
    creep /= 1.0 + float(np.sum(weights))
    out = resonance(resonance_zoh(resonance_hz, damping_ratio, sample_rate), creep)
    if delay < 0:
        out = out[1:]
    elif delay > 0:
        out = np.r_[np.zeros(min(delay, out.size)), out[: max(out.size - delay, 0)]]
    return rest + out


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
