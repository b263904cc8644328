"""Identification of the classical Preisach model from any record, by least squares.

The paper identifies the Everett function of eq. (5) from first-order descending reversal
curves (:mod:`hystcomp.identify.preisach`). Any record determines it, though: given the
input's memory of alternating dominant extrema with the wipe-out property (eqs. 3-4), the
output of a Preisach model at each sample is a sum of Everett differences over the memory
staircase, so for an Everett function that is linear in its parameters,
``X = sum_m c_m X_m``, the output ``x[k] = x_0 + sum_m c_m R_m[k]`` is linear in ``c`` and
``x_0``. :func:`~hystcomp._kernels.preisach.preisach_rows` computes the regressors
``R_m[k]`` (eqs. 3-4 with ``X_m`` alone) in one pass over the record, and the normal
equations are accumulated block by block, as :mod:`hystcomp.identify.lsq` does for PI.

Two bases (see :func:`~hystcomp._kernels.preisach.everett_basis`):

* ``"polynomial"``: eq. (5)'s monomials of any degree with ``X(v, v) = 0`` built in (eq. 2);
* ``"table"``: non-negative masses on the cells of a uniform grid of the limiting triangle
  and on its diagonal segments, whose Everett function is exactly the bilinear interpolation
  of its values on the grid nodes: the table representation of :class:`~hystcomp.Preisach`.

The fit is constrained to a non-negative Preisach density ``mu = -d2X / (dalpha dbeta)``
(and a non-negative reversible part ``dX/dalpha`` on the diagonal): then every branch of
the model rises with the input (``dX/dalpha = X_alpha(alpha, alpha) + integral of mu >= 0``)
and the exact inverse exists. For the table this holds exactly (the unknowns are the
masses); for the polynomial it is enforced on a grid of ``(alpha, beta)`` points.

The memory starts with every relay off at ``v_min`` (as the model does), and only the
samples from the first time the input reaches an end of its range
(:func:`~hystcomp.identify.scoring.transient_end`) enter the fit: from there on the memory
is known whatever state the actuator started in.
"""

from __future__ import annotations

import math

import numpy as np

from hystcomp._kernels import preisach as pk
from hystcomp._notice import Notice
from hystcomp.errors import IdentificationError
from hystcomp.identify.compensation import inside_training
from hystcomp.identify.lsq import solve_inequality_qp
from hystcomp.identify.scoring import transient_end

#: Largest work of a Gram accumulation, rows * (p + 2)**2: beyond it rows are taken at a
#: stride (but at least :data:`MIN_ROWS` rows). A rate-independent loop is described by far
#: fewer samples than a 20 kHz record holds; the stride only thins the noise averaging.
GRAM_BUDGET = 5e8
MIN_ROWS = 5_000
#: Largest table for least squares: (n - 1) n / 2 unknowns in a dense quadratic programme.
MAX_LSQ_GRID = 41
#: Rows per block of the Gram accumulation.
BLOCK = 1024
#: Points per axis of the grid on which a polynomial's density is kept non-negative.
DENSITY_GRID = 25
#: Weight of the table's smoothness penalty, relative to the mean diagonal of the normal matrix.
SMOOTHING = 1e-3


class EverettBasis:
    """A linear Everett function ``X = sum_m c_m X_m`` over the Preisach plane ``[lo, hi]``.

    Parameters
    ----------
    everett : {"polynomial", "table"}
        Monomials vanishing on the diagonal, or masses on a grid's cells and diagonal.
    degree : int
        Degree of the polynomial (3 is eq. 5).
    grid_size : int
        Nodes per axis of the table (``grid_size - 1`` segments of the range).
    voltage_range : (float, float)
        The Preisach plane in V.
    """

    def __init__(self, everett: str, *, degree: int, grid_size: int, voltage_range):
        self.everett = everett
        self.degree = degree
        self.grid_size = grid_size
        self.lo, self.hi = (float(v) for v in voltage_range)
        if everett == "polynomial":
            self.kind = pk.BASIS_POLYNOMIAL
            free = [(i, j) for i, j in pk.monomial_exponents(degree) if j > 0]
            self.exps = np.array(free, dtype=np.int64).reshape(-1, 2)
            self.n_seg = 0
            self.size = len(free)
        else:
            self.kind = pk.BASIS_CELLS
            self.exps = np.zeros((0, 2), dtype=np.int64)
            self.n_seg = grid_size - 1
            self.size = self.n_seg * (self.n_seg + 1) // 2

    def evaluate(self, alpha, beta) -> np.ndarray:
        """``X_m(alpha, beta)`` for every basis element, shape ``(n, size)``.

        Parameters
        ----------
        alpha, beta : array_like
            Upper and lower switching voltages, V, broadcast together (one row each).

        Returns
        -------
        numpy.ndarray
            The basis functions' values, µm per unit coefficient, shape ``(n, size)``.
        """
        alpha, beta = np.broadcast_arrays(np.asarray(alpha, float), np.asarray(beta, float))
        out = np.empty((alpha.size, self.size))
        for k, (a, b) in enumerate(zip(alpha.ravel(), beta.ravel(), strict=True)):
            pk.everett_basis(self.kind, self.exps, self.n_seg, self.lo, self.hi, a, b, out[k])
        return out

    def rows(self, v, x, *, start=0, stride=1, block=BLOCK):
        """Regressor rows ``[R_0 .. R_(p-1), 1, x]`` of samples ``start, start + stride, ...``,
        in blocks of at most ``block`` rows (a generator of views on one buffer).

        Parameters
        ----------
        v, x : array_like
            The record: voltage (V) and displacement (µm), one sample each.
        start, stride : int, optional
            The rows taken: samples ``start, start + stride, ...``.
        block : int, optional
            The most rows in a block.

        Yields
        ------
        numpy.ndarray
            A block of rows, shape ``(rows, size + 2)``, a view on a buffer reused by the next
            block.
        """
        v = np.ascontiguousarray(v, dtype=np.float64)
        x = np.ascontiguousarray(x, dtype=np.float64)
        depth = pk.DEFAULT_DEPTH
        e = np.zeros(depth)
        e[0] = self.lo
        memory = (e, np.zeros((depth, self.size)), np.array([0.0, self.lo]))
        buffer = np.empty((block, self.size + 2))
        k = 0
        while k < v.size:
            k, count = pk.preisach_rows(
                self.kind,
                self.exps,
                self.n_seg,
                self.lo,
                self.hi,
                v,
                x,
                k,
                start,
                stride,
                memory,
                buffer,
            )
            if count:
                yield buffer[:count]

    def design(self, v, x=None, *, start=0, stride=1) -> np.ndarray:
        """The regressors ``R`` as a dense ``(rows, size)`` matrix (for small records).

        Parameters
        ----------
        v : array_like
            The record's voltage, V.
        x : array_like, optional
            Not used; the regressors depend on the voltage only.
        start, stride : int, optional
            The rows taken: samples ``start, start + stride, ...``.

        Returns
        -------
        numpy.ndarray
            The regressors, shape ``(rows, size)``.
        """
        x = np.zeros(len(v)) if x is None else x
        parts = [
            block[:, : self.size].copy() for block in self.rows(v, x, start=start, stride=stride)
        ]
        return np.concatenate(parts) if parts else np.zeros((0, self.size))

    def normal_equations(self, v, x, *, start=0, stride=1, folds=None, n_folds=1) -> np.ndarray:
        """The augmented Gram matrix ``[R | 1 | x]^T [R | 1 | x]`` over the chosen rows.

        With ``folds`` (a fold ``0 .. n_folds - 1`` for every sample, -1 for none), one Gram
        matrix per fold over its own rows, and one over those of its rows whose input lies
        inside the range of the other folds (:func:`~hystcomp.identify.compensation.
        inside_training`): shape ``(2, n_folds, p + 2, p + 2)``.

        Parameters
        ----------
        v, x : array_like
            The record whose :meth:`rows` are summed: voltage (V) and displacement (µm).
        start, stride : int, optional
            Only the rows of samples ``start, start + stride, ...`` enter the sums.
        folds : array_like of int, optional
            The fold of every sample (-1 for none).
        n_folds : int, optional
            The number of folds.

        Returns
        -------
        numpy.ndarray
            The Gram matrix, shape ``(size + 2, size + 2)``, or ``(2, n_folds, size + 2, size +
            2)`` with ``folds``.
        """
        size = self.size + 2
        if folds is None:
            gram = np.zeros((size, size))
            for block in self.rows(v, x, start=start, stride=stride):
                pk.gram_update(block, block.shape[0], gram)
            return np.triu(gram) + np.triu(gram, 1).T
        folds = np.asarray(folds)
        grams = np.zeros((2, n_folds, size, size))
        row_v = np.asarray(v)[start::stride]
        row_folds = folds[start::stride]
        scored = np.zeros(row_v.size, dtype=bool)
        for fold in range(n_folds):
            scored |= inside_training(row_v, row_folds, fold)
        at = 0
        for block in self.rows(v, x, start=start, stride=stride):
            mine = row_folds[at : at + block.shape[0]]
            kept = scored[at : at + block.shape[0]]
            at += block.shape[0]
            for fold in range(n_folds):
                for which, rows in enumerate((mine == fold, (mine == fold) & kept)):
                    part = np.ascontiguousarray(block[rows])
                    if part.shape[0]:
                        pk.gram_update(part, part.shape[0], grams[which, fold])
        return np.triu(grams) + np.swapaxes(np.triu(grams, 1), -1, -2)

    def density_constraints(self) -> np.ndarray:
        """Rows ``A`` with ``A c >= 0`` iff the density (and the reversible part) is >= 0.

        Table: the masses themselves. Polynomial, in unit-square coordinates ``a, b``:
        ``-d2X/(da db) >= 0`` on a triangular grid of :data:`DENSITY_GRID` points per axis
        (diagonal included) and ``dX/da (v, v) >= 0`` on the diagonal; between the points
        a polynomial of low degree cannot dip far below 0.

        Returns
        -------
        numpy.ndarray
            The constraint rows, shape ``(constraints, size)``.
        """
        if self.kind == pk.BASIS_CELLS:
            return np.eye(self.size)
        g = np.linspace(0.0, 1.0, DENSITY_GRID)
        ia, ib = np.tril_indices(g.size)
        a, b = g[ia], g[ib]
        i, j = self.exps[:, 0], self.exps[:, 1]
        mixed = -(i * j) * _power(b[:, None], i - 1) * _power(a[:, None], j - 1)
        reversible = j * _power(g[:, None], i + j - 1)
        return np.vstack([mixed, reversible])

    def smoothness_penalty(self) -> np.ndarray:
        """``D^T D`` of first differences of the density between neighbouring cells, and of the
        reversible part between neighbouring diagonal segments (zero for the polynomial).

        Returns
        -------
        numpy.ndarray
            The penalty matrix, shape ``(size, size)``.
        """
        if self.kind == pk.BASIS_POLYNOMIAL:
            return np.zeros((self.size, self.size))
        n = self.n_seg
        # Keys: ("d", s) for diagonal segment s, (sa, sb) for the cell of segments sa > sb.
        index: dict[tuple[str | int, int], int] = {}
        for s in range(n):
            index[("d", s)] = s
        m = n
        for sa in range(1, n):
            for sb in range(sa):
                index[(sa, sb)] = m
                m += 1
        pairs = [(index[("d", s)], index[("d", s + 1)]) for s in range(n - 1)]
        for sa in range(1, n):
            for sb in range(sa):
                if sa + 1 < n:
                    pairs.append((index[(sa, sb)], index[(sa + 1, sb)]))
                if sb + 1 < sa:
                    pairs.append((index[(sa, sb)], index[(sa, sb + 1)]))
        diff = np.zeros((len(pairs), self.size))
        for r, (p, q) in enumerate(pairs):
            diff[r, p], diff[r, q] = 1.0, -1.0
        return diff.T @ diff

    def to_model(self, coef):
        """``(theta, table)`` of :class:`~hystcomp.Preisach` for the coefficients ``coef``.

        Parameters
        ----------
        coef : array_like
            The basis coefficients.

        Returns
        -------
        theta : numpy.ndarray or None
            The polynomial's coefficients, µm/V^k (None for a table).
        table : numpy.ndarray or None
            The table on the grid, µm (None for a polynomial).
        """
        span = self.hi - self.lo
        if self.kind == pk.BASIS_POLYNOMIAL:
            fitted = {(int(i), int(j)): float(c) for (i, j), c in zip(self.exps, coef, strict=True)}
            for k in range(1, self.degree + 1):
                fitted[(k, 0)] = -sum(fitted[(k - j, j)] for j in range(1, k + 1))
            exps = pk.monomial_exponents(self.degree)
            return np.array([fitted[(i, j)] / span ** (i + j) for i, j in exps]), None
        nodes = np.linspace(self.lo, self.hi, self.grid_size)
        ia, ib = np.tril_indices(self.grid_size)
        lower = np.zeros((self.grid_size, self.grid_size))
        lower[ia, ib] = self.evaluate(nodes[ia], nodes[ib]) @ coef
        return None, pk.antisymmetric_table(lower)


def _power(base, exponent):
    """``base ** exponent`` with ``0 ** 0 = 1`` and a zero where the exponent is negative."""
    exponent = np.broadcast_to(exponent, np.broadcast_shapes(np.shape(base), np.shape(exponent)))
    out = np.where(exponent >= 0, np.power(base, np.maximum(exponent, 0)), 0.0)
    return out


def fit_preisach_lsq(v, x, *, everett, degree, grid_size, voltage_range, start=None, folds=None):
    """Fit a Preisach model to a record by density-constrained least squares.

    Parameters
    ----------
    v, x : ndarray
        Validated input (V) and output (µm) of the same length.
    everett : {"polynomial", "table"}
        The representation of X.
    degree, grid_size : int
        Its size.
    voltage_range : (float, float)
        The Preisach plane (V), containing the record.
    start : int, optional
        First sample of the fit; default :func:`~hystcomp.identify.scoring.transient_end`.
    folds : ndarray of int, optional
        A fold for every sample (:func:`~hystcomp.identify.scoring.reversal_folds`, -1
        before ``start``): the model is also fitted without each fold, and the report holds
        ``held_out_rms_um``, its error on the reversal segments each fit did not see.

    Returns
    -------
    theta, table : ndarray or None
        One of them, as :meth:`~hystcomp.Preisach.from_parameters` takes them.
    offset : float
        ``x_0`` in µm.
    report : dict
        ``first_used_sample``, ``n_rows``, ``stride``, ``density_min`` (and
        ``held_out_rms_um`` with ``folds``).

    Raises
    ------
    IdentificationError
        If the record after the start-up transient does not move the input.
    """
    basis = EverettBasis(everett, degree=degree, grid_size=grid_size, voltage_range=voltage_range)
    start = transient_end(v) if start is None else int(start)
    used = v.size - start
    lo, hi = voltage_range
    if used < 2 or np.ptp(v[start:]) <= 1e-9 * (hi - lo):
        raise IdentificationError(
            Notice(
                "After the start-up transient (first sample used: "
                f"{start}) the input does not move, so it traces no hysteresis. Record the "
                "actuator while the voltage sweeps its range (any waveform: {excite_preisach}, "
                "{excite_pi}, or a random one)."
            )
        )
    max_rows = max(MIN_ROWS, int(GRAM_BUDGET / (basis.size + 2) ** 2))
    stride = max(1, math.ceil(used / max_rows))
    n_folds = 0 if folds is None else int(np.max(folds)) + 1
    if n_folds >= 2:
        per_fold, scored = basis.normal_equations(
            v, x, start=start, stride=stride, folds=folds, n_folds=n_folds
        )
        gram = per_fold.sum(axis=0)
    else:
        gram = basis.normal_equations(v, x, start=start, stride=stride)
    penalty = basis.smoothness_penalty()
    if np.any(penalty):
        count = gram[-2, -2]
        mean = gram[-2, : basis.size] / count
        centred = np.diag(gram[: basis.size, : basis.size]) - count * mean**2
        penalty *= SMOOTHING * max(float(centred.mean()), 0.0) / float(np.diag(penalty).mean())
    constraints = basis.density_constraints()
    coef, _ = solve_inequality_qp(gram, constraints, penalty=penalty)
    theta, table = basis.to_model(coef[:-1])
    report = {
        "first_used_sample": int(start),
        "n_rows": int(gram[-2, -2]),
        "stride": int(stride),
        "density_min": float((constraints @ coef[:-1]).min()),
    }
    if n_folds >= 2:
        report["held_out_rms_um"] = _held_out_rms(per_fold, scored, gram, constraints, penalty)
    return theta, table, float(coef[-1]), report


def _held_out_rms(per_fold, scored, gram, constraints, penalty) -> float:
    """The rms error (µm) of the fits without each fold on the rows of that fold inside the
    range of the others (``scored``).

    A fold's squared error is a quadratic form of its Gram matrix: with ``w = (c, x_0,
    -1)``, ``sum (R c + x_0 - x)^2 = w^T G_fold w``."""
    sse, count = 0.0, 0.0
    for fold_gram, scored_gram in zip(per_fold, scored, strict=True):
        if scored_gram[-2, -2] == 0.0:
            continue
        coef, _ = solve_inequality_qp(gram - fold_gram, constraints, penalty=penalty)
        w = np.r_[coef, -1.0]
        sse += float(w @ scored_gram @ w)
        count += float(scored_gram[-2, -2])
    return float(np.sqrt(max(sse, 0.0) / count)) if count else float("nan")
