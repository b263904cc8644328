"""Analytic inversion of Prandtl-Ishlinskii superpositions (paper eqs. 24-26).

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
    """
    partial = np.cumsum(weights)
    weighted = weights * initial_state
    tail = weighted.sum() - np.cumsum(weighted)
    return partial * initial_state + tail
