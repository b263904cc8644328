"""Compiled loops of the simulated raster scanner's axes (:mod:`hystcomp.plant.scanner`).

Hysteresis besides the twin's Bouc-Wen (:mod:`hystcomp._kernels.twin`), and the lightly
damped mode every axis has:

* :func:`kp_run`: Krasnosel'skii-Pokrovskii hysterons, ramps of finite width on a grid of the
  half plane ``alpha > beta`` of the normalised input (0 .. 1 over the range), weighted,
  each at rest driven down to the low end; a width near 0 makes them Preisach relays;
* :func:`mode_run`: the zero-order-hold discretised second-order mode (position and velocity).

Kernels trust their input; the plant validates.
"""

from __future__ import annotations

from hystcomp._kernels._jit import kernel


@kernel
def kp_run(u, alpha, beta, weight, width, state, out):
    """Krasnosel'skii-Pokrovskii ramps (thresholds ``alpha > beta``, ``width`` > 0) of the
    normalised input ``u``: ``out[k] = sum_i weight_i s_i[k]``, ``s_i`` in -1 .. 1; ``state``
    holds the ramps' states (updated in place)."""
    for k in range(u.size):
        total = 0.0
        uk = u[k]
        for i in range(alpha.size):
            up = min(max((uk - alpha[i]) / width, -1.0), 1.0)
            down = min(max((uk - beta[i]) / width, -1.0), 1.0)
            s = min(max(state[i], up), down)
            state[i] = s
            total += weight[i] * s
        out[k] = total


@kernel
def mode_run(q, ad, bd, out):
    """The mode's position for the input ``q`` from rest at ``q[0]`` (unit steady-state gain):
    the sensor sees the state before this sample's input acts, as on a sampled rig."""
    pos = q[0]
    vel = 0.0
    for k in range(q.size):
        out[k] = pos
        p = ad[0, 0] * pos + ad[0, 1] * vel + bd[0] * q[k]
        vel = ad[1, 0] * pos + ad[1, 1] * vel + bd[1] * q[k]
        pos = p
