"""The Modified Prandtl-Ishlinskii model (paper eq. 15) and its analytic inverse (eq. 23).

The MPI model is the PI model of :mod:`hystcomp.models.pi` with a saturation stage ``S``
after the plays; only that stage and the fit of eq. (19) are written here.
"""

from __future__ import annotations

from typing import Any, ClassVar, Self

import numpy as np

from hystcomp import paper
from hystcomp._hyperparameters import (
    OPERATOR_COUNT,
    REGULARIZATION_OPTION,
    Constraint,
    Options,
)
from hystcomp._validation import as_vector, check_thresholds
from hystcomp.identify.compensation import CV_FOLDS
from hystcomp.identify.mpi import REGULARIZATION_GRID, fit_mpi_path
from hystcomp.identify.pi import INITIAL_MEMORIES
from hystcomp.models.base import DEFAULT_VOLTAGE_RANGE
from hystcomp.models.inversion import check_invertible, invert_superposition
from hystcomp.models.pi import (
    PrandtlIshlinskii,
    _checked_offsets,
    _checked_plays,
)


class ModifiedPrandtlIshlinskii(PrandtlIshlinskii):
    """Modified Prandtl-Ishlinskii model, eq. (15): ``x = x_0 + S[H[v - v_0]]``.

    ``H`` is a PI model (eq. 12) of plays, ``S`` a superposition of one-sided dead-zones
    (eqs. 13-14), which makes the loops asymmetric and lets them saturate. It is a
    :class:`~hystcomp.models.pi.PrandtlIshlinskii` with the stage ``S`` added (its plays,
    offsets, inverse and play hyperparameters are the PI model's) and its own fit, eq. (19).

    Parameters
    ----------
    n_operators : int, default 16
        Number of play operators in ``H`` (``n + 1``; the paper uses 16).
    n_deadzones : int, default 16
        Number of dead-zones in ``S`` (``m + 1``; the paper uses 16).
    voltage_range : (float, float) or None, default None
        The amplifier's range in V; ``None`` takes the range of the identification data.
    transient : int or None, default None
        Samples at the start of the record left out of the fit; ``None``: until the input
        first reaches an end of its range (:func:`hystcomp.identify.scoring.transient_end`).
    margin : float, default 1e-3
        Invertibility margin of the fit (see :func:`hystcomp.identify.mpi.fit_mpi`).
    regularization : float or "auto", default "auto"
        Tikhonov penalty on the inverse dead-zone weights; 0 is eq. (19) as printed. A
        deviation from the paper for records of actuators that are not exactly MPI systems
        (see :mod:`hystcomp.identify.mpi`). ``"auto"`` fits every value of
        :data:`~hystcomp.identify.mpi.REGULARIZATION_GRID` (0 included) and keeps the model
        that predicts tracking best by cross-validation over the record's reversal
        segments (``fit_report_["criterion_um"]``, see
        :func:`hystcomp.identify.compensation.tracking_scorer`), not the smallest fit
        error: a model that reproduces its record best can still predict other branches
        worse, or have an inverse with steep slopes. With a second record of the actuator,
        choose it by prediction there with
        :func:`hystcomp.identify.validation.choose_regularization`.
    constraints : {"physical", "paper"}, default "physical"
        ``"physical"``: play weights beyond the first are non-negative, ``S`` stays
        monotone, and the plays start virgin (eq. 18) or descended, whichever is predicted
        to track best, as the regularisation (see :mod:`hystcomp.identify.mpi`);
        ``"paper"``: eq. (19) with only its partial sums kept positive, from eq. (18)'s virgin
        start. ``constraints="paper", regularization=0`` is the paper's fit exactly.
    initial_memory : {"auto", "virgin", "descended"}, default "auto"
        Where the plays start (:func:`hystcomp.identify.pi.initial_play_states`), for the
        fit and for the compensator: ``"auto"`` as ``constraints`` says above; ``"virgin"``
        is eq. (18); ``"descended"`` is a stage at rest after it has been driven, as most
        are when a reference starts. The record cannot say how the stage will be when a
        reference starts, and a reference that stays inside the range never wipes that
        start out: give it when you know.

    Attributes
    ----------
    thresholds_, weights_, initial_state_ : ndarray
        The plays of ``H``: V, µm/V, V.
    deadzone_thresholds_, deadzone_weights_ : ndarray
        The dead-zones of ``S``: thresholds in µm (of ``H``'s output) and unitless weights.
        Identification finds the *inverse* dead-zones (eq. 19); these are the forward ones,
        computed with eqs. (24)-(25) as the paper says after eq. 19.
    voltage_range_, input_offset_, output_offset_
        As in :class:`~hystcomp.models.pi.PrandtlIshlinskii`.
    fit_report_ : dict
        After :meth:`fit`: errors of the model on the record, the ``regularization`` it was
        fitted with (the chosen value if ``"auto"``), the ``initial_memory`` of its plays
        (``"virgin"`` or ``"descended"``), ``tracking_rms_um`` (the estimated
        tracking error of its compensator, µm rms), ``baseline_tracking_rms_um`` (the same
        for a straight line ``v = x / k_lin``), and the cross-validated errors
        ``held_out_rms_um``, ``held_out_tracking_rms_um`` and ``criterion_um``
        (:func:`hystcomp.identify.compensation.tracking_scorer`).

    Examples
    --------
    >>> model = ModifiedPrandtlIshlinskii.from_parameters(
    ...     thresholds=[0, 10], weights=[0.2, 0.1],
    ...     deadzone_thresholds=[0, 4], deadzone_weights=[1.0, -0.5])
    >>> v = np.array([0.0, 20.0, 5.0])
    >>> x = model.simulate(v)
    >>> x.round(6).tolist()
    [0.0, 4.5, 2.0]
    >>> model.inverse().simulate(x).round(9).tolist()
    [0.0, 20.0, 5.0]
    """

    kind = "mpi"
    _learned = (
        "thresholds",
        "weights",
        "initial_state",
        "deadzone_thresholds",
        "deadzone_weights",
        "voltage_range",
        "input_offset",
        "output_offset",
    )
    _parameter_constraints: ClassVar[dict[str, Constraint]] = {
        **PrandtlIshlinskii._parameter_constraints,
        "n_deadzones": OPERATOR_COUNT,
        "regularization": REGULARIZATION_OPTION,
        "initial_memory": Options(
            ("auto", *INITIAL_MEMORIES), wording=f"'auto' or one of {INITIAL_MEMORIES}"
        ),
    }
    deadzone_thresholds_: np.ndarray
    deadzone_weights_: np.ndarray

    def __init__(
        self,
        *,
        n_operators=paper.N_OPERATORS,
        n_deadzones=paper.N_DEADZONES,
        voltage_range=None,
        transient=None,
        margin=1e-3,
        regularization="auto",
        constraints="physical",
        initial_memory="auto",
    ):
        super().__init__(
            n_operators=n_operators,
            voltage_range=voltage_range,
            transient=transient,
            margin=margin,
            constraints=constraints,
        )
        self.n_deadzones = n_deadzones
        self.regularization = regularization
        self.initial_memory = initial_memory

    def _fits(self, v, x, params: dict[str, Any]) -> list:
        """The candidate fits of eq. (19) (:func:`~hystcomp.identify.mpi.fit_mpi_path`): one
        per value of the regularisation (the grid for ``"auto"``) and initial memory of the
        plays (eq. 18's virgin plays, and with the physical constraints the descended ones
        too, for ``"auto"``); :meth:`fit` keeps the one predicted to track best."""
        regularization = params["regularization"]
        penalties = REGULARIZATION_GRID if regularization == "auto" else (regularization,)
        if params["initial_memory"] != "auto":
            memories: tuple[str, ...] = (params["initial_memory"],)
        else:
            memories = INITIAL_MEMORIES if params["constraints"] == "physical" else ("virgin",)
        return fit_mpi_path(
            v,
            x,
            n_operators=params["n_operators"],
            n_deadzones=params["n_deadzones"],
            transient=params["transient"],
            margin=params["margin"],
            regularizations=penalties,
            constraints=params["constraints"],
            n_folds=CV_FOLDS,
            initial_memories=memories,
        )

    def _fit_extra(self, fit) -> dict[str, Any]:
        """The report names the chosen fit's ``regularization`` and ``initial_memory``."""
        return {"regularization": fit.regularization, "initial_memory": fit.initial_memory}

    def _from_fit(self, fit, voltage_range) -> Self:
        """The model of an :class:`~hystcomp.identify.mpi.MPIFit`, its forward dead-zones
        from the identified inverse ones (eqs. 24-25; see :meth:`_set_fitted`)."""
        rs, ws = invert_superposition(fit.inverse_deadzone_thresholds, fit.inverse_deadzone_weights)
        model = type(self)(n_operators=fit.thresholds.size, n_deadzones=rs.size, voltage_range=None)
        model._set_fitted(fit, voltage_range, deadzone_thresholds=rs, deadzone_weights=ws)
        return model

    @classmethod
    def from_parameters(  # type: ignore[override]  # S's dead-zones are required
        cls,
        *,
        thresholds,
        weights,
        deadzone_thresholds,
        deadzone_weights,
        initial_state=None,
        voltage_range=DEFAULT_VOLTAGE_RANGE,
        input_offset=0.0,
        output_offset=0.0,
    ) -> Self:
        """A model with the given parameters (V, µm/V, µm, unitless); all validated.

        Parameters
        ----------
        thresholds, weights, initial_state
            The plays of ``H``, as in :meth:`PrandtlIshlinskii.from_parameters
            <hystcomp.models.pi.PrandtlIshlinskii.from_parameters>`: thresholds (V, rising
            from 0), weights (µm/V) and initial states (V; zeros if None, eq. 18).
        deadzone_thresholds : array_like
            The dead-zone thresholds ``r_S`` of ``S``, µm of ``H``'s output, rising from 0.
        deadzone_weights : array_like
            The dead-zone weights ``w_S``, unitless.
        voltage_range, input_offset, output_offset
            The amplifier's range (V), the voltage subtracted before the plays (V) and the
            displacement added after the dead-zones (µm).

        Returns
        -------
        ModifiedPrandtlIshlinskii
            The model, as if fitted.
        """
        owner = cls.__name__
        rs = check_thresholds(deadzone_thresholds, "deadzone_thresholds", owner)
        model = cls(n_operators=np.size(thresholds), n_deadzones=rs.size, voltage_range=None)
        model._set_learned(
            **_checked_plays(owner, thresholds, weights, initial_state),
            deadzone_thresholds=rs,
            deadzone_weights=as_vector(deadzone_weights, "deadzone_weights", owner, length=rs.size),
            **_checked_offsets(owner, voltage_range, input_offset, output_offset),
        )
        return model

    def _derived_hyperparameters(self) -> dict[str, Any]:
        return {
            **super()._derived_hyperparameters(),
            "n_deadzones": int(self.deadzone_thresholds_.size),
        }

    def _saturation(self) -> tuple[np.ndarray, np.ndarray]:
        return self.deadzone_thresholds_, self.deadzone_weights_

    def _check_invertible(self) -> None:
        owner = type(self).__name__
        check_invertible(self.weights_, f"The hysteresis operator H of this {owner} model")
        check_invertible(self.deadzone_weights_, f"The saturation operator S of this {owner} model")

    @staticmethod
    def forward_deadzones(inverse_thresholds, inverse_weights) -> tuple[np.ndarray, np.ndarray]:
        """Forward dead-zones ``(r_S, w_S)`` from the identified inverse ones ``(r'_S, w'_S)``.

        The paper's remark after eq. (19): the same transform as eqs. (24)-(25).

        Parameters
        ----------
        inverse_thresholds : array_like
            The identified inverse dead-zone thresholds ``r'_S``.
        inverse_weights : array_like
            The identified inverse dead-zone weights ``w'_S``.

        Returns
        -------
        thresholds : numpy.ndarray
            The forward thresholds ``r_S``.
        weights : numpy.ndarray
            The forward weights ``w_S``.
        """
        r = check_thresholds(inverse_thresholds, "inverse_thresholds", "forward_deadzones")
        w = as_vector(inverse_weights, "inverse_weights", "forward_deadzones", length=r.size)
        check_invertible(w, "The inverse saturation operator")
        return invert_superposition(r, w)
