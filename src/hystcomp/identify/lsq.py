"""Least squares with the invertibility constraints of the PI-type models (eqs. 12, 19, 24-25).

Both identification problems of the paper are linear in the weights:

* PI, eq. (12): ``x[k] ~ c + sum_i w_i play_{r_i}(u)[k]``;
* MPI, eq. (19): ``sum_i w_i play_{r_i}(u)[k] + b ~ sum_j w'_j s_{r'_j}(z)[k]`` with
  ``w'_0 = 1`` (the normalisation, see :mod:`hystcomp.identify.mpi`), i.e.
  ``z[k] ~ b + sum_i w_i play_{r_i}(u)[k] - sum_{j>=1} w'_j s_{r'_j}(z)[k]``.

So one design serves both: the regressor row of sample ``k`` is ::

    [ play_{r_0}(u)[k] ... play_{r_n}(u)[k] | -s_{r'_1}(z[k]) ... -s_{r'_m}(z[k]) | 1 ]

with target ``z[k]`` (``m = 0`` for PI). :func:`normal_equations` accumulates the augmented
Gram matrix ``[Phi | z]^T [Phi | z]`` in one pass over the record, block by block, without
ever holding the ``N x p`` design matrix. :func:`constrained_lsq` then solves the small
quadratic programme: weights whose every partial sum stays above a margin (eqs. 24-25 need
``w_0 + ... + w_i > 0``; the same for the inverse dead-zones), solved with quadprog (the
Goldfarb-Idnani dual active-set method, like the paper's Matlab ``quadprog``).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import quadprog

from hystcomp._blas import one_blas_thread
from hystcomp._kernels import chain
from hystcomp.errors import IdentificationError

_BLOCK = 2048  # rows per BLAS update of the Gram matrix: 0.5 MB, in L2 cache (256: 25 % slower)


def normal_equations(
    u, thresholds, initial_state, z, deadzone_thresholds, start, folds=None, n_folds=1, weights=None
) -> np.ndarray:
    """The augmented Gram matrix of the PI/MPI regressors over samples ``start..``.

    Parameters
    ----------
    u : ndarray
        Play input, ``v - v_0`` in V.
    thresholds, initial_state : ndarray
        Play thresholds and initial states, V.
    z : ndarray
        Target (and dead-zone input), displacement minus an offset, in µm.
    deadzone_thresholds : ndarray
        Positive thresholds ``r'_1..r'_m`` of the inverse dead-zones in µm (empty for PI).
    start : int
        First sample in the sums (the start-up transient before it is left out).
    folds : ndarray of int, optional
        A fold ``0..n_folds - 1`` for every sample (:func:`~hystcomp.identify.scoring.
        reversal_folds`): then one Gram matrix per fold, each over its own samples, in one
        pass (their sum is the matrix over every sample).
    n_folds : int, default 1
        Number of folds (with ``folds``).
    weights : ndarray, optional
        A weight ``c_k >= 0`` for every sample (:func:`~hystcomp.identify.scoring.
        range_weights`): the sums are then ``[Phi | z]^T C [Phi | z]``, the normal equations
        of the weighted cost ``sum_k c_k e_k^2``. None: every sample weighs 1.

    Returns
    -------
    ndarray, shape (p + 1, p + 1), or (n_folds, p + 1, p + 1) with ``folds``
        ``[Phi | z]^T [Phi | z]`` with ``p = n + m + 1`` regressors (plays, negated
        dead-zones, constant) and the target last.

    Notes
    -----
    The block products run on one BLAS thread (:func:`hystcomp._blas.one_blas_thread`):
    they are too small to gain from more, and on a busy machine threads woken for every
    block made a fit many times slower.
    """
    with one_blas_thread():
        return _normal_equations(
            u, thresholds, initial_state, z, deadzone_thresholds, start, folds, n_folds, weights
        )


def _normal_equations(
    u, thresholds, initial_state, z, deadzone_thresholds, start, folds, n_folds, weights
) -> np.ndarray:
    n, m = len(thresholds), len(deadzone_thresholds)
    u = np.ascontiguousarray(u, dtype=np.float64)
    r = np.ascontiguousarray(thresholds, dtype=np.float64)
    y = np.array(initial_state, dtype=np.float64)  # the play states, advanced block by block
    z = np.ascontiguousarray(z, dtype=np.float64)
    rs = np.ascontiguousarray(deadzone_thresholds, dtype=np.float64)
    root = None if weights is None else np.sqrt(np.asarray(weights, dtype=np.float64))
    start = int(start)
    gram = np.zeros((n_folds if folds is not None else 1, n + m + 2, n + m + 2))
    rows = np.empty((max(_BLOCK, start), n + m + 2))
    chain.regressor_rows(u, r, y, z, rs, 0, rows[:start])  # the plays' state at `start`
    # where the fold changes (a fold is a set of whole runs of samples), and which blocks
    # hold a change (most do not: a run is a whole reversal segment)
    changes = np.empty(0, np.int64) if folds is None else np.flatnonzero(np.diff(folds)) + 1
    mixed = set(((changes[changes > start] - start - 1) // _BLOCK).tolist())
    for block, begin in enumerate(range(start, u.size, _BLOCK)):
        part = rows[: min(_BLOCK, u.size - begin)]
        chain.regressor_rows(u, r, y, z, rs, begin, part)
        if root is not None:
            part *= root[begin : begin + part.shape[0], None]
        if folds is None:
            gram[0] += part.T @ part
        elif block not in mixed:
            gram[folds[begin]] += part.T @ part
        else:
            lo, hi = np.searchsorted(changes, (begin, begin + part.shape[0]), side="right")
            cuts = [0, *(changes[lo:hi] - begin), part.shape[0]]
            for a, b in itertools.pairwise(cuts):  # runs of one fold each
                piece = part[a:b]
                gram[folds[begin + a]] += piece.T @ piece
    sign = np.r_[np.ones(n), -np.ones(m), 1.0, 1.0]  # the dead-zone regressors are negated
    gram *= np.outer(sign, sign)
    return gram if folds is not None else gram[0]


@dataclass(frozen=True)
class LsqSolution:
    """Result of :func:`constrained_lsq`.

    Attributes
    ----------
    coef : ndarray
        One coefficient per regressor, the constant last. Coefficients of regressors that do
        not vary over the samples are 0 (see :func:`constrained_lsq`).
    rss : float
        Residual sum of squares of the fit, in the target's units squared.
    varies : ndarray of bool
        Which regressors vary over the samples (and so were fitted).
    """

    coef: np.ndarray
    rss: float
    varies: np.ndarray


#: The relative ridge that keeps the unit-scaled normal matrix positive definite.
RIDGE = 1e-10


class _Centred(NamedTuple):
    """The parts of an augmented Gram matrix ``[X 1 z]^T [X 1 z]`` and its centred block:
    ``G, g, zz`` are the blocks ``[X 1]^T [X 1]``, ``[X 1]^T z`` and ``z^T z``; ``G_c, g_c``
    the centred ``X^T X`` and ``X^T z`` (the intercept eliminated)."""

    G: np.ndarray
    g: np.ndarray
    zz: float
    samples: float  # the constant regressor's square: the sample count
    mean: np.ndarray  # of the regressors
    z_mean: float
    G_c: np.ndarray
    g_c: np.ndarray


def _centred(gram: np.ndarray) -> _Centred:
    """The blocks of ``gram`` and its centred normal equations (:class:`_Centred`)."""
    p = gram.shape[0] - 1
    G, g, zz = gram[:p, :p], gram[:p, p], float(gram[p, p])
    count = float(G[-1, -1])
    mean = G[-1, :-1] / count
    z_mean = float(g[-1] / count)
    G_c = G[:-1, :-1] - count * np.outer(mean, mean)
    g_c = g[:-1] - count * mean * z_mean
    return _Centred(G, g, zz, count, mean, z_mean, G_c, g_c)


def _unscaled(c: _Centred, solution, idx, scale) -> tuple[np.ndarray, float]:
    """The coefficients of a solution for the unit-scaled columns ``idx`` (the others 0), with
    the constant that the centring eliminated, and the residual sum of squares."""
    coef = np.zeros(c.G.shape[0])
    coef[idx] = solution * scale
    coef[-1] = c.z_mean - c.mean @ coef[:-1]
    rss = float(c.zz - 2.0 * c.g @ coef + coef @ c.G @ coef)
    return coef, max(rss, 0.0)


def constrained_lsq(
    gram, *, blocks, scales, floors=(), caps=(), flat_tol=1e-6, ridge=RIDGE
) -> LsqSolution:
    """Least squares from normal equations, every partial sum in each block above a bound.

    Minimises ``|Phi theta - z|^2`` subject to ``theta[a] + ... + theta[i] >= bound`` for
    every block ``(a, b, bound)`` and every ``a <= i < b``; optionally also
    ``theta[i] >= bound`` for every ``(a, b, bound)`` of ``floors`` and ``a <= i < b``
    (non-negative weights), and ``theta[a] + ... + theta[i] <= bound`` for every
    ``(a, b, bound)`` of ``caps`` (a largest slope). The last regressor is the
    constant (an unconstrained offset): it is eliminated exactly first (the Schur complement,
    i.e. the columns are centred), which also removes the large column means that would
    otherwise spoil the conditioning.

    A regressor whose standard deviation over the samples is below ``flat_tol`` times its
    ``scale`` carries no information beyond the constant: its coefficient is fixed at 0.
    This happens for plays with ``r >= (v_max - v_min) / 2`` once the input has visited both
    ends of its range: such a play can never move again, so only the sum of its weight and
    the offset is identifiable. The remaining columns are scaled to unit norm and a relative
    ``ridge`` keeps the quadratic form positive definite when two of them are nearly equal.

    Parameters
    ----------
    gram : ndarray, shape (p + 1, p + 1)
        From :func:`normal_equations`: regressors, constant last, then the target.
    blocks : sequence of (int, int, float)
        ``(first, stop, bound)``: partial sums of ``theta[first:stop]`` must be ``>= bound``.
        The first regressor of a block with ``bound > 0`` must vary over the samples.
    floors : sequence of (int, int, float), optional
        ``(first, stop, bound)``: each of ``theta[first:stop]`` must be ``>= bound``.
    caps : sequence of (int, int, float), optional
        ``(first, stop, bound)``: partial sums of ``theta[first:stop]`` must be ``<= bound``.
    scales : array_like, shape (p - 1,)
        Typical size of each non-constant regressor (its range), in its own units.
    flat_tol : float
        Relative standard deviation under which a regressor counts as constant.
    ridge : float or array_like, shape (p - 1,)
        Added to the diagonal of the unit-scaled normal matrix: one value for every
        regressor, or one each (a Tikhonov penalty on chosen coefficients).

    Returns
    -------
    LsqSolution

    Raises
    ------
    IdentificationError
        If the constrained problem has no solution (it always has one when the first
        regressor of each block varies; the message says what to check otherwise).
    """
    (solution,) = constrained_lsq_path(
        gram,
        (ridge,),
        blocks=blocks,
        scales=scales,
        floors=floors,
        caps=caps,
        flat_tol=flat_tol,
    )
    return solution


def constrained_lsq_path(
    gram, ridges, *, blocks, scales, floors=(), caps=(), flat_tol=1e-6
) -> list[LsqSolution]:
    """:func:`constrained_lsq` for each ridge of ``ridges`` on the same Gram matrix.

    The problem (centring, scaling, constraint rows) is set up once and only the ridge
    changes from one quadratic programme to the next, which is most of the cost of one
    (a path of penalties, :func:`~hystcomp.identify.mpi.fit_mpi_path`).

    Parameters
    ----------
    gram : numpy.ndarray
        The augmented Gram matrix of the regressors and the target.
    ridges : sequence of float
        The ridge penalties, one fit each.
    blocks : sequence of (int, int, float)
        ``(first, stop, bound)``: partial sums of ``theta[first:stop]`` must be ``>= bound``.
    scales : array_like
        Typical size of each non-constant regressor (its range), in its own units.
    floors : sequence of (int, int, float), optional
        ``(first, stop, bound)``: each of ``theta[first:stop]`` must be ``>= bound``.
    caps : sequence of (int, int, float), optional
        ``(first, stop, bound)``: partial sums of ``theta[first:stop]`` must be ``<= bound``.
    flat_tol : float, optional
        Relative variance under which a regressor counts as constant.

    Returns
    -------
    list of LsqSolution
        One solution per ridge, in order.
    """
    p = gram.shape[0] - 1
    c = _centred(gram)
    spread = np.sqrt(np.maximum(np.diag(c.G_c), 0.0) / c.samples)
    varies = spread > flat_tol * np.asarray(scales, dtype=np.float64)
    blocks = [(a, b, bound) for a, b, bound in blocks if b > a]
    for first, _, bound in blocks:
        if bound > 0 and not varies[first]:
            raise IdentificationError(
                f"Regressor {first} does not vary over the samples used, so the weights "
                "cannot be identified: the input must vary after the start-up transient."
            )
    idx = np.flatnonzero(varies)
    scale = 1.0 / np.sqrt(np.diag(c.G_c)[idx])
    quad = c.G_c[np.ix_(idx, idx)] * np.outer(scale, scale)
    lin = c.g_c[idx] * scale
    rows, bounds = [np.empty((0, idx.size))], [np.empty(0)]
    # one row per coefficient that varies (partial sums at a fixed, zero, coefficient
    # repeat the one before): partial sums from `first` for blocks and caps, itself for floors
    for group, sign, partial in ((blocks, 1.0, True), (caps, -1.0, True), (floors, 1.0, False)):
        for first, stop, bound in group:
            i = np.arange(first, stop)
            i = i[varies[first:stop]]
            if partial:
                mask = (idx[None, :] >= first) & (idx[None, :] <= i[:, None])
            else:
                mask = idx[None, :] == i[:, None]
            rows.append(np.where(mask, sign * scale, 0.0))
            bounds.append(np.full(i.size, sign * bound))
    cons_t = np.vstack(rows).T.copy()
    bound = np.concatenate(bounds)
    diagonal = np.diag_indices_from(quad)
    solutions = []
    for ridge in ridges:
        ridged = quad.copy()
        ridged[diagonal] += np.broadcast_to(ridge, (p - 1,))[idx]
        try:
            solution = quadprog.solve_qp(ridged, lin, cons_t, bound)[0]
        except ValueError as exc:
            raise IdentificationError(
                f"The constrained least-squares problem could not be solved ({exc}). Check "
                "that the record is one experiment (input and displacement of the same "
                "samples) and try fewer operators."
            ) from None
        coef, rss = _unscaled(c, solution, idx, scale)
        solutions.append(LsqSolution(coef=coef, rss=rss, varies=varies))
    return solutions


def held_out_fits(grams, solve) -> tuple:
    """``solve(G - G_f)`` for every fold ``f`` of per-fold Gram matrices ``grams``, or ``()``.

    The fits of a cross-validation over the folds of :func:`normal_equations` (with
    ``folds``), each on every fold but one. Empty if a fold has no sample or if the other
    folds do not determine a fit (an :class:`~hystcomp.errors.IdentificationError`).

    Parameters
    ----------
    grams : array_like
        Per-fold Gram matrices, shape ``(n_folds, p, p)``.
    solve : callable
        ``solve(gram) -> fit``, the fit on a Gram matrix.

    Returns
    -------
    tuple
        One fit per fold (fold ``f`` left out), or ``()``.
    """
    counts = grams[:, -2, -2]  # the constant regressor's square: the samples of each fold
    if not np.all(counts > 0):
        return ()
    total = grams.sum(axis=0)
    try:
        return tuple(solve(total - grams[f]) for f in range(grams.shape[0]))
    except IdentificationError:
        return ()


def solve_inequality_qp(
    gram, constraints, *, penalty=None, ridge=RIDGE
) -> tuple[np.ndarray, float]:
    """Least squares from normal equations under general inequalities ``A theta >= 0``.

    The general form of :func:`constrained_lsq` (whose partial-sum blocks are one choice of
    ``A``), for fits whose constraints are not partial sums, such as a non-negative Preisach
    density: minimises ``|Phi theta - z|^2 + theta^T P theta`` subject to
    ``constraints @ theta >= 0``, the constant regressor (last) unconstrained and eliminated
    exactly first, as there. Columns are scaled to unit norm (with the penalty) and a
    relative ``ridge`` keeps the form positive definite; a regressor that is constant over
    the samples and unpenalised carries no information and gets coefficient 0.

    Parameters
    ----------
    gram : ndarray, shape (p + 1, p + 1)
        ``[Phi | z]^T [Phi | z]``, the constant regressor last in ``Phi``.
    constraints : ndarray, shape (c, p - 1)
        ``A``, on the non-constant coefficients.
    penalty : ndarray, shape (p - 1, p - 1), optional
        ``P``, positive semi-definite, in the coefficients' own units.
    ridge : float
        Added to the diagonal of the unit-scaled quadratic form.

    Returns
    -------
    coef : ndarray, shape (p,)
        The coefficients, the constant last.
    rss : float
        ``|Phi theta - z|^2`` (without the penalty).

    Raises
    ------
    IdentificationError
        If quadprog finds no solution.
    """
    c = _centred(gram)
    quad_full = c.G_c if penalty is None else c.G_c + penalty
    diag = np.maximum(np.diag(quad_full), 0.0)
    idx = np.flatnonzero(diag > 1e-14 * max(float(diag.max()), 1e-300))
    scale = 1.0 / np.sqrt(diag[idx])
    quad = quad_full[np.ix_(idx, idx)] * np.outer(scale, scale)
    quad[np.diag_indices_from(quad)] += ridge
    lin = c.g_c[idx] * scale
    cons = np.asarray(constraints, dtype=np.float64)[:, idx] * scale
    keep = np.any(cons != 0.0, axis=1)  # rows on dropped coefficients only hold at 0
    cons = cons[keep]
    try:
        if cons.shape[0] == 0:
            solution = np.linalg.solve(quad, lin)
        else:
            solution = quadprog.solve_qp(quad, lin, cons.T.copy(), np.zeros(cons.shape[0]))[0]
    except (ValueError, np.linalg.LinAlgError) as exc:
        raise IdentificationError(
            f"The constrained least-squares problem could not be solved ({exc}). Check that "
            "the record is one experiment (input and displacement of the same samples)."
        ) from None
    return _unscaled(c, solution, idx, scale)
