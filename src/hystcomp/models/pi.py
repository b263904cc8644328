"""The classical Prandtl-Ishlinskii model (paper eq. 12) and its analytic inverse (eqs. 24-26).

:class:`PrandtlIshlinskii` is also the base of the Modified PI model
(:class:`~hystcomp.models.mpi.ModifiedPrandtlIshlinskii`, eq. 15): the plays, the offsets, the
packed chain, the inverse and the play hyperparameters live here once, and the saturation
stage ``S`` enters through :meth:`PrandtlIshlinskii._saturation` (none for PI).
"""

from __future__ import annotations

from typing import Any, ClassVar, Self

import numpy as np

from hystcomp import paper
from hystcomp._hyperparameters import check_constraints, check_margin, check_operator_count
from hystcomp._kernels import chain
from hystcomp._validation import (
    as_vector,
    check_int,
    check_range,
    check_reachable_state,
    check_real,
    check_thresholds,
)
from hystcomp.identify.compensation import CV_FOLDS, tracking_scorer
from hystcomp.identify.pi import fit_pi, paper_thresholds
from hystcomp.identify.scoring import error_report
from hystcomp.models.base import (
    DEFAULT_VOLTAGE_RANGE,
    HysteresisModel,
    compensator_rate,
    fit_voltage_range,
    input_range_report,
    slew_to_step,
)
from hystcomp.models.compensator import Compensator
from hystcomp.models.dynamic_compensator import DynamicCompensator
from hystcomp.models.dynamics import with_dynamics
from hystcomp.models.estimator import fit_signals
from hystcomp.models.inversion import (
    check_invertible,
    inverse_initial_state,
    invert_superposition,
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
        widen with amplitude and the inverse has no steep slopes, and every part of the
        input range weighs the same in the fit (deviations from the paper, see
        :mod:`hystcomp.identify.pi`); ``"paper"``: eq. (12) with only the partial sums of
        the weights kept positive, over every sample alike.

    Attributes
    ----------
    thresholds_ : ndarray
        Play thresholds ``0 = r_0 < ... < r_n`` in V (identified: eq. 16 with
        ``constraints="paper"``, over half the input span with the physical default).
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
    _learned: ClassVar[tuple[str, ...]] = (
        "thresholds",
        "weights",
        "initial_state",
        "voltage_range",
        "input_offset",
        "output_offset",
    )
    thresholds_: np.ndarray
    weights_: np.ndarray
    initial_state_: np.ndarray
    input_offset_: float
    output_offset_: float

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

    @fit_signals
    def fit(self, v, x) -> Self:
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
        n = check_operator_count(self.n_operators, "n_operators", owner)
        fit = fit_pi(
            v,
            x,
            n_operators=n,
            transient=self.transient,
            margin=self.margin,
            constraints=self.constraints,
            n_folds=CV_FOLDS,
        )
        # the samples the fit ran over: they hold the extremes of the input (thin)
        v_k, x_k, first = thinned_record(v, x, fit)
        voltage_range = fit_voltage_range(self.voltage_range, v_k, owner)
        fitted = self._from_fit(fit, voltage_range)
        score = tracking_scorer(v_k, x_k, start=first, folds=fit.folds)
        held_out = tuple(self._from_fit(part, voltage_range) for part in fit.held_out)
        self._adopt_fit(fitted, v_k, x_k, first, score(fitted, held_out))
        return self

    def _from_fit(self, fit, voltage_range) -> Self:
        """The model of a :class:`~hystcomp.identify.pi.PIFit` (see :meth:`_set_fitted`)."""
        model = type(self)(n_operators=fit.thresholds.size, voltage_range=None)
        model._set_fitted(fit, voltage_range)
        return model

    def _set_fitted(self, fit, voltage_range, **arrays) -> None:
        """Set the learned attributes from an identification's ``fit`` (and ``arrays``).

        They are not validated again, as :meth:`from_parameters` does: the fit computed them
        under its constraints (finite, every partial sum above the margin) and
        ``voltage_range`` was checked, while a fit builds dozens of candidate models.
        """
        fields = {
            "thresholds_": fit.thresholds,
            "weights_": fit.weights,
            "initial_state_": fit.initial_state,
            **arrays,
        }
        for name, value in fields.items():
            value = np.array(value, dtype=np.float64)  # the model's own, read-only
            value.setflags(write=False)
            setattr(self, name, value)
        self.voltage_range_ = voltage_range
        self.input_offset_ = float(fit.input_offset)
        self.output_offset_ = float(fit.output_offset)

    def _adopt_fit(self, fitted: Self, v_k, x_k, first: int, est: dict, **extra) -> None:
        """Take ``fitted``'s parameters, with its fit report on the thinned record: the
        errors of :func:`~hystcomp.identify.scoring.error_report`, then ``extra``, then the
        estimated tracking errors ``est`` of its compensator and of a straight line."""
        report = error_report(x_k, fitted.simulate(v_k), first)
        report.update(input_range_report(v_k))  # (the thinned record keeps the extremes)
        report.update(extra)
        report["tracking_rms_um"] = est["tracking_rms_um"]
        report["baseline_tracking_rms_um"] = est["baseline_rms_um"]
        for key in ("held_out_rms_um", "held_out_tracking_rms_um"):
            if key in est:
                report[key] = est[key]
        report["criterion_um"] = est["criterion_um"]
        self._adopt(fitted, report)

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
    ) -> Self:
        """A model with the given parameters (V, µm/V, µm); every value is validated.

        Parameters
        ----------
        thresholds : array_like
            The play thresholds ``r_i``, V, rising from 0.
        weights : array_like
            The play weights ``w_i``, µm/V.
        initial_state : array_like, optional
            The plays' initial states, V (zeros if None, eq. 18).
        voltage_range : tuple of (float, float), optional
            The amplifier's range, V.
        input_offset : float, optional
            The voltage subtracted before the plays, V.
        output_offset : float, optional
            The displacement added after them, µm.

        Returns
        -------
        PrandtlIshlinskii
            The model, as if fitted.
        """
        owner = cls.__name__
        model = cls(n_operators=np.size(thresholds), voltage_range=None)
        model._set_plays(owner, thresholds, weights, initial_state)
        model._set_offsets(owner, voltage_range, input_offset, output_offset)
        return model

    def _set_plays(self, owner: str, thresholds, weights, initial_state) -> None:
        """Validate and set ``thresholds_``, ``weights_`` and ``initial_state_`` (eq. 18:
        zero unless given)."""
        r = check_thresholds(thresholds, "thresholds", owner)
        self.thresholds_ = r
        self.weights_ = as_vector(weights, "weights", owner, length=r.size)
        if initial_state is None:
            zeros = np.zeros(r.size)
            zeros.setflags(write=False)
            self.initial_state_ = zeros
        else:
            y = as_vector(initial_state, "initial_state", owner, length=r.size)
            check_reachable_state(y, r, owner)
            self.initial_state_ = y

    def _set_offsets(self, owner: str, voltage_range, input_offset, output_offset) -> None:
        """Validate and set ``voltage_range_``, ``input_offset_`` and ``output_offset_``."""
        self.voltage_range_ = check_range(voltage_range, "voltage_range", owner)
        self.input_offset_ = check_real(input_offset, "input_offset", owner)
        self.output_offset_ = check_real(output_offset, "output_offset", owner)

    def _derived_hyperparameters(self) -> dict[str, Any]:
        return {"n_operators": int(self.thresholds_.size)}

    def _check_hyperparameters(self) -> None:
        """The range, then the play hyperparameters: operator count, transient, margin,
        constraints."""
        super()._check_hyperparameters()
        owner = type(self).__name__
        check_int(self.n_operators, "n_operators", owner)
        if self.transient is not None:
            check_int(self.transient, "transient", owner, minimum=0)
        check_margin(self.margin, owner)
        check_constraints(self.constraints, owner)

    def _saturation(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The dead-zones ``(thresholds, weights)`` of the saturation stage ``S`` after the
        plays (eq. 15), or None: a PI model has none."""
        return None

    def _check_invertible(self) -> None:
        """Raise :class:`~hystcomp.errors.NotInvertibleError` unless eqs. (24)-(25) apply."""
        check_invertible(self.weights_, f"This {type(self).__name__} model")

    def _packed(self) -> np.ndarray:
        self._check_fitted()
        return chain.pack_chain(
            plays=(self.thresholds_, self.weights_, self.initial_state_),
            post=self._saturation(),
            in_offset=self.input_offset_,
            out_offset=self.output_offset_,
        )

    def inverse(
        self, *, slew_rate=None, sample_rate=None, voltage_range=None, dynamics=None
    ) -> Compensator | DynamicCompensator:
        """The analytic inverse PI (eqs. 24-26) as a compensator clamped to the voltage range.

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
            The compensator; with ``dynamics``, in series with their inverse.

        Raises
        ------
        NotInvertibleError
            If a partial sum of the weights is not positive; its ``index`` names it.
        """
        self._check_fitted()
        self._check_invertible()
        # the chain x -> (x - x_0) -> [S^-1 dead-zones] -> inverse plays (eqs. 24-26) -> + v_0
        owner = type(self).__name__
        sample_rate = compensator_rate(sample_rate, dynamics, f"{owner}.inverse")
        max_step = slew_to_step(slew_rate, sample_rate, owner)
        lo, hi = self._clamp_range(voltage_range, f"{owner}.inverse")
        saturation = self._saturation()
        packed = chain.pack_chain(
            pre=None if saturation is None else invert_superposition(*saturation),
            plays=(
                *invert_superposition(self.thresholds_, self.weights_),
                inverse_initial_state(self.weights_, self.initial_state_),
            ),
            in_offset=self.output_offset_,
            out_offset=self.input_offset_,
            low=lo,
            high=hi,
            max_step=max_step,
        )
        compensator = Compensator(packed, kind=self.kind, voltage_range=(lo, hi))
        return compensator if dynamics is None else with_dynamics(self, compensator, dynamics)


def thinned_record(v, x, fit) -> tuple[np.ndarray, np.ndarray, int]:
    """The samples a PI/MPI fit ran over (``fit.samples``), and the first one in its cost.

    For a record longer than :data:`hystcomp.identify.scoring.MAX_SAMPLES` these are its
    turning points and a regular subset: the fit report and the tracking estimate are
    computed there, which gives the same figures as the whole record at a fraction of the
    cost (rate independence).
    """
    keep = fit.samples
    v, x = np.asarray(v, dtype=np.float64), np.asarray(x, dtype=np.float64)
    if keep is None or keep.size == v.size:
        return v, x, fit.first_sample
    return v[keep], x[keep], int(np.searchsorted(keep, fit.first_sample))
