"""The classical Prandtl-Ishlinskii model (paper eq. 12) and its analytic inverse (eqs. 24-26)."""

from __future__ import annotations

import numpy as np

from hystcomp import operators, paper
from hystcomp._validation import check_int
from hystcomp.identify.compensation import compensation_error
from hystcomp.identify.pi import fit_pi, paper_thresholds
from hystcomp.identify.scoring import error_report
from hystcomp.models.base import (
    DEFAULT_VOLTAGE_RANGE,
    HysteresisModel,
    check_play_hyperparameters,
    fit_voltage_range,
    inverse_play_compensator,
    set_common_parameters,
    set_plays,
    thinned_record,
)
from hystcomp.models.compensator import Compensator
from hystcomp.models.dynamic_compensator import with_dynamics
from hystcomp.models.inversion import (
    check_invertible,
)

__all__ = ["PrandtlIshlinskii", "paper_thresholds"]


class PrandtlIshlinskii(HysteresisModel):
    """Classical Prandtl-Ishlinskii model, eq. (12): ``x = x_0 + sum_i w_i play_{r_i}(v - v_0)``.

    The paper's model has ``v_0 = x_0 = 0``; the offsets let the same model describe records
    with a sensor offset or a bipolar input (the plays then act on ``v - v_0``, so that the
    thresholds of eq. 16 span the input range from its lower end).

    Parameters
    ----------
    n_operators : int, default 16
        Number of play operators ``n + 1`` (the paper uses 16).
    voltage_range : (float, float) or None, default None
        The amplifier's range in V, to which the compensator clamps its output. ``None``
        takes the range of the identification data.
    transient : int or None, default None
        Samples at the start of the record left out of the fit (a start-up transient).
        ``None``: until the input first reaches an end of its range
        (:func:`hystcomp.identify.scoring.transient_end`).
    margin : float, default 1e-3
        Invertibility margin of the fit: every partial sum of the weights is at least
        ``margin`` times the record's mean slope (see :func:`hystcomp.identify.pi.fit_pi`).
    constraints : {"physical", "paper"}, default "physical"
        ``"physical"``: the weights beyond the first are also non-negative, so the loops
        widen with amplitude and the inverse has no steep slopes (a deviation from the
        paper, see :mod:`hystcomp.identify.pi`); ``"paper"``: the partial-sum constraints
        of eq. (12) only.

    Attributes
    ----------
    thresholds_ : ndarray
        Play thresholds ``0 = r_0 < ... < r_n`` in V (eq. 16 when identified).
    weights_ : ndarray
        Play weights in µm/V.
    initial_state_ : ndarray
        Initial play states in V (eq. 18: zero).
    voltage_range_ : (float, float)
        Output clamp of the compensator, in V.
    input_offset_, output_offset_ : float
        ``v_0`` in V and ``x_0`` in µm.
    fit_report_ : dict
        After :meth:`fit`: errors of the model on the record
        (:func:`hystcomp.identify.scoring.error_report`), ``tracking_rms_um`` (the estimated
        tracking error of its compensator, µm rms,
        :func:`hystcomp.identify.compensation.compensation_error`) and
        ``baseline_tracking_rms_um`` (the same for a straight line ``v = x / k_lin``).

    Examples
    --------
    >>> model = PrandtlIshlinskii.from_parameters(thresholds=[0, 10], weights=[0.2, 0.1])
    >>> v = np.array([0.0, 20.0, 5.0, 20.0])
    >>> model.simulate(v).round(6).tolist()
    [0.0, 5.0, 2.0, 5.0]
    >>> model.inverse().simulate(model.simulate(v)).round(9).tolist()
    [0.0, 20.0, 5.0, 20.0]
    """

    kind = "pi"
    _learned = (
        "thresholds",
        "weights",
        "initial_state",
        "voltage_range",
        "input_offset",
        "output_offset",
    )

    def __init__(
        self,
        *,
        n_operators=paper.N_OPERATORS,
        voltage_range=None,
        transient=None,
        margin=1e-3,
        constraints="physical",
    ):
        self.n_operators = n_operators
        self.voltage_range = voltage_range
        self.transient = transient
        self.margin = margin
        self.constraints = constraints

    def fit(self, v, x) -> PrandtlIshlinskii:
        """Identify the model from a measured record (Section IV-A, eqs. 12, 16, 18).

        Delegates to :func:`hystcomp.identify.pi.fit_pi` (constrained least squares, with
        the invertibility of eqs. 24-26 guaranteed), then sets the learned attributes and
        ``fit_report_``.

        Parameters
        ----------
        v, x : array_like
            Input voltage (V) and measured displacement (µm), one sample each per instant.

        Returns
        -------
        PrandtlIshlinskii
            ``self``, fitted.
        """
        owner = type(self).__name__
        self._check_hyperparameters()
        n = check_int(self.n_operators, "n_operators", owner)
        fit = fit_pi(
            v,
            x,
            n_operators=n,
            transient=self.transient,
            margin=self.margin,
            constraints=self.constraints,
        )
        fitted = self.from_parameters(
            thresholds=fit.thresholds,
            weights=fit.weights,
            initial_state=fit.initial_state,
            voltage_range=fit_voltage_range(self.voltage_range, v, owner),
            input_offset=fit.input_offset,
            output_offset=fit.output_offset,
        )
        v_k, x_k, first = thinned_record(v, x, fit)
        report = error_report(x_k, fitted.simulate(v_k), first)
        est = compensation_error(fitted, v_k, x_k, start=first)
        report["tracking_rms_um"] = est["tracking_rms_um"]
        report["baseline_tracking_rms_um"] = est["baseline_rms_um"]
        self._adopt(fitted, report)
        return self

    @classmethod
    def from_parameters(
        cls,
        *,
        thresholds,
        weights,
        initial_state=None,
        voltage_range=DEFAULT_VOLTAGE_RANGE,
        input_offset=0.0,
        output_offset=0.0,
    ) -> PrandtlIshlinskii:
        """A model with the given parameters (V, µm/V, µm); every value is validated."""
        owner = cls.__name__
        model = cls(n_operators=np.size(thresholds), voltage_range=None)
        set_plays(model, owner, thresholds=thresholds, weights=weights, initial_state=initial_state)
        set_common_parameters(
            model,
            owner,
            voltage_range=voltage_range,
            input_offset=input_offset,
            output_offset=output_offset,
        )
        return model

    def _derived_hyperparameters(self) -> dict:
        return {"n_operators": int(self.thresholds_.size)}

    def _check_hyperparameters(self) -> None:
        super()._check_hyperparameters()
        check_play_hyperparameters(self)

    def _packed(self) -> np.ndarray:
        self._check_fitted()
        return operators.pack_chain(
            plays=(self.thresholds_, self.weights_, self.initial_state_),
            in_offset=self.input_offset_,
            out_offset=self.output_offset_,
        )

    def inverse(
        self, *, slew_rate=None, sample_rate=paper.SAMPLE_RATE, voltage_range=None, dynamics=None
    ) -> Compensator:
        """The analytic inverse PI (eqs. 24-26) as a compensator clamped to the voltage range.

        Parameters
        ----------
        slew_rate : float, optional
            Largest output slew rate in V/s (none by default).
        sample_rate : float, default 20000
            Sample rate in Hz at which the compensator runs; sets the per-sample slew step.
        voltage_range : (float, float), optional
            A narrower output clamp in V, inside ``voltage_range_`` (never wider).
        dynamics : LinearDynamics, optional
            Put an inverse of the actuator's linear dynamics (creep, first resonance) in
            series: ``v = H^-1[D^-1[x_ref]]`` (beyond the paper; see
            :mod:`hystcomp.models.dynamics`). Returns a
            :class:`~hystcomp.models.dynamic_compensator.DynamicCompensator` then.

        Raises
        ------
        NotInvertibleError
            If a partial sum of the weights is not positive; its ``index`` names it.
        """
        self._check_fitted()
        owner = type(self).__name__
        check_invertible(self.weights_, f"This {owner} model")
        compensator = inverse_play_compensator(
            self, slew_rate=slew_rate, sample_rate=sample_rate, voltage_range=voltage_range
        )
        return compensator if dynamics is None else with_dynamics(self, compensator, dynamics)
