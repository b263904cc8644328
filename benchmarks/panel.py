"""A panel of simulated actuators of none of the three model families, for accuracy benchmarks.

Every compensator of hystcomp is fitted to a model family (PI, MPI, polynomial-Everett
Preisach); an actuator of one of those families would make its own family win by
construction. The actuators here are of none of them, each with sensor noise (3 nm rms),
creep and a lightly damped mode. Each carries its own amplifier range (``voltage_range``)
and sample rate (``sample_rate``); its identification records and references are scaled
to them. Hysteresis is the largest loop width over the displacement range on the
full-range loop of the quasi-static part (``tests/test_panels.py`` holds each within the
band given here):

``twin``
    The built-in simulated axis (:class:`hystcomp.plant.Twin`), as shipped (no creep).
    0..120 V, 20 kHz, 37 µm, 11 % hysteresis.
``boucwen``
    An asymmetric Bouc-Wen stage with other shape parameters than the twin's, 3 % creep and
    a 1.2 kHz mode (the twin's kernel, parameterised). 0..120 V, 20 kHz, 34 µm, 13 %.
``duhem``
    A Coleman-Hodgdon (Duhem) model with a cubic anhysteretic curve, creep and a 900 Hz mode.
    0..120 V, 20 kHz, 36 µm, 17 %.
``preisach``
    A Preisach stage of 40 x 40 relays with a skewed, non-polynomial density (a log-normal
    ridge in the loop width times a skewed bump in the loop centre), output saturation
    (``tanh``), creep and an 800 Hz mode. 0..120 V, 20 kHz, 34 µm, 17 %.
``kp``
    A Krasnosel'skii-Pokrovskii stage (ramp hysterons of finite width on a 30 x 30 grid),
    a convex-then-saturating output map, creep and a 1 kHz mode. 0..120 V, 20 kHz, 35 µm,
    13 %. Held out.
``maxwell``
    A Maxwell-slip stage (Goldfarb and Celanovic's lumped model): the piezo's force
    ``T v`` against a main spring and 30 elasto-slip elements, ``k0 x + sum_i k_i d_i =
    T v``, each element's deflection ``d_i`` following ``x`` until its slip limit ``r_i``
    (limits log-spaced from 0.5 % to 26 % of the stroke, stiffnesses falling with them and
    1.7 times the main spring's in all, both jittered by a seeded draw; solved exactly per
    sample), then an asymmetric cubic output map (steepest at a seventh of the stroke,
    0.37 times as steep at the top). Its thresholds are on no grid of the PI family and its
    output map is smooth. 2 % creep, a 700 Hz mode (zeta 0.06). 0..100 V, 10 kHz, 31 µm,
    14 %.
``narrow``
    A bipolar Preisach stage of 80 x 80 relays whose density vanishes on the diagonal
    (``w^2 exp(-w / 0.1)``, ``w = (alpha - beta)`` over the span of the range: a minor loop
    of small amplitude is a nearly closed curve, its width growing as the fourth power of
    its amplitude; 5 % of the range wide, it is 0.1 % of the stroke wide, a tenth of the
    twin's) beside a convex reversible part, then an asymmetric saturation of the output
    (``tanh``, centred low: the slope at the top of the range is a fifth of the steepest,
    at the bottom three fifths). 3 % creep, a 1 kHz mode (zeta 0.1). -150..+150 V (a
    bipolar amplifier), 5 kHz, -18..+18 µm (0 µm near 0 V), 14 %.
``ratedep``
    A Bouc-Wen stage whose hysteretic amplitude grows with the input's rate (``w0 (1 + 0.2
    r / (r + 3 kV/s))``, ``r`` the rate's magnitude low-passed over 2 ms): the loop of a
    0..120 V triangle is 16 % wider at 50 Hz than at 1 Hz, so no rate-independent model is
    exact. 4 % creep, a 1.5 kHz mode (zeta 0.05). 0..120 V, 20 kHz, 32 µm, 14 %. Held out.
``jiles``
    A Jiles-Atherton polarization (a Langevin anhysteretic curve, ``a = 45 V``, pinning
    ``k = 20 V``, coupling ``alpha = 0.02``, 45 % reversible), ``x = 34 µm M + 0.05 µm/V v``,
    on a semi-bipolar amplifier, with 2.5 % creep from 0.2 to 20 s and a 1.1 kHz mode (zeta
    0.07). -30..150 V, 10 kHz, 32 µm, 12 %. Held out: added after every choice on the
    other stages, and run once.

Tuning and holding out: :data:`ACTUATORS` are the stages that defaults are chosen on;
:data:`HELD_OUT` are kept out of every such choice and checked last (``python
benchmarks/bench_accuracy.py --held-out``). :data:`STAGES` is both.

Usage::

    from benchmarks.panel import ACTUATORS, Bench, actuator, excitation
    act = actuator("duhem", seed=0)
    v = excitation("pi", act.sample_rate, act.voltage_range)
    x = act.run(v)
    bench = Bench("duhem")                         # its 1 Hz reference and baseline
    ratio = bench.ratio(hystcomp.Preisach().fit(*bench.record("rich")))
"""

from __future__ import annotations

import dataclasses

import numba
import numpy as np
from scipy import signal

from hystcomp.experiment.baseline import linear_gain
from hystcomp.experiment.references import triangle_reference
from hystcomp.identify.excitation import (
    excitation_signal,
    random_turning_points,
    rich_sequence,
)
from hystcomp.plant import Twin, TwinParameters
from hystcomp.plant.parameters import dynamics_matrices

#: The stages that defaults are tuned on.
ACTUATORS = ("twin", "boucwen", "duhem", "preisach", "maxwell", "narrow")
#: Held-out stages are not used to tune any default: a default is chosen on ACTUATORS alone
#: and checked on these last (``bench_accuracy.py --held-out``).
HELD_OUT = ("kp", "ratedep", "jiles")
STAGES = ACTUATORS + HELD_OUT
EXCITATIONS = ("pi", "preisach", "random", "rich")
V_MAX = 120.0
UNIPOLAR = (0.0, V_MAX)
BIPOLAR = (-150.0, 150.0)

#: ``name: (voltage_range in V, sample_rate in Hz)`` of each stage.
SPECS = {
    "twin": (UNIPOLAR, 20_000.0),
    "boucwen": (UNIPOLAR, 20_000.0),
    "duhem": (UNIPOLAR, 20_000.0),
    "preisach": (UNIPOLAR, 20_000.0),
    "kp": (UNIPOLAR, 20_000.0),
    "maxwell": ((0.0, 100.0), 10_000.0),
    "narrow": (BIPOLAR, 5_000.0),
    "ratedep": (UNIPOLAR, 20_000.0),
    "jiles": ((-30.0, 150.0), 10_000.0),
}


@numba.njit(cache=True)
def _duhem_run(v, alpha, c1, c2, c3, a, b, out):  # pragma: no cover - compiled
    """Coleman-Hodgdon: dx = alpha |dv| (f(v) - x) + g(v) dv, integrated per increment."""
    x = 0.0
    v_prev = v[0]
    for k in range(v.size):
        dv = v[k] - v_prev
        v_prev = v[k]
        if dv != 0.0:
            # a few sub-steps keep the explicit integration accurate on coarse records
            steps = 1 + int(abs(dv) / 0.25)
            h = dv / steps
            vv = v[k] - dv
            for _ in range(steps):
                vm = vv + 0.5 * h
                u = vm / 120.0
                f = 120.0 * u * (c1 + u * (c2 + u * c3))
                g = a + b * u
                x += alpha * abs(h) * (f - x) + g * h
                vv += h
        out[k] = x


@numba.njit(cache=True)
def _hysteron_run(v, alpha, beta, weight, width, state, out):  # pragma: no cover - compiled
    """Preisach relays (width 0) or Krasnosel'skii-Pokrovskii ramps (width > 0), weighted."""
    for k in range(v.size):
        total = 0.0
        vk = v[k]
        for i in range(alpha.size):
            if width > 0.0:
                up = min(max((vk - alpha[i]) / width, -1.0), 1.0)
                down = min(max((vk - beta[i]) / width, -1.0), 1.0)
                s = min(max(state[i], up), down)
            else:
                s = state[i]
                if vk >= alpha[i]:
                    s = 1.0
                elif vk <= beta[i]:
                    s = -1.0
            state[i] = s
            total += weight[i] * s
        out[k] = total


@numba.njit(cache=True)
def _maxwell_run(f, stiffness, limits, out):  # pragma: no cover - compiled
    """Maxwell slip: ``x + sum_i k_i d_i = f`` (main stiffness 1), exactly, per sample.

    ``d_i`` follows ``x`` while ``|d_i| < r_i`` and sticks at ``+-r_i`` (the element slips):
    the left side is monotone and piecewise linear in ``x``, solved by adding the elements
    that slip within the step one set at a time (each pass can only move ``x`` further).
    At rest (``f = 0``) every element is deflected to ``-r_i``, as after a descent.
    """
    d = -limits.copy()
    x = 0.0
    f_prev = 0.0
    for k in range(f.size):
        df = f[k] - f_prev
        f_prev = f[k]
        if df != 0.0:
            sign = 1.0 if df > 0.0 else -1.0
            dx = 0.0
            for _ in range(limits.size + 1):
                slope = 1.0
                slipped = 0.0
                for i in range(limits.size):
                    room = limits[i] - sign * d[i]  # how far x moves before element i slips
                    if room <= dx:
                        slipped += stiffness[i] * room
                    else:
                        slope += stiffness[i]
                step = (sign * df - slipped) / slope
                if step <= dx:
                    break
                dx = step
            for i in range(limits.size):
                d[i] = sign * min(sign * d[i] + dx, limits[i])
            x += sign * dx
        out[k] = x


@numba.njit(cache=True)
def _ratedep_run(v, lo, hi, fs, shape, rate_gain, rate_half, lag, out):  # pragma: no cover
    """Bouc-Wen (n = 1, normalised input) with a hysteretic amplitude that grows with rate.

    ``shape = (c1, c2, c3, w0, u_w, rho, sigma)`` as the twin's (:mod:`hystcomp._kernels.twin`);
    the amplitude is ``w0 (1 + rate_gain r / (r + rate_half))``, ``r`` the input's rate
    (V/s) through a first-order lag of pole ``lag``. Sub-steps of 0.2 % of the range.
    """
    c1, c2, c3, w0, uw, rho, sigma = shape
    span = hi - lo
    z = -1.0
    u_prev = 0.0
    rate = 0.0
    for k in range(v.size):
        u = (v[k] - lo) / span
        du = u - u_prev
        u_prev = u
        rate = lag * rate + (1.0 - lag) * abs(du) * span * fs
        if du != 0.0:
            steps = 1 + int(abs(du) / 0.002)
            h = du / steps
            for _ in range(steps):
                z += rho * (h - sigma * abs(h) * z + (sigma - 1.0) * h * abs(z))
        amplitude = w0 * (1.0 + rate_gain * rate / (rate + rate_half))
        out[k] = u * (c1 + u * (c2 + u * c3)) - amplitude * (1.0 - np.exp(-u / uw)) * z


@numba.njit(cache=True)
def _jiles_run(v, ms, a, k, alpha, c, out):  # pragma: no cover - compiled
    """Jiles-Atherton polarization, integrated in sub-steps of at most 0.25 V.

    ``M_an = ms (coth(H_e / a) - a / H_e)``, ``H_e = v + alpha M``; the irreversible part
    moves as ``dM_irr/dv = (M_an - M_irr) / (delta k - alpha (M_an - M_irr))`` only towards
    ``M_an`` (``delta`` the sign of ``dv``); ``M = c M_an + (1 - c) M_irr``.
    """
    m_irr = 0.0
    m = 0.0
    v_prev = v[0]
    for j in range(v.size):
        dv = v[j] - v_prev
        v_prev = v[j]
        if dv != 0.0:
            steps = 1 + int(abs(dv) / 0.25)
            h = dv / steps
            vv = v[j] - dv
            delta = 1.0 if h > 0.0 else -1.0
            for _ in range(steps):
                vv += h
                he = vv + alpha * m
                r = he / a
                man = ms * (1.0 / np.tanh(r) - 1.0 / r) if abs(r) > 1e-4 else ms * r / 3.0
                gap = man - m_irr
                if gap * delta > 0.0:
                    m_irr += h * gap / (delta * k - alpha * gap)
                m = c * man + (1.0 - c) * m_irr
        out[j] = m


@dataclasses.dataclass(frozen=True)
class Dynamics:
    """Creep, a lightly damped mode and a noisy sensor behind a quasi-static hysteresis."""

    resonance_hz: float
    damping: float = 0.08
    creep_gain: float = 0.03
    creep_taus: tuple[float, ...] = (0.1, 1.0, 10.0)
    noise_um: float = 0.003

    def apply(self, q: np.ndarray, sample_rate: float, rng) -> np.ndarray:
        out = q.copy()
        for tau in self.creep_taus:
            a = np.exp(-1.0 / (tau * sample_rate))
            lag = signal.lfilter([1.0 - a], [1.0, -a], q, zi=[a * q[0]])[0]
            out += self.creep_gain / len(self.creep_taus) * (lag - q[0])
        params = TwinParameters(
            sample_rate=sample_rate, resonance_hz=self.resonance_hz, damping_ratio=self.damping
        )
        ad, bd = dynamics_matrices(params)
        num, den = signal.ss2tf(ad, bd[:, None], np.array([[1.0, 0.0]]), np.zeros((1, 1)))
        num = num[0] / (np.sum(num[0]) / np.sum(den))  # unit static gain
        zi = signal.lfiltic(num, den, np.full(3, out[0]), np.full(3, out[0]))
        x = signal.lfilter(num, den, out, zi=zi)[0]
        return x + self.noise_um * rng.standard_normal(x.size)


class Actuator:
    """A simulated actuator: ``run(v)`` (V at ``sample_rate``) -> measured µm, from rest.

    The amplifier clips the voltage to ``voltage_range`` before the stage sees it, in
    :meth:`run` and in :meth:`hysteresis` (the quasi-static part alone).
    """

    def __init__(
        self, name, quasi_static, dynamics: Dynamics | None, sample_rate, seed, voltage_range
    ):
        self.name = name
        self._quasi_static = quasi_static
        self._dynamics = dynamics
        self.sample_rate = float(sample_rate)
        self.voltage_range = tuple(float(b) for b in voltage_range)
        self._rng = np.random.default_rng(seed)

    def hysteresis(self, v) -> np.ndarray:
        return self._quasi_static(np.clip(np.asarray(v, dtype=np.float64), *self.voltage_range))

    def run(self, v) -> np.ndarray:
        q = self.hysteresis(v)
        if self._dynamics is None:
            return q
        return self._dynamics.apply(q, self.sample_rate, self._rng)


class _TwinActuator(Actuator):
    def __init__(self, name, params, sample_rate, seed):
        self._twin = Twin(params.replace(sample_rate=sample_rate), seed=seed)
        super().__init__(
            name, self._twin.hysteresis, None, sample_rate, seed, self._twin.voltage_range
        )

    def run(self, v) -> np.ndarray:
        return self._twin.run(np.asarray(v, dtype=np.float64))


def duhem(v):
    """The quasi-static part of ``duhem`` (0..120 V)."""
    out = np.empty_like(v)
    _duhem_run(v, 0.035, 0.20, 0.28, -0.17, 0.13, 0.16, out)
    return out


def _grid(n, skew_density, voltage_range=UNIPOLAR):
    """Relay thresholds on the half plane ``alpha > beta`` of the range and their weights."""
    edges = np.linspace(*voltage_range, n + 1)
    mid = 0.5 * (edges[:-1] + edges[1:])
    a, b = np.meshgrid(mid, mid, indexing="ij")
    keep = a > b
    a, b = a[keep], b[keep]
    w = skew_density(a, b)
    return a.copy(), b.copy(), w / w.sum()


def _lognormal_skewed(a, b):
    width = a - b
    centre = 0.5 * (a + b)
    ridge = np.exp(-((np.log(width / 12.0)) ** 2) / 0.9) / width
    bump = (1.0 + 2.5 * (centre / V_MAX) ** 1.5) * np.exp(-(((centre - 45.0) / 55.0) ** 2))
    return ridge * bump + 0.25 * np.exp(-width / 3.0)


def _kp_density(a, b):
    width = a - b
    centre = 0.5 * (a + b)
    return np.exp(-width / 7.0) * (0.4 + np.sin(np.pi * centre / V_MAX) ** 2)


def hysteron_model(n, density, width, out_map, voltage_range=UNIPOLAR, reversible=None):
    """Relays (``width`` 0) or KP ramps on an ``n x n`` grid of ``voltage_range``, at rest
    driven down to its low end; ``out_map(s, v)`` of their weighted sum ``s`` (-1 .. 1) and
    the voltage (for a reversible part)."""
    alpha, beta, weight = _grid(n, density, voltage_range)

    def run(v):
        state = -np.ones(alpha.size)  # at rest: driven down to the low end
        raw = np.empty_like(v)
        _hysteron_run(v, alpha, beta, weight, width, state, raw)
        return out_map(raw, v)

    return run


def preisach_stage(v):
    """The quasi-static part of ``preisach`` (0..120 V)."""
    return _PREISACH(v)


def kp_stage(v):
    """The quasi-static part of ``kp`` (0..120 V)."""
    return _KP(v)


_PREISACH = hysteron_model(
    40, _lognormal_skewed, 0.0, lambda s, v: 42.0 * np.tanh(1.1 * (s + 1.0) / 2.0)
)
_KP = hysteron_model(30, _kp_density, 8.0, lambda s, v: 35.0 * (0.5 * (s + 1.0)) ** 1.25)


def maxwell_slip(voltage_range=(0.0, 100.0), *, seed=7):
    """The quasi-static part of ``maxwell`` on ``voltage_range`` (see the module).

    ``x + sum k_i d_i = T (v - lo)`` (:func:`_maxwell_run`), normalised by its value at the
    top of the range from rest (``p``), then ``31 µm * (1.2 p + 0.15 p^2 - 0.35 p^3)``.
    """
    lo, hi = voltage_range
    rng = np.random.default_rng(seed)
    n = 30
    limits = np.geomspace(0.15, 9.0, n) * rng.uniform(0.8, 1.25, n)
    stiffness = 0.09 * np.exp(-limits / 4.0) * rng.uniform(0.6, 1.4, n)
    drive = 40.0 / (hi - lo)

    def raw(v):
        out = np.empty_like(v)
        _maxwell_run(drive * (v - lo), stiffness, limits, out)
        return out

    top = float(raw(np.linspace(lo, hi, 1001))[-1])

    def run(v):
        p = raw(v) / top
        return 31.0 * p * (1.2 + p * (0.15 - 0.35 * p))

    return run


def narrow_preisach(voltage_range=BIPOLAR, n=80):
    """The quasi-static part of ``narrow`` on ``voltage_range`` (see the module): ``n x n``
    relays of a density that vanishes on the diagonal, a convex reversible part, a
    saturation that is harder at the top of the range than at the bottom."""
    lo, hi = voltage_range

    def density(a, b):
        width = (a - b) / (hi - lo)
        centre = (0.5 * (a + b) - lo) / (hi - lo)
        return width**2 * np.exp(-width / 0.1) * (1.0 + 0.8 * centre)

    def out_map(s, v):
        u = (v - lo) / (hi - lo)
        z = 0.74 * u * (0.8 + 0.2 * u) + 0.13 * (s + 1.0)
        return 23.5 * np.tanh(2.2 * (z - 0.35)) - 2.7

    return hysteron_model(n, density, 0.0, out_map, voltage_range)


#: The twin's Bouc-Wen shape ``(c1, c2, c3, w0, u_w, rho, sigma)`` for ``ratedep``.
RATEDEP_SHAPE = (26.0, 30.0, -21.0, 2.6, 0.12, 6.0, 0.7)


def rate_dependent_bouc_wen(voltage_range=UNIPOLAR, sample_rate=20_000.0):
    """The quasi-static part of ``ratedep`` (see the module): its loop widens with rate."""
    lo, hi = voltage_range
    lag = float(np.exp(-1.0 / (0.002 * sample_rate)))
    shape = np.array(RATEDEP_SHAPE)

    def run(v):
        out = np.empty_like(v)
        _ratedep_run(v, lo, hi, float(sample_rate), shape, 0.2, 3000.0, lag, out)
        return out

    return run


def jiles_atherton(gain=34.0, slope=0.05):
    """The quasi-static part of ``jiles``: a Jiles-Atherton polarization (not of any model
    family) on -30..150 V, ``x = gain M + slope v`` (µm, V)."""

    def run(v):
        out = np.empty_like(v)
        _jiles_run(v, 1.0, 45.0, 20.0, 0.02, 0.45, out)
        return gain * out + slope * v

    return run


#: ``boucwen``: the twin with another Bouc-Wen shape, 3 % creep and a 1.2 kHz mode.
BOUCWEN = TwinParameters(
    anhysteretic=(34.0, 12.0, -9.0),
    hysteresis_amplitude=3.4,
    hysteresis_onset=0.25,
    bouc_wen_rate=4.0,
    bouc_wen_shape=0.9,
    resonance_hz=1200.0,
    damping_ratio=0.06,
    creep_gain=0.03,
)


def actuator(name: str, *, seed: int = 0, sample_rate: float | None = None) -> Actuator:
    """One actuator of the panel (see the module docstring), at its own sample rate unless
    ``sample_rate`` (Hz) is given."""
    if name not in SPECS:
        raise ValueError(f"unknown actuator {name!r}; choose one of {STAGES}")
    voltage_range, own_rate = SPECS[name]
    fs = own_rate if sample_rate is None else float(sample_rate)
    if name == "twin":
        return _TwinActuator(name, TwinParameters(), fs, seed)
    if name == "boucwen":
        return _TwinActuator(name, BOUCWEN, fs, seed)
    stages = {
        "duhem": (duhem, Dynamics(900.0)),
        "preisach": (preisach_stage, Dynamics(800.0)),
        "kp": (kp_stage, Dynamics(1000.0)),
        "maxwell": (
            maxwell_slip(voltage_range),
            Dynamics(700.0, damping=0.06, creep_gain=0.02, creep_taus=(0.05, 0.5, 5.0)),
        ),
        "narrow": (narrow_preisach(voltage_range), Dynamics(1000.0, damping=0.1)),
        "ratedep": (
            rate_dependent_bouc_wen(voltage_range, fs),
            Dynamics(1500.0, damping=0.05, creep_gain=0.04),
        ),
        "jiles": (
            jiles_atherton(),
            Dynamics(1100.0, damping=0.07, creep_gain=0.025, creep_taus=(0.2, 2.0, 20.0)),
        ),
    }
    quasi_static, dynamics = stages[name]
    return Actuator(name, quasi_static, dynamics, fs, seed, voltage_range)


def excitation(kind: str, sample_rate: float, voltage_range=UNIPOLAR) -> np.ndarray:
    """The identification voltage over ``voltage_range`` (V) at ``sample_rate`` (Hz):

    ``pi`` (the paper's triangles) and ``preisach`` (the paper's sinusoids), their amplitudes
    scaled from 0..120 V to the range (:func:`hystcomp.identify.excitation.excitation_signal`);
    ``random`` (:func:`hystcomp.identify.excitation.random_turning_points`) and ``rich``
    (:func:`hystcomp.identify.excitation.rich_sequence`, ``hystcomp excite rich``), ramps at
    the slope of the largest triangle (twice the span per second: 240 V/s on 0..120 V).
    """
    lo, hi = (float(b) for b in voltage_range)
    if kind in ("pi", "preisach"):
        return excitation_signal(kind, sample_rate=sample_rate, voltage_range=(lo, hi))[1]
    rate = 2.0 * (hi - lo)
    if kind == "random":
        _, v = random_turning_points(rate=rate, sample_rate=sample_rate, voltage_range=(lo, hi))
        return v
    if kind == "rich":
        return rich_sequence(rate=rate, sample_rate=sample_rate, v_min=lo, v_max=hi)[1]
    raise ValueError(f"unknown excitation {kind!r}; choose one of {EXCITATIONS}")


class RestLine:
    """The uncompensated baseline: the straight line ``v = lo + (x_ref - x_rest) / gain``
    through the stage's rest point, clamped to the range (on 0..120 V stages at rest at
    0 µm, :class:`hystcomp.experiment.baseline.LinearCompensator`)."""

    def __init__(self, gain, voltage_range, x_rest):
        self.gain = float(gain)
        self.voltage_range = voltage_range
        self.x_rest = float(x_rest)

    def simulate(self, x_ref) -> np.ndarray:
        lo, hi = self.voltage_range
        return np.clip(lo + (np.asarray(x_ref) - self.x_rest) / self.gain, lo, hi)


def tracking_rms(act: Actuator, compensator, x_ref: np.ndarray, period: int) -> float:
    """Rms tracking error (µm) over the periods after the first."""
    v = compensator.simulate(x_ref)
    lo, hi = act.voltage_range
    assert v.min() >= lo - 1e-9
    assert v.max() <= hi + 1e-9
    x = act.run(v)
    window = slice(period, period * (x_ref.size // period))
    return float(np.sqrt(np.mean((x[window] - x_ref[window]) ** 2)))


@dataclasses.dataclass
class Cell:
    """The measured tracking of one compensator on one actuator, relative to none."""

    actuator: str
    excitation: str
    method: str
    rms_um: float
    ratio: float


class Bench:
    """One actuator with its 1 Hz triangle reference and its uncompensated baseline.

    The reference rises from the displacement the actuator returns to at the low end of
    its range after the paper's triangles (its remanence: 0.02 to 0.34 µm above rest on
    most of the panel, 3.4 µm on ``duhem``) to 90 % of its stroke above rest, so that every
    reference is reachable in the voltage range. The baseline is the straight line through
    the rest point (:class:`RestLine`) with the least-squares slope of the triangles' record.
    """

    def __init__(self, name: str, *, seed: int = 0, sample_rate: float | None = None):
        self.act = actuator(name, seed=seed, sample_rate=sample_rate)
        fs = self.act.sample_rate
        lo = self.act.voltage_range[0]
        self.records = {}
        v = excitation("pi", fs, self.act.voltage_range)
        x = self.act.run(v)
        self.records["pi"] = (v, x)
        self.x_rest = float(self.act.hysteresis(np.array([lo]))[0])
        self.gain = linear_gain(v - lo, x - self.x_rest)
        # from where the actuator comes back to at the low end after its largest loop (a
        # Duhem stage keeps 3.4 µm there: below it no voltage in range reaches) to 90 % of
        # the stroke
        self.x_low = max(self.x_rest, float(x[-1]))
        amplitude = self.x_rest + 0.9 * (float(x.max()) - self.x_rest) - self.x_low
        _, self.x_ref = triangle_reference(
            amplitude, 1.0, periods=3, sample_rate=fs, offset=self.x_low
        )
        self.period = round(fs)
        self.baseline = RestLine(self.gain, self.act.voltage_range, self.x_rest)
        self.baseline_rms = tracking_rms(self.act, self.baseline, self.x_ref, self.period)

    def record(self, kind: str):
        if kind not in self.records:
            v = excitation(kind, self.act.sample_rate, self.act.voltage_range)
            self.records[kind] = (v, self.act.run(v))
        return self.records[kind]

    def ratio(self, model) -> float:
        """Tracking rms of ``model.inverse()`` over the uncompensated rms."""
        return tracking_rms(self.act, model.inverse(), self.x_ref, self.period) / self.baseline_rms
