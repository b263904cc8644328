"""Slow, obviously-correct references for the twin's kernels, written independently of them."""

from __future__ import annotations

import numpy as np
from scipy import signal


def bouc_wen(u, rho, sigma, z0=-1.0, substeps=4000):
    """``dz = rho (du - sigma |du| z + (sigma - 1) du |z|)`` by explicit Euler, many substeps."""
    z, out = float(z0), []
    u_prev = float(u[0])
    for uk in u:
        du = (float(uk) - u_prev) / substeps
        for _ in range(substeps):
            z += rho * (du - sigma * abs(du) * z + (sigma - 1.0) * du * abs(z))
        u_prev = float(uk)
        out.append(z)
    return np.array(out)


def hysteresis(v, params, substeps=4000):
    """The twin's quasi-static displacement (µm): anhysteretic curve minus the hysteretic term."""
    lo, hi = params.voltage_range
    u = (np.clip(params.amplifier_gain * np.asarray(v, dtype=float), lo, hi) - lo) / (hi - lo)
    z = bouc_wen(np.concatenate([[0.0], u]), params.bouc_wen_rate, params.bouc_wen_shape,
                 substeps=substeps)[1:]  # fmt: skip
    c1, c2, c3 = params.anhysteretic
    gain = params.hysteresis_amplitude * (1.0 - np.exp(-u / params.hysteresis_onset))
    return c1 * u + c2 * u**2 + c3 * u**3 - gain * z


def second_order(q, params):
    """``D(s) = wn^2 / (s^2 + 2 zeta wn s + wn^2)`` driven by ``q`` held over each sample.

    Continuous-time simulation (scipy.signal.lsim without interpolation): the output at
    sample k has seen the inputs up to k - 1, as a sampled rig does.
    """
    wn = 2 * np.pi * params.resonance_hz
    system = signal.lti([wn**2], [1.0, 2 * params.damping_ratio * wn, wn**2])
    t = np.arange(len(q)) / params.sample_rate
    _, y, _ = signal.lsim(system, np.asarray(q, dtype=float), t, interp=False)
    return y
