"""The linear dynamics of the actuator (creep, one or two resonances) and its stable inverse.

Beyond the paper: the paper's rig (its Fig. 2) puts the piezo dynamics ``D(s)`` after the
hysteresis ``H``, and its compensators invert ``H`` alone, so that their error grows with
the reference's rate (Table I). As Croft, Shed and Devasia (2001) do, hystcomp can put an
inverse of ``D`` in series: ``v = H^-1[D^-1[x_ref]]``.

The model, in discrete time at the sample rate ``fs`` (``Ts = 1/fs``)::

    D(z) = z^-d C(z) R(z)
    C(z) = (1 + sum_i c_i (1 - a_i) / (1 - a_i z^-1)) / (1 + sum_i c_i),  a_i = exp(-Ts/tau_i)
    R(z) = R1(z)                          (one mode)
    R(z) = (1 - g) R1(z) + g R2(z)        (two modes, in parallel)
    Rk(z) = ZOH{ wk^2 / (s^2 + 2 zeta_k wk s + wk^2) } = (b1 z + b2) / (z^2 + a1 z + a2)

``C`` is a bank of first-order creep modes with log-spaced time constants ``tau_i`` and
weights ``c_i >= 0`` (creep rising roughly as ``log t`` over the decades they span), ``R``
the first resonance, or the first and a second, higher one in parallel (modal: each mode a
second-order section of unit static gain, ``g`` the second's share of the static gain),
each discretised with a zero-order hold (exactly as a sampled rig sees it),
``d`` the rig's latency in whole samples beyond the hold's one (converters, filters; -1
for a record whose displacement answers the voltage of the same sample).
Both have unit gain at steady state, ``D(1) = 1``, so the hysteresis model keeps its static
map: the creep weights say how far the displacement still moves after a step, as a fraction
of where it settles.

The inverse (:meth:`LinearDynamics.inverse`) is stable whatever was identified:

* ``C`` is minimum phase (a sum of positive first-order lags has real zeros between its
  poles), and its inverse is computed exactly by solving the bank's equation each sample.
* ``R`` itself, sampling zeros included (near ``-1`` at fast sampling, beyond ``-1``
  non-minimum phase; with two modes, the zeros between them too), is never inverted: a
  FIR with non-negative taps
  (:func:`~hystcomp.models.dynamic_compensator.inverse_fir`) is fitted so that ``R`` times
  it is close to 1 on ``0 .. bandwidth_hz``. Non-negative taps summing to 1 bound its gain
  by 1 at every frequency, and make the inverse of a step rise monotonically: no overshoot
  and no dip, so that the hysteresis downstream (model and actuator) is never driven into a
  minor loop by the inverse itself (a windowed-sinc low-pass with an exact resonance
  inverse overshoots a step by 10 % and rings). The price is an in-band error growing as
  ``f^4`` (1.5 % at 200 Hz for a 630 Hz, zeta 0.1 resonance at 20 kHz).

The FIR part is non-causal by a fixed number of samples (:attr:`~hystcomp.models.dynamic_compensator.DynamicsInverse.preview`,
the latency ``d`` included: its inverse is a look-ahead of ``d`` samples):
a batch run of a known reference takes those samples from the future; a streaming stepper
takes the reference that many samples ahead (or, fed the reference of *now*, its output
lags the reference by ``preview`` samples).
"""

from __future__ import annotations

import warnings
from typing import Any, ClassVar

import numpy as np

from hystcomp import _lti
from hystcomp._notice import Notice
from hystcomp._validation import as_signal, as_vector, check_int, check_real
from hystcomp.errors import (
    HystcompWarning,
    InvalidParameterError,
    InvalidTypeError,
    NotFittedError,
)
from hystcomp.identify.dynamics import DELAY_RANGE, fit_dynamics
from hystcomp.models.dynamic_compensator import (
    MATCH_HZ,
    DynamicCompensator,
    DynamicsInverse,
    DynamicStepper,
    inverse_fir,
)
from hystcomp.models.estimator import ModelFile, learned_values, set_learned

__all__ = [
    "MATCH_HZ",
    "DynamicCompensator",
    "DynamicStepper",
    "DynamicsInverse",
    "LinearDynamics",
    "inverse_fir",
    "with_dynamics",
]

#: Default band on which the inverse is fitted, as a multiple of the resonance (capped
#: at 0.4 fs); chosen on the step and 100/200 Hz figures of ``benchmarks/bench_dynamics.py``.
BANDWIDTH_FACTOR = 1.0
#: Slowest resonance, as a fraction of the sample rate, and the damping ratios accepted:
#: beyond them the discrete poles are not resolved in double precision.
MIN_RESONANCE = 1e-6
DAMPING_RANGE = (1e-6, 1e3)


class LinearDynamics(ModelFile):
    """Creep modes and the first resonance (and a second) of an actuator, unit steady-state gain.

    Build it with :meth:`from_parameters`, identify it with :meth:`fit`
    (:func:`hystcomp.workflows.pair.identify_dynamics_record` reports the fit) or load it with
    :func:`hystcomp.load_model`.

    Attributes
    ----------
    sample_rate_ : float
        Hz; the model is discrete-time at this rate.
    resonance_hz_, damping_ratio_ : float
        The first resonance ``wn / 2 pi`` in Hz and its damping ratio.
    second_resonance_hz_, second_damping_ratio_, second_mode_gain_ : float or None
        The second mode, in parallel with the first and above it: Hz, damping ratio, and
        its share ``g`` of the static gain (``0 < g < 1``; the first mode has ``1 - g``).
        None for a model of one mode (and for model files written before it existed).
    creep_time_constants_ : ndarray
        ``tau_i`` in s.
    creep_weights_ : ndarray
        ``c_i >= 0``: the step response rises by ``c_i / (1 + sum c)`` of its final value
        with time constant ``tau_i``.

    Examples
    --------
    >>> dyn = LinearDynamics.from_parameters(sample_rate=20_000.0, resonance_hz=780.0,
    ...     damping_ratio=0.05, creep_time_constants=[0.01, 0.1, 1.0],
    ...     creep_weights=[0.01, 0.01, 0.01])
    >>> round(float(abs(dyn.frequency_response([0.0])[0])), 12)
    1.0
    >>> x = dyn.simulate(np.r_[np.zeros(10), np.ones(100_000)])
    >>> round(float(x[2010]), 3), round(float(x[-1]), 3)   # 0.1 s and 5 s after a unit step
    (0.988, 1.0)
    """

    kind: ClassVar[str] = "dynamics"
    _learned: ClassVar[tuple[str, ...]] = (
        "sample_rate",
        "resonance_hz",
        "damping_ratio",
        "creep_time_constants",
        "creep_weights",
        "delay_samples",
        "second_resonance_hz",
        "second_damping_ratio",
        "second_mode_gain",
    )
    sample_rate_: float
    resonance_hz_: float
    damping_ratio_: float
    creep_time_constants_: np.ndarray
    creep_weights_: np.ndarray
    delay_samples_: int
    second_resonance_hz_: float | None
    second_damping_ratio_: float | None
    second_mode_gain_: float | None

    @classmethod
    def from_parameters(
        cls,
        *,
        sample_rate,
        resonance_hz,
        damping_ratio,
        creep_time_constants=(),
        creep_weights=(),
        delay_samples=0,
        second_resonance_hz=None,
        second_damping_ratio=None,
        second_mode_gain=None,
    ) -> LinearDynamics:
        """A model from its parameters (units as in the class attributes), validated.

        ``delay_samples`` (0 by default, and in model files written before it existed) is
        the latency in whole samples beyond the sample-and-hold's one. The second mode
        (``second_resonance_hz``, ``second_damping_ratio``, ``second_mode_gain``) is given
        whole or not at all (None, the default and what model files written before it
        existed hold: one mode).

        Parameters
        ----------
        sample_rate : float
            The sample rate the model runs at, Hz.
        resonance_hz : float
            The first resonance, Hz.
        damping_ratio : float
            Its damping ratio, unitless, in ``(0, 1)``.
        creep_time_constants : sequence of float, optional
            The creep modes' time constants, s.
        creep_weights : sequence of float, optional
            Their weights, as fractions of the steady-state displacement.
        delay_samples : int, optional
            The latency in whole samples beyond the sample-and-hold's one.
        second_resonance_hz : float, optional
            A second mode's resonance, Hz.
        second_damping_ratio : float, optional
            Its damping ratio.
        second_mode_gain : float, optional
            Its share of the steady-state gain.

        Returns
        -------
        LinearDynamics
            The model, as if fitted (``fit_report_`` empty).
        """
        owner = cls.__name__
        model = cls()
        rate = check_real(sample_rate, "sample_rate", owner, positive=True)
        first = _check_mode(resonance_hz, damping_ratio, rate, "", owner)
        second = {
            "second_resonance_hz": second_resonance_hz,
            "second_damping_ratio": second_damping_ratio,
            "second_mode_gain": second_mode_gain,
        }
        given = [name for name, value in second.items() if value is not None]
        if given and len(given) < len(second):
            missing = ", ".join(repr(name) for name in second if name not in given)
            raise InvalidParameterError(
                f"The second mode of {owner} needs 'second_resonance_hz', "
                f"'second_damping_ratio' and 'second_mode_gain' together. Got "
                f"{', '.join(repr(name) for name in given)} without {missing}; give all three, "
                "or none for a model of one mode."
            )
        if given:
            hz, zeta = _check_mode(
                second_resonance_hz, second_damping_ratio, rate, "second_", owner
            )
            if not hz > first[0]:
                raise InvalidParameterError(
                    f"The 'second_resonance_hz' parameter of {owner} must be above "
                    f"'resonance_hz' ({first[0]:g} Hz): the first mode is the "
                    f"lowest. Got {hz:g}; swap the two modes."
                )
            gain = check_real(second_mode_gain, "second_mode_gain", owner)
            if not 0.0 < gain < 1.0:
                raise InvalidParameterError(
                    f"The 'second_mode_gain' parameter of {owner} is the second mode's share "
                    f"of the static gain, in (0, 1) (the first mode has the rest). Got "
                    f"{gain:g}; leave the second mode out (None) for a model of one mode."
                )
            second = {
                "second_resonance_hz": hz,
                "second_damping_ratio": zeta,
                "second_mode_gain": gain,
            }
        if np.size(creep_time_constants) == 0 and np.size(creep_weights) == 0:  # no creep
            taus = weights = np.zeros(0)
        else:
            taus = as_vector(np.atleast_1d(creep_time_constants), "creep_time_constants", owner)
            weights = as_vector(
                np.atleast_1d(creep_weights), "creep_weights", owner, length=taus.size
            )
        if np.any(taus <= 0) or np.any(weights < 0):
            raise InvalidParameterError(
                f"The creep of {owner} needs time constants > 0 s and weights >= 0. Got "
                f"time constants {taus.tolist()} and weights {weights.tolist()}."
            )
        if isinstance(delay_samples, float) and delay_samples.is_integer():
            delay_samples = int(delay_samples)  # 3.0, as some JSON writers put 3
        delay = check_int(
            delay_samples, "delay_samples", owner, minimum=DELAY_RANGE[0], maximum=DELAY_RANGE[1]
        )
        set_learned(
            model,
            cls._learned,
            sample_rate=rate,
            resonance_hz=first[0],
            damping_ratio=first[1],
            creep_time_constants=taus,
            creep_weights=weights,
            delay_samples=delay,
            **second,
        )
        return model

    def fit(self, v, x, sample_rate: float, *, u=None) -> LinearDynamics:
        """Identify the model from the answer ``x`` (µm) to ``hystcomp excite dynamics``.

        Delegates to :func:`hystcomp.identify.dynamics.fit_dynamics` (see there for the
        method); ``v`` in V, ``sample_rate`` in Hz, ``u`` the input of the dynamics when
        they are fitted behind a hysteresis model (its output ``H[v]`` in µm; see
        :class:`~hystcomp.models.hammerstein.HammersteinModel`). Sets the parameters and
        ``fit_report_``; returns ``self``.

        Parameters
        ----------
        v : array_like
            The voltage applied, V (the answer to ``hystcomp excite dynamics``).
        x : array_like
            The measured displacement, µm, one sample per voltage sample.
        sample_rate : float
            The record's sample rate, Hz.
        u : array_like, optional
            The input of the dynamics, µm, when they are fitted behind a hysteresis model (its
            output ``H[v]``).

        Returns
        -------
        LinearDynamics
            ``self``, fitted.
        """
        result = fit_dynamics(v, x, sample_rate, u=u)
        fitted = type(self).from_parameters(**result.parameters)
        set_learned(self, self._learned, **learned_values(fitted, self._learned))
        self.fit_report_ = dict(result.report)
        return self

    # -- the model -------------------------------------------------------------------------

    def _check_fitted(self) -> None:
        if not hasattr(self, "resonance_hz_"):
            raise NotFittedError(
                "This LinearDynamics has no parameters yet. Identify it with "
                "LinearDynamics().fit(v, x, sample_rate), build it with "
                "LinearDynamics.from_parameters(...) or load one with hystcomp.load_model."
            )

    @property
    def modes(self) -> tuple[tuple[float, float, float], ...]:
        """``((hz, damping ratio, share of the static gain), ...)``: the modes in parallel,
        the first first (one or two; the shares sum to 1)."""
        self._check_fitted()
        hz, zeta, g = self.second_resonance_hz_, self.second_damping_ratio_, self.second_mode_gain_
        if hz is None or zeta is None or g is None:
            return ((self.resonance_hz_, self.damping_ratio_, 1.0),)
        return ((self.resonance_hz_, self.damping_ratio_, 1.0 - g), (hz, zeta, g))

    @property
    def creep_lags(self) -> np.ndarray:
        """``a_i = exp(-Ts / tau_i)``, the creep poles in discrete time."""
        return _lti.creep_lags(self.creep_time_constants_, self.sample_rate_)

    def resonance(self):
        """``(b, a)`` of ``R(z)``, every mode (see :func:`hystcomp._lti.modal_tf`; one mode:
        :func:`hystcomp._lti.resonance_zoh`).

        Returns
        -------
        b : numpy.ndarray
            The numerator of ``R(z)``, in powers of ``z``.
        a : numpy.ndarray
            The denominator of ``R(z)``, in powers of ``z``.
        """
        return _lti.modal_tf(self.modes, self.sample_rate_)

    def frequency_response(self, frequencies) -> np.ndarray:
        """``D(exp(j 2 pi f Ts))`` at ``frequencies`` in Hz (complex, unit gain at 0 Hz).

        Parameters
        ----------
        frequencies : array_like
            Frequencies, Hz.

        Returns
        -------
        numpy.ndarray
            The complex response at each frequency (unitless, 1 at 0 Hz).
        """
        self._check_fitted()
        return _lti.frequency_response(
            as_vector(frequencies, "frequencies", "LinearDynamics.frequency_response"),
            self.sample_rate_,
            self.modes,
            self.creep_lags,
            self.creep_weights_,
            self.delay_samples_,
        )

    def simulate(self, u, *, initial: float | None = None) -> np.ndarray:
        """The output of ``D`` for the input ``u``, from rest at ``initial`` (``u[0]`` if None).

        Parameters
        ----------
        u : array_like
            The input of the dynamics, µm (the output of the hysteresis, or the voltage times a
            linear gain).
        initial : float, optional
            The level the model is at rest at before the first sample, µm (``u[0]`` if None).

        Returns
        -------
        numpy.ndarray
            The displacement, µm, one sample per input sample.
        """
        self._check_fitted()
        u = as_signal(u, "u")
        rest = float(u[0]) if initial is None else check_real(initial, "initial", "simulate")
        return _lti.output(
            u,
            rest,
            self.sample_rate_,
            self.modes,
            self.creep_lags,
            self.creep_weights_,
            self.delay_samples_,
        )

    def creep_fraction(self, seconds: float) -> float:
        """How far a step response still has to rise after ``seconds``, as a fraction of its end.

        Parameters
        ----------
        seconds : float
            The time after a step, s.

        Returns
        -------
        float
            The part of the step response still to come, a fraction of its end value (0 to 1).
        """
        self._check_fitted()
        seconds = check_real(seconds, "seconds", "LinearDynamics.creep_fraction")
        if seconds < 0.0:
            raise InvalidParameterError(
                "The 'seconds' parameter of LinearDynamics.creep_fraction is the time since "
                f"the step, >= 0. Got {seconds:g}."
            )
        return _lti.creep_fraction(seconds, self.creep_time_constants_, self.creep_weights_)

    def remove(self, x, sample_rate: float | None = None) -> np.ndarray:
        """``D^-1[x]``: what went into the dynamics, for a measured displacement ``x`` (µm).

        Offline, for a record: the hysteresis model of a pair is fitted on it, in front of
        ``D`` (:class:`~hystcomp.models.hammerstein.HammersteinModel`). At the model's own
        rate it is the stable inverse of :meth:`inverse` (unit steady-state gain, its
        look-ahead taken from the record, from rest at ``x[0]``). At another
        ``sample_rate`` (a hysteresis record taken slower or faster) the creep is inverted
        exactly at that rate and the latency as the nearest whole number of its samples;
        the resonance is left in: at the rates such records hold (1 Hz triangles) it is
        1 to within ``(f / f_n)^2``.

        Parameters
        ----------
        x : array_like
            A measured displacement, µm.
        sample_rate : float, optional
            The record's sample rate, Hz (the model's own if None).

        Returns
        -------
        numpy.ndarray
            The input of the dynamics, µm, one sample per sample of ``x``.
        """
        self._check_fitted()
        x = as_signal(x, "x")
        fs = (
            self.sample_rate_
            if sample_rate is None
            else check_real(sample_rate, "sample_rate", "LinearDynamics.remove", positive=True)
        )
        rest = float(x[0])
        if abs(fs - self.sample_rate_) <= 1e-9 * self.sample_rate_:
            return self.inverse(rest=rest).simulate(x)
        lead = round(self.delay_samples_ * fs / self.sample_rate_)
        taps = np.r_[np.zeros(max(0, -lead)), 1.0]
        inverse = DynamicsInverse(
            taps,
            _lti.creep_lags(self.creep_time_constants_, fs),
            self.creep_weights_,
            preview=max(0, lead),
            rest=rest,
        )
        return inverse.simulate(x)

    # -- the inverse -----------------------------------------------------------------------

    def inverse(
        self,
        *,
        bandwidth_hz: float | None = None,
        rest: float = 0.0,
        output_range: tuple[float, float] = (-np.inf, np.inf),
        match_hz: float = 0.0,
        match_centre: float | None = None,
    ) -> DynamicsInverse:
        """The stable, bandwidth-limited inverse of ``D`` (see the module's notes).

        Parameters
        ----------
        bandwidth_hz : float, optional
            Upper end of the band on which the inverse is fitted, Hz; by default
            :data:`BANDWIDTH_FACTOR` times the resonance, at most ``0.4 fs``.
        rest : float, default 0
            The reference (µm) at which the filter starts at rest.
        output_range : (float, float), optional
            Clamp of the output, µm (none by default; the hysteresis model's displacement
            range in :func:`with_dynamics`).
        match_hz : float, default 0
            The inverse of ``D / |D(match_hz)|`` is built, scaled about ``match_centre``:
            0 Hz inverts ``D`` itself (unit steady-state gain); see :func:`with_dynamics`.
        match_centre : float, optional
            The displacement (µm) that the scaling of ``match_hz`` leaves in place;
            ``rest`` by default.

        Returns
        -------
        DynamicsInverse
        """
        self._check_fitted()
        owner = "LinearDynamics.inverse"
        fs = self.sample_rate_
        if bandwidth_hz is None:
            bandwidth_hz = min(BANDWIDTH_FACTOR * self.resonance_hz_, 0.4 * fs)
        bandwidth_hz = check_real(bandwidth_hz, "bandwidth_hz", owner, positive=True)
        if bandwidth_hz >= 0.5 * fs:
            raise InvalidParameterError(
                f"The 'bandwidth_hz' parameter of {owner} must be below the Nyquist frequency "
                f"({0.5 * fs:g} Hz). Got {bandwidth_hz:g}."
            )
        rest = check_real(rest, "rest", owner)
        taps, preview = self._inverse_fir(bandwidth_hz)
        match_hz = check_real(match_hz, "match_hz", owner)
        if not 0.0 <= match_hz < 0.5 * fs:
            raise InvalidParameterError(
                f"The 'match_hz' parameter of {owner} must be in [0, {0.5 * fs:g}) Hz. "
                f"Got {match_hz:g}."
            )
        gain = float(abs(self.frequency_response([match_hz])[0]))
        centre = rest if match_centre is None else check_real(match_centre, "match_centre", owner)
        low, high = (float(b) for b in output_range)
        if not low <= rest <= high:
            raise InvalidParameterError(
                f"The 'rest' parameter of {owner} must lie in 'output_range' ({low:g} .. "
                f"{high:g} µm). Got {rest:g}."
            )
        preview += self.delay_samples_  # the latency's inverse: a look-ahead
        if preview < 0:  # a record that answers early, and a FIR that looks ahead 0
            taps, preview = np.r_[np.zeros(-preview), taps], 0
        return DynamicsInverse(
            gain * taps,
            self.creep_lags,
            self.creep_weights_,
            preview=preview,
            rest=rest,
            output_range=(low, high),
            bias=(1.0 - gain) * centre,
        )

    def _inverse_fir(self, bandwidth_hz: float) -> tuple[np.ndarray, int]:
        """:func:`inverse_fir` of this model's modes, designed once per band.

        The design (a non-negative least squares) depends only on the modes, the
        sample rate and the band, which key the designs kept; a copy or a pickled model
        carries them (``hystcomp compare`` designs the inverse in the process that
        identifies the dynamics, so that its own never imports SciPy's optimisers).
        """
        key = (bandwidth_hz, self.sample_rate_, self.modes)
        designs = self.__dict__.setdefault("_fir_designs", {})
        if key not in designs:
            designs[key] = inverse_fir(self.resonance(), bandwidth_hz, self.sample_rate_)
        taps, preview = designs[key]
        return taps.copy(), preview

    # -- files -----------------------------------------------------------------------------

    def parameters(self) -> dict[str, Any]:
        """The parameters as plain Python values (the second mode's only when there is one,
        so that a model of one mode writes the file it always did).

        Returns
        -------
        dict
            The parameters by name (those of :meth:`from_parameters`), as floats, ints and lists.
        """
        self._check_fitted()
        out = {
            "sample_rate": self.sample_rate_,
            "resonance_hz": self.resonance_hz_,
            "damping_ratio": self.damping_ratio_,
            "creep_time_constants": self.creep_time_constants_.tolist(),
            "creep_weights": self.creep_weights_.tolist(),
            "delay_samples": self.delay_samples_,
        }
        if self.second_mode_gain_ is not None:
            out["second_resonance_hz"] = self.second_resonance_hz_
            out["second_damping_ratio"] = self.second_damping_ratio_
            out["second_mode_gain"] = self.second_mode_gain_
        return out

    def get_params(self) -> dict[str, Any]:
        """No hyperparameters: the model is its parameters.

        Returns
        -------
        dict
            An empty dictionary.
        """
        return {}

    def _document_parts(self) -> dict[str, Any]:
        return {"hyperparameters": {}, "parameters": self.parameters()}

    @classmethod
    def _from_document(cls, data: dict[str, Any]) -> LinearDynamics:
        return cls.from_parameters(**data["parameters"])

    def __repr__(self) -> str:
        if not hasattr(self, "resonance_hz_"):
            return "LinearDynamics(unfitted)"
        second = (
            ""
            if self.second_mode_gain_ is None
            else f", second_resonance_hz={self.second_resonance_hz_:.6g}, "
            f"second_damping_ratio={self.second_damping_ratio_:.4g}, "
            f"second_mode_gain={self.second_mode_gain_:.4g}"
        )
        return (
            f"LinearDynamics(resonance_hz={self.resonance_hz_:.6g}, damping_ratio="
            f"{self.damping_ratio_:.4g}{second}, creep={100 * self.creep_fraction(0.0):.3g} %, "
            f"sample_rate={self.sample_rate_:g})"
        )


def check_dynamics(dynamics, what: str) -> None:
    """Refuse ``dynamics`` unless it is a :class:`LinearDynamics`; ``what`` names the
    argument ("The 'dynamics' parameter of inverse")."""
    if not isinstance(dynamics, LinearDynamics):
        raise InvalidTypeError(
            Notice(
                "{what} must be a LinearDynamics, identified from a record: "
                "{identify_dynamics}. Got {got}.",
                what=what,
                got=type(dynamics).__name__,
            )
        )


def _check_mode(hz, zeta, sample_rate: float, prefix: str, owner: str) -> tuple[float, float]:
    """A mode's frequency (Hz) and damping ratio, checked: below Nyquist, resolved in
    double precision. ``prefix`` names the parameters (``""`` or ``"second_"``)."""
    name, damping = f"{prefix}resonance_hz", f"{prefix}damping_ratio"
    hz = check_real(hz, name, owner, positive=True)
    zeta = check_real(zeta, damping, owner, positive=True)
    if hz >= 0.5 * sample_rate:
        raise InvalidParameterError(
            f"The {name!r} parameter of {owner} must be below the Nyquist frequency "
            f"({0.5 * sample_rate:g} Hz). Got {hz:g}; identify from a record sampled faster."
        )
    if hz < MIN_RESONANCE * sample_rate:
        raise InvalidParameterError(
            Notice(
                f"The {name!r} parameter of {owner} must be at least {MIN_RESONANCE:g} of the "
                f"sample rate ({MIN_RESONANCE * sample_rate:g} Hz at {sample_rate:g} Hz): "
                f"slower, the resonance's poles cannot be told from 1 in double precision. Got "
                f"{hz:g}; identify the dynamics from a record instead: {{identify_dynamics}}."
            )
        )
    if not DAMPING_RANGE[0] <= zeta <= DAMPING_RANGE[1]:
        raise InvalidParameterError(
            Notice(
                f"The {damping!r} parameter of {owner} must be in {DAMPING_RANGE[0]:g} .. "
                f"{DAMPING_RANGE[1]:g} (outside, the resonance's poles leave double "
                f"precision). Got {zeta:g}; identify the dynamics from a record instead: "
                "{identify_dynamics}."
            )
        )
    return hz, zeta


def with_dynamics(
    model, compensator, dynamics, *, bandwidth_hz=None, paired=False
) -> DynamicCompensator:
    """``compensator`` (``model.inverse()``) in series with the inverse of ``dynamics``.

    The filter starts at rest at the model's displacement for the low end of its voltage
    range, where the compensator starts, and its output is clamped to the model's
    displacement range (from there to the end of the ascending branch to the top of the
    range): a reference step asks the inverse of the dynamics for a spike far beyond the
    stroke, which the voltage clamp cuts anyway, and a hysteresis inverse fed the spike
    would keep in its memory a turning point that the actuator never reached.

    ``paired``: the model was identified in front of the dynamics, as one pair
    (:class:`~hystcomp.models.hammerstein.HammersteinModel`), and ``D`` is inverted with its
    unit steady-state gain. Otherwise (``model.inverse(dynamics=dyn)``, the two identified
    apart) a :class:`~hystcomp.errors.HystcompWarning` says so, and the two are matched at
    :data:`MATCH_HZ` (1 Hz): a hysteresis model identified from 1 Hz records (the paper's
    signals, ``hystcomp excite``) already holds the creep and lag of that record, so the
    inverse of the dynamics is scaled to unit gain there, ``D^-1 |D(1 Hz)|``, and adds only
    what the hysteresis model lacks, the creep slower than 1 Hz and the fast dynamics. It
    cannot remove the creep faster than 1 Hz that such a model holds, which the pair does
    (Benchmarks, "Dynamics"). Creep scales the
    displacement from rest, so the scaling is about rest for a PI or MPI model whose loops
    close there (one that starts descended,
    :func:`hystcomp.identify.pi.initial_play_states`), and about the middle of the
    displacement range for other models, where the identification triangles have their
    mean.

    Parameters
    ----------
    model : HysteresisModel
        The hysteresis model the compensator inverts.
    compensator : Compensator or PreisachCompensator
        ``model.inverse()``.
    dynamics : LinearDynamics
        The linear dynamics to invert in series.
    bandwidth_hz : float, optional
        The band the inverse of the dynamics must follow, Hz (the model's default if None).
    paired : bool, optional
        Whether ``model`` and ``dynamics`` were identified as one pair.

    Returns
    -------
    DynamicCompensator
        The compensator in series with the inverse of the dynamics.
    """
    check_dynamics(dynamics, "The 'dynamics' parameter of inverse")
    lo, hi = compensator.voltage_range
    rest, top, back = (float(x) for x in model.simulate([lo, hi, lo]))
    output_range = (min(rest, top), max(rest, top))
    if paired:
        match_hz, centre = 0.0, rest
    else:
        warnings.warn(APART, HystcompWarning, stacklevel=3)
        # a play model whose loops close at rest (started descended): scaled about rest
        closes = getattr(model, "kind", None) in ("pi", "mpi") and abs(back - rest) <= 1e-9 * abs(
            top
        )
        match_hz, centre = MATCH_HZ, rest if closes else 0.5 * (rest + top)
    inverse = dynamics.inverse(
        bandwidth_hz=bandwidth_hz,
        rest=rest,
        output_range=output_range,
        match_hz=match_hz,
        match_centre=centre,
    )
    return DynamicCompensator(compensator, inverse, sample_rate=dynamics.sample_rate_)


#: The warning of a hysteresis model and dynamics identified apart, put in series.
APART = Notice(
    "the hysteresis model and the dynamics were identified apart, so the inverse of the "
    "dynamics is matched to the model at 1 Hz and may correct creep and lag that the model "
    "already holds; identify them as one pair: {identify_pair}.",
    kind="apart",
)
