"""A scikit-learn scorer that rates what matters: the compensator's tracking.

A model's R² on its record is 0.998 to 0.999 for every sensible candidate of a grid search,
and says nothing about how its inverse tracks (DESIGN: "compensation is the product, not
the fit"). :func:`tracking_score` rates a fitted model by the tracking error its
compensator is expected to make on the held-out record
(:func:`hystcomp.identify.compensation.compensation_error`: the inverse run on the measured
displacement, its voltage error through the record's gain), as a scorer
``scorer(estimator, X, y)`` for ``GridSearchCV``, ``cross_val_score`` and friends::

    GridSearchCV(ModifiedPrandtlIshlinskii(), {"n_deadzones": [4, 8, 16]},
                 scoring=hystcomp.tracking_score, cv=3)

Greater is better, as scikit-learn wants: the score is minus the estimated tracking error
in µm rms. It imports nothing from scikit-learn.
"""

from __future__ import annotations

from hystcomp.identify.compensation import compensation_error
from hystcomp.identify.scoring import transient_end
from hystcomp.models.estimator import check_target, one_column

__all__ = ["tracking_score"]


def tracking_score(estimator, X, y) -> float:
    """Minus the estimated tracking error (µm rms) of ``estimator``'s compensator on ``(X, y)``.

    A scorer for scikit-learn (``scoring=tracking_score``): it scores the compensator, not
    the fit. The compensator (``inverse()``) is run on the measured displacement ``y`` from
    the model's initial state; the samples before the input first reaches an end of its
    range (a start-up transient, or a fold of a cross-validation that starts in the middle
    of the record, where the stage's memory and the model's differ) are left out of the
    score.

    Parameters
    ----------
    estimator : fitted model, or a fitted ``Pipeline`` ending in one
        Any model with ``inverse()``; a pipeline's earlier steps transform ``X`` first.
    X : array_like
        The voltage (V): 1-D, ``(n_samples, 1)`` or a one-column DataFrame.
    y : array_like
        The measured displacement (µm).

    Returns
    -------
    float
        ``-tracking_rms_um`` (0 is perfect tracking; greater is better).

    Examples
    --------
    >>> from hystcomp import presets
    >>> from hystcomp.identify.excitation import triangle_sequence
    >>> model = presets.paper_mpi()
    >>> v = triangle_sequence(sample_rate=500)[1]  # the voltage of (t, v)
    >>> bool(-1e-6 < tracking_score(model, v[:, None], model.simulate(v)) <= 0.0)
    True
    """
    model = estimator
    steps = getattr(estimator, "steps", None)
    if steps is not None:  # a Pipeline: its earlier steps transform X, the last is the model
        for _, step in steps[:-1]:
            if step is not None and step != "passthrough":
                X = step.transform(X)
        model = steps[-1][1]
    owner = "tracking_score"
    v = one_column(X, "v", owner)
    x = check_target(y, owner)
    start = transient_end(v)
    if start >= len(v) - 1:  # the input never reaches an end of its range: score it all
        start = 0
    return -float(compensation_error(model, v, x, start=start)["tracking_rms_um"])
