"""A panel of stages for the compensation of creep and vibration (beyond the paper).

hystcomp can put an inverse of the identified linear dynamics in series with the hysteresis
inverse (:class:`hystcomp.LinearDynamics`). The stages here test it on what no model holds
exactly: each is ::

    voltage -> amplifier rails -> quasi-static hysteresis -> creep -> resonance(s)
            -> latency -> sensor noise (3 nm rms, seeded)

at 20 kHz on 0..120 V, its hysteresis of none of the model families (the kinds of
:mod:`benchmarks.panel`, shifted to rest at 0 µm: 31 to 36 µm of stroke, 9 to 14 %
hysteresis) and its linear part of unit steady-state gain. Creep is the share of the final
displacement that comes after a step, once the mode has settled; latency is in whole samples
beyond the sample-and-hold's one (as :class:`hystcomp.LinearDynamics` counts it).

================  ============  =============================  ==============================  ===
stage             hysteresis    modes: Hz (damping ratio)      creep                           lat
================  ============  =============================  ==============================  ===
``narrow400``     narrow        400 (0.2)                      5 %, lags 10 ms .. 10 s         0
``boucwen630``    Bouc-Wen      630 (0.12)                     3 %, log-uniform 10 ms .. 10 s  0
``maxwell900``    Maxwell slip  900 (0.07)                     2 %, lags 30 ms .. 3 s          2
``narrow1200``    narrow        1200 (0.05) + 3100 (0.03) 8 %  3 %, lags 10 ms .. 10 s         0
``boucwen2000``   Bouc-Wen      2000 (0.02)                    1 %, lags 10 ms, 100 ms         1
``maxwell1500``   Maxwell slip  1500 (0.035)                   4 %, lags 0.1 .. 10 s           0
``kp800`` (held)  KP            800 (0.1)                      2.5 %, log-uniform 10 ms..10 s  1
================  ============  =============================  ==============================  ===

* Hysteresis: ``narrow`` is :func:`benchmarks.panel.narrow_preisach` on 0..120 V (60 x 60
  relays; its small loops nearly closed curves), ``Bouc-Wen`` the ``boucwen`` stage's
  (:data:`benchmarks.panel.BOUCWEN`), ``Maxwell slip`` :func:`benchmarks.panel.maxwell_slip`
  on 0..120 V (with its cubic output map), KP the ``kp`` stage's (0.65 of it) beside a
  reversible part (``12 µm u (1.2 - 0.2 u)``, ``u = v / 120 V``): alone, its hysterons
  stick for several volts after a reversal, so that a small signal around mid-range moves
  it by steps only (a backlash that no piezo stage has, and from which no dynamics can be
  identified; the relays of the ``preisach`` stage alike). 35 µm, 9 % hysteresis.
* Modes: each a zero-order-hold discretised ``wn^2 / (s^2 + 2 zeta wn s + wn^2)``; the two
  of ``narrow1200`` are in parallel (modal), the second with 8 % of the static gain: the
  response peaks at 8.9 at 1.2 kHz and at 1.3 at 3.1 kHz.
* Creep: "lags", first-order lags ``y[k] = a y[k-1] + (1 - a) u[k]``, one per decade of the
  span, equal weights, exactly the creep bank of :class:`hystcomp.LinearDynamics`;
  "log-uniform" (:class:`LogCreep`), a continuum of such lags with time constants spread
  evenly in ``log tau`` over 10 ms .. 10 s, so that the step response rises as ``log t``
  there: no finite bank of lags is exact.

:meth:`DynamicsStage.true_dynamics` gives the linear part as a
:class:`hystcomp.LinearDynamics`: exact where the structure allows (one mode or two in
parallel, creep by lags); for the log-uniform creep of ``boucwen630`` and ``kp800`` lags
fitted to its step response (one per half decade, non-negative least squares);
:attr:`DynamicsStage.dynamics_exact` says which. (``LinearDynamics`` held one mode before it
held two: the bound of ``narrow1200`` was then its dominant mode alone,
:meth:`LinearPart.true_dynamics` with ``modes=1``.)

Tuning and holding out: defaults are chosen on :data:`DYNAMICS_STAGES`;
:data:`DYNAMICS_HELD_OUT` (``kp800``, whose hysteresis kind is held out of the accuracy panel
too) is kept out of every such choice and checked last.

The references (:func:`references`) and the measurement (:func:`tracking`) are those of the
targets of ``benchmarks/bench_dynamics.py``: triangles over 5..90 % of the stroke at 1, 10,
100 and 200 Hz, rms over the periods after the first; a step from 10 % to 60 % of the stroke
held 3 s, mean |error| from 20 ms to 3 s after it.

Usage::

    from benchmarks.dynamics_panel import DYNAMICS_STAGES, stage, tracking
    st = stage("maxwell900")
    x = st.run(v)                                   # measured µm, from rest
    errors = tracking(st, model.inverse(dynamics=dyn))   # {"1 Hz": rms, ..., "step": mean}
"""

from __future__ import annotations

import dataclasses

import numpy as np
from benchmarks.panel import BOUCWEN, kp_stage, maxwell_slip, narrow_preisach
from scipy import optimize, signal, special

from hystcomp import LinearDynamics
from hystcomp.experiment.references import triangle_reference
from hystcomp.plant import Twin

#: The stages that defaults are tuned on.
DYNAMICS_STAGES = (
    "narrow400",
    "boucwen630",
    "maxwell900",
    "narrow1200",
    "boucwen2000",
    "maxwell1500",
)
#: Held-out stages are not used to tune any default: a default is chosen on DYNAMICS_STAGES
#: alone and checked on these last.
DYNAMICS_HELD_OUT = ("kp800",)
SAMPLE_RATE = 20_000.0
VOLTAGE_RANGE = (0.0, 120.0)
NOISE_UM = 0.003

#: Triangle references: frequency (Hz) -> periods (the first is not scored).
PERIODS = {1.0: 3, 10.0: 5, 100.0: 10, 200.0: 20}
TRIANGLE_SPAN = (0.05, 0.90)  # of the stroke
STEP_LEVELS = (0.10, 0.60)  # of the stroke
STEP_BEFORE = 0.5  # s at the first level
STEP_HOLD = 3.0  # s at the second
STEP_FROM = 0.02  # s after the step: the scored window starts here


@dataclasses.dataclass(frozen=True)
class LagCreep:
    """Creep by first-order lags of equal weights: ``fraction`` of the final displacement
    comes after a step, with the ``time_constants`` (s)."""

    fraction: float
    time_constants: tuple[float, ...]

    @property
    def weights(self) -> np.ndarray:
        """``c_i`` of :class:`hystcomp.LinearDynamics` (``sum c / (1 + sum c) = fraction``)."""
        n = len(self.time_constants)
        return np.full(n, self.fraction / (1.0 - self.fraction) / n)

    def apply(self, u: np.ndarray, sample_rate: float) -> np.ndarray:
        """The creep bank's output for ``u`` from rest at 0."""
        out = u.copy()
        for tau, c in zip(self.time_constants, self.weights, strict=True):
            a = np.exp(-1.0 / (tau * sample_rate))
            out += c * signal.lfilter([1.0 - a], [1.0, -a], u)
        return out / (1.0 + self.weights.sum())

    def response(self, z1: np.ndarray, sample_rate: float) -> np.ndarray:
        """The bank at ``z^-1 = z1``."""
        out = np.ones_like(z1)
        for tau, c in zip(self.time_constants, self.weights, strict=True):
            a = np.exp(-1.0 / (tau * sample_rate))
            out = out + c * (1.0 - a) / (1.0 - a * z1)
        return out / (1.0 + self.weights.sum())

    def lags(self, sample_rate: float) -> tuple[np.ndarray, np.ndarray]:
        """``(time constants, weights)`` of :class:`hystcomp.LinearDynamics`: exact."""
        return np.asarray(self.time_constants, dtype=float), self.weights


@dataclasses.dataclass(frozen=True)
class LogCreep:
    """Creep by a continuum of first-order lags, time constants spread evenly in ``log tau``
    over ``tau_min .. tau_max`` (s): after a step, ``fraction`` of the final displacement is
    still to come, ``R(t) = fraction (E1(t / tau_max) - E1(t / tau_min)) / ln(tau_max /
    tau_min)`` of it at ``t``, which falls as ``log t`` between the two."""

    fraction: float
    tau_min: float = 0.01
    tau_max: float = 10.0

    def remaining(self, t) -> np.ndarray:
        """``R(t)``: the share of the final displacement still to come ``t`` s after a step."""
        t = np.asarray(t, dtype=float)
        span = np.log(self.tau_max / self.tau_min)
        with np.errstate(divide="ignore", invalid="ignore"):
            r = (special.exp1(t / self.tau_max) - special.exp1(t / self.tau_min)) / span
        return self.fraction * np.where(t > 0.0, r, 1.0)

    def apply(self, u: np.ndarray, sample_rate: float) -> np.ndarray:
        """The output for ``u`` from rest at 0: ``u`` convolved with the impulse response of
        the continuum (whose step response is ``1 - R((k + 1) Ts)`` at sample ``k``, as a
        lag's ``1 - a^(k + 1)``)."""
        rest = 1.0 - self.remaining(np.arange(1, u.size + 1) / sample_rate)
        h = np.diff(np.r_[0.0, rest])
        return signal.fftconvolve(u, h)[: u.size]

    def response(self, z1: np.ndarray, sample_rate: float) -> np.ndarray:
        """The continuum at ``z^-1 = z1``: the mean of its lags' responses (midpoint rule in
        ``log tau``, 4000 nodes)."""
        edges = np.linspace(np.log(self.tau_min), np.log(self.tau_max), 4001)
        a = np.exp(-1.0 / (np.exp(0.5 * (edges[1:] + edges[:-1])) * sample_rate))
        lags = ((1.0 - a) / (1.0 - a * np.asarray(z1)[..., None])).mean(axis=-1)
        return 1.0 - self.fraction + self.fraction * lags

    def lags(self, sample_rate: float) -> tuple[np.ndarray, np.ndarray]:
        """``(time constants, weights)`` of lags, one per half decade over the span, fitted
        to ``R(t)`` on 1 ms .. 100 s (non-negative least squares, log-spaced times): an
        approximation."""
        decades = np.log10(self.tau_max / self.tau_min)
        taus = self.tau_min * np.logspace(0.0, decades, round(2 * decades) + 1)
        t = np.logspace(-3.0, 2.0, 400)
        shares, _ = optimize.nnls(np.exp(-t[:, None] / taus), self.remaining(t))
        return taus, shares / (1.0 - shares.sum())


@dataclasses.dataclass(frozen=True)
class Mode:
    """A zero-order-hold discretised ``wn^2 / (s^2 + 2 zeta wn s + wn^2)``, ``weight`` of the
    static gain."""

    hz: float
    damping: float
    weight: float = 1.0

    def ba(self, sample_rate: float) -> tuple[np.ndarray, np.ndarray]:
        """``(b, a)`` in powers of ``z^-1``: the position before the sample's input acts."""
        wn = 2.0 * np.pi * self.hz
        system = (
            np.array([[0.0, 1.0], [-(wn**2), -2.0 * self.damping * wn]]),
            np.array([[0.0], [wn**2]]),
            np.array([[1.0, 0.0]]),
            np.zeros((1, 1)),
        )
        ad, bd, c, d, _ = signal.cont2discrete(system, 1.0 / sample_rate, method="zoh")
        b, a = signal.ss2tf(ad, bd, c, d)
        return self.weight * b[0], a


@dataclasses.dataclass(frozen=True)
class LinearPart:
    """``z^-latency M(z) C(z)``: creep ``C``, the modes ``M`` in parallel, the latency;
    unit gain at steady state."""

    creep: LagCreep | LogCreep
    modes: tuple[Mode, ...]
    latency: int = 0
    sample_rate: float = SAMPLE_RATE

    def apply(self, u, rest: float | None = None) -> np.ndarray:
        """The output (µm) for the input ``u`` (µm), from rest at ``rest`` (``u[0]`` if None)."""
        u = np.asarray(u, dtype=np.float64)
        rest = float(u[0]) if rest is None else float(rest)
        q = self.creep.apply(u - rest, self.sample_rate)
        x = sum(signal.lfilter(*m.ba(self.sample_rate), q) for m in self.modes)
        x = np.r_[np.zeros(min(self.latency, x.size)), x[: x.size - self.latency]]
        return rest + x

    def frequency_response(self, frequencies) -> np.ndarray:
        """At ``frequencies`` (Hz), complex."""
        z1 = np.exp(-2j * np.pi * np.asarray(frequencies, dtype=float) / self.sample_rate)
        modes = sum(
            np.polyval(b[::-1], z1) / np.polyval(a[::-1], z1)
            for b, a in (m.ba(self.sample_rate) for m in self.modes)
        )
        return self.creep.response(z1, self.sample_rate) * modes * z1**self.latency

    @property
    def exact(self) -> bool:
        """Whether :meth:`true_dynamics` is this linear part exactly."""
        return isinstance(self.creep, LagCreep) and len(self.modes) <= 2

    def true_dynamics(self, modes: int = 2) -> LinearDynamics:
        """The part as a :class:`hystcomp.LinearDynamics`: its first ``modes`` modes (a
        second one's weight its share of the static gain; ``modes=1``, the dominant mode
        alone at unit gain), and the creep's lags (exact or fitted, see :attr:`exact`)."""
        taus, weights = self.creep.lags(self.sample_rate)
        second = {}
        if modes > 1 and len(self.modes) > 1:
            second = {
                "second_resonance_hz": self.modes[1].hz,
                "second_damping_ratio": self.modes[1].damping,
                "second_mode_gain": self.modes[1].weight,
            }
        return LinearDynamics.from_parameters(
            sample_rate=self.sample_rate,
            resonance_hz=self.modes[0].hz,
            damping_ratio=self.modes[0].damping,
            creep_time_constants=taus,
            creep_weights=weights,
            delay_samples=self.latency,
            **second,
        )


def _decades(first, last):
    return tuple(first * 10.0**k for k in range(round(np.log10(last / first)) + 1))


#: ``name: (hysteresis kind, linear part)``.
SPECS = {
    "narrow400": ("narrow", LinearPart(LagCreep(0.05, _decades(0.01, 10.0)), (Mode(400, 0.2),))),
    "boucwen630": ("boucwen", LinearPart(LogCreep(0.03), (Mode(630, 0.12),))),
    "maxwell900": (
        "maxwell",
        LinearPart(LagCreep(0.02, _decades(0.03, 3.0)), (Mode(900, 0.07),), latency=2),
    ),
    "narrow1200": (
        "narrow",
        LinearPart(
            LagCreep(0.03, _decades(0.01, 10.0)), (Mode(1200, 0.05, 0.92), Mode(3100, 0.03, 0.08))
        ),
    ),
    "boucwen2000": (
        "boucwen",
        LinearPart(LagCreep(0.01, (0.01, 0.1)), (Mode(2000, 0.02),), latency=1),
    ),
    "maxwell1500": (
        "maxwell",
        LinearPart(LagCreep(0.04, _decades(0.1, 10.0)), (Mode(1500, 0.035),)),
    ),
    "kp800": ("kp", LinearPart(LogCreep(0.025), (Mode(800, 0.1),), latency=1)),
}


def _hysteresis(kind):
    """The quasi-static map of ``kind`` on :data:`VOLTAGE_RANGE`, shifted to rest at 0 µm."""
    if kind == "narrow":
        raw = narrow_preisach(VOLTAGE_RANGE, n=60)
    elif kind == "boucwen":
        raw = Twin(BOUCWEN).hysteresis
    elif kind == "maxwell":
        raw = maxwell_slip(VOLTAGE_RANGE)
    else:  # KP beside a reversible part, as every stage answers a small signal

        def raw(v):
            u = (v - VOLTAGE_RANGE[0]) / (VOLTAGE_RANGE[1] - VOLTAGE_RANGE[0])
            return 0.65 * kp_stage(v) + 12.0 * u * (1.2 - 0.2 * u)

    rest = float(raw(np.array([VOLTAGE_RANGE[0]]))[0])
    return lambda v: raw(v) - rest


class DynamicsStage:
    """One stage of the panel: ``run(v)`` (V) -> measured µm, from rest at the low rail.

    Attributes
    ----------
    name, sample_rate, voltage_range
        As in :data:`SPECS`, Hz, V.
    linear_part : LinearPart
        The true linear part.
    """

    def __init__(self, name: str, *, seed: int = 0):
        if name not in SPECS:
            raise ValueError(
                f"unknown stage {name!r}; choose one of {DYNAMICS_STAGES + DYNAMICS_HELD_OUT}"
            )
        kind, self.linear_part = SPECS[name]
        self.name = name
        self.kind = kind
        self.sample_rate = self.linear_part.sample_rate
        self.voltage_range = VOLTAGE_RANGE
        self._quasi_static = _hysteresis(kind)
        self._rng = np.random.default_rng(seed)

    def hysteresis(self, v) -> np.ndarray:
        """The quasi-static part alone (µm), the voltage clipped to the rails first."""
        return self._quasi_static(np.clip(np.asarray(v, dtype=np.float64), *self.voltage_range))

    def linear(self, u, rest: float | None = None) -> np.ndarray:
        """The true linear part applied to ``u`` (µm), from rest at ``rest`` (``u[0]``)."""
        return self.linear_part.apply(u, rest)

    def run(self, v) -> np.ndarray:
        """The measured displacement (µm) for the voltage ``v`` (V), from rest at the low
        rail, with sensor noise (the generator advances from run to run)."""
        x = self.linear(self.hysteresis(v), rest=0.0)
        return x + NOISE_UM * self._rng.standard_normal(x.size)

    def true_dynamics(self, modes: int = 2) -> LinearDynamics:
        """:meth:`LinearPart.true_dynamics` (see :attr:`dynamics_exact`)."""
        return self.linear_part.true_dynamics(modes)

    @property
    def dynamics_exact(self) -> bool:
        """Whether :meth:`true_dynamics` is the linear part exactly."""
        return self.linear_part.exact

    @property
    def stroke(self) -> float:
        """The quasi-static displacement (µm) at the top rail, from rest."""
        return float(self.hysteresis(np.array(self.voltage_range))[-1])


def stage(name: str, *, seed: int = 0) -> DynamicsStage:
    """One stage of the panel (see the module)."""
    return DynamicsStage(name, seed=seed)


@dataclasses.dataclass(frozen=True)
class Reference:
    """A reference (µm), the samples it is scored on, and how: ``"rms"`` or ``"mean"`` |e|."""

    x_ref: np.ndarray
    window: slice
    metric: str

    def score(self, x: np.ndarray) -> float:
        e = (x - self.x_ref)[self.window]
        if self.metric == "rms":
            return float(np.sqrt(np.mean(e**2)))
        return float(np.mean(np.abs(e)))


def references(st: DynamicsStage) -> dict[str, Reference]:
    """``{"1 Hz", "10 Hz", "100 Hz", "200 Hz", "step"}``: triangles over
    :data:`TRIANGLE_SPAN` of the stroke, :data:`PERIODS` periods each, scored (rms) over the
    periods after the first; the step from ``STEP_LEVELS[0]`` to ``STEP_LEVELS[1]`` of the
    stroke after :data:`STEP_BEFORE` s, held :data:`STEP_HOLD` s, scored (mean |error|)
    from :data:`STEP_FROM` s after the step to the end."""
    fs = st.sample_rate
    stroke = st.stroke
    low, high = (p * stroke for p in TRIANGLE_SPAN)
    out = {}
    for f, periods in PERIODS.items():
        _, x_ref = triangle_reference(high - low, f, periods=periods, sample_rate=fs, offset=low)
        n = round(fs / f)
        out[f"{f:g} Hz"] = Reference(x_ref, slice(n, n * periods), "rms")
    before = round(STEP_BEFORE * fs)
    x_ref = np.r_[np.full(before, STEP_LEVELS[0]), np.full(round(STEP_HOLD * fs), STEP_LEVELS[1])]
    out["step"] = Reference(stroke * x_ref, slice(before + round(STEP_FROM * fs), None), "mean")
    return out


REFERENCES = (*(f"{f:g} Hz" for f in PERIODS), "step")


def tracking(st: DynamicsStage, compensator, refs: dict | None = None) -> dict[str, float]:
    """The error (µm) of ``compensator`` (``simulate(x_ref) -> v``) on ``st`` for each
    reference of :func:`references` (or ``refs``): rms for the triangles, mean |error| for
    the step. The voltage must stay in the stage's range."""
    refs = references(st) if refs is None else refs
    lo, hi = st.voltage_range
    out = {}
    for name, ref in refs.items():
        v = compensator.simulate(ref.x_ref)
        assert v.min() >= lo - 1e-9, name
        assert v.max() <= hi + 1e-9, name
        out[name] = ref.score(st.run(v))
    return out
