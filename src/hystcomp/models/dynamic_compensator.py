"""The inverse of the linear dynamics, and its composition with a hysteresis compensator.

:meth:`hystcomp.LinearDynamics.inverse` builds a :class:`DynamicsInverse` (see
:mod:`hystcomp.models.dynamics` for the model and why the inverse is stable);
``model.inverse(dynamics=dyn)`` puts it in front of the hysteresis compensator as a
:class:`DynamicCompensator` (:func:`with_dynamics`). The filter loop is the kernel of
:mod:`hystcomp._kernels.dynamics`, shared by the batch run, the stepper and (as C) the export.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from hystcomp._kernels import dynamics as dk
from hystcomp._kernels._jit import step_function
from hystcomp._validation import as_signal, as_vector, check_int
from hystcomp.errors import InvalidSignalError
from hystcomp.models.compensator import CompensatorRun
from hystcomp.models.system import (
    Rebound,
    Stepper,
    block,
    checked_pair_step,
    checked_state,
    checked_step,
)

#: Frequency (Hz) at which a hysteresis compensator and the inverse of the dynamics are
#: matched in :func:`with_dynamics`: that of the paper's identification signals.
MATCH_HZ = 1.0
#: Largest preview of the inverse in samples (and the half length of its FIR).
MAX_PREVIEW = 64
#: Frequency points of the band on which the FIR is fitted.
_FIT_POINTS = 200
#: Weight of the unit-sum row in the non-negative least squares (an equality in effect).
_SUM_WEIGHT = 1e3


def inverse_fir(resonance, bandwidth_hz: float, sample_rate: float):
    """Taps of the FIR part of the inverse (newest sample first), and its preview in samples.

    The taps ``g_j >= 0`` (summing to 1) of ``G(z) = sum_j g_j z^(P - j)``, ``P`` the
    half length, that bring ``R(z) G(z)`` closest to 1 on ``0 .. bandwidth_hz``, in least
    squares weighted by ``1 / (1 + (f / 0.3 bandwidth_hz)^2)`` (a triangle's harmonics fall
    as ``1 / f^2``): :func:`scipy.optimize.nnls` on the real and imaginary parts, the sum
    as a heavily weighted row. ``R(z)`` is the resonance with its sampling zero, fitted as
    it is (nothing is inverted, so a zero beyond ``-1`` is no matter): the whole ``R`` of
    :meth:`hystcomp.LinearDynamics.resonance`, both modes of a model that has two (the
    FIR then undoes the second mode's share of the in-band lag too).

    Non-negative taps give the inverse of a step a monotone rise (no overshoot, no dip)
    and ``|G| <= 1`` at every frequency (the inverse never amplifies). They cannot invert
    ``R`` exactly in the band: the error grows as ``f^4``, 0.2 % at 100 Hz and 1.5 % at
    200 Hz for a 630 Hz, zeta 0.1 resonance at 20 kHz. ``P = ceil(fs / (2 f_n))`` (at
    most ``MAX_PREVIEW``), ``f_n`` the first (lowest) mode, leaves room for the half
    period of the resonance that the taps span; zero taps at the ends are dropped, and the
    preview is the look-ahead of the first tap left.

    Parameters
    ----------
    resonance : tuple of numpy.ndarray
        ``(b, a)`` of the resonance ``R(z)`` in powers of ``z``.
    bandwidth_hz : float
        The upper end of the band to invert, Hz.
    sample_rate : float
        The sample rate, Hz.

    Returns
    -------
    taps : numpy.ndarray
        The non-negative taps, newest sample first, summing to 1.
    preview : int
        The look-ahead of the first tap, in samples.
    """
    from scipy.optimize import nnls

    design, target, lead = band_fit(resonance, bandwidth_hz, sample_rate)
    g = nnls(np.vstack([design, np.full(lead.size, _SUM_WEIGHT)]), np.r_[target, _SUM_WEIGHT])[0]
    kept = np.flatnonzero(g > 1e-12 * g.max())
    taps = g[kept[0] : kept[-1] + 1]
    return taps / taps.sum(), int(lead[kept[0]])


def band_fit(resonance, bandwidth_hz: float, sample_rate: float):
    """The least-squares problem of :func:`inverse_fir`: ``(design, target, lead)``.

    ``design @ g - target`` is the weighted error of ``R(z) G(z)`` against 1 on the band,
    real parts over imaginary parts, for taps ``g`` with the look-aheads ``lead`` (from
    ``P`` down to ``-P``). ``resonance`` is ``(b, a)`` in powers of ``z``, ``b`` one
    degree below ``a``: one mode's ``(b0 z + b1) / (z^2 + a1 z + a2)`` or the modes in
    parallel of :func:`hystcomp._lti.modal_tf`.

    Parameters
    ----------
    resonance : tuple of numpy.ndarray
        ``(b, a)`` of the resonance ``R(z)`` in powers of ``z``, ``b`` one degree below ``a``.
    bandwidth_hz : float
        The upper end of the band the inverse must be close to 1 on, Hz.
    sample_rate : float
        The sample rate, Hz.

    Returns
    -------
    design : numpy.ndarray
        The weighted regressors, real parts over imaginary parts (one column per tap).
    target : numpy.ndarray
        The weighted target, 1 on the band (real parts), 0 (imaginary parts).
    lead : numpy.ndarray
        The look-ahead of each tap in samples, from ``P`` down to ``-P``.
    """
    b, a = (np.asarray(c, dtype=np.float64) for c in resonance)
    fn = _resonance_hz(a, sample_rate)
    half = min(max(2, math.ceil(0.5 * sample_rate / fn)), MAX_PREVIEW)
    f = np.linspace(0.0, bandwidth_hz, _FIT_POINTS)
    z = np.exp(2j * np.pi * f / sample_rate)
    n = a.size - 1  # the order: powers z^n .. z^0 (as one mode's (b0 z + b1) / (z^2 + ...))
    r = sum(c * z ** (n - 1 - k) for k, c in enumerate(b)) / sum(
        c * z ** (n - k) for k, c in enumerate(a)
    )
    lead = np.arange(half, -half - 1, -1)  # tap j multiplies z^(half - j)
    m = r[:, None] * np.exp(2j * np.pi * np.outer(f / sample_rate, lead))
    w = 1.0 / (1.0 + (f / (0.3 * bandwidth_hz)) ** 2)
    return np.vstack([m.real, m.imag]) * np.r_[w, w][:, None], np.r_[w, np.zeros_like(w)], lead


def _resonance_hz(a, sample_rate: float) -> float:
    """The undamped natural frequency (Hz) of the discrete poles ``z^2 + a1 z + a2``; of
    a higher order (modes in parallel), of the two slowest poles: the first mode's."""
    poles = np.roots(a).astype(complex)
    s = np.log(poles) * sample_rate
    s = s[np.argsort(np.abs(s), kind="stable")]
    return float(np.sqrt(np.abs(s[0] * s[1]))) / (2.0 * np.pi)


def _run_ahead(stepper, x_ref, preview: int) -> np.ndarray:
    """``stepper``'s outputs for a known reference, aligned with it: primed with its first
    ``preview`` samples, and the reference held at its last value past its end."""
    x = as_signal(x_ref, "x_ref")
    ahead = np.concatenate([x, np.full(preview, x[-1])])  # held, even if shorter than preview
    stepper.prime(ahead[:preview])
    return stepper.step_block(ahead[preview:])


class DynamicsInverse:
    """The inverse of :class:`~hystcomp.LinearDynamics`: reference (µm) in, the input ``D`` needs out.

    Made by :meth:`~hystcomp.LinearDynamics.inverse`. :meth:`simulate` runs a known reference with
    :attr:`preview` samples of look-ahead; :meth:`stepper` streams.

    Parameters
    ----------
    taps : array_like
        The FIR taps (newest sample first) that invert the resonance, unitless.
    lags : array_like
        The per-sample decay factors of the creep modes, each in ``[0, 1)``.
    weights : array_like
        The creep weights, one per lag (fractions of the steady-state displacement).
    preview : int
        Samples of look-ahead of the FIR part.
    rest : float, optional
        The reference at which the filter starts at rest, µm.
    output_range : tuple of (float, float), optional
        The clamp on the output, µm (unbounded by default).
    bias : float, optional
        A constant added to the output, µm.

    Attributes
    ----------
    preview : int
        Samples of look-ahead of the FIR part (``D[inverse[x]]`` equals ``x`` filtered by
        ``R G``, close to 1 in the band, with no delay, once the stepper is given the
        reference this many samples ahead).
    rest : float
        The reference at which the filter starts at rest, µm.
    """

    def __init__(
        self,
        taps,
        lags,
        weights,
        *,
        preview: int,
        rest: float = 0.0,
        output_range=(-np.inf, np.inf),
        bias: float = 0.0,
    ):
        taps = as_vector(taps, "taps", "DynamicsInverse")  # at least one: the delay line's
        lags = np.asarray(lags, dtype=np.float64)
        weights = np.asarray(weights, dtype=np.float64)
        self.preview = check_int(preview, "preview", "DynamicsInverse", minimum=0)
        self.rest = float(rest)
        self.output_range = (float(output_range[0]), float(output_range[1]))
        header = [taps.size, lags.size, 1.0 + weights.sum(), 1.0 + (weights * (1.0 - lags)).sum()]
        header += [*self.output_range, float(bias)]
        # the head of the delay line (slot 0) and the scratch slots, the delay line (held
        # twice over, see hystcomp._kernels.dynamics) and the creep lags at rest, the count
        state = np.r_[np.zeros(dk.ST_LINE), np.full(2 * taps.size + lags.size, self.rest), 0.0]
        packed = np.concatenate([header, taps, lags, weights, state])
        packed.setflags(write=False)
        self._packed = packed

    @property
    def packed(self) -> np.ndarray:
        """The read-only packed filter (parameters and initial state), e.g. for C export."""
        return self._packed

    @property
    def taps(self) -> np.ndarray:
        """The FIR taps (newest sample first)."""
        return self._packed[dk.HEADER : dk.HEADER + int(self._packed[dk.N_FIR])]

    def simulate(self, x_ref) -> np.ndarray:
        """The filter's output for a known reference, aligned with it (look-ahead used).

        The reference is held at its last value beyond its end; the filter starts at rest
        at :attr:`rest` and is primed with the first :attr:`preview` samples.

        Parameters
        ----------
        x_ref : array_like
            The reference displacement, µm.

        Returns
        -------
        numpy.ndarray
            What the dynamics need as input, µm, one sample per reference sample.
        """
        return _run_ahead(self.stepper(), x_ref, self.preview)

    def stepper(self) -> DynamicsInverseStepper:
        """A streaming filter at rest.

        Returns
        -------
        DynamicsInverseStepper
            A stepper at rest at :attr:`rest`.
        """
        return DynamicsInverseStepper(self._packed, self.preview)

    def __repr__(self) -> str:
        return f"DynamicsInverse({self.taps.size} taps, preview={self.preview} samples)"


class DynamicsInverseStepper(Rebound):
    """The inverse filter one sample at a time (same kernel as the batch run).

    Parameters
    ----------
    packed : numpy.ndarray
        The packed filter (parameters and initial state), :attr:`DynamicsInverse.packed`.
    preview : int
        Samples of look-ahead of the FIR part.
    """

    def __init__(self, packed: np.ndarray, preview: int):
        self._initial = packed
        self._p = packed.copy()
        self._start = int(dk.state_start.py_func(packed))
        self.preview = preview
        self._bind()

    def _bind(self) -> None:
        # bound fast path, with the stepper's check of the sample's type
        self.step = checked_step(step_function(dk.inverse_step), self._p)  # type: ignore[method-assign]

    def step(self, u: float) -> float:
        """One reference sample (µm, ``preview`` samples ahead) -> filter output; NaN held out.

        Parameters
        ----------
        u : float
            The reference ``preview`` samples ahead, µm; a non-finite one holds the last output.

        Returns
        -------
        float
            The filter's output for now, µm.
        """
        return dk.inverse_step(self._p, u)

    def step_block(self, x_ref) -> np.ndarray:
        """A block of reference samples.

        Parameters
        ----------
        x_ref : array_like
            Reference samples, µm.

        Returns
        -------
        numpy.ndarray
            The filter's outputs, µm, one per reference sample.
        """
        u = block(x_ref, "step_block")
        out = np.empty_like(u)
        dk.inverse_run(self._p, u, out)
        return out

    def step_block_cuts(self, x_ref) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`step_block`, and where the clamp to the displacement range counted.

        Parameters
        ----------
        x_ref : array_like
            The block, µm; the filter's state advances past it as in :meth:`step_block`.

        Returns
        -------
        outputs : numpy.ndarray
            The filter's outputs, µm.
        cut : numpy.ndarray
            1.0 where the clamp to the displacement range counted the sample, else 0.0.
        """
        u = block(x_ref, "step_block")
        out = np.empty_like(u)
        cuts = np.empty_like(u)
        dk.inverse_run_cuts(self._p, u, out, cuts)
        return out, cuts != 0.0

    def prime(self, x_ref) -> None:
        """Feed the first ``preview`` reference samples, whose outputs come before time 0.

        Parameters
        ----------
        x_ref : array_like
            The first ``preview`` reference samples, µm.
        """
        u = block(x_ref, "prime")
        if u.size > self.preview:
            raise InvalidSignalError(
                f"prime takes the first 'preview' = {self.preview} reference samples, the "
                f"filter's look-ahead. Got {u.size}; pass x_ref[:{self.preview}], then step "
                f"from x_ref[{self.preview}]."
            )
        slot = dk.clamped_slot.py_func(self._p)
        counted = self._p[slot]
        self.step_block(u)
        self._p[slot] = counted  # outputs before time 0 are never applied: none clamped

    def reset(self) -> None:
        """Back to rest."""
        self._p[:] = self._initial

    @property
    def clamped_count(self) -> int:
        """Outputs that the clamp to the displacement range cut since the last reset."""
        return int(self._p[dk.clamped_slot.py_func(self._p)])

    def copy(self) -> DynamicsInverseStepper:
        """An independent stepper in the same state.

        Returns
        -------
        DynamicsInverseStepper
            A new stepper in this one's state; stepping either leaves the other as it is.
        """
        other = type(self)(self._initial, self.preview)
        other._p[:] = self._p
        return other

    @property
    def state(self) -> np.ndarray:
        """The filter's state: its delay line, its creep lags and its count (a copy); set it
        to go back to a saved state (see :attr:`Stepper.state
        <hystcomp.models.system.Stepper.state>`).

        Returns
        -------
        ndarray
            1-D float64, a copy.
        """
        return self._p[self._start :].copy()

    @state.setter
    def state(self, value) -> None:
        self._p[self._start :] = checked_state(value, self._p.size - self._start, self)


class DynamicCompensator:
    """A hysteresis compensator in series with an inverse of the dynamics.

    ``v = H^-1[D^-1[x_ref]]`` (Croft, Shed and Devasia's composition): the output is the
    hysteresis compensator's, so it stays clamped to :attr:`voltage_range` and its
    slew-rate limit holds. Made by ``model.inverse(dynamics=dyn)``.

    Parameters
    ----------
    hysteresis : Compensator or PreisachCompensator
        The hysteresis compensator (``model.inverse()``), which gives the output clamp.
    dynamics_inverse : DynamicsInverse
        The inverse of the linear dynamics, run before it.
    sample_rate : float, optional
        The rate both run at, Hz (that of the dynamics).

    Attributes
    ----------
    hysteresis : Compensator
        The hysteresis compensator (``model.inverse()``).
    dynamics_inverse : DynamicsInverse
        The inverse of the dynamics.
    preview : int
        Samples by which :meth:`stepper` takes its reference ahead (see :meth:`stepper`).
    sample_rate : float or None
        Hz: that of the dynamics, the only rate it runs at (None if not given).
    kind, voltage_range, max_step
        Those of :attr:`hysteresis`.
    """

    def __init__(self, hysteresis, dynamics_inverse: DynamicsInverse, sample_rate=None):
        self.hysteresis = hysteresis
        self.dynamics_inverse = dynamics_inverse
        self.sample_rate = sample_rate
        self.kind = hysteresis.kind
        self.voltage_range = hysteresis.voltage_range
        self.max_step = hysteresis.max_step
        self.preview = dynamics_inverse.preview

    def simulate(self, x_ref) -> np.ndarray:
        """The voltage (V) for a known reference ``x_ref`` (µm), aligned with it.

        The inverse of the dynamics looks :attr:`preview` samples ahead in ``x_ref``
        (held at its last value past the end).

        Parameters
        ----------
        x_ref : array_like
            The reference displacement, µm, one sample per period of :attr:`sample_rate`.

        Returns
        -------
        numpy.ndarray
            The voltage to apply, V, one sample per reference sample, inside :attr:`voltage_range`.
        """
        return self.hysteresis.simulate(self.dynamics_inverse.simulate(x_ref))

    def run(self, x_ref) -> CompensatorRun:
        """Like :meth:`simulate`, and also count the samples out of reach.

        Returns a ``CompensatorRun`` (see :meth:`hystcomp.models.compensator.Compensator.run`)
        whose ``clamped`` counts the samples that either clamp cut (once each): the inverse
        of the dynamics' clamp to the model's displacement range (a reference out of the
        model's reach, or creep to undo beyond it) or the voltage range's.

        Parameters
        ----------
        x_ref : array_like
            The reference, µm, run from the initial state through a new :meth:`stepper`.

        Returns
        -------
        CompensatorRun
            ``(v, clamped, nonfinite)``: the voltage (V), the count of samples out of reach and the
            count of non-finite reference samples held.
        """
        s = self.stepper()
        v = _run_ahead(s, x_ref, self.preview)
        return CompensatorRun(v, s.clamped_count, s.nonfinite_count)

    def stepper(self) -> DynamicStepper:
        """Streaming: ``step(x_ref[k + preview])`` returns the voltage to apply at sample ``k``.

        Call ``prime(x_ref[:preview])`` first when the reference is known ahead; fed the
        reference of *now* instead, the displacement lags it by :attr:`preview` samples.

        Returns
        -------
        DynamicStepper
            A stepper at rest, the filter at its rest reference and the hysteresis compensator in
            its initial state.
        """
        return DynamicStepper(self.dynamics_inverse.stepper(), self.hysteresis.stepper())

    def __repr__(self) -> str:
        return f"DynamicCompensator({self.hysteresis!r}, {self.dynamics_inverse!r})"


class DynamicStepper(Rebound):
    """The stepper of a :class:`DynamicCompensator`: the inverse filter, then the hysteresis.

    A non-finite reference leaves the filter as it was and holds the last voltage.
    :meth:`step` is bound to one compiled kernel that runs both stages on their states
    (:data:`hystcomp._kernels.dynamics.PAIR_STEPS`), behind the same type test of the sample
    as the hysteresis stepper's: one call from Python a sample (Benchmarks, "Speed"), and
    the bits of :meth:`step_block`.

    Parameters
    ----------
    dynamics : DynamicsInverseStepper
        The stepper of the inverse of the dynamics (the first stage).
    hysteresis : Stepper or PreisachStepper
        The stepper of the hysteresis compensator (the second stage).
    """

    def __init__(self, dynamics, hysteresis):
        self._dyn = dynamics
        self._hyst = hysteresis
        self._bind()

    def _bind(self) -> None:
        self.step = self._bound_step()  # type: ignore[method-assign]

    def _bound_step(self):
        """The step as one compiled call over both stages' states (the type test of the
        sample aside): the filter, then the hysteresis compensator, whose count of clamped
        outputs is put back where the filter's clamp counted the sample (out of reach:
        counted once)."""
        kernel = dk.PAIR_STEPS[self._hyst.kernels.step]
        return checked_pair_step(step_function(kernel, arrays=2), self._dyn._p, self._hyst._p)

    def step(self, x_ref: float) -> float:
        """One reference sample (µm, :attr:`preview` ahead) -> the voltage to apply now (V).

        Parameters
        ----------
        x_ref : float
            The reference displacement :attr:`preview` samples ahead, µm.

        Returns
        -------
        float
            The voltage to apply now, V.
        """
        return self._bound_step()(x_ref)

    def step_block(self, x_ref) -> np.ndarray:
        """A block of reference samples -> voltages.

        Parameters
        ----------
        x_ref : array_like
            Reference samples, µm, each :attr:`preview` samples ahead of its output.

        Returns
        -------
        numpy.ndarray
            The voltages, V, one per reference sample.
        """
        r, cut = self._dyn.step_block_cuts(x_ref)
        if not cut.any():
            return self._hyst.step_block(r)
        hyst_p, counted = self._hyst._p, self._hyst._clamped_slot
        out = np.empty_like(r)
        edges = [0, *(np.flatnonzero(np.diff(cut)) + 1).tolist(), r.size]
        for a, b in itertools.pairwise(edges):  # runs of cut and of uncut samples
            kept = hyst_p[counted]
            out[a:b] = self._hyst.step_block(r[a:b])
            if cut[a]:  # out of reach, counted by the filter: not twice
                hyst_p[counted] = kept
        return out

    def prime(self, x_ref) -> None:
        """Feed the first ``preview`` reference samples to the filter (no voltage is output).

        Parameters
        ----------
        x_ref : array_like
            The first :attr:`preview` reference samples, µm.
        """
        self._dyn.prime(x_ref)

    def reset(self) -> None:
        """Back to rest."""
        self._dyn.reset()
        self._hyst.reset()

    def copy(self) -> DynamicStepper:
        """An independent stepper in the same state.

        Returns
        -------
        DynamicStepper
            A new stepper in this one's state; stepping either leaves the other as it is.
        """
        return type(self)(self._dyn.copy(), self._hyst.copy())

    @property
    def dynamics_inverse(self) -> DynamicsInverseStepper:
        """The first stage, the inverse filter of the dynamics (it steps with this stepper)."""
        return self._dyn

    @property
    def hysteresis(self) -> Stepper:
        """The second stage, the hysteresis compensator's stepper (it steps with this one)."""
        return self._hyst

    @property
    def state(self) -> np.ndarray:
        """Both stages' states: the filter's (:attr:`dynamics_inverse`), then the hysteresis
        compensator's (:attr:`hysteresis`), as a copy; set it to go back to a saved state
        (see :attr:`Stepper.state <hystcomp.models.system.Stepper.state>`).

        Returns
        -------
        ndarray
            1-D float64, a copy.
        """
        return np.concatenate([self._dyn.state, self._hyst.state])

    @state.setter
    def state(self, value) -> None:
        n_dyn = self._dyn.state.size
        value = checked_state(value, n_dyn + self._hyst.state.size, self)
        self._dyn.state = value[:n_dyn]
        self._hyst.state = value[n_dyn:]

    @property
    def nonfinite_count(self) -> int:
        """Non-finite reference samples held since the last reset."""
        return self._hyst.nonfinite_count

    @property
    def clamped_count(self) -> int:
        """Samples since the last reset that a clamp cut, once each: the filter's, to the
        model's displacement range (a reference out of reach), or the voltage range's (the
        C export counts the same)."""
        return self._dyn.clamped_count + self._hyst.clamped_count

    @property
    def last_output(self) -> float:
        """The last voltage output."""
        return self._hyst.last_output
