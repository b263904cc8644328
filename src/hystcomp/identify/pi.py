"""Identification of the classical Prandtl-Ishlinskii model (Section IV-A, eqs. 12, 16, 18).

The paper fixes the thresholds (eq. 16) and the initial states (eq. 18) and fits the weights
by quadratic programming. We do the same, with three generalisations for real records:

* the plays act on ``u = v - v_0`` with ``v_0 = min(v)``, so that eq. (16)'s thresholds
  ``r_i = i/(n+1) max{u}`` span the input range from its lower end (bipolar inputs too);
* the initial states are ``u[0]`` (relaxed at the first sample), which is eq. (18)'s zero for
  a record that starts at ``v_min`` like the paper's;
* a displacement offset ``x_0`` is fitted as an unconstrained constant, and a start-up
  transient can be left out of the cost (:func:`~hystcomp.identify.scoring.transient_end`).

The weights are constrained so that every partial sum ``w_0 + ... + w_i`` stays above a
small margin: then the inverse of eqs. (24)-(26) exists.

Physical constraints (the default, a deviation from the paper; ``constraints="paper"`` is
eq. 12 with the partial-sum constraints only). On an actuator that is not exactly a PI
system the partial-sum constraint alone lets the weights alternate in sign: the fit uses
pairs of nearly cancelling plays to follow the mismatch, the loading curve gets nearly flat
stretches and the inverse huge slopes there. ``constraints="physical"`` also keeps every
weight beyond the first non-negative (``w_i >= 0``, ``i >= 1``): the initial loading curve
is then convex without wiggles (its slope only grows), the loop width grows with amplitude
as a piezo's does, and the inverse's slopes stay below ``1 / w_0``.

The physical fit also spreads its thresholds over half the input span, where the plays
can move (:func:`play_thresholds`), and weights the samples so that every part of the input
range counts the same (:func:`~hystcomp.identify.scoring.range_weights`): the paper's
signals linger at the bottom of the range, and the unweighted fit gave the top of the
stroke away for it.

The plays start as eq. (18) has them (:func:`initial_play_states`, ``"virgin"``). The MPI
fit also tries the descended start and keeps the one predicted to track best
(:mod:`hystcomp.identify.mpi`); for PI that choice picks the worse memory too often, so PI
keeps eq. 18.

Each of these choices was made on the tracking measured on the panel of
``benchmarks/bench_accuracy.py``; the figures are in the documentation (Benchmarks, "The PI
fit").

Records longer than :data:`~hystcomp.identify.scoring.MAX_SAMPLES` are fitted on every
turning point and a regular subset of the samples (:func:`prepare_record`): the play
outputs there are exact (rate independence), and the cost weights the record as the whole
does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hystcomp import paper
from hystcomp._hyperparameters import (
    DEFAULT_MARGIN,
    FIT_CONSTRAINTS,
    MARGIN,
    OPERATOR_COUNT,
    Constraint,
    Integer,
    validate_parameters,
)
from hystcomp._validation import as_signal_pair, check_int, check_real
from hystcomp.errors import IdentificationError, InvalidParameterError
from hystcomp.identify import scoring
from hystcomp.identify.lsq import constrained_lsq, held_out_fits, normal_equations
from hystcomp.identify.outliers import check_isolated
from hystcomp.identify.scoring import (
    check_response,
    check_transient,
    range_weights,
    reversal_folds,
    thin,
)


def paper_thresholds(n_operators: int, span: float) -> np.ndarray:
    """Eq. (16)/(17): ``r_i = i / (n+1) * span`` for ``i = 0..n`` (``n_operators = n + 1``).

    Parameters
    ----------
    n_operators : int
        The number of plays, ``n + 1``.
    span : float
        The input span (``v_max``, eq. 16) or ``max{x_p}`` (eq. 17).

    Returns
    -------
    numpy.ndarray
        The thresholds, rising from 0.

    Examples
    --------
    >>> paper_thresholds(4, 120.0).tolist()
    [0.0, 30.0, 60.0, 90.0]
    """
    n_operators = check_int(n_operators, "n_operators", "paper_thresholds", maximum=10**6)
    span = check_real(span, "span", "paper_thresholds", positive=True, bound=np.inf)
    return np.arange(n_operators) / n_operators * span


def play_thresholds(n_operators: int, span: float, constraints: str) -> np.ndarray:
    """The play thresholds of a fit: eq. (16) for ``"paper"``, over half the span otherwise.

    A play of threshold ``r`` can only move while the input travels more than ``2 r``, so
    once the input has visited both ends of its span ``U`` the plays with ``r >= U / 2`` are
    frozen for good: eq. (16)'s ``r_i = i / (n+1) U`` leaves half of them without use (their
    regressors are constant, see :func:`~hystcomp.identify.lsq.constrained_lsq`). The
    physical fit spreads the same number of plays over ``r_i = i / (n+1) U / 2`` instead,
    where the record has data, which lowers the tracking error on most of the benchmark
    panel's cells (Benchmarks, "The PI fit").

    Parameters
    ----------
    n_operators : int
        The number of plays.
    span : float
        The input span, V.
    constraints : str
        ``"paper"`` or ``"physical"``.

    Returns
    -------
    numpy.ndarray
        The thresholds, V, rising from 0.

    Examples
    --------
    >>> play_thresholds(4, 120.0, "paper").tolist()
    [0.0, 30.0, 60.0, 90.0]
    >>> play_thresholds(4, 120.0, "physical").tolist()
    [0.0, 15.0, 30.0, 45.0]
    """
    return paper_thresholds(n_operators, span if constraints == "paper" else 0.5 * span)


#: The initial memories of a play superposition that a fit can start from.
INITIAL_MEMORIES = ("virgin", "descended")


def check_initial_memory(initial_memory) -> str:
    """The ``initial_memory`` option: one of :data:`INITIAL_MEMORIES`.

    Parameters
    ----------
    initial_memory : str
        The option as given.

    Returns
    -------
    str
        ``initial_memory``, checked.
    """
    if initial_memory not in INITIAL_MEMORIES:
        raise InvalidParameterError(
            f"The 'initial_memory' parameter must be one of {INITIAL_MEMORIES}. "
            f"Got {initial_memory!r} instead."
        )
    return initial_memory


def initial_play_states(u0: float, thresholds, initial_memory: str) -> np.ndarray:
    """The states of plays of ``thresholds`` at a first input ``u0``, for an initial memory.

    ``"virgin"``: every play at the input, ``y_i = u0`` (eq. 18's zero states for a record
    that starts at ``v_min``): the loading curve from there is the initial one, and a loop
    back to ``u0`` ends above its start by ``sum_i w_i r_i``. ``"descended"``: every play at
    the top of its band, ``y_i = u0 + r_i``, as after a descent from far above (for the
    plays, the state of a Preisach model whose every relay is off, the start of
    :class:`~hystcomp.Preisach`): every loop from ``u0`` closes there again.

    Parameters
    ----------
    u0 : float
        The first input of the plays, V.
    thresholds : array_like
        The play thresholds, V.
    initial_memory : str
        ``"virgin"`` or ``"descended"``.

    Returns
    -------
    numpy.ndarray
        The initial states, V.

    Examples
    --------
    >>> initial_play_states(0.0, np.array([0.0, 10.0]), "descended").tolist()
    [0.0, 10.0]
    """
    initial_memory = check_initial_memory(initial_memory)
    r = np.asarray(thresholds, dtype=np.float64)
    return np.full(r.size, float(u0)) + (r if initial_memory == "descended" else 0.0)


@dataclass(frozen=True)
class PreparedRecord:
    """A validated identification record, thinned, with the play input and the fit's start.

    ``v``, ``x`` and ``u`` hold the samples the fit uses (``samples`` of the record: all of
    them, or for a record longer than :data:`~hystcomp.identify.scoring.MAX_SAMPLES` its
    turning points and a regular subset, :func:`~hystcomp.identify.scoring.thin`); ``start``
    indexes them.

    Parameters
    ----------
    v : numpy.ndarray
        The voltages the fit uses, V.
    x : numpy.ndarray
        The displacements the fit uses, µm.
    input_offset : float
        The voltage subtracted before the plays, V.
    u : numpy.ndarray
        The plays' input ``v - input_offset``, V.
    start : int
        The first of the kept samples in the fit's cost (after the start-up transient).
    input_span : float
        The span of the input, V.
    slope : float
        The straight line's slope, µm/V.
    samples : numpy.ndarray
        The indices of the kept samples in the record.
    weights : numpy.ndarray, optional
        The samples' weights in the fit (None: all equal).
    """

    v: np.ndarray
    x: np.ndarray
    input_offset: float  # v_0 = min(v), V
    u: np.ndarray  # v - v_0, V
    start: int  # first sample in the cost (among the kept samples)
    input_span: float  # max(u), V
    slope: float  # displacement range / input span over the fit samples, µm/V
    samples: np.ndarray  # indices of the kept samples in the record
    weights: np.ndarray | None = None  # per kept sample in the cost (None: all 1)


def prepare_record(
    v, x, *, n_weights: int, transient, owner: str, weighted: bool = False
) -> PreparedRecord:
    """Validate ``(v, x)`` for identification, thin it and find the samples the fit uses.

    Every sample is read for validation, for the start-up transient and for the turning
    points (:func:`~hystcomp.identify.scoring.thin`); every other check runs on the kept
    samples, which hold the extremes of the input (turning points or end points). With
    ``weighted``, the kept samples get weights under which every part of the input range
    counts the same (:func:`~hystcomp.identify.scoring.range_weights`); otherwise every
    sample weighs the same.

    Parameters
    ----------
    v, x : array_like
        The record: voltage (V) and displacement (µm), one sample each.
    n_weights : int
        The number of weights to fit (the record must hold more samples).
    transient : int or None
        The first sample of the fit (found from the record if None).
    owner : str
        The class named in an error message.
    weighted : bool, optional
        Whether every part of the input range should weigh the same.

    Returns
    -------
    PreparedRecord
        The record, ready for the fit.
    """
    v, x = as_signal_pair(v, x, ("v", "x"), owner, min_samples=2, kinds=("voltage", "displacement"))
    check_isolated(v, owner)  # one glitch would set the range and the transient's end
    start = check_transient(transient, v, owner, min_used=2 * n_weights)
    keep = thin(v, start, scoring.MAX_SAMPLES)
    if keep.size < v.size:
        v, x = v[keep], x[keep]
        start = int(np.searchsorted(keep, start))
    v0 = float(v.min())
    u = v - v0
    span = float(u.max())
    if span <= 0.0:
        raise IdentificationError(
            f"{owner}: the input 'v' is constant ({v0!r} V), so it shows no hysteresis to "
            "identify. Record the response to an input that sweeps the actuator's range, "
            "such as the paper's triangles of 30 to 120 V (excitation_signal('pi'))."
        )
    u_fit, x_fit = u[start:], x[start:]
    if np.ptp(u_fit) <= 0.0:
        raise IdentificationError(
            f"{owner}: the input 'v' is constant after the start-up transient (sample "
            f"{start} on). Set a shorter transient."
        )
    x_span = float(np.ptp(x_fit))
    if x_span <= 0.0:
        raise IdentificationError(
            f"{owner}: the displacement 'x' is constant after sample {start}; the sensor "
            "recorded no motion. Check the displacement column."
        )
    check_response(u_fit, x_fit, owner)  # rising, and more than noise
    weights = range_weights(u, start) if weighted else None
    return PreparedRecord(v, x, v0, u, start, span, x_span / span, keep, weights)


@dataclass(frozen=True)
class PIFit:
    """Parameters of a PI model identified by :func:`fit_pi` (eq. 12).

    Attributes
    ----------
    thresholds : ndarray
        ``r_i`` in V (eq. 16; over half the input span with the physical constraints,
        :func:`play_thresholds`).
    weights : ndarray
        ``w_i`` in µm/V; every partial sum is at least the margin.
    initial_state : ndarray
        Initial play states in V (``v[0] - v_0``).
    input_offset : float
        ``v_0 = min(v)`` in V.
    output_offset : float
        ``x_0`` in µm.
    samples : ndarray
        Indices of the samples the fit ran over: all of them, or for a record longer than
        :data:`~hystcomp.identify.scoring.MAX_SAMPLES` its turning points and a regular
        subset (:func:`~hystcomp.identify.scoring.thin`).
    first_sample : int
        First sample of the record in the cost (after the start-up transient).
    folds : ndarray or None
        With ``held_out``: the fold of each of the ``samples`` (-1 before the first).
    held_out : tuple of PIFit
        Fit ``f`` on every fold but fold ``f`` (:func:`fit_pi` with ``n_folds``), or empty.
    """

    thresholds: np.ndarray
    weights: np.ndarray
    initial_state: np.ndarray
    input_offset: float
    output_offset: float
    first_sample: int
    samples: np.ndarray | None = None
    folds: np.ndarray | None = None
    held_out: tuple = ()


#: The options of :func:`fit_pi` checked at its boundary (the record's, by prepare_record).
FIT_PI_OPTIONS: dict[str, Constraint] = {
    "n_operators": OPERATOR_COUNT,
    "margin": MARGIN,
    "constraints": FIT_CONSTRAINTS,
    "n_folds": Integer(0),
}


def fit_pi(
    v,
    x,
    *,
    n_operators=paper.N_OPERATORS,
    transient=None,
    margin=DEFAULT_MARGIN,
    constraints="physical",
    n_folds=0,
) -> PIFit:
    """Identify a classical PI model (eq. 12) from a measured record by constrained least squares.

    Minimises ``sum_k c_k (x_0 + sum_i w_i play_{r_i}(v - v_0)[k] - x[k])^2`` over the
    samples after the start-up transient (``c_k = 1`` for the paper's fit, the range
    weights of :func:`~hystcomp.identify.scoring.range_weights` for the physical one),
    subject to ``w_0 + ... + w_i >= margin * X / U`` for every ``i`` (``X``: measured
    displacement range, ``U``: input span; so the smallest allowed slope is ``margin``
    times the mean slope of the record) and, with the default ``constraints="physical"``,
    ``w_i >= 0`` for ``i >= 1`` (module docstring).

    Parameters
    ----------
    v, x : array_like
        Input voltage (V) and measured displacement (µm), one sample each per instant,
        at any sample rate (the model is rate-independent).
    n_operators : int, default 16
        Number of plays ``n + 1`` (the paper uses 16).
    transient : int or None, default None
        Number of samples at the start left out of the cost (the model still runs over
        them). ``None``: until the input first reaches an end of its range
        (:func:`~hystcomp.identify.scoring.transient_end`).
    margin : float, default 1e-3
        Relative lower bound on the partial sums of the weights (invertibility).
    constraints : {"physical", "paper"}, default "physical"
        ``"physical"``: also ``w_i >= 0`` beyond the first weight, thresholds over half
        the span and range weights (module docstring); ``"paper"``: the partial-sum
        constraints only, eq. (16)'s thresholds and every sample alike, eq. (12) as the
        paper fits it.
    n_folds : int, default 0
        With 2 or more, also fit on all but one fold of the record's reversal segments, for
        every fold (``PIFit.held_out``), as :func:`~hystcomp.identify.mpi.fit_mpi_path`.

    Returns
    -------
    PIFit

    Examples
    --------
    >>> v = np.concatenate([np.linspace(0, 10, 21), np.linspace(10, 0, 21)[1:]])
    >>> x = 0.5 * v + 2.0
    >>> fit = fit_pi(v, x, n_operators=2)
    >>> fit.weights.round(6).tolist(), round(fit.output_offset, 6)
    ([0.5, 0.0], 2.0)
    """
    owner = "fit_pi"
    options = validate_parameters(FIT_PI_OPTIONS, locals(), owner, fitting=True)
    n, margin = options["n_operators"], options["margin"]
    constraints, n_folds = options["constraints"], options["n_folds"]
    rec = prepare_record(
        v, x, n_weights=n + 1, transient=transient, owner=owner, weighted=constraints == "physical"
    )
    r = play_thresholds(n, rec.input_span, constraints)
    y0 = initial_play_states(rec.u[0], r, "virgin")  # eq. 18 (module docstring)
    x_ref = float(rec.x[rec.start :].min())
    folds = reversal_folds(rec.u, rec.start, n_folds) if n_folds > 1 else None
    grams = normal_equations(
        rec.u, r, y0, rec.x - x_ref, np.empty(0), rec.start, folds, max(n_folds, 1), rec.weights
    )

    def solve(gram, **extra) -> PIFit:
        sol = constrained_lsq(
            gram,
            blocks=[(0, n, margin * rec.slope)],
            floors=[(1, n, 0.0)] if constraints == "physical" else (),
            scales=np.full(n, rec.input_span),
        )
        return PIFit(
            thresholds=r,
            weights=sol.coef[:n],
            initial_state=y0,
            input_offset=rec.input_offset,
            output_offset=x_ref + float(sol.coef[n]),
            first_sample=int(rec.samples[rec.start]),
            samples=rec.samples,
            **extra,
        )

    if folds is None:
        return solve(grams)
    held_out = held_out_fits(grams, solve)
    return solve(grams.sum(axis=0), folds=folds if held_out else None, held_out=held_out)
