"""Choosing a hyperparameter on a validation record: the one that predicts it best.

A model identified on one record should predict another, different signal on the same
actuator. :func:`choose_regularization` fits the estimator once per candidate value on the
identification record and keeps the value whose model predicts the validation record with
the smallest rms error (after each record's start-up transient). It is how the MPI
regularisation of :mod:`hystcomp.identify.mpi` is meant to be set.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hystcomp._validation import as_signal_pair, check_real
from hystcomp.errors import InvalidParameterError, InvalidTypeError
from hystcomp.identify.mpi import REGULARIZATION_GRID
from hystcomp.identify.scoring import transient_end


@dataclass(frozen=True)
class Choice:
    """Result of :func:`choose_regularization`.

    Attributes
    ----------
    model : estimator
        Fitted with the chosen value (a new estimator; the one given is left unfitted).
    value : float
        The chosen ``regularization``.
    scores : dict
        Validation rms error in µm for each candidate value.
    """

    model: object
    value: float
    scores: dict[float, float]


def choose_regularization(estimator, v, x, v_val, x_val, *, grid=REGULARIZATION_GRID) -> Choice:
    """Fit ``estimator`` on ``(v, x)`` for each value in ``grid``; keep the best on validation.

    Parameters
    ----------
    estimator : ModifiedPrandtlIshlinskii
        An estimator with a ``regularization`` hyperparameter; it is not modified.
    v, x : array_like
        Identification record: voltage (V) and displacement (µm).
    v_val, x_val : array_like
        Validation record of the same actuator, another signal: voltage (V), displacement (µm).
    grid : sequence of float
        Candidate values (>= 0).

    Returns
    -------
    Choice

    Examples
    --------
    >>> from hystcomp import ModifiedPrandtlIshlinskii, presets
    >>> from hystcomp.identify.excitation import triangle_sequence
    >>> true = presets.paper_mpi()
    >>> _, v = triangle_sequence(sample_rate=500)
    >>> v_val = 100.0 * np.abs(np.sin(np.linspace(0.0, 9.0, 3000)))
    >>> estimator = ModifiedPrandtlIshlinskii(constraints="paper")  # eq. 19: the paper's model
    >>> choice = choose_regularization(estimator, v, true.simulate(v), v_val, true.simulate(v_val))
    >>> choice.value  # an MPI system of the estimator's size needs none
    0.0
    >>> bool(choice.scores[0.0] < 1e-6 < choice.scores[1e-2])
    True
    """
    owner = "choose_regularization"
    params = estimator.get_params() if hasattr(estimator, "get_params") else {}
    if "regularization" not in params:
        raise InvalidTypeError(
            f"The 'estimator' parameter of {owner} must have a 'regularization' "
            f"hyperparameter (a ModifiedPrandtlIshlinskii). Got {type(estimator).__name__}."
        )
    values = [check_real(g, "grid", owner) for g in grid]
    if not values or min(values) < 0:
        raise InvalidParameterError(
            f"The 'grid' parameter of {owner} must hold at least one value >= 0. "
            f"Got {list(grid)!r} instead."
        )
    v_val, x_val = as_signal_pair(v_val, x_val, ("v_val", "x_val"), owner, min_samples=2)
    start = transient_end(v_val)
    scores, models = {}, {}
    for value in values:
        model = type(estimator)(**{**params, "regularization": value}).fit(v, x)
        error = model.simulate(v_val)[start:] - x_val[start:]
        # the validation record's own offset is not the model's business
        scores[value] = float(np.sqrt(np.mean((error - error.mean()) ** 2)))
        models[value] = model
    best = min(values, key=lambda value: scores[value])
    return Choice(model=models[best], value=best, scores=scores)
