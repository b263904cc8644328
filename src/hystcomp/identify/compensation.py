"""How well a model's compensator is expected to track, estimated from the record alone.

A model that reproduces its record can still make a bad compensator: its inverse amplifies
every place where the fitted curve is nearly flat. The tracking error of a compensator is
the error of the voltage it commands, seen through the actuator's gain. So we run the
model's inverse on the *measured* displacement of the record: where the compensator would
ask for ``v_hat[k]`` to reach ``x[k]``, the actuator needed ``v[k]``; the difference,
mapped to µm through the record's straight-line gain ``a`` (µm/V), estimates the tracking
error in µm::

    e[k] ~ a * (v_hat[k] - v[k]),        v_hat = model.inverse().simulate(x)

The same estimate for the straight-line compensator ``v = (x - b) / a`` (the uncompensated
baseline of the paper's Table I, with the record's least-squares line) is the line's own
residual ``x - a v - b``: the two numbers are comparable, and a model is predicted to help
only if its estimate is below the line's.

It works for any model with ``inverse()`` (an object with ``simulate``) and is cheap: a
long record is thinned first (the models are rate-independent, so keeping every turning
point and a regular subset of the samples between them changes nothing for them;
:func:`~hystcomp.identify.scoring.thin`).

Choosing among candidate fits of one record (the MPI ``regularization="auto"``) needs more
than the record's own errors: a fit with less regularisation always follows its record
closer, while the compensator meets other signals. :func:`tracking_scorer` with the fits
of a cross-validation over the record's reversal segments
(:func:`~hystcomp.identify.scoring.reversal_folds`, :data:`CV_FOLDS` folds, each fit on the
other folds) rates each candidate by ``criterion_um``: the geometric mean of the held-out
forward error and the held-out inverse error above, on the branches each fit did not see.
It ranks candidate fits closer to their measured tracking than the fit error or the
inverse's estimate alone do (Benchmarks, "Ranking candidate fits"). The estimate alone is
weakest on a Preisach actuator with output saturation, where a voltage error at the
saturated top counts more than the tracking error it causes; the held-out forward error is
not.
"""

from __future__ import annotations

import itertools

import numpy as np

from hystcomp._validation import as_signal_pair, check_int
from hystcomp.errors import IdentificationError
from hystcomp.identify.scoring import straight_line, thin, turning_indices

#: Records longer than this are thinned before the inverse is run on them.
MAX_SCORED_SAMPLES = 100_000


#: Records longer than this are thinned further for the held-out fits' runs.
MAX_CV_SAMPLES = 5_000

#: Folds of the cross-validation over reversal segments in :func:`tracking_scorer`.
CV_FOLDS = 6


def inside_training(v, folds, fold: int) -> np.ndarray:
    """Samples of ``fold`` whose input lies inside the range the other folds cover.

    A cross-validation over reversal segments that scores a held-out segment beyond every
    other segment's reach (the top of the paper's largest triangle, its only visit there)
    measures the model's extrapolation, not its error on the branches a reference meets:
    those samples are not scored.

    Parameters
    ----------
    v : array_like
        The record's input, V.
    folds : array_like of int
        The fold of every sample (-1 for none), :func:`~hystcomp.identify.scoring.reversal_folds`.
    fold : int
        The held-out fold.

    Returns
    -------
    numpy.ndarray
        A boolean mask over the samples: in ``fold`` and inside the other folds' input range.

    Examples
    --------
    >>> inside_training(np.array([0.0, 5.0, 10.0, 5.0]), np.array([0, 1, 1, 0]), 1).tolist()
    [False, True, False, False]
    """
    mine = folds == fold
    others = v[(folds >= 0) & ~mine]
    if others.size == 0:
        return np.zeros_like(mine)
    return mine & (v >= others.min()) & (v <= others.max())


def tracking_scorer(v, x, *, start: int = 0, max_samples=MAX_SCORED_SAMPLES, folds=None):
    """A function ``score(model, held_out=()) -> dict`` that rates a model's compensator.

    The record is validated, its straight line fitted and thinned once, so that scoring many
    candidate models of the same record costs one inverse run of the thinned record each
    (:func:`compensation_error`), and one forward run per held-out fit.

    With ``folds`` (the fold of every sample, :func:`~hystcomp.identify.scoring.
    reversal_folds`) and, for a model, its fits ``held_out`` on all folds but one (fit
    ``f`` leaves out fold ``f``), the score also holds the cross-validated forward error
    ``held_out_rms_um``: each held-out fit's error on the reversal segments it did not see.
    The tracking error of a compensator is the forward model's error at the voltages the
    compensator commands, so an error on unseen branches predicts it where the record's
    own error cannot (a fit with less regularisation always follows its own record
    better). The ranking criterion ``criterion_um`` is the geometric mean of the two
    estimates: the held-out forward error (the size of the model's error away from its
    record) and the inverse's error on the record (which sees the steep slopes of an
    inverse the forward error cannot). Without held-out fits it is the latter alone.

    ``score(model, held_out, estimate=False)`` leaves out the inverse's run over the whole
    record: the score then holds the held-out figures and ``criterion_um`` only, enough to
    rank candidates at a fraction of the cost.

    Parameters
    ----------
    v, x : array_like
        The record: voltage (V) and displacement (µm), one sample each.
    start : int, optional
        The first sample scored (after the start-up transient).
    max_samples : int, optional
        The record is thinned to about this many samples for the inverse's run.
    folds : array_like of int, optional
        The fold of every sample, for the held-out forward error.

    Returns
    -------
    callable
        ``score(model, held_out=(), estimate=True) -> dict`` with the estimates in µm
        (``criterion_um``, and ``held_out_rms_um`` with held-out fits).
    """
    owner = "compensation_error"
    v, x = as_signal_pair(v, x, ("v", "x"), owner, min_samples=2)
    start = check_int(start, "start", owner, minimum=0)
    max_samples = check_int(max_samples, "max_samples", owner, minimum=2)
    if start >= v.size - 1:
        raise IdentificationError(
            f"{owner}: 'start' ({start}) leaves fewer than 2 of the {v.size} samples to score."
        )
    a, b = straight_line(v[start:], x[start:])
    if not a > 0:
        raise IdentificationError(
            f"{owner}: the record's straight-line gain is {a:g} µm/V; the displacement must "
            "rise with the voltage. Check the sign and the columns of the record."
        )
    keep = thin(v, start, max_samples)
    v_k, x_k = v[keep], np.ascontiguousarray(x[keep])
    scored = keep >= start
    v_s = v_k[scored]
    line = x_k[scored] - a * v_s - b
    line_rms = float(np.sqrt(np.mean(line**2)))
    folds_k = None
    if folds is not None:
        folds = np.asarray(folds)
        if folds.shape != v.shape:
            raise IdentificationError(
                f"{owner}: 'folds' must give one fold per sample ({v.size}). "
                f"Got shape {folds.shape}."
            )
        # the held-out fits run on fewer samples still (every turning point kept)
        cv_keep = thin(v_k, int(np.searchsorted(keep, start)), MAX_CV_SAMPLES)
        v_cv, x_cv = v_k[cv_keep], np.ascontiguousarray(x_k[cv_keep])
        folds_k = folds[keep][cv_keep]

    def score(model, held_out=(), *, estimate=True) -> dict:
        out: dict = {}
        if estimate or not (held_out and folds_k is not None):
            v_hat = np.asarray(model.inverse().simulate(x_k), dtype=np.float64)
            err = a * (v_hat[scored] - v_s)
            model_rms = float(np.sqrt(np.mean(err**2)))
            out = {
                "tracking_rms_um": model_rms,
                "baseline_rms_um": line_rms,
                "ratio": model_rms / line_rms if line_rms > 0 else float("inf"),
                "gain_um_per_v": a,
                "n_scored": int(v_s.size),
                "criterion_um": model_rms,
            }
        if held_out and folds_k is not None:
            forward, inverse, count = 0.0, 0.0, 0
            for fold, fitted in enumerate(held_out):
                mine = inside_training(v_cv, folds_k, fold)
                e = np.asarray(fitted.simulate(v_cv), dtype=np.float64)[mine] - x_cv[mine]
                forward += float(e @ e)
                e = np.asarray(fitted.inverse().simulate(x_cv), dtype=np.float64)[mine]
                e = a * (e - v_cv[mine])
                inverse += float(e @ e)
                count += int(mine.sum())
            count = max(count, 1)
            out["held_out_rms_um"] = float(np.sqrt(forward / count))
            out["held_out_tracking_rms_um"] = float(np.sqrt(inverse / count))
            out["criterion_um"] = float(np.sqrt(np.sqrt(forward * inverse) / count))
        return out

    return score


def compensation_error(model, v, x, *, start: int = 0, max_samples=MAX_SCORED_SAMPLES) -> dict:
    """Estimated tracking error of ``model.inverse()`` from a record ``(v, x)``, in µm rms.

    Parameters
    ----------
    model : object
        Any fitted model with ``inverse()`` (PI, MPI, Preisach).
    v, x : array_like
        The record: voltage (V) and measured displacement (µm).
    start : int, default 0
        First sample scored (after a start-up transient); the inverse runs from sample 0.
    max_samples : int, default 100000
        Thin longer records to about this many samples
        (:func:`~hystcomp.identify.scoring.thin`).

    Returns
    -------
    dict
        ``tracking_rms_um``: the estimate for the model's compensator; ``baseline_rms_um``:
        the same for the straight line ``v = (x - b) / a``; ``ratio``: their quotient
        (below 1 when the model is predicted to track better than the line);
        ``gain_um_per_v``: ``a``; ``n_scored``: samples scored.

    Examples
    --------
    >>> from hystcomp import presets
    >>> from hystcomp.identify.excitation import triangle_sequence
    >>> model = presets.paper_mpi()
    >>> _, v = triangle_sequence(sample_rate=500)
    >>> est = compensation_error(model, v, model.simulate(v))
    >>> bool(est["tracking_rms_um"] < 1e-6 < est["baseline_rms_um"])
    True
    """
    return tracking_scorer(v, x, start=start, max_samples=max_samples)(model)


#: Swings of at least this share of the input span are those a tracking reference makes.
SWING = 0.5
#: The references of :func:`tracking_estimate`'s inverse term span this part of the reach.
REFERENCE_SPAN = (0.05, 0.90)
#: Samples a period of that reference (a 1 Hz triangle at 20 kHz, as the paper tracks).
REFERENCE_PERIOD = 20_000
#: The estimate is said to flatter references that turn inside the range when the error on
#: held-out reversal segments exceeds it by this factor, and is more than
#: :data:`FLATTERS_FLOOR` of the straight line's (below that, the model tracks such
#: references within a few percent of the line's error whatever the ratio: a model of the
#: stage's own family fits its record to the noise, and its held-out error is a few times
#: that).
FLATTERS = 2.0
FLATTERS_FLOOR = 0.05


def swing_mask(v, start: int = 0, share: float = SWING) -> np.ndarray:
    """Samples of the record's swings of at least ``share`` of its input span (after
    ``start``): the monotone stretches between turning points (reversals under 5 % of
    the span ignored) that travel that far.

    Parameters
    ----------
    v : array_like
        The record's input, V.
    start : int, optional
        The first sample considered (after the start-up transient).
    share : float, optional
        The least travel of a swing, as a share of the input span.

    Returns
    -------
    numpy.ndarray
        A boolean mask over the samples: True on the swings that travel that far.

    Examples
    --------
    >>> v = np.r_[np.linspace(0.0, 10.0, 11), np.linspace(9.0, 7.0, 3), np.linspace(8.0, 0.0, 9)]
    >>> swing_mask(v).astype(int).tolist()
    [1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1, 1]
    """
    v = np.asarray(v, dtype=np.float64)
    part = v[start:]
    mask = np.zeros(v.size, dtype=bool)
    span = float(np.ptp(part)) if part.size else 0.0
    if span <= 0.0:
        return mask
    idx, _ = turning_indices(part, 0.05 * span)
    for a, b in itertools.pairwise(idx):
        if abs(part[b] - part[a]) >= share * span:
            mask[start + a : start + b + 1] = True
    return mask


#: The measured displacement is smoothed over this share of the input span of travel.
TRAVEL_SMOOTHING = 0.005


def _travel(v: np.ndarray, x: np.ndarray, fitted: np.ndarray) -> np.ndarray:
    """The displacement a reference at constant speed covers at each sample of a record:
    the smaller of the stage's (``x`` smoothed over :data:`TRAVEL_SMOOTHING` of the input
    span, against its noise) and the model's (``fitted``). A reference visits only what
    the stage travels, and a compensator walks the model's curve at the reference's speed:
    the record's dwell (a sinusoid's at its turns) counts for nothing."""
    if v.size < 2:
        return np.ones(v.size)
    steps = np.abs(np.diff(v))
    moving = steps[steps > 0.0]
    if moving.size == 0:
        return np.ones(v.size)
    half = int(min(max(1.0, TRAVEL_SMOOTHING * np.ptp(v) / np.median(moving)), v.size // 4))
    kernel = np.ones(2 * half + 1) / (2 * half + 1)
    smooth = np.convolve(np.pad(x, half, mode="edge"), kernel, mode="valid")
    return np.minimum(np.abs(np.gradient(smooth)), np.abs(np.gradient(fitted)))


def _weighted_rms(error: np.ndarray, weight: np.ndarray) -> float:
    return float(np.sqrt(np.sum(weight * error**2) / np.sum(weight)))


def tracking_estimate(model, v, x, *, start: int = 0) -> dict:
    """How well ``model.inverse()`` will track a reference over most of its range, in µm rms.

    The tracking error of a compensator is the model's error at the voltages it commands,
    plus what its inverse itself misses::

        estimate^2 = e_swing^2 + e_inverse^2

    * ``e_swing``: the model's error against the record on its swings over at least half
      the input range (:func:`swing_mask`), where a reference over the range drives the
      stage; each sample weighted by the displacement travelled there, the stage's or the
      model's, whichever is smaller (:func:`_travel`), as a reference at constant speed
      spends equal time on each micrometre the stage travels (a sinusoid's record dwells at
      its turns, a triangle's does not);
    * ``e_inverse``: the compensator's error on its own model for a triangle over 5-90 %
      of the model's reach, with :data:`REFERENCE_PERIOD` samples a period: the one-sample
      lag of eq. 10, and any part out of reach.

    Beside it, ``held_out_rms_um`` (from the fit, where the fit has one): the model's
    error on the reversal segments of a cross-validation, each fitted without them, which
    a reference that turns inside the range meets; ``flatters`` is True when that is more
    than :data:`FLATTERS` times the estimate and :data:`FLATTERS_FLOOR` of the line's. How
    close the estimate comes to the measured tracking is in the documentation
    (Benchmarks, "The tracking estimate").

    Parameters
    ----------
    model : object
        A fitted PI, MPI or Preisach model.
    v, x : array_like
        The record it was fitted on: voltage (V), displacement (µm).
    start : int, default 0
        First sample scored (after a start-up transient).

    Returns
    -------
    dict
        ``tracking_rms_um`` (the estimate), ``swing_rms_um``, ``inverse_rms_um``,
        ``held_out_rms_um`` (NaN without one), ``flatters``, ``baseline_rms_um`` (a
        straight line's error on the same swings, ``v = (x - b) / a`` with the record's
        least-squares line), ``ratio`` (estimate over the line's), ``n_scored``.
    """
    owner = "tracking_estimate"
    v, x = as_signal_pair(v, x, ("v", "x"), owner, min_samples=2)
    start = check_int(start, "start", owner, minimum=0)
    mask = swing_mask(v, start)
    if not mask.any():  # no swing over half the range: the whole record
        mask[start:] = True
    fitted = np.asarray(model.simulate(v), dtype=np.float64)
    weight = _travel(v, x, fitted) * mask
    if not weight.sum() > 0.0:
        weight = mask.astype(np.float64)
    swing = _weighted_rms(fitted - x, weight)
    a, b = straight_line(v[start:], x[start:])
    line = _weighted_rms(a * v + b - x, weight)
    lo, hi = model.voltage_range_
    swept = np.asarray(model.simulate(np.array([lo, hi, lo, hi])), dtype=np.float64)
    bottom, top = float(swept[2]), float(swept[3])
    low, high = REFERENCE_SPAN
    phase = np.arange(2 * REFERENCE_PERIOD) % REFERENCE_PERIOD / REFERENCE_PERIOD
    x_ref = bottom + (top - bottom) * (low + (high - low) * (1.0 - np.abs(1.0 - 2.0 * phase)))
    back = np.asarray(model.simulate(model.inverse().simulate(x_ref)), dtype=np.float64)
    inverse = float(np.sqrt(np.mean((back - x_ref)[REFERENCE_PERIOD:] ** 2)))
    estimate = float(np.hypot(swing, inverse))
    held = float(getattr(model, "fit_report_", {}).get("held_out_rms_um", float("nan")))
    return {
        "tracking_rms_um": estimate,
        "swing_rms_um": swing,
        "inverse_rms_um": inverse,
        "held_out_rms_um": held,
        "flatters": bool(held > FLATTERS * estimate and held > FLATTERS_FLOOR * line),
        "baseline_rms_um": line,
        "ratio": estimate / line if line > 0 else float("inf"),
        "n_scored": int(mask.sum()),
    }
