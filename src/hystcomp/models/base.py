"""The forward hysteresis models' base: an estimator that is also a packed system.

:class:`HysteresisModel` joins the estimator contract (:mod:`hystcomp.models.estimator`) and
the packed system that computes the output (:mod:`hystcomp.models.system`), and adds what
every forward model knows about its voltage range: the compensator's clamp and the
reachable displacements.
"""

from __future__ import annotations

from abc import abstractmethod
from typing import TYPE_CHECKING, Any, ClassVar, Self

import numpy as np

from hystcomp import paper
from hystcomp._hyperparameters import VOLTAGE_RANGE, Constraint
from hystcomp._validation import check_range, check_real
from hystcomp.errors import InvalidParameterError
from hystcomp.models.estimator import Estimator
from hystcomp.models.system import PackedSystem

if TYPE_CHECKING:  # the compensators import this module
    from hystcomp.models.compensator import Compensator
    from hystcomp.models.dynamic_compensator import DynamicCompensator

DEFAULT_VOLTAGE_RANGE = paper.VOLTAGE_RANGE  # V, the paper's piezo voltage v_px
#: The fit report's entry for the input range (V) that the fitted record covered.
INPUT_RANGE_KEY = "input_range_v"


class HysteresisModel(PackedSystem, Estimator):
    """Base of the forward models: voltage (V) in, displacement (µm) out.

    An :class:`~hystcomp.models.estimator.Estimator` (hyperparameters, ``fit``, ``score``,
    model files) run as a :class:`~hystcomp.models.system.PackedSystem` (``simulate``,
    ``stepper``). Every forward model has a ``voltage_range`` hyperparameter and learns
    ``voltage_range_``, the range its compensators clamp to.

    What every forward model gives:

    - :meth:`fit` ``(v, x)``: identify the model from a record, return ``self``;
    - :meth:`simulate` ``(v)``: the displacement for a voltage, from the initial state,
      without changing the model (:meth:`PackedSystem.simulate
      <hystcomp.models.system.PackedSystem.simulate>`);
    - :meth:`stepper`: the same, one sample at a time, with a state of its own;
    - :meth:`inverse`: its compensator, clamped to ``voltage_range_``;
    - :meth:`reachable_range`: the displacements the compensator can ask for.
    """

    voltage_range: Any  # the hyperparameter, stored as given
    voltage_range_: tuple[float, float]
    _parameter_constraints: ClassVar[dict[str, Constraint]] = {"voltage_range": VOLTAGE_RANGE}

    @abstractmethod
    def fit(self, v, x) -> Self:
        """Identify the model from a record: voltage ``v`` (V) and displacement ``x`` (µm).

        Parameters
        ----------
        v, x : array_like
            Input voltage (V) and measured displacement (µm), one sample each per instant.

        Returns
        -------
        HysteresisModel
            ``self``, fitted.
        """

    @abstractmethod
    def inverse(
        self, *, slew_rate=None, sample_rate=None, voltage_range=None, dynamics=None
    ) -> Compensator | DynamicCompensator:
        """The model's compensator: reference (µm) in, voltage (V) out.

        Parameters
        ----------
        slew_rate : float, optional
            Largest output slew rate in V/s (none by default).
        sample_rate : float, optional
            Sample rate in Hz at which the compensator runs; sets the per-sample slew step
            (by default that of ``dynamics``, else 20000; another than the dynamics' is
            refused).
        voltage_range : (float, float), optional
            A narrower output clamp in V, inside ``voltage_range_`` (never wider).
        dynamics : LinearDynamics, optional
            Put an inverse of the actuator's linear dynamics (creep, first resonance) in
            series: ``v = H^-1[D^-1[x_ref]]`` (beyond the paper; see
            :mod:`hystcomp.models.dynamics`). Returns a
            :class:`~hystcomp.models.dynamic_compensator.DynamicCompensator` then.

        Returns
        -------
        Compensator or DynamicCompensator
            The compensator, clamped to the voltage range.
        """

    def _output_limits(
        self, slew_rate, sample_rate, voltage_range, dynamics
    ) -> tuple[float, tuple[float, float]]:
        """The checked limits of a compensator's output, for :meth:`inverse`: the largest
        step per sample (V; ``inf`` without a slew rate) and the clamp ``(lo, hi)`` (V)."""
        owner = f"{type(self).__name__}.inverse"
        rate = compensator_rate(sample_rate, dynamics, owner)
        return slew_to_step(slew_rate, rate, owner), self._clamp_range(voltage_range, owner)

    def _clamp_range(self, voltage_range, owner: str) -> tuple[float, float]:
        """The compensator's clamp: ``voltage_range_``, or a ``voltage_range`` inside it.

        A compensator may be told to stay in a narrower range than the model's (a stage
        rated below the amplifier), never a wider one: the model was identified inside its
        range and says nothing about the actuator outside it.
        """
        lo, hi = self.voltage_range_
        if voltage_range is None:
            return lo, hi
        low, high = check_range(voltage_range, "voltage_range", owner)
        if low < lo or high > hi:
            raise InvalidParameterError(
                f"The 'voltage_range' parameter of {owner} may only narrow the model's voltage "
                f"range {lo:g} .. {hi:g} V: the model was identified inside it and would "
                f"command voltages it never saw. Got {low:g} .. {high:g} V; choose limits "
                f"within {lo:g} .. {hi:g} V, or identify the model over a wider range."
            )
        return low, high

    def covered_range(self) -> tuple[float, float] | None:
        """The input range (V) that the record the model was fitted on covered, or None.

        ``voltage_range_`` is the amplifier's range, the compensator's clamp: the fitted
        record's by default, or one given wider (``allow_extrapolation`` of
        :func:`~hystcomp.workflows.identify.identify_record`) or narrower. This is what the
        record really covered, from the fit report (``fit_report_["input_range_v"]``); a
        model built from parameters, or read from a file without it, returns None.

        Returns
        -------
        tuple of (float, float) or None
            ``(min v, max v)`` of the fitted record, in V; None for a model without a fit report.
        """
        report = getattr(self, "fit_report_", None)
        value = report.get(INPUT_RANGE_KEY) if isinstance(report, dict) else None
        try:  # a model file's report is not validated: anything else is "unknown"
            lo, hi = (float(b) for b in value)  # type: ignore[union-attr]
        except (TypeError, ValueError):
            return None
        return (lo, hi) if np.isfinite(lo) and np.isfinite(hi) and lo < hi else None

    def reachable_range(self, voltage_range=None) -> tuple[float, float]:
        """The displacements (µm) the model reaches with voltages inside a range.

        The extremes of the major loop: the model run from its initial state over
        ``lo -> hi -> lo -> hi`` (its branches are monotone, so the extremes lie at the
        ends). A compensator clamps every reference beyond this range
        (:meth:`Compensator.run <hystcomp.models.compensator.Compensator.run>` counts them).

        Parameters
        ----------
        voltage_range : (float, float), optional
            A range in V inside ``voltage_range_`` (default: ``voltage_range_``).

        Returns
        -------
        (float, float)
            Lowest and highest displacement in µm.
        """
        self._check_fitted()
        lo, hi = self._clamp_range(voltage_range, f"{type(self).__name__}.reachable_range")
        x = self.simulate(np.array([lo, hi, lo, hi]))
        return float(x.min()), float(x.max())


def slew_to_step(slew_rate, sample_rate, owner) -> float:
    """Largest voltage change per sample from a slew-rate limit in V/s (``inf`` if None).

    Parameters
    ----------
    slew_rate : float or None
        The amplifier's slew-rate limit, V/s; None for no limit.
    sample_rate : float
        The compensator's sample rate, Hz.
    owner : str
        The class named in an error message.

    Returns
    -------
    float
        The largest voltage change per sample, V (``inf`` without a limit).
    """
    if slew_rate is None:
        return np.inf
    slew_rate = check_real(slew_rate, "slew_rate", owner, positive=True)
    sample_rate = check_real(sample_rate, "sample_rate", owner, positive=True)
    return slew_rate / sample_rate


def compensator_rate(sample_rate, dynamics, owner) -> float:
    """The sample rate (Hz) a compensator runs at: ``sample_rate``, else that of
    ``dynamics`` (a discrete-time model, which runs at its own rate only), else the
    twin's 20 kHz; a ``sample_rate`` other than the dynamics' is refused.

    Parameters
    ----------
    sample_rate : float or None
        The rate asked for, Hz; None takes that of ``dynamics``, else the twin's 20 kHz.
    dynamics : LinearDynamics or None
        The linear dynamics in series with the compensator, which run at their own rate only.
    owner : str
        The class named in an error message.

    Returns
    -------
    float
        The compensator's sample rate, Hz.
    """
    own = getattr(dynamics, "sample_rate_", None)
    if sample_rate is None:
        return paper.SAMPLE_RATE if own is None else float(own)
    sample_rate = check_real(sample_rate, "sample_rate", owner, positive=True)
    if own is not None and abs(sample_rate - own) > 1e-9 * own:
        raise InvalidParameterError(
            f"The 'sample_rate' parameter of {owner} ({sample_rate:g} Hz) differs from the "
            f"sample rate of its 'dynamics' ({own:g} Hz), which run at that rate only. Leave "
            "sample_rate out, or identify the dynamics at the compensator's rate."
        )
    return sample_rate


def input_range_report(v) -> dict[str, list[float]]:
    """The fit report's entry for the input range (V) that ``v`` covers.

    Parameters
    ----------
    v : array_like
        The voltage record the model was fitted on, V.

    Returns
    -------
    dict
        ``{"input_range_v": [min v, max v]}``, the entry of ``fit_report_``.
    """
    v = np.asarray(v, dtype=np.float64)
    return {INPUT_RANGE_KEY: [float(v.min()), float(v.max())]}


def fit_voltage_range(voltage_range, v) -> tuple[float, float]:
    """The checked ``voltage_range`` hyperparameter, or the data's ``(min v, max v)`` if it
    is None.

    Parameters
    ----------
    voltage_range : tuple of (float, float) or None
        The amplifier's range, V, as the hyperparameter's constraint checked it; None to
        take the data's.
    v : array_like
        The voltage record the model is fitted on, V.

    Returns
    -------
    tuple of (float, float)
        The range ``(low, high)``, V, with ``low < high``.
    """
    if voltage_range is None:
        v = np.asarray(v, dtype=np.float64)
        return float(v.min()), float(v.max())
    return voltage_range
