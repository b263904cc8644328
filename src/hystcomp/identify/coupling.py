"""The coupling between the axes of a multi-axis stage, from one record of all of them.

The stage is ``x = M h`` with ``h_i = H_i[v_i]``: every axis has its own hysteresis ``H_i``
(voltage ``v_i`` in V to µm), and ``M`` (unitless, unit diagonal) mixes the axes'
displacements into the sensors' readings: driving X moves the Y sensor by ``M_yx`` times X's
own displacement (a few percent on a flexure scanner).

How it is identified, without knowing the ``H_i``: ``h = A x`` with ``A = M^-1``, so row
``i`` reads ``x_i = h_i / A_ii - sum_{j != i} (A_ij / A_ii) x_j``. That is linear in the
unknowns once ``h_i / A_ii`` is written as a flexible function of ``v_i``'s history (here:
plays of ``v_i`` at thresholds spanning half its range, eq. 11, with a quadratic and a cubic
term of ``v_i`` for saturation). Each row is one least-squares fit, ``x_i`` on ``v_i``'s
regressors and the other axes' displacements ``x_j``; it gives ``B_ij = -A_ij / A_ii``, and
the unit diagonal of ``M`` fixes the scales ``A_ii``. ``x_j`` holds a part of axis ``i``'s
own displacement (the coupling of ``i`` into ``j``), through which the part of ``H_i`` the
regressors miss biases ``B_ij``; so the fit is refined: ``x_i`` on ``v_i``'s regressors and
the other axes' *decoupled* displacements ``(M^-1 x)_j``, whose coefficients are row ``i``
of ``M`` itself, a few rounds (:data:`ROUNDS`).

What is identifiable, from what:

* ``M``'s off-diagonal entries need a record in which the axes move *independently*: the
  other axes' displacements must not be a function of axis ``i``'s input (``hystcomp excite
  multiaxis`` moves each axis over its range, with turning points of its own). A record
  that drives every axis with the same waveform, or moves one axis at a time while the others
  rest, cannot separate an axis's own hysteresis from the coupling into it: refused with
  :class:`~hystcomp.errors.IdentificationError`, naming the axes.
* ``M``'s diagonal is 1 by convention: ``H_i`` is the displacement axis ``i``'s own sensor
  reads when it alone moves. Any other scale of ``H_i`` would fit as well.
* Constant offsets: ``M`` times the axes' offsets is a constant, absorbed by each axis
  model's own offset; only each sensor's mean is identified, not how it splits.
* ``H_i`` itself is identified on the decoupled displacements ``h = A x``, over the input
  range the record sweeps, as a single axis is (any family).

Array level: no model is built here (:mod:`hystcomp.models.multiaxis` does that).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hystcomp._kernels import chain
from hystcomp._notice import Notice
from hystcomp.errors import IdentificationError

#: Plays per axis in the regressors of :func:`fit_coupling`.
N_PLAYS = 24
#: Most samples of the least-squares fits (the record is thinned evenly beyond it).
MAX_SAMPLES = 60_000
#: Refinements of M by :func:`fit_coupling` after the first fit.
ROUNDS = 3
#: An axis whose displacement the other axis's input explains to R^2 above this (as a
#: function of that input's history) moves with it: their coupling is not identifiable.
MAX_SHARED_R2 = 0.98


@dataclass(frozen=True)
class CouplingFit:
    """What :func:`fit_coupling` found.

    Attributes
    ----------
    matrix : ndarray, shape (N, N)
        ``M``, unit diagonal: ``x = M h``.
    decoupling : ndarray, shape (N, N)
        ``A = M^-1``: ``h = A x``.
    shared_r2 : ndarray, shape (N, N)
        ``[i, j]``: how much of axis ``j``'s displacement the history of axis ``i``'s input
        explains (R^2; 0 on the diagonal). Near 1 means the two moved together.
    residual_um : ndarray, shape (N,)
        rms of each row's least-squares residual, µm (what the regressors leave of ``x_i``).
    """

    matrix: np.ndarray
    decoupling: np.ndarray
    shared_r2: np.ndarray
    residual_um: np.ndarray


def axis_regressors(v: np.ndarray, n_plays: int = N_PLAYS) -> np.ndarray:
    """Regressors of one axis's own hysteresis: plays of ``v`` (eq. 11) and saturation terms.

    Parameters
    ----------
    v : ndarray
        The axis's input, V (1-D, finite, not constant).
    n_plays : int
        Plays, thresholds ``0 .. span/2`` evenly (the first is ``v`` itself).

    Returns
    -------
    ndarray, shape (n, n_plays + 3)
        Columns: the plays of ``v - min v`` from a virgin start, ``u^2``, ``u^3`` (``u`` the
        input scaled to 0..1) and 1.
    """
    lo, span = float(v.min()), float(np.ptp(v))
    u = np.ascontiguousarray(v - lo)
    r = np.linspace(0.0, 0.5 * span, n_plays)
    out = np.empty((u.size, n_plays + 3))
    plays = np.empty((u.size, n_plays))
    chain.play_outputs(u, r, np.zeros(n_plays), plays)
    out[:, :n_plays] = plays / span
    s = u / span
    out[:, n_plays] = s * s
    out[:, n_plays + 1] = s * s * s
    out[:, n_plays + 2] = 1.0
    return out


def _lstsq(basis: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Least-squares coefficients of ``y`` on the columns of ``basis``, by the normal
    equations of the columns scaled to unit rms (a few dozen columns and tens of thousands
    of rows: the Gram matrix is small and well conditioned, and forming it costs a tenth
    of an SVD of the rows)."""
    scale = np.sqrt(np.mean(basis**2, axis=0))
    scale[scale == 0.0] = 1.0
    b = basis / scale
    coef, *_ = np.linalg.lstsq(b.T @ b, b.T @ y, rcond=1e-12)
    return coef / scale


def _r2(y: np.ndarray, basis: np.ndarray) -> float:
    """R^2 of the least-squares fit of ``y`` on the columns of ``basis``."""
    coef = _lstsq(basis, y)
    total = float(np.sum((y - y.mean()) ** 2))
    return 1.0 - float(np.sum((y - basis @ coef) ** 2)) / total if total > 0 else 1.0


def _row(x, own, others) -> tuple[np.ndarray, float]:
    """The coefficients of ``others`` in the least-squares fit of ``x`` on ``[own, others]``,
    and the rms residual."""
    basis = np.hstack([own, others])
    coef = _lstsq(basis, x)
    return coef[own.shape[1] :], float(np.sqrt(np.mean((x - basis @ coef) ** 2)))


def fit_coupling(
    V, X, *, start: int = 0, n_plays: int = N_PLAYS, rounds: int = ROUNDS
) -> CouplingFit:
    """Identify ``M`` of ``x = M [H_1(v_1), ..., H_N(v_N)]`` from one record (module notes).

    Parameters
    ----------
    V, X : ndarray, shape (n, N)
        Inputs (V) and displacements (µm) of the N axes, finite; every input sweeps.
    start : int, default 0
        Samples left out of the fits (a start-up transient); the plays still run over them.
    n_plays : int
        Plays per axis in the regressors.
    rounds : int
        Refinements of ``M`` on the decoupled displacements (module notes).

    Returns
    -------
    CouplingFit

    Raises
    ------
    IdentificationError
        If two axes move together, so that their coupling is not identifiable.
    """
    V = np.asarray(V, dtype=np.float64)
    X = np.asarray(X, dtype=np.float64)
    n, n_axes = X.shape
    if n_axes == 1:
        one = np.ones((1, 1))
        return CouplingFit(one, one.copy(), np.zeros((1, 1)), np.zeros(1))
    step = max(1, (n - start) // MAX_SAMPLES)
    keep = np.arange(start, n, step)
    Xk = X[keep]
    regs = [axis_regressors(V[:, i], n_plays)[keep] for i in range(n_axes)]
    shared = np.zeros((n_axes, n_axes))
    for i in range(n_axes):
        for j in range(n_axes):
            if i != j:
                shared[i, j] = _r2(Xk[:, j], regs[i])
    together = [
        (i, j)
        for i in range(n_axes)
        for j in range(n_axes)
        if i < j and max(shared[i, j], shared[j, i]) > MAX_SHARED_R2
    ]
    if together:
        i, j = together[0]
        raise IdentificationError(
            Notice(
                f"Axes {i + 1} and {j + 1} move together in the record (the input of one "
                f"explains {100 * max(shared[i, j], shared[j, i]):.3g} % of the other's "
                "displacement), so the coupling between them cannot be told from their own "
                "hysteresis. Record the axes moving independently, each over its range "
                "({excite_multiaxis})."
            )
        )
    B = np.zeros((n_axes, n_axes))
    residual = np.zeros(n_axes)
    for i in range(n_axes):
        others = [j for j in range(n_axes) if j != i]
        B[i, others], residual[i] = _row(Xk[:, i], regs[i], Xk[:, others])
    inner = np.linalg.inv(np.eye(n_axes) - B)  # (I - B)^-1
    d = np.diag(inner).copy()
    if not np.all(d > 0):
        raise IdentificationError(
            Notice(
                "The record gives a coupling between the axes that reverses an axis's own "
                "direction (a diagonal of M^-1 <= 0): check that every v column drives the x "
                "column of the same number ({columns})."
            )
        )
    M = inner / d[None, :]
    # Refinements: each sensor on its own input's regressors and the other axes' decoupled
    # displacements h_j = (M^-1 x)_j, which no longer hold a part of axis i's own (as x_j
    # does, by the coupling of i into j): M's row directly, without that bias.
    for _ in range(rounds):
        Hk = Xk @ np.linalg.inv(M).T
        for i in range(n_axes):
            others = [j for j in range(n_axes) if j != i]
            M[i, others], residual[i] = _row(Xk[:, i], regs[i], Hk[:, others])
    np.fill_diagonal(M, 1.0)
    A = np.linalg.inv(M)
    return CouplingFit(M, A, shared, residual)


def refine_coupling(V, X, H_model, matrix, *, start: int = 0, rounds: int = ROUNDS):
    """``M`` again, with each axis's fitted model among its own regressors.

    The plays and saturation terms of :func:`axis_regressors` leave a part of an axis's
    hysteresis unexplained (1-2 % of the stroke on a stage of none of the model families);
    where the axes' displacements correlate in the record, that part biases the coupling
    by a tenth or more of its size. A model of the axis fitted on the decoupled
    displacements leaves a few times less: with its output ``H_i[v_i]`` as one more
    regressor, row ``i`` of ``M`` is fitted again on the decoupled displacements of the
    other axes, a few rounds.

    Parameters
    ----------
    V, X : ndarray, shape (n, N)
        The record, as for :func:`fit_coupling`.
    H_model : ndarray, shape (n, N)
        Each axis's fitted model run on its input, µm.
    matrix : ndarray, shape (N, N)
        ``M`` from :func:`fit_coupling`.
    start : int
        Samples left out of the fits.
    rounds : int
        Rounds of the fit.

    Returns
    -------
    ndarray, shape (N, N)
        ``M``, unit diagonal.
    """
    V = np.asarray(V, dtype=np.float64)
    X = np.asarray(X, dtype=np.float64)
    n, n_axes = X.shape
    M = np.array(matrix, dtype=np.float64)
    if n_axes == 1:
        return M
    step = max(1, (n - start) // MAX_SAMPLES)
    keep = np.arange(start, n, step)
    Xk = X[keep]
    regs = [
        np.hstack([axis_regressors(V[:, i])[keep], H_model[keep, i : i + 1]]) for i in range(n_axes)
    ]
    for _ in range(rounds):
        Hk = Xk @ np.linalg.inv(M).T
        for i in range(n_axes):
            others = [j for j in range(n_axes) if j != i]
            M[i, others], _ = _row(Xk[:, i], regs[i], Hk[:, others])
    np.fill_diagonal(M, 1.0)
    return M
