"""Identification of the Modified Prandtl-Ishlinskii model (Section IV-A, eqs. 15-19).

Eq. (19) compares the two sides of the MPI model in the middle: the plays of ``H`` driven by
the input, and the *inverse* saturation operator ``S^-1`` driven by the measured
displacement. Both are linear in their weights, so the joint problem ::

    minimise  sum_k ( H[v](k) + b - S^-1[x - x_0](k) )^2   over  w_H, b, w'_S

is a least-squares problem (solved by :mod:`hystcomp.identify.lsq`), subject to both
invertibility constraints (every partial sum of ``w_H`` and of ``w'_S`` above a margin).

Normalisation. The error is homogeneous: ``(w_H, b, w'_S) -> c (w_H, b, w'_S)`` scales it
by ``c``, so without a normalisation the minimum is the useless ``0``. We fix
``w'_S0 = 1``. This loses nothing: every feasible solution has ``w'_S0 > 0`` (the first
partial sum), and the MPI map itself is unchanged by the rescaling (``S`` with weights
``c w'`` and ``H`` with weights ``c w_H`` compose to the same ``S[H[v]]``: the forward
dead-zones of eqs. 24-25 take inputs scaled by ``c``). With ``w'_S0 = 1`` the cost is in µm
at the lower end of the range, where ``S^-1`` has slope 1.

Offsets. ``x_0`` is the smallest measured displacement after the transient, so that eq. (17)'s
thresholds ``r'_j = j/(m+1) max{x - x_0}`` (the paper's ``max{x_p}``) span the measured
range. The constant ``b`` on the ``H`` side absorbs the rest of the offset; because the play
is shift-equivariant, ``play_r(u + c; y_0 + c) = play_r(u; y_0) + c``, a constant ``b`` equals
``H`` with its input offset lowered and its initial states raised by ``c = b / sum(w_H)``
(:func:`absorb_bias`), so the identified model has the form of eq. (15) exactly.

Physical constraints (the default, a deviation from the paper; ``constraints="paper"`` with
``regularization=0`` is eq. 19 as printed). The play weights of ``H`` beyond the first are
non-negative, as for the PI model (:mod:`hystcomp.identify.pi`), and the saturation stays
monotone (every partial sum of ``w'_S`` above the margin) and smooth (the penalty below, on
its changes of slope). No sign is imposed on ``w'_S`` itself: a piezo's loading curve is
often convex at low voltage and saturating at high voltage, so ``S`` must be able to bend
both ways.

Regularisation (a deviation from the paper; ``regularization=0`` is eq. 19 as printed). On a record of an
actuator that is not exactly an MPI system, eq. (19) is ill-conditioned: the dead-zones of
the measured ``x`` are themselves close to combinations of plays of ``v`` (``x`` is nearly a
PI output), so weights of opposite signs in ``H`` and ``S^-1`` nearly cancel in the cost and
the least-squares solution uses them to fit the model's mismatch. The fit on the record
improves while a different signal is predicted worse; a tell-tale is inverse dead-zone
weights far above 1 with alternating signs. ``regularization > 0`` adds the Tikhonov penalty
``regularization * |D w'|^2`` on the inverse dead-zone weights ``w'_1..w'_m`` (the changes of
slope of ``S^-1``), with ``D`` the scaling that gives each dead-zone regressor unit norm: the
model then explains the record with ``H`` first and bends ``S`` only where the data ask for
it. It biases the fit of a true MPI system (about 0.5 % of the range at 1e-3), so it is chosen
for compensation, not for fit: ``ModifiedPrandtlIshlinskii(regularization="auto")``, the
default, fits every value of :data:`REGULARIZATION_GRID` at the cost of about one fit
(:func:`fit_mpi_path`), each also on every fold but one of the record's reversal segments
(``n_folds``, from the same pass), and keeps the one whose held-out fits predict the
branches they did not see best, forward and through their inverse
(:func:`hystcomp.identify.compensation.tracking_scorer`, ``criterion_um``).
With a second record of the actuator,
:func:`hystcomp.identify.validation.choose_regularization` chooses by prediction instead.

Samples weigh alike. The PI fit weights them so that every part of the input range counts
the same (:func:`~hystcomp.identify.scoring.range_weights`); for MPI that is no gain (it
tracks worse weighted), so eq. (19)'s unweighted sum stays.

Initial memory (a deviation from eq. 18 with the physical constraints). Eq. (18) starts
every play at zero, the *virgin* state of a demagnetised actuator: a loop from ``v_min``
back to ``v_min`` then ends above its start by ``sum_i w_i r_i``. A piezo that has been
driven before (by its own identification run, for one) rests at ``v_min`` in the state
that the last descent left, and most stages close their loops there. The physical fit
therefore also fits the *descended* start, every play at the top of its band as after a
descent from above (:func:`~hystcomp.identify.pi.initial_play_states`; for the plays, the
state of a Preisach model with every relay off, where :class:`~hystcomp.Preisach`
starts), and
``ModifiedPrandtlIshlinskii`` keeps the one whose compensator is predicted to track best
(the same criterion as the regularisation).

Limits of the family. ``S`` bends the loop as a function of the *output* level, so an
actuator whose loop width depends on the *input* level in another way than its loading
curve's slope (a Bouc-Wen stage whose hysteretic gain grows from nothing at 0 V) is beyond
any MPI model.

Each of these choices was made on the tracking measured on the panel of
``benchmarks/bench_accuracy.py``; the figures are in the documentation (Benchmarks, "The MPI
fit").
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass

import numpy as np

from hystcomp import paper
from hystcomp._hyperparameters import (
    DEFAULT_MARGIN,
    FIT_CONSTRAINTS,
    MARGIN,
    OPERATOR_COUNT,
    REGULARIZATION,
    Constraint,
    Each,
    Integer,
    validate_parameters,
)
from hystcomp._validation import as_vector, check_real
from hystcomp.errors import InvalidParameterError
from hystcomp.identify.lsq import RIDGE, constrained_lsq_path, held_out_fits, normal_equations
from hystcomp.identify.pi import (
    check_initial_memory,
    initial_play_states,
    paper_thresholds,
    play_thresholds,
    prepare_record,
)
from hystcomp.identify.scoring import reversal_folds

#: Candidate values of ``regularization`` for a choice: none, then one per decade.
REGULARIZATION_GRID = (0.0, 1e-4, 1e-3, 1e-2, 1e-1)


@dataclass(frozen=True)
class MPIFit:
    """Parameters of an MPI model identified by :func:`fit_mpi` (eqs. 15, 19).

    Attributes
    ----------
    thresholds, weights, initial_state : ndarray
        The plays of ``H``: V (eq. 16, or over half the input span with the physical
        constraints), µm/V, V.
    inverse_deadzone_thresholds : ndarray
        ``r'_S`` of eq. (17), in µm of ``x - x_0``.
    inverse_deadzone_weights : ndarray
        ``w'_S``, unitless, with ``w'_S0 = 1``.
    input_offset, output_offset : float
        ``v_0`` in V (with the bias absorbed, see :func:`absorb_bias`) and ``x_0`` in µm.
    samples : ndarray
        Indices of the samples the fit ran over: all of them, or for a record longer than
        :data:`~hystcomp.identify.scoring.MAX_SAMPLES` its turning points and a regular
        subset (:func:`~hystcomp.identify.scoring.thin`).
    first_sample : int
        First sample of the record in the cost.
    regularization : float
        The penalty it was fitted with.
    initial_memory : {"virgin", "descended"}
        The plays' initial memory it was fitted with
        (:func:`~hystcomp.identify.pi.initial_play_states`).
    folds : ndarray or None
        With ``held_out``: the fold of each of the ``samples`` (-1 before the first).
    held_out : tuple of MPIFit
        Fit ``f`` of the same options on every fold but fold ``f`` (:func:`fit_mpi_path`
        with ``n_folds``), or empty.
    """

    thresholds: np.ndarray
    weights: np.ndarray
    initial_state: np.ndarray
    inverse_deadzone_thresholds: np.ndarray
    inverse_deadzone_weights: np.ndarray
    input_offset: float
    output_offset: float
    first_sample: int
    samples: np.ndarray | None = None
    regularization: float = 0.0
    initial_memory: str = "virgin"
    folds: np.ndarray | None = None
    held_out: tuple = ()


def absorb_bias(weights, initial_state, input_offset: float, bias: float):
    """Fold a constant ``b`` added to a play superposition into its offset and states.

    ``b + sum_i w_i play_{r_i}(v - v_0; y_0)`` equals ``sum_i w_i play_{r_i}(v - v_0'; y_0')``
    with ``c = b / sum(w)``, ``v_0' = v_0 - c`` and ``y_0' = y_0 + c`` (shift equivariance of
    eq. 11). Needs ``sum(w) != 0`` (guaranteed by the invertibility constraint).

    Parameters
    ----------
    weights : array_like
        The play weights ``w_i``.
    initial_state : array_like
        The plays' initial states ``y_0``, V.
    input_offset : float
        The input offset ``v_0``, V.
    bias : float
        The constant ``b`` added to the superposition.

    Returns
    -------
    initial_state, input_offset
        The new initial states (V) and input offset (V).

    Examples
    --------
    >>> absorb_bias(np.array([0.5, 0.5]), np.zeros(2), 10.0, 2.0)
    (array([2., 2.]), 8.0)
    """
    weights = as_vector(weights, "weights", "absorb_bias")
    initial_state = as_vector(initial_state, "initial_state", "absorb_bias", length=weights.size)
    input_offset = check_real(input_offset, "input_offset", "absorb_bias")
    bias = check_real(bias, "bias", "absorb_bias")
    if float(np.sum(weights)) == 0.0:
        raise InvalidParameterError(
            "absorb_bias: the weights sum to 0, so a bias cannot be absorbed."
        )
    return _absorb_bias(weights, initial_state, input_offset, bias)


def _absorb_bias(weights, initial_state, input_offset: float, bias: float):
    """:func:`absorb_bias` for a fit's own values (finite; ``sum(w) > 0`` by its constraints)."""
    shift = bias / float(np.sum(weights))
    return initial_state + shift, input_offset - shift


def fit_mpi(
    v,
    x,
    *,
    n_operators=paper.N_OPERATORS,
    n_deadzones=paper.N_DEADZONES,
    transient=None,
    margin=DEFAULT_MARGIN,
    regularization=0.0,
    constraints="physical",
    initial_memory="virgin",
) -> MPIFit:
    """Identify an MPI model (eq. 15) from a measured record, by eq. (19) with constraints.

    Parameters
    ----------
    v, x : array_like
        Input voltage (V) and measured displacement (µm), at any sample rate.
    n_operators : int, default 16
        Number of plays ``n + 1`` in ``H`` (the paper uses 16).
    n_deadzones : int, default 16
        Number of dead-zones ``m + 1`` in ``S`` (the paper uses 16).
    transient : int or None, default None
        Samples at the start left out of the cost; ``None``: until the input first reaches
        an end of its range (:func:`~hystcomp.identify.scoring.transient_end`).
    margin : float, default 1e-3
        Relative lower bound on the partial sums: ``margin`` times the record's mean slope
        (µm/V) for ``w_H``, ``margin`` for ``w'_S`` (relative to ``w'_S0 = 1``).
    regularization : float, default 0
        Tikhonov penalty on the inverse dead-zone weights ``w'_1..w'_m`` (module
        docstring); 0 is eq. (19) as printed.
    constraints : {"physical", "paper"}, default "physical"
        ``"physical"``: also ``w_i >= 0`` for the plays beyond the first; ``"paper"``:
        eq. (19) with only the partial sums of the weights kept positive (invertibility).
    initial_memory : {"virgin", "descended"}, default "virgin"
        The plays' state at the first sample
        (:func:`~hystcomp.identify.pi.initial_play_states`): eq. (18)'s ``"virgin"``
        state, or ``"descended"``, as after a descent from above.

    Returns
    -------
    MPIFit
        With the *inverse* dead-zones; the forward ones follow from eqs. (24)-(25)
        (``ModifiedPrandtlIshlinskii.forward_deadzones``).
    """
    (fit,) = fit_mpi_path(
        v,
        x,
        n_operators=n_operators,
        n_deadzones=n_deadzones,
        transient=transient,
        margin=margin,
        regularizations=(regularization,),
        constraints=constraints,
        initial_memories=(initial_memory,),
    )
    return fit


#: The options of :func:`fit_mpi_path` checked at its boundary.
FIT_MPI_OPTIONS: dict[str, Constraint] = {
    "n_operators": OPERATOR_COUNT,
    "n_deadzones": OPERATOR_COUNT,
    "margin": MARGIN,
    "constraints": FIT_CONSTRAINTS,
    "regularizations": Each(REGULARIZATION, "regularization", "value >= 0"),
    "n_folds": Integer(0),
}


def fit_mpi_path(
    v,
    x,
    *,
    n_operators=paper.N_OPERATORS,
    n_deadzones=paper.N_DEADZONES,
    transient=None,
    margin=DEFAULT_MARGIN,
    regularizations=REGULARIZATION_GRID,
    constraints="physical",
    n_folds=0,
    initial_memories=("virgin",),
) -> list[MPIFit]:
    """:func:`fit_mpi` for several values of ``regularization`` at the cost of about one.

    The normal equations of eq. (19) do not depend on the penalty, so they are accumulated
    once over the record for each initial memory; each value costs one small quadratic
    programme.

    Parameters
    ----------
    v, x, n_operators, n_deadzones, transient, margin, constraints
        As in :func:`fit_mpi`.
    regularizations : sequence of float, default :data:`REGULARIZATION_GRID`
        The penalties (>= 0), in the order of the fits returned.
    initial_memories : sequence of {"virgin", "descended"}, default ("virgin",)
        The plays' initial memories to fit
        (:func:`~hystcomp.identify.pi.initial_play_states`), each with every penalty, in
        this order.
    n_folds : int, default 0
        With 2 or more, also fit each value on all but one fold of the record's reversal
        segments (:func:`~hystcomp.identify.scoring.reversal_folds`), for every fold, from
        the same pass over the record (``MPIFit.held_out``; see
        :func:`~hystcomp.identify.compensation.tracking_scorer`). Empty if a fold cannot
        be left out (a record of fewer segments, or one whose other folds do not determine
        the fit).

    Returns
    -------
    list of MPIFit
        One fit per initial memory and value of ``regularizations``, memory by memory.
    """
    owner = "fit_mpi"
    options = validate_parameters(FIT_MPI_OPTIONS, locals(), owner, fitting=True)
    n, m, margin = options["n_operators"], options["n_deadzones"], options["margin"]
    constraints, penalties = options["constraints"], options["regularizations"]
    n_folds = options["n_folds"]
    memories = [check_initial_memory(memory) for memory in initial_memories]
    rec = prepare_record(v, x, n_weights=n + m, transient=transient, owner=owner)
    r = play_thresholds(n, rec.input_span, constraints)
    x0 = float(rec.x[rec.start :].min())
    z = rec.x - x0
    z_span = float(z[rec.start :].max())
    rs = paper_thresholds(m, z_span)  # eq. (17)
    folds = reversal_folds(rec.u, rec.start, n_folds) if n_folds > 1 else None
    scales = np.concatenate([np.full(n, rec.input_span), np.full(m - 1, z_span)])
    on_deadzones = np.concatenate([np.zeros(n), np.ones(m - 1)])

    ridges = [RIDGE + penalty * on_deadzones for penalty in penalties]

    def solve(gram, y0, memory) -> list[MPIFit]:
        """The fits of every penalty on ``gram``, plays starting at ``y0``."""
        solutions = constrained_lsq_path(
            gram,
            ridges,
            blocks=[(0, n, margin * rec.slope), (n, n + m - 1, margin - 1.0)],
            floors=[(1, n, 0.0)] if constraints == "physical" else (),
            scales=scales,
        )
        fits = []
        for penalty, sol in zip(penalties, solutions, strict=True):
            weights = sol.coef[:n]
            initial_state, input_offset = _absorb_bias(weights, y0, rec.input_offset, sol.coef[-1])
            fits.append(
                MPIFit(
                    thresholds=r,
                    weights=weights,
                    initial_state=initial_state,
                    inverse_deadzone_thresholds=rs,
                    inverse_deadzone_weights=np.r_[1.0, sol.coef[n : n + m - 1]],
                    input_offset=input_offset,
                    output_offset=x0,
                    first_sample=int(rec.samples[rec.start]),
                    samples=rec.samples,
                    regularization=penalty,
                    initial_memory=memory,
                )
            )
        return fits

    fits = []
    for memory in memories:
        y0 = initial_play_states(rec.u[0], r, memory)
        grams = normal_equations(rec.u, r, y0, z, rs[1:], rec.start, folds, max(n_folds, 1))
        gram = grams.sum(axis=0) if folds is not None else grams
        # per fold left out, the fits of every penalty
        solve_fold = functools.partial(solve, y0=y0, memory=memory)
        held_out = () if folds is None else held_out_fits(grams, solve_fold)
        for k, fit in enumerate(solve(gram, y0, memory)):
            parts = tuple(by_penalty[k] for by_penalty in held_out)
            fits.append(dataclasses.replace(fit, folds=folds if parts else None, held_out=parts))
    return fits
