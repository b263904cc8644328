"""Compiled kernels of the linear dynamics: the inverse (one step, and a batch loop over it)
and the two stages of the forward model (a creep lag, the resonance) that
:mod:`hystcomp._lti` runs for the model's output and its identification.

The inverse filter (see :mod:`hystcomp.models.dynamics`) is a FIR stage (non-negative taps
fitted so that the resonance times them is close to 1 in the band) in series with the
exact inverse of the creep bank. Its parameters and state are one packed
float64 array, as the chain's (:mod:`hystcomp._kernels.chain`)::

    [N_FIR, N_CREEP, SCALE, DIRECT, LOW, HIGH, BIAS, h_0 .. h_{N_FIR-1}, a_1 .. a_n, c_1 .. c_n,
     delay line (N_FIR samples, newest first), creep lag states (n), count of clamped outputs]

The creep bank of the forward model is ``D_c[q] = (q + sum_i c_i lag_i) / SCALE`` with
``lag_i[k] = a_i lag_i[k-1] + (1 - a_i) q[k]`` and ``SCALE = 1 + sum_i c_i``. Its inverse
solves that equation for ``q[k]`` each sample (``DIRECT = 1 + sum_i c_i (1 - a_i)``): no
root of any polynomial is computed, so creep poles a hair below 1 stay exact. The output
is clamped to ``[LOW, HIGH]`` (the hysteresis model's displacement range), so that the
hysteresis inverse downstream never takes a memory the actuator cannot follow; the creep
lags follow the clamped output, and an output that the clamp moves by more than
:data:`~hystcomp._kernels.chain.CLAMP_TOLERANCE` of the range is counted (the reference
is out of reach there), as the chain counts its voltage clamp. Kernels trust
their input. The FIR's output is ``BIAS + sum_j h_j u[k - j]`` (a gain other than 1 at
0 Hz, about a rest point, is a scaling of the taps and a bias).
"""

from __future__ import annotations

import math

from hystcomp._kernels._jit import kernel, step_kernel
from hystcomp._kernels.chain import CLAMP_TOLERANCE

N_FIR, N_CREEP, SCALE, DIRECT, LOW, HIGH, BIAS = range(7)
HEADER = 7


@kernel
def state_start(p):
    """Index of the first state slot (the newest sample of the delay line)."""
    return HEADER + int(p[N_FIR]) + 2 * int(p[N_CREEP])


@kernel
def clamped_slot(p):
    """Index of the count of clamped outputs (the last slot)."""
    return HEADER + 2 * int(p[N_FIR]) + 3 * int(p[N_CREEP])


@step_kernel
def inverse_step(p, u):
    """One reference sample ``u`` (µm) through the inverse filter; NaN (state kept) if not finite."""
    if not math.isfinite(u):
        return math.nan
    n_fir = int(p[N_FIR])
    n_creep = int(p[N_CREEP])
    h = HEADER
    a = h + n_fir
    c = a + n_creep
    d = c + n_creep
    lags = d + n_fir
    for j in range(n_fir - 1, 0, -1):
        p[d + j] = p[d + j - 1]
    p[d] = u
    w = p[BIAS]
    for j in range(n_fir):
        w += p[h + j] * p[d + j]
    acc = w * p[SCALE]
    for i in range(n_creep):
        acc -= p[c + i] * p[a + i] * p[lags + i]
    y = acc / p[DIRECT]
    if not math.isfinite(y):  # a huge finite reference overflowed: held downstream
        return math.nan
    tol = CLAMP_TOLERANCE * (p[HIGH] - p[LOW])  # inf without a clamp: nothing counts
    if y > p[HIGH] + tol or y < p[LOW] - tol:
        p[lags + n_creep] += 1.0
    y = min(max(y, p[LOW]), p[HIGH])
    for i in range(n_creep):
        ai = p[a + i]
        p[lags + i] = ai * p[lags + i] + (1.0 - ai) * y
    return y


@kernel
def inverse_run(p, u, out):
    """Run :func:`inverse_step` over every sample of ``u`` (state kept in ``p``)."""
    for k in range(u.size):
        out[k] = inverse_step(p, u[k])


@kernel
def inverse_run_cuts(p, u, out, cuts):
    """:func:`inverse_run`, and ``cuts[k]`` True where the clamp counted sample ``k``."""
    slot = clamped_slot(p)
    for k in range(u.size):
        before = p[slot]
        out[k] = inverse_step(p, u[k])
        cuts[k] = p[slot] != before


@kernel
def lag_run(a, u, out):
    """A first-order lag of unit gain from rest at 0: ``y[k] = a y[k-1] + (1 - a) u[k]``.

    One creep mode of the forward model (``lfilter([1 - a], [1, -a], u)``).
    """
    y = 0.0
    for k in range(u.size):
        y = a * y + (1.0 - a) * u[k]
        out[k] = y


@kernel
def resonance_run(b, a, u, out):
    """``R(z) = (b0 z^-1 + b1 z^-2) / (1 + a1 z^-1 + a2 z^-2)`` from rest at 0.

    The resonance of the forward model (``lfilter([0, b0, b1], a, u)``): the output of
    sample ``k`` is the position before the input of sample ``k`` acts.
    """
    u1 = 0.0
    u2 = 0.0
    y1 = 0.0
    y2 = 0.0
    for k in range(u.size):
        y = b[0] * u1 + b[1] * u2 - a[1] * y1 - a[2] * y2
        out[k] = y
        y2 = y1
        y1 = y
        u2 = u1
        u1 = u[k]
