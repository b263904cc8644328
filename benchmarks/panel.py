"""A panel of simulated actuators of none of the three model families, for accuracy benchmarks.

Every compensator of hystcomp is fitted to a model family (PI, MPI, polynomial-Everett
Preisach); an actuator of one of those families would make its own family win by
construction. The actuators here are of none of them, each with sensor noise, creep and a
lightly damped mode:

``twin``
    The built-in simulated axis (:class:`hystcomp.plant.Twin`), as shipped (no creep).
``boucwen``
    An asymmetric Bouc-Wen stage with other shape parameters than the twin's, 3 % creep and
    a 1.2 kHz mode (the twin's kernel, parameterised).
``duhem``
    A Coleman-Hodgdon (Duhem) model with a cubic anhysteretic curve, creep and a 900 Hz mode.
``preisach``
    A Preisach stage of 40 x 40 relays with a skewed, non-polynomial density (a log-normal
    ridge in the loop width times a skewed bump in the loop centre), output saturation
    (``tanh``), creep and an 800 Hz mode.
``kp``
    A Krasnosel'skii-Pokrovskii stage (ramp hysterons of finite width on a 30 x 30 grid),
    a convex-then-saturating output map, creep and a 1 kHz mode.

Usage::

    from benchmarks.panel import ACTUATORS, actuator, excitation, track_ratio
    act = actuator("duhem", seed=0)
    v = excitation("pi", act.sample_rate)
    x = act.run(v)
"""

from __future__ import annotations

import dataclasses

import numba
import numpy as np
from scipy import signal

from hystcomp.experiment.baseline import LinearCompensator, linear_gain
from hystcomp.experiment.references import triangle_reference
from hystcomp.identify.excitation import (
    PREISACH_AMPLITUDES,
    random_turning_points,
    rich_sequence,
    sinusoid_sequence,
    triangle_sequence,
)
from hystcomp.plant import Twin, TwinParameters
from hystcomp.plant.parameters import dynamics_matrices

ACTUATORS = ("twin", "boucwen", "duhem", "preisach", "kp")
EXCITATIONS = ("pi", "preisach", "random", "rich")
V_MAX = 120.0


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
    """A simulated actuator: ``run(v)`` (V at ``sample_rate``) -> measured µm, from rest."""

    def __init__(self, name, quasi_static, dynamics: Dynamics | None, sample_rate, seed):
        self.name = name
        self._quasi_static = quasi_static
        self._dynamics = dynamics
        self.sample_rate = float(sample_rate)
        self.voltage_range = (0.0, V_MAX)
        self._rng = np.random.default_rng(seed)

    def hysteresis(self, v) -> np.ndarray:
        return self._quasi_static(np.asarray(v, dtype=np.float64))

    def run(self, v) -> np.ndarray:
        v = np.clip(np.asarray(v, dtype=np.float64), *self.voltage_range)
        q = self._quasi_static(v)
        if self._dynamics is None:
            return q
        return self._dynamics.apply(q, self.sample_rate, self._rng)


class _TwinActuator(Actuator):
    def __init__(self, name, params, sample_rate, seed):
        self._twin = Twin(params.replace(sample_rate=sample_rate), seed=seed)
        super().__init__(name, self._twin.hysteresis, None, sample_rate, seed)

    def run(self, v) -> np.ndarray:
        return self._twin.run(np.asarray(v, dtype=np.float64))


def _duhem(v):
    out = np.empty_like(v)
    _duhem_run(v, 0.035, 0.20, 0.28, -0.17, 0.13, 0.16, out)
    return out


def _grid(n, skew_density):
    """Relay thresholds on the half plane ``alpha > beta`` of 0..120 V and their weights."""
    edges = np.linspace(0.0, V_MAX, n + 1)
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


def _hysteron_model(n, density, width, out_map):
    alpha, beta, weight = _grid(n, density)

    def run(v):
        state = -np.ones(alpha.size)  # at rest: driven down to 0 V
        raw = np.empty_like(v)
        _hysteron_run(v, alpha, beta, weight, width, state, raw)
        return out_map(raw)

    return run


def actuator(name: str, *, seed: int = 0, sample_rate: float = 20_000.0) -> Actuator:
    """One actuator of the panel (see the module docstring)."""
    if name == "twin":
        return _TwinActuator(name, TwinParameters(), sample_rate, seed)
    if name == "boucwen":
        params = TwinParameters(
            anhysteretic=(34.0, 12.0, -9.0),
            hysteresis_amplitude=3.4,
            hysteresis_onset=0.25,
            bouc_wen_rate=4.0,
            bouc_wen_shape=0.9,
            resonance_hz=1200.0,
            damping_ratio=0.06,
            creep_gain=0.03,
        )
        return _TwinActuator(name, params, sample_rate, seed)
    if name == "duhem":
        return Actuator(name, _duhem, Dynamics(900.0), sample_rate, seed)
    if name == "preisach":
        model = _hysteron_model(
            40, _lognormal_skewed, 0.0, lambda s: 42.0 * np.tanh(1.1 * (s + 1.0) / 2.0)
        )
        return Actuator(name, model, Dynamics(800.0), sample_rate, seed)
    if name == "kp":
        model = _hysteron_model(30, _kp_density, 8.0, lambda s: 35.0 * (0.5 * (s + 1.0)) ** 1.25)
        return Actuator(name, model, Dynamics(1000.0), sample_rate, seed)
    raise ValueError(f"unknown actuator {name!r}; choose one of {ACTUATORS}")


def excitation(kind: str, sample_rate: float) -> np.ndarray:
    """The identification voltage: ``pi`` (the paper's triangles), ``preisach`` (the paper's
    sinusoids), ``random`` (:func:`hystcomp.identify.excitation.random_turning_points`),
    ``rich`` (:func:`hystcomp.identify.excitation.rich_sequence`, ``hystcomp excite rich``)."""
    if kind == "pi":
        return triangle_sequence(sample_rate=sample_rate)[1]
    if kind == "preisach":
        return sinusoid_sequence(PREISACH_AMPLITUDES, sample_rate=sample_rate)[1]
    if kind == "random":
        return random_turning_points(sample_rate=sample_rate)[1]
    if kind == "rich":
        return rich_sequence(sample_rate=sample_rate)[1]
    raise ValueError(f"unknown excitation {kind!r}; choose one of {EXCITATIONS}")


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

    The reference rises from the displacement the actuator returns to at 0 V after the
    paper's 120 V triangle (its remanence: 0.02 to 0.34 µm on most of the panel, 3.4 µm on
    ``duhem``) to 90 % of its stroke, so that every reference is reachable in the voltage
    range.
    """

    def __init__(self, name: str, *, seed: int = 0, sample_rate: float = 20_000.0):
        self.act = actuator(name, seed=seed, sample_rate=sample_rate)
        fs = self.act.sample_rate
        self.records = {}
        v = excitation("pi", fs)
        x = self.act.run(v)
        self.records["pi"] = (v, x)
        self.gain = linear_gain(v, x)
        # from where the actuator comes back to at 0 V after its largest loop (a Duhem
        # stage keeps 3.4 µm there: below it no voltage in range reaches) to 90 % of the stroke
        self.x_low = max(0.0, float(x[-1]))
        amplitude = 0.9 * float(x.max()) - self.x_low
        _, self.x_ref = triangle_reference(
            amplitude, 1.0, periods=3, sample_rate=fs, offset=self.x_low
        )
        self.period = round(fs)
        self.baseline_rms = tracking_rms(
            self.act, LinearCompensator(self.gain, self.act.voltage_range), self.x_ref, self.period
        )

    def record(self, kind: str):
        if kind not in self.records:
            v = excitation(kind, self.act.sample_rate)
            self.records[kind] = (v, self.act.run(v))
        return self.records[kind]

    def ratio(self, model) -> float:
        """Tracking rms of ``model.inverse()`` over the uncompensated rms."""
        return tracking_rms(self.act, model.inverse(), self.x_ref, self.period) / self.baseline_rms
