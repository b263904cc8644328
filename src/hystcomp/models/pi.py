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
from hystcomp._hyperparameters import (
    FIT_CONSTRAINTS,
    MARGIN,
    OPERATOR_COUNT,
    TRANSIENT,
    Constraint,
)
from hystcomp._kernels import chain
from hystcomp._validation import (
    as_vector,
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
    fit_voltage_range,
    input_range_report,
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
    _parameter_constraints: ClassVar[dict[str, Constraint]] = {
        **HysteresisModel._parameter_constraints,
        "n_operators": OPERATOR_COUNT,
        "transient": TRANSIENT,
        "margin": MARGIN,
        "constraints": FIT_CONSTRAINTS,
    }
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
        """Identify the model from a measured record (Section IV-A).

        The constrained least squares of :meth:`_fits` (for PI
        :func:`hystcomp.identify.pi.fit_pi`, eqs. 12, 16, 18; for MPI
        :func:`hystcomp.identify.mpi.fit_mpi_path`, eq. 19), with the invertibility of
        eqs. 24-26 guaranteed; of several candidate fits, the one predicted to track best
        by cross-validation (``fit_report_["criterion_um"]``,
        :func:`hystcomp.identify.compensation.tracking_scorer`). Then sets the learned
        attributes and ``fit_report_``.

        Parameters
        ----------
        v, x : array_like
            The record, as in :meth:`HysteresisModel.fit
            <hystcomp.models.base.HysteresisModel.fit>`.

        Returns
        -------
        PrandtlIshlinskii
            ``self``, fitted.
        """
        params = self._check_hyperparameters(fitting=True)
        fits = self._fits(v, x, params)
        # scored on the samples the fits ran over (a long record is thinned, see
        # fit_mpi_path); they hold the extremes of the input
        v_k, x_k, first = thinned_record(v, x, fits[0])
        voltage_range = fit_voltage_range(params["voltage_range"], v_k)
        score = tracking_scorer(v_k, x_k, start=first, folds=fits[0].folds)

        candidates = [  # (model, fit, the models fitted with a fold left out)
            (
                self._from_fit(fit, voltage_range),
                fit,
                tuple(self._from_fit(part, voltage_range) for part in fit.held_out),
            )
            for fit in fits
        ]
        if len(candidates) == 1:
            model, fit, held_out = candidates[0]
            est = score(model, held_out)
        else:  # the smallest criterion (the first of equals), then its estimate on the record
            scored = [(m, f, score(m, held, estimate=False)) for m, f, held in candidates]
            model, fit, cv = min(scored, key=lambda c: c[2]["criterion_um"])
            est = {**score(model), **cv}
        self._adopt_fit(model, v_k, x_k, first, est, **self._fit_extra(fit))
        return self

    def _fits(self, v, x, params: dict[str, Any]) -> list:
        """The candidate fits of the record, from the checked hyperparameters ``params``:
        one :class:`~hystcomp.identify.pi.PIFit` (:func:`~hystcomp.identify.pi.fit_pi`)."""
        return [
            fit_pi(
                v,
                x,
                n_operators=params["n_operators"],
                transient=params["transient"],
                margin=params["margin"],
                constraints=params["constraints"],
                n_folds=CV_FOLDS,
            )
        ]

    def _fit_extra(self, fit) -> dict[str, Any]:
        """What the fit report says of the chosen fit beyond the errors (nothing for PI)."""
        return {}

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
        self._set_learned(
            thresholds=np.array(fit.thresholds, dtype=np.float64),
            weights=np.array(fit.weights, dtype=np.float64),
            initial_state=np.array(fit.initial_state, dtype=np.float64),
            **{name: np.array(value, dtype=np.float64) for name, value in arrays.items()},
            voltage_range=voltage_range,
            input_offset=float(fit.input_offset),
            output_offset=float(fit.output_offset),
        )

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
        model._set_learned(
            **_checked_plays(owner, thresholds, weights, initial_state),
            **_checked_offsets(owner, voltage_range, input_offset, output_offset),
        )
        return model

    def _derived_hyperparameters(self) -> dict[str, Any]:
        return {"n_operators": int(self.thresholds_.size)}

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
        """The analytic inverse (eqs. 24-26) as a compensator clamped to the voltage range.

        For PI the inverse plays of eqs. (24)-(26); for MPI eq. (23),
        ``v = v_0 + H^-1[S^-1[x - x_0]]``, with ``S^-1`` a dead-zone superposition and
        ``H^-1`` a PI model, both from eqs. (24)-(25) (and eq. 26 for the initial states).

        Parameters
        ----------
        slew_rate, sample_rate, voltage_range, dynamics
            The output's limits and the dynamics in series, as in
            :meth:`HysteresisModel.inverse <hystcomp.models.base.HysteresisModel.inverse>`.

        Returns
        -------
        Compensator or DynamicCompensator
            The compensator, clamped to the voltage range.

        Returns
        -------
        Compensator or DynamicCompensator
            The compensator; with ``dynamics``, in series with their inverse.

        Raises
        ------
        NotInvertibleError
            If a partial sum of the play weights (or, for MPI, of the dead-zone weights) is
            not positive; its ``index`` names it.
        """
        self._check_fitted()
        self._check_invertible()
        # the chain x -> (x - x_0) -> [S^-1 dead-zones] -> inverse plays (eqs. 24-26) -> + v_0
        max_step, (lo, hi) = self._output_limits(slew_rate, sample_rate, voltage_range, dynamics)
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


def _checked_plays(owner: str, thresholds, weights, initial_state) -> dict[str, np.ndarray]:
    """The validated ``thresholds``, ``weights`` and ``initial_state`` of a chain's plays
    (eq. 18: a zero state unless given)."""
    r = check_thresholds(thresholds, "thresholds", owner)
    w = as_vector(weights, "weights", owner, length=r.size)
    if initial_state is None:
        y = np.zeros(r.size)
    else:
        y = as_vector(initial_state, "initial_state", owner, length=r.size)
        check_reachable_state(y, r, owner)
    return {"thresholds": r, "weights": w, "initial_state": y}


def _checked_offsets(owner: str, voltage_range, input_offset, output_offset) -> dict[str, Any]:
    """The validated ``voltage_range``, ``input_offset`` and ``output_offset``."""
    return {
        "voltage_range": check_range(voltage_range, "voltage_range", owner),
        "input_offset": check_real(input_offset, "input_offset", owner),
        "output_offset": check_real(output_offset, "output_offset", owner),
    }


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
