"""When a hysteresis model has an inverse, and the analytic inversion of PI superpositions.

:func:`check_invertible` (PI and MPI: every partial sum of the weights positive) and
:func:`check_rising_everett` (Preisach: every branch rises) are the checks every
compensator of a model goes through, whatever its method, and so C export too.

The same transform inverts a superposition of play operators (the PI model, eq. 12) and a
superposition of one-sided dead-zones (the saturation operator, eq. 14): both are piecewise
linear in the input with slope ``w_0 + ... + w_i`` past threshold ``r_i``, so both invert to
a superposition of the same kind with thresholds (24) and weights (25). The transform is an
involution: applied twice it returns the original parameters.
"""

from __future__ import annotations

import numpy as np

from hystcomp.errors import NotInvertibleError

#: Largest inverse weight (eq. 25) accepted: with the bounded parameters and signals of
#: :mod:`hystcomp._validation`, no sum or product in the inverse can then overflow.
MAX_INVERSE_WEIGHT = 1e24


def check_invertible(weights: np.ndarray, what: str) -> None:
    """Raise :class:`NotInvertibleError` unless every partial sum of ``weights`` is positive.

    Also refuses partial sums so close to zero that the inverse weights of eq. (25) would
    exceed :data:`MAX_INVERSE_WEIGHT` (or overflow): such an inverse is not computable.

    Parameters
    ----------
    weights : numpy.ndarray
        Weights of a superposition (play operators or dead-zones), in order of threshold.
    what : str
        What they belong to, for the error message.

    Examples
    --------
    >>> check_invertible(np.array([1.0, -0.5, 0.2]), "the model")
    >>> check_invertible(np.array([1.0, -1.5, 0.2]), "the model")
    Traceback (most recent call last):
    ...
    hystcomp.errors.NotInvertibleError: the model is not invertible: ...(index 1)...
    """
    partial = np.cumsum(weights)
    if not partial.min() > 0:  # also NaN; the index is looked for only on a refusal
        i = int(np.flatnonzero(~(partial > 0))[0])
        raise NotInvertibleError(
            f"{what} is not invertible: {_partial_sum(i)} = "
            f"{partial[i]:.6g} is not positive (index {i}). Eqs. 24-26 need every partial sum "
            f"> 0: identify the model with the invertibility constraint, or change weights[{i}].",
            index=i,
        )
    # |w'_i| of eq. 25: 1 / w_0, then w_i / (p_i p_{i-1}) (p_0 = w_0 makes the first term so)
    before = np.concatenate((partial[:1], partial[:-1]))
    with np.errstate(all="ignore"):  # an overflow or a NaN is judged below
        gains = np.abs(weights / (partial * before))
    if not gains.max() <= MAX_INVERSE_WEIGHT:
        i = int(np.flatnonzero(~(gains <= MAX_INVERSE_WEIGHT))[0])
        raise NotInvertibleError(
            f"{what} is not invertible in floating point: {_partial_sum(i)} = "
            f"{partial[i]:.6g} is so close to 0 that the inverse weight "
            f"w'_{i} of eq. 25 would be {gains[i]:.3g} in size (index {i}; at most "
            f"{MAX_INVERSE_WEIGHT:g}). Identify the model with the invertibility constraint, "
            f"or change weights[{i}].",
            index=i,
        )


#: A branch may fall by this share of the largest ``|X|`` (rounding), no more.
EVERETT_TOLERANCE = 1e-9


def check_rising_everett(table: np.ndarray, voltages: np.ndarray, what: str, *, cells: str):
    """Raise :class:`NotInvertibleError` unless every branch of a Preisach model rises.

    ``table[i, j] = X(voltages[i], voltages[j])`` (eq. 2) on a grid (``j <= i`` read). A
    branch rising from a minimum ``beta`` is ``X(v, beta)`` plus a constant, one falling
    from a maximum ``alpha`` is a constant minus ``X(alpha, v)`` (eqs. 3-4): all rise with
    ``v`` when ``X`` never falls as ``alpha`` rises nor as ``beta`` falls, which on the
    grid's nodes is enough for a bilinear table. And the major loop must rise:
    ``X(v_max, v_min) > 0``. A compensator (eq. 10 or the exact inverse) needs both: where
    a branch falls, eq. (10)'s recursion amplifies its error (its factor ``1 - s / rho``
    exceeds 1 for a slope ``s < 0``), and the exact inverse jumps over the fall on a slow
    ramp; a model that does not rise has nothing to invert. A fall within
    :data:`EVERETT_TOLERANCE` of the largest ``|X|`` is rounding and passes.

    ``cells`` says how the message names a node: ``"table"`` as ``table[i, j]`` (the
    model file's entry), else as its voltages.

    Parameters
    ----------
    table : numpy.ndarray
        The Everett function on the grid, µm, ``table[i, j] = X(voltages[i], voltages[j])``.
    voltages : numpy.ndarray
        The grid's voltages, V, rising.
    what : str
        What the table belongs to, for the error message.
    cells : str
        How the message names a cell of the table (``"table"`` or ``"grid"``).

    Examples
    --------
    >>> nodes = np.array([0.0, 1.0, 2.0])
    >>> X = np.array([[0.0, 0, 0], [1.0, 0, 0], [3.0, 2.0, 0]])
    >>> check_rising_everett(X, nodes, "the model", cells="table")
    >>> X[1, 0] = 4.0
    >>> check_rising_everett(X, nodes, "the model", cells="table")
    Traceback (most recent call last):
    ...
    hystcomp.errors.NotInvertibleError: the model is not invertible: its ascending branch \
from 0 V turns back down by 1 µm as the voltage rises from 1 to 2 V (table[1, 0] = 4, \
table[2, 0] = 3), ...
    """
    n = table.shape[0]
    stroke = float(table[-1, 0])
    if not stroke > 0:
        raise NotInvertibleError(
            f"{what} is not invertible: its major loop does not rise from "
            f"{voltages[0]:.6g} to {voltages[-1]:.6g} V: X(v_max, v_min) = {stroke:.6g} µm"
            + (f" (table[{n - 1}, 0])" if cells == "table" else "")
            + ", where it must be > 0 (eq. 2). No compensator can follow a reference with "
            "it. Identify the model again from a record of the stage.",
            index=None,
        )
    tol = EVERETT_TOLERANCE * float(np.abs(np.tril(table)).max())
    lower = np.tril(np.ones((n, n), dtype=bool))
    rise_alpha = np.where(lower[:-1], table[1:] - table[:-1], np.inf)  # [i, j] -> [i+1, j]
    rise_beta = np.where(lower[:, 1:], table[:, :-1] - table[:, 1:], np.inf)  # [i, j+1] -> [i, j]
    worst_a, worst_b = float(rise_alpha.min()), float(rise_beta.min())
    if min(worst_a, worst_b) >= -tol:
        return
    if worst_a <= worst_b:  # an ascending branch from beta_j, between alpha_i and alpha_i+1
        i, j = np.unravel_index(int(np.argmin(rise_alpha)), rise_alpha.shape)
        a, b = (int(i), int(j)), (int(i) + 1, int(j))
        branch = f"its ascending branch from {voltages[j]:.6g} V turns back down by {-worst_a:.3g}"
        span = f"as the voltage rises from {voltages[i]:.6g} to {voltages[i + 1]:.6g} V"
    else:  # a descending branch from alpha_i, between beta_j+1 and beta_j
        i, j = np.unravel_index(int(np.argmin(rise_beta)), rise_beta.shape)
        a, b = (int(i), int(j) + 1), (int(i), int(j))
        branch = f"its descending branch from {voltages[i]:.6g} V turns back up by {-worst_b:.3g}"
        span = f"as the voltage falls from {voltages[j + 1]:.6g} to {voltages[j]:.6g} V"
    if cells == "table":
        where = f"table[{a[0]}, {a[1]}] = {table[a]:.6g}, table[{b[0]}, {b[1]}] = {table[b]:.6g}"
    else:
        where = (
            f"X({voltages[a[0]]:.6g}, {voltages[a[1]]:.6g}) = {table[a]:.6g}, "
            f"X({voltages[b[0]]:.6g}, {voltages[b[1]]:.6g}) = {table[b]:.6g}"
        )
    raise NotInvertibleError(
        f"{what} is not invertible: {branch} µm {span} ({where}), where every branch must "
        "move with the voltage: eq. (10) amplifies its error there and the exact inverse "
        "jumps over it. Identify the model again by least squares (the default fit, whose "
        "non-negative density makes every branch rise)"
        + (f", or correct table[{b[0]}, {b[1]}]." if cells == "table" else "."),
        index=None,
    )


def _partial_sum(i: int) -> str:
    """How the messages name the partial sum of the weights up to index ``i``."""
    if i == 0:
        return "the first weight w_0"
    return (
        "the partial sum of weights w_0 + w_1"
        if i == 1
        else (f"the partial sum of weights w_0 + ... + w_{i}")
    )


def invert_superposition(
    thresholds: np.ndarray, weights: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Thresholds and weights of the inverse superposition, eqs. (24) and (25).

    ``r'_i = sum_{j<=i} w_j (r_i - r_j)`` and ``w'_0 = 1/w_0``,
    ``w'_i = -w_i / ((w_0+...+w_i)(w_0+...+w_{i-1}))``. The caller checks invertibility.

    Parameters
    ----------
    thresholds : numpy.ndarray
        The forward thresholds ``r_i``, rising from 0.
    weights : numpy.ndarray
        The forward weights ``w_i``.

    Returns
    -------
    thresholds : numpy.ndarray
        The inverse thresholds ``r'_i``.
    weights : numpy.ndarray
        The inverse weights ``w'_i``.

    Examples
    --------
    >>> r, w = np.array([0.0, 1.0]), np.array([2.0, -1.0])
    >>> r_inv, w_inv = invert_superposition(r, w)
    >>> r_inv.tolist(), w_inv.tolist()
    ([0.0, 2.0], [0.5, 0.5])
    """
    partial = np.cumsum(weights)
    r_inv = partial * thresholds - np.cumsum(weights * thresholds)
    w_inv = np.empty_like(weights)
    w_inv[0] = 1.0 / weights[0]
    w_inv[1:] = -weights[1:] / (partial[1:] * partial[:-1])
    return r_inv, w_inv


def inverse_initial_state(weights: np.ndarray, initial_state: np.ndarray) -> np.ndarray:
    """Initial states of the inverse play operators, eq. (26).

    ``z_i = (w_0+...+w_i) y_i + sum_{j>i} w_j y_j``, which makes the inverse start exactly
    where the forward model starts.

    Parameters
    ----------
    weights : numpy.ndarray
        The forward play weights ``w_i``.
    initial_state : numpy.ndarray
        The forward plays' initial states ``y_i``, V.

    Returns
    -------
    numpy.ndarray
        The inverse plays' initial states ``z_i``, µm.
    """
    partial = np.cumsum(weights)
    weighted = weights * initial_state
    tail = weighted.sum() - np.cumsum(weighted)
    return partial * initial_state + tail
