"""The Modified Prandtl-Ishlinskii model (paper eq. 15) and its analytic inverse (eq. 23).

The MPI model is the PI model of :mod:`hystcomp.models.pi` with a saturation stage ``S``
after the plays; only that stage and the fit of eq. (19) are written here.
"""

from __future__ import annotations

from typing import Any, Self

import numpy as np

from hystcomp import paper
from hystcomp._hyperparameters import check_operator_count, check_regularization_option
from hystcomp._validation import as_vector, check_int, check_thresholds
from hystcomp.errors import InvalidParameterError
from hystcomp.identify.compensation import CV_FOLDS, tracking_scorer
from hystcomp.identify.mpi import REGULARIZATION_GRID, fit_mpi_path
from hystcomp.identify.pi import INITIAL_MEMORIES
from hystcomp.models.base import DEFAULT_VOLTAGE_RANGE, fit_voltage_range
from hystcomp.models.compensator import Compensator
from hystcomp.models.dynamic_compensator import DynamicCompensator
from hystcomp.models.estimator import fit_signals
from hystcomp.models.inversion import check_invertible, invert_superposition
from hystcomp.models.pi import PrandtlIshlinskii, thinned_record


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
        self.n_operators = n_operators
        self.n_deadzones = n_deadzones
        self.voltage_range = voltage_range
        self.transient = transient
        self.margin = margin
        self.regularization = regularization
        self.constraints = constraints
        self.initial_memory = initial_memory

    @fit_signals
    def fit(self, v, x) -> Self:
        """Identify the model from a measured record by eq. (19) (Section IV-A).

        Delegates to :func:`hystcomp.identify.mpi.fit_mpi`, which finds the plays of ``H``
        and the *inverse* dead-zones; the forward dead-zones ``deadzone_thresholds_``,
        ``deadzone_weights_`` follow from eqs. (24)-(25) (:meth:`forward_deadzones`).

        Parameters
        ----------
        v, x : array_like
            Input voltage (V) and measured displacement (µm), one sample each per instant.

        Returns
        -------
        ModifiedPrandtlIshlinskii
            ``self``, fitted.
        """
        owner = type(self).__name__
        self._check_hyperparameters()
        n = check_operator_count(self.n_operators, "n_operators", owner)
        m = check_operator_count(self.n_deadzones, "n_deadzones", owner)
        penalties = self._penalties(owner)
        # eq. 18's virgin plays, and with the physical constraints the descended ones too
        if self.initial_memory != "auto":
            memories: tuple[str, ...] = (self.initial_memory,)
        else:
            memories = INITIAL_MEMORIES if self.constraints == "physical" else ("virgin",)
        fits = fit_mpi_path(
            v,
            x,
            n_operators=n,
            n_deadzones=m,
            transient=self.transient,
            margin=self.margin,
            regularizations=penalties,
            constraints=self.constraints,
            n_folds=CV_FOLDS,
            initial_memories=memories,
        )
        # scored on the samples the fit used (a long record is thinned, see fit_mpi_path);
        # they hold the extremes of the input
        v_k, x_k, first = thinned_record(v, x, fits[0])
        voltage_range = fit_voltage_range(self.voltage_range, v_k, owner)
        score = tracking_scorer(v_k, x_k, start=first, folds=fits[0].folds)
        candidates = []
        for fit in fits:
            candidate = self._from_fit(fit, voltage_range)
            held_out = tuple(self._from_fit(part, voltage_range) for part in fit.held_out)
            candidates.append((candidate, fit, score(candidate, held_out, estimate=False)))
        # the smallest criterion (the first of equals), then its estimate on the record
        model, fit, cv = min(candidates, key=lambda c: c[2]["criterion_um"])
        est = {**score(model), **cv}
        self._adopt_fit(
            model,
            v_k,
            x_k,
            first,
            est,
            regularization=fit.regularization,
            initial_memory=fit.initial_memory,
        )
        return self

    def _from_fit(self, fit, voltage_range) -> Self:
        """The model of an :class:`~hystcomp.identify.mpi.MPIFit`, its forward dead-zones
        from the identified inverse ones (eqs. 24-25; see :meth:`_set_fitted`)."""
        rs, ws = invert_superposition(fit.inverse_deadzone_thresholds, fit.inverse_deadzone_weights)
        model = type(self)(n_operators=fit.thresholds.size, n_deadzones=rs.size, voltage_range=None)
        model._set_fitted(fit, voltage_range, deadzone_thresholds_=rs, deadzone_weights_=ws)
        return model

    def _penalties(self, owner: str) -> tuple[float, ...]:
        """The regularisation values to fit: the grid for ``"auto"``, else the one given."""
        value = check_regularization_option(self.regularization, owner)
        return REGULARIZATION_GRID if isinstance(value, str) else (value,)

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
        thresholds : array_like
            The play thresholds ``r_i``, V, rising from 0.
        weights : array_like
            The play weights ``w_i``, unitless (µm per µm of the dead-zones' input).
        deadzone_thresholds : array_like
            The dead-zone thresholds ``r_S``, rising from 0.
        deadzone_weights : array_like
            The dead-zone weights ``w_S``.
        initial_state : array_like, optional
            The plays' initial states, V (zeros if None, eq. 18).
        voltage_range : tuple of (float, float), optional
            The amplifier's range, V.
        input_offset : float, optional
            The voltage subtracted before the plays, V.
        output_offset : float, optional
            The displacement added after the dead-zones, µm.

        Returns
        -------
        ModifiedPrandtlIshlinskii
            The model, as if fitted.
        """
        owner = cls.__name__
        rs = check_thresholds(deadzone_thresholds, "deadzone_thresholds", owner)
        model = cls(n_operators=np.size(thresholds), n_deadzones=rs.size, voltage_range=None)
        model._set_plays(owner, thresholds, weights, initial_state)
        model.deadzone_thresholds_ = rs
        model.deadzone_weights_ = as_vector(
            deadzone_weights, "deadzone_weights", owner, length=rs.size
        )
        model._set_offsets(owner, voltage_range, input_offset, output_offset)
        return model

    def _derived_hyperparameters(self) -> dict[str, Any]:
        return {
            **super()._derived_hyperparameters(),
            "n_deadzones": int(self.deadzone_thresholds_.size),
        }

    def _check_hyperparameters(self) -> None:
        super()._check_hyperparameters()
        owner = type(self).__name__
        check_int(self.n_deadzones, "n_deadzones", owner)
        check_regularization_option(self.regularization, owner)
        if self.initial_memory not in ("auto", *INITIAL_MEMORIES):
            raise InvalidParameterError(
                f"The 'initial_memory' parameter of {owner} must be 'auto' or one of "
                f"{INITIAL_MEMORIES}. Got {self.initial_memory!r} instead."
            )

    def _saturation(self) -> tuple[np.ndarray, np.ndarray]:
        return self.deadzone_thresholds_, self.deadzone_weights_

    def _check_invertible(self) -> None:
        owner = type(self).__name__
        check_invertible(self.weights_, f"The hysteresis operator H of this {owner} model")
        check_invertible(self.deadzone_weights_, f"The saturation operator S of this {owner} model")

    def inverse(
        self, *, slew_rate=None, sample_rate=None, voltage_range=None, dynamics=None
    ) -> Compensator | DynamicCompensator:
        """The analytic inverse MPI, eq. (23): ``v = v_0 + H^-1[S^-1[x - x_0]]``, clamped.

        ``S^-1`` is a dead-zone superposition and ``H^-1`` a PI model, both from eqs. 24-25
        (and eq. 26 for the initial states). ``slew_rate`` (V/s), ``sample_rate`` (Hz) and
        ``voltage_range`` (a narrower clamp, V) and ``dynamics`` (an inverse of the linear
        dynamics in series) are as in :meth:`PrandtlIshlinskii.inverse`.

        Parameters
        ----------
        slew_rate : float, optional
            Largest output slew rate, V/s (none by default).
        sample_rate : float, optional
            The rate the compensator runs at, Hz.
        voltage_range : tuple of (float, float), optional
            A narrower output clamp, V.
        dynamics : LinearDynamics, optional
            The linear dynamics to invert in series.

        Returns
        -------
        Compensator or DynamicCompensator
            The compensator; with ``dynamics``, in series with their inverse.

        Raises
        ------
        NotInvertibleError
            If a partial sum of the play weights or of the dead-zone weights is not positive.
        """
        return super().inverse(
            slew_rate=slew_rate,
            sample_rate=sample_rate,
            voltage_range=voltage_range,
            dynamics=dynamics,
        )

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
