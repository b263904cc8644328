"""Linear time-invariant helpers of the dynamics model: discretisation, responses, output.

Below both the model (:mod:`hystcomp.models.dynamics`) and its identification
(:mod:`hystcomp.identify.dynamics`), which share them: NumPy, the filter kernels of
:mod:`hystcomp._kernels.dynamics`, and two small solvers (:func:`nnls`,
:func:`least_squares`). Neither ``scipy.signal`` nor ``scipy.optimize`` is imported: their
import alone (1.5-2 s on a busy machine) cost twenty times the identification itself.
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
    wn = 2.0 * math.pi * resonance_hz
    ts = 1.0 / sample_rate
    m = np.array([[0.0, 1.0], [-(wn**2), -2.0 * damping_ratio * wn]])
    # exp(M Ts) of a 2x2 matrix in closed form: e^(s Ts) (cosh(q Ts) I + sinh(q Ts)/q (M - s I))
    shift = -damping_ratio * wn
    q = cmath.sqrt(shift**2 - wn**2)
    sinhc = ts if abs(q * ts) < 1e-12 else cmath.sinh(q * ts) / q
    ad = np.real(
        math.exp(shift * ts) * (cmath.cosh(q * ts) * np.eye(2) + sinhc * (m - shift * np.eye(2)))
    )
    # Bd = M^-1 (Ad - I) B with B = (0, wn^2)
    bd = np.linalg.solve(m, (ad - np.eye(2)) @ np.array([0.0, wn**2]))
    b = np.array([bd[0], ad[0, 1] * bd[1] - ad[1, 1] * bd[0]])
    a = np.array([1.0, -np.trace(ad), np.linalg.det(ad)])
    return b, a


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


def frequency_response(frequencies, sample_rate, resonance_hz, damping_ratio, lags, weights):
    """``D(exp(j 2 pi f Ts))`` of the model (see :mod:`hystcomp.models.dynamics`)."""
    f = np.asarray(frequencies, dtype=np.float64)
    z1 = np.exp(-2j * np.pi * f / sample_rate)  # z^-1
    b, a = resonance_zoh(resonance_hz, damping_ratio, sample_rate)
    return creep_response(lags, weights, z1) * resonance_response(b, a, z1)


def output(u, rest, sample_rate, resonance_hz, damping_ratio, lags, weights) -> np.ndarray:
    """``D[u]`` from rest at ``rest``: the creep bank, then the resonance."""
    q = np.ascontiguousarray(u, dtype=np.float64) - rest
    creep = q.copy()
    for a, c in zip(lags, weights, strict=True):
        creep += c * lag(a, q)
    creep /= 1.0 + float(np.sum(weights))
    return rest + resonance(resonance_zoh(resonance_hz, damping_ratio, sample_rate), creep)


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


def nnls(a, b) -> np.ndarray:
    """``argmin ||a x - b||`` subject to ``x >= 0``: Lawson and Hanson's active-set method.

    For the small, dense problems of the dynamics (a few to a hundred and some columns, the
    positive ones a handful), on the normal equations (Bro and de Jong's "fast NNLS"): every
    step is a product or a solve of a few rows and columns. A LAPACK least-squares solve of
    the tall matrix itself would be exact to a few digits more but can take 100 ms on a
    busy machine (OpenBLAS's threads), a thousand times its work. The solution is unique
    when ``a`` has full column rank on the positive coefficients.

    Examples
    --------
    >>> nnls(np.eye(2), np.array([1.0, -1.0])).tolist()
    [1.0, 0.0]
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    gram = a.T @ a
    right = a.T @ b
    n = gram.shape[0]
    x = np.zeros(n)
    passive = np.zeros(n, dtype=bool)
    tol = 10.0 * np.finfo(float).eps * np.abs(gram).max() * n
    for _ in range(3 * n):
        w = right - gram @ x  # minus the gradient
        w[passive] = -np.inf
        j = int(np.argmax(w))
        if passive.all() or not w[j] > tol:
            break
        passive[j] = True
        while True:
            z = np.zeros(n)
            z[passive] = np.linalg.solve(gram[np.ix_(passive, passive)], right[passive])
            if np.all(z[passive] > 0.0):
                x = z
                break
            # back along x -> z to the first coefficient that reaches 0, which leaves
            blocking = passive & (z <= 0.0)
            alpha = np.min(x[blocking] / (x[blocking] - z[blocking]))
            x = x + alpha * (z - x)
            passive &= x > 0.0
            x[~passive] = 0.0
    return x


def least_squares(residual, theta0, lower, upper, *, max_iterations: int = 200) -> np.ndarray:
    """``argmin ||residual(theta)||`` for a few parameters within bounds: Levenberg-Marquardt.

    Central-difference Jacobian, steps clipped to ``[lower, upper]``; stops when a step
    changes no parameter by more than ``1e-10`` (in the parameters' units) or the cost by
    less than ``1e-14`` of itself.

    Examples
    --------
    >>> t = np.linspace(0.0, 1.0, 50)
    >>> fit = least_squares(lambda p: p[0] * np.exp(-p[1] * t) - 3.0 * np.exp(-2.0 * t),
    ...                     [1.0, 1.0], [0.0, 0.0], [10.0, 10.0])
    >>> np.round(fit, 9).tolist()
    [3.0, 2.0]
    >>> least_squares(lambda p: p - [1.0, 5.0], [0.0, 0.0], [-2.0, -2.0], [2.0, 2.0])[1]   # at the bound
    np.float64(2.0)
    """
    theta = np.clip(np.asarray(theta0, dtype=np.float64), lower, upper)
    r = np.asarray(residual(theta))
    cost = float(r @ r)
    damping = 1e-3
    for _ in range(max_iterations):
        h = 1e-6 * (1.0 + np.abs(theta))
        jac = np.empty((r.size, theta.size))
        for i in range(theta.size):
            e = np.zeros_like(theta)
            e[i] = h[i]
            jac[:, i] = (np.asarray(residual(theta + e)) - np.asarray(residual(theta - e))) / (
                2.0 * h[i]
            )
        gradient = jac.T @ r
        normal = jac.T @ jac
        scale = np.diag(normal).copy()
        scale[scale == 0.0] = 1.0
        while True:
            step = np.linalg.solve(normal + damping * np.diag(scale), -gradient)
            trial = np.clip(theta + step, lower, upper)
            r_trial = np.asarray(residual(trial))
            cost_trial = float(r_trial @ r_trial)
            if cost_trial <= cost:
                break
            damping *= 4.0
            if damping > 1e12:
                return theta
        moved = np.abs(trial - theta).max()
        gained = cost - cost_trial
        theta, r, cost = trial, r_trial, cost_trial
        damping = max(damping / 3.0, 1e-12)
        if moved < 1e-10 or gained <= 1e-14 * cost:
            break
    return theta
