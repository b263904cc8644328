"""Compiled kernels of the simulated axis (the twin): one step, and a batch loop over it.

The parameters and the state of a twin are one packed float64 array, parameters then state
(see the slot constants below), so that a streaming step is one compiled call and the batch
run is a loop over the very same step; :data:`TWIN_KERNELS` lets the package's one streaming
stepper (:class:`hystcomp.models.system.Stepper`) run it. :func:`axis_step` takes the
parameters and the state apart, for callers that keep the state elsewhere. Kernels trust
their input; :mod:`hystcomp.plant.twin` validates and packs.

Hysteresis (rate independent, asymmetric, saturating), in the normalised input
``u = (v_px - low) / (high - low)``::

    dz = rho * (du - sigma * |du| * z + (sigma - 1) * du * |z|)       (Bouc-Wen, n = 1)
    q  = c1 u + c2 u^2 + c3 u^3 - w0 (1 - exp(-u / u_w)) z              (um)

The Bouc-Wen equation is integrated *exactly* over each input increment (it is linear in
``z`` while the signs of ``du`` and ``z`` are fixed), so the output depends only on the
sequence of input values, never on how finely they are sampled.
"""

from __future__ import annotations

import math

from hystcomp._kernels._jit import StepKernels, inline_kernel, kernel, step_kernel

# Parameter slots.
(
    P_LOW,
    P_HIGH,
    P_GAIN,
    P_C1,
    P_C2,
    P_C3,
    P_W0,
    P_UW,
    P_RHO,
    P_SIGMA,
    P_A11,
    P_A12,
    P_A21,
    P_A22,
    P_B1,
    P_B2,
    P_N_CREEP,
) = range(17)
P_CREEP = 17  # then n_creep lag factors a_i, then n_creep gains g_i
# State slots, from state_start(p): last normalised input, Bouc-Wen state, position and
# velocity of D(s), last output, count of non-finite commands, count of clamped outputs
# (always 0: the axis has no output clamp), then the creep lags.
S_U, S_Z, S_POS, S_VEL, S_LAST, S_NONFINITE, S_CLAMPED = range(7)
S_CREEP = 7


@inline_kernel
def state_start(p):
    """Index of the first state slot of packed twin ``p`` (after the creep parameters)."""
    return P_CREEP + 2 * int(p[P_N_CREEP])


@inline_kernel
def bw_rise(z, s, c):
    """Advance the Bouc-Wen state along an *increasing* input by ``s = rho * du >= 0``.

    Solves ``dz/ds = 1 - c z`` for ``z < 0`` (``c = 2 sigma - 1``) and ``dz/ds = 1 - z``
    for ``z >= 0`` exactly, switching law where ``z`` crosses 0. A decreasing input is the
    mirror image: ``-bw_rise(-z, s, c)``.
    """
    if z < 0.0:
        # the part of s needed to reach z = 0: solve z + (1 - c z) phi(c, s0) = 0
        q = -z / (1.0 - c * z)
        s0 = q if abs(c * q) < 1e-12 else -math.log1p(-c * q) / c
        if s <= s0:
            cs = c * s
            phi = s if abs(cs) < 1e-12 else -math.expm1(-cs) / c
            return z + (1.0 - c * z) * phi
        s -= s0
        z = 0.0
    return 1.0 - (1.0 - z) * math.exp(-s)


@inline_kernel
def hysteresis_step(p, s, v):
    """Amplifier and hysteresis for one command sample ``v`` (V): the displacement in µm.

    A non-finite command holds the last one (the amplifier keeps its voltage) and is counted.
    """
    lo = p[P_LOW]
    hi = p[P_HIGH]
    if v - v == 0.0:  # finite
        v_px = min(max(p[P_GAIN] * v, lo), hi)  # the amplifier's rails
        u = (v_px - lo) / (hi - lo)
    else:
        s[S_NONFINITE] += 1.0
        u = s[S_U]
    du = u - s[S_U]
    s[S_U] = u
    z = s[S_Z]
    c = 2.0 * p[P_SIGMA] - 1.0
    if du > 0.0:
        z = bw_rise(z, p[P_RHO] * du, c)
    elif du < 0.0:
        z = -bw_rise(-z, -p[P_RHO] * du, c)
    s[S_Z] = z
    anhysteretic = u * (p[P_C1] + u * (p[P_C2] + u * p[P_C3]))
    return anhysteretic + p[P_W0] * math.expm1(-u / p[P_UW]) * z


# A called kernel, not an inlined one: the step and the batch loop then run the same
# machine code, so they agree bit for bit (inlined, the fast-math contractions differed).
@kernel
def axis_step(p, s, v):
    """One sample of the whole axis: returns the displacement (µm) seen by the sensor now.

    Amplifier and hysteresis, optional creep (first-order lags), then the piezo dynamics
    ``D`` discretised with a zero-order hold: the sensor sees the state before this
    sample's voltage acts, as on a sampled rig.
    """
    q = hysteresis_step(p, s, v)
    n_creep = int(p[P_N_CREEP])
    creep = 0.0
    for i in range(n_creep):
        a = p[P_CREEP + i]
        lag = a * s[S_CREEP + i] + (1.0 - a) * q
        s[S_CREEP + i] = lag
        creep += p[P_CREEP + n_creep + i] * lag
    q += creep
    pos = s[S_POS]
    vel = s[S_VEL]
    s[S_POS] = p[P_A11] * pos + p[P_A12] * vel + p[P_B1] * q
    s[S_VEL] = p[P_A21] * pos + p[P_A22] * vel + p[P_B2] * q
    s[S_LAST] = pos
    return pos


@step_kernel
def twin_step(p, v):
    """One command sample ``v`` (V) through packed twin ``p`` (state kept in ``p``).

    :func:`axis_step` on the state part of ``p``: the displacement (µm) seen by the sensor now.
    """
    return axis_step(p, p[state_start(p) :], v)


@kernel
def twin_run(p, v, out):
    """Run :func:`twin_step` over every sample of ``v`` (state kept in ``p``)."""
    s = p[state_start(p) :]
    for k in range(v.size):
        out[k] = axis_step(p, s, v[k])


@kernel
def hysteresis_run(p, v, out):
    """Run :func:`hysteresis_step` over every sample (quasi-static: no creep, no dynamics)."""
    s = p[state_start(p) :]
    for k in range(v.size):
        out[k] = hysteresis_step(p, s, v[k])


#: The :class:`~hystcomp._kernels._jit.StepKernels` of a packed twin.
TWIN_KERNELS = StepKernels(twin_step, twin_run, state_start.py_func, S_LAST, S_NONFINITE, S_CLAMPED)
