"""How well a fitted model describes a record: start-up transient, errors, hold-out test.

Functions here work on arrays and on any object with ``simulate(v)``; they never import
the model classes (the models import the identification layer, not the reverse).
"""

from __future__ import annotations

import numpy as np

from hystcomp._kernels.reversals import turning_points
from hystcomp._notice import Notice
from hystcomp._validation import as_signal, as_signal_pair, check_int
from hystcomp.errors import IdentificationError
from hystcomp.identify.outliers import bulk_range

#: How close (as a fraction of the input span) the input must come to an end of its range.
END_TOLERANCE = 0.01


def transient_end(v) -> int:
    """Default start of the fit: the first sample at which the input reaches an end of its range.

    A record may start anywhere, from a rest state the model does not know: the stage was
    switched on, the command jumped to ``v[0]``, the sensor and the creep are settling
    (the real record of the data folder starts mid-range, with the displacement 4 µm below
    the loop). Reaching ``min(v)`` or ``max(v)`` (within 1 % of the span) ends that phase:
    by then the plays with ``r <= |v_end - v[0]| / 2`` have forgotten their initial state
    (wipe-out), the fast part of the transient is over, and from there on the record is
    the periodic hysteresis loop the model describes. A record that starts at an end of its
    range, like the paper's identification signal (eq. 18: relaxed at ``v_min``), loses no
    sample. The range is that of the record without its isolated samples
    (:func:`~hystcomp.identify.outliers.isolated_samples`): a single glitch far outside
    the rest does not stand for an end, and the end it would set is never reached.

    Parameters
    ----------
    v : array_like
        Input voltage in V.

    Returns
    -------
    int
        Index of the first sample to use.

    Examples
    --------
    >>> transient_end([0.0, 1.0, 2.0, 1.0, 0.0])
    0
    >>> transient_end([1.0, 1.5, 2.0, 1.0, 0.0])
    2
    >>> v = np.r_[np.linspace(60, 90, 50), -60, np.linspace(90, 120, 51), np.linspace(120, 0, 200)]
    >>> transient_end(v)  # near 120 V, not the glitch at -60 V (sample 50)
    99
    """
    v = as_signal(v, "v", min_samples=1)
    return _first_near_an_end(v)


#: Samples per block of the block-wise scans of long records (a few hundred kB: the blocks
#: stay in the cache, and a scan that finds what it seeks early stops there).
_SCAN_BLOCK = 1 << 16


def _first_near_an_end(v: np.ndarray) -> int:
    """:func:`transient_end` of a validated signal: the range without isolated samples,
    then a scan block by block that stops at the first block holding a sample near an end
    (within the range: an isolated sample beyond it is not)."""
    lo, hi = bulk_range(v)
    tol = END_TOLERANCE * (hi - lo)
    for begin in range(0, v.size, _SCAN_BLOCK):
        part = v[begin : begin + _SCAN_BLOCK]
        near = ((part <= lo + tol) & (part >= lo)) | ((part >= hi - tol) & (part <= hi))
        if near.any():
            return begin + int(np.argmax(near))
    return 0  # not reached: the extremes are samples


def check_transient(transient, v: np.ndarray, owner: str, *, min_used: int) -> int:
    """The first sample of the fit: ``transient`` validated, or :func:`transient_end`.

    Parameters
    ----------
    transient : int or None
        The first sample of the fit as the user gave it (found from the record if None).
    v : numpy.ndarray
        The record's voltage, V.
    owner : str
        The class named in an error message.
    min_used : int
        The fewest samples the fit needs after the transient.

    Returns
    -------
    int
        The first sample of the fit.
    """
    start = (
        _first_near_an_end(v)
        if transient is None
        else check_int(transient, "transient", owner, minimum=0)
    )
    if v.size - start < min_used:
        raise IdentificationError(
            Notice(
                "{owner}: only "
                f"{v.size - start} of {v.size} samples remain after the start-up transient "
                f"(first sample used: {start}), fewer than the {min_used} needed. Record "
                "longer, use fewer operators, or set a shorter transient ({transient}).",
                owner=owner,
            )
        )
    return start


#: Records longer than this are thinned (:func:`thin`) before a PI or MPI fit. A
#: rate-independent loop is described by far fewer samples than a 20 kHz record holds
#: (Benchmarks, "Thinning a record").
MAX_SAMPLES = 20_000


def input_noise(v: np.ndarray) -> float:
    """Robust estimate of white noise on ``v`` (V) from the MAD of second differences.

    Parameters
    ----------
    v : numpy.ndarray
        The record's voltage, V.

    Returns
    -------
    float
        The noise's standard deviation, V.
    """
    if v.size < 4:
        return 0.0
    d2 = np.diff(v, 2)
    return float(1.4826 * np.median(np.abs(d2 - np.median(d2))) / np.sqrt(6.0))


def default_tolerance(v: np.ndarray) -> float:
    """Dead band of the turning-point search: ``max(1e-3 * span, 8 * noise)`` in V.

    Parameters
    ----------
    v : numpy.ndarray
        The voltage whose span and :func:`input_noise` set the band, V.

    Returns
    -------
    float
        The dead band, V.
    """
    return max(1e-3 * float(np.ptp(v)), 8.0 * input_noise(v))


def turning_indices(v: np.ndarray, tolerance: float) -> tuple[np.ndarray, bool]:
    """``(indices, first_is_max)``: the alternating extrema of ``v``, reversals smaller than
    ``tolerance`` ignored; the last index is where ``v`` stands at its end (see
    :func:`hystcomp._kernels.reversals.turning_points`).

    Parameters
    ----------
    v : numpy.ndarray
        The signal, V.
    tolerance : float
        The dead band, V: smaller reversals are ignored.

    Returns
    -------
    indices : numpy.ndarray
        The indices of the alternating extrema, the last sample's index last.
    first_is_max : bool
        Whether the first extremum is a maximum.
    """
    idx = np.empty(v.size, dtype=np.int64)
    count, first_is_max = turning_points(v, tolerance, idx)
    return idx[:count], bool(first_is_max)


#: A record that never rises (or never falls) over this share of its input span leaves the
#: model's branches of that direction over the wider part to the fit's guess.
MIN_SWING = 0.75
#: Turning points within this share of the span from an end of the range count as the end's,
#: and reversals smaller than it are not minor loops (dither, noise, a filter's ripple).
END_ZONE = 0.05


def largest_swings(levels) -> tuple[float, float]:
    """The largest rise and the largest fall in a sequence of turning points, as a
    rate-independent hysteresis model with wipe-out sees them: a turning point beyond the
    one before last wipes out the minor loop between them, so a climb through small dips
    counts as one rise (the first level, where the record's memory is known, stays).

    Parameters
    ----------
    levels : sequence of float
        Turning points, in order.

    Returns
    -------
    rise : float
        The largest rise.
    fall : float
        The largest fall.

    Examples
    --------
    >>> largest_swings([0.0, 60.0, 50.0, 100.0, 90.0])
    (100.0, 10.0)
    >>> largest_swings([89.0, 90.0, 0.0, 50.0, 40.0, 90.0])  # starts just below its top
    (90.0, 90.0)
    """
    stack: list[float] = []
    rise = fall = 0.0
    for level in levels:
        while stack:  # the swing from each stored extremum that the level reaches past
            rise = max(rise, level - stack[-1])
            fall = max(fall, stack[-1] - level)
            if len(stack) < 3 or abs(level - stack[-1]) < abs(stack[-2] - stack[-1]):
                break
            del stack[-2:]
        stack.append(float(level))
    return rise, fall


def coverage_warning(v, start: int = 0) -> Notice | None:
    """Why a record may not show what a compensator meets, or None.

    The tracking estimate of ``hystcomp identify`` is measured on the record itself, so it
    cannot see what the record never does. Two things a tracking reference does that a
    record can lack, after its start-up transient:

    * rise, and fall, over most of the range (:func:`largest_swings`, minor loops on the
      way wiped out). A random walk that drifts across the range once rises over it only
      in short stretches: the model's rising branches beyond them are fitted on nothing;
    * turn back inside the range. A single loop, or a staircase up and down, turns only at
      the ends, so no branch after a reversal inside the range (a minor loop) is seen.

    The records flagged here track far worse than their estimate more often than the
    records passed (Benchmarks, "Records that flatter the estimate").

    Parameters
    ----------
    v : array_like
        The record's voltage, V.
    start : int, optional
        The first sample after the start-up transient.

    Returns
    -------
    str or None
        The reason, or None if the record rises, falls and turns back inside its range.

    The sentence is a :class:`~hystcomp._notice.Notice`: the signals it suggests recording
    and the transient option are named as data, which the command line words as its own.

    Examples
    --------
    >>> def ramps(*levels):  # straight lines between turning points, 100 samples each
    ...     return np.interp(np.linspace(0, len(levels) - 1, 100 * len(levels)),
    ...                      np.arange(len(levels)), levels)
    >>> coverage_warning(ramps(100, 40, 60, 10, 30, 0, 20, 5)).split(":")[0]
    'after its start-up transient the record never rises over more than 20 % of its input range'
    >>> coverage_warning(ramps(0, 100, 0)).split(";")[0]
    'the record turns back only at the ends of its input range'
    >>> coverage_warning(ramps(0, 100, 20, 100, 0)) is None
    True
    """
    v = np.asarray(v, dtype=np.float64)[start:]
    span = float(np.ptp(v)) if v.size else 0.0
    if span <= 0.0:
        return None
    idx, _ = turning_indices(v, END_ZONE * span)
    levels = v[idx]
    what = "{excite_rich}, or the paper's triangles of {excite_mpi}"
    if start:
        what += (
            f"; the first {start} samples are left out as a start-up transient, until the "
            "input first reaches an end of its range: {transient} changes that"
        )
    for swing, verb, noun in zip(
        largest_swings(levels), ("rises", "falls"), ("rising", "falling"), strict=True
    ):
        if swing < MIN_SWING * span:
            return Notice(
                f"after its start-up transient the record never {verb} over more than "
                f"{100 * swing / span:.0f} % of its input range: the model's {noun} branches "
                "beyond that are fitted on nothing, and a reference that swings further may "
                "track far worse than estimated. Record swings across the whole range in "
                f"both directions ({what}).",
                kind="coverage",
            )
    low, high = float(v.min()), float(v.max())
    inner = levels[1:-1]
    if not np.any((inner > low + END_ZONE * span) & (inner < high - END_ZONE * span)):
        return Notice(
            "the record turns back only at the ends of its input range; it shows no minor "
            "loop, and a reference that turns inside the range may track far worse than "
            f"estimated. Record turning points inside the range ({what}).",
            kind="coverage",
        )
    return None


def thin(v, start: int = 0, max_samples: int = MAX_SAMPLES) -> np.ndarray:
    """Indices of at most about ``max_samples`` samples: every turning point, and a regular grid.

    The output of a rate-independent model (plays, dead-zones, relays) at the kept samples
    is unchanged when the others are dropped, as long as every turning point of its input is
    kept: between two turning points the input is monotone, and a play or a relay only moves
    further the same way. A least-squares fit or a score over a regular subset of the samples
    weights the record as the whole does. Before ``start`` (a start-up transient, out of the
    cost) only the turning points are kept, to set the model's state.

    Parameters
    ----------
    v : array_like
        The record's input, V.
    start : int, optional
        The first sample of the fit; before it only turning points are kept.
    max_samples : int, optional
        About how many samples to keep.

    Returns
    -------
    numpy.ndarray
        The kept indices, rising.

    Examples
    --------
    >>> thin(np.array([0.0, 1.0, 2.0, 3.0, 2.0, 1.0, 2.0]), max_samples=2).tolist()
    [0, 3, 5, 6]
    """
    v = np.asarray(v, dtype=np.float64)
    n = v.size
    if n <= max_samples:
        return np.arange(n)
    keep = np.zeros(n, dtype=bool)
    # sample i (1 <= i <= n - 2) turns where the sign of v[i+1] - v[i] differs from the one
    # before; block by block, so that the differences and signs stay in the cache
    for begin in range(1, n - 1, _SCAN_BLOCK):
        stop = min(begin + _SCAN_BLOCK, n - 1)
        sign = np.sign(np.diff(v[begin - 1 : stop + 1]))
        keep[begin:stop] = sign[1:] != sign[:-1]
    keep[start :: max(1, (n - start) // max_samples)] = True
    keep[0] = keep[-1] = True
    return np.flatnonzero(keep)


#: Parts of the input range that :func:`range_weights` weighs equally.
RANGE_BINS = 24
#: The largest weight :func:`range_weights` gives a sample, relative to the average sample.
RANGE_WEIGHT_CAP = 3.0


def range_weights(u, start: int = 0) -> np.ndarray:
    """Sample weights under which every part of the input range counts the same in a fit.

    A record lingers where its signal does: the paper's nested triangles and sinusoids,
    which all start from ``v_min``, hold 8 to 9 times as many samples in the lowest quarter
    of the range as in the highest. An unweighted least-squares fit then buys its accuracy
    at the bottom of the stroke with errors at the top, while a compensator is judged over
    the whole stroke. So the span of ``u[start:]`` is cut into :data:`RANGE_BINS` equal
    parts, and each sample is weighted by the mean count of samples per part over the count
    of its own part, at most :data:`RANGE_WEIGHT_CAP` (a part that the record barely visits
    must not let a few noisy samples steer the fit); the weights average 1 over
    ``u[start:]``. Samples before ``start`` get the weight of their part (they are out of
    the cost anyway).

    The PI fit with physical constraints uses it (:func:`hystcomp.identify.pi.fit_pi`); the
    cap, the number of parts and the power of the weights were chosen on the benchmark
    panel (Benchmarks, "The PI fit").

    Parameters
    ----------
    u : array_like
        The fit's input, V.
    start : int, optional
        The first sample in the fit's cost.

    Returns
    -------
    numpy.ndarray
        One weight per sample, averaging 1 over ``u[start:]``.

    Examples
    --------
    >>> w = range_weights(np.r_[np.zeros(30), np.linspace(0.0, 1.0, 24)])
    >>> bool(w[0] < w[-1]), round(float(w.mean()), 12)
    (True, 1.0)
    """
    u = np.asarray(u, dtype=np.float64)
    fitted = u[start:]
    low, span = float(fitted.min()), float(np.ptp(fitted))
    if span <= 0.0:
        return np.ones(u.size)
    part = np.clip(((u - low) * (RANGE_BINS / span)).astype(np.int64), 0, RANGE_BINS - 1)
    counts = np.bincount(part[start:], minlength=RANGE_BINS).astype(np.float64)
    # a part holding a sample has a count of at least 1, so no division by zero below
    weights = np.minimum(counts.mean() / np.maximum(counts[part], 1.0), RANGE_WEIGHT_CAP)
    return weights / weights[start:].mean()


def reversal_folds(v, start: int, n_folds: int) -> np.ndarray:
    """Folds of a record for cross-validation: its reversal segments dealt out in turn.

    The samples from ``start`` on are cut at the turning points of the input into segments
    (monotone stretches between reversals), and segment ``i`` goes to fold ``i % n_folds``:
    every fold holds ascending and descending branches from all over the record, and a
    model fitted on the other folds must predict whole branches it has not seen. Samples
    before ``start`` get -1.

    Parameters
    ----------
    v : array_like
        The record's input, V.
    start : int
        The first sample dealt out (earlier ones get -1).
    n_folds : int
        The number of folds.

    Returns
    -------
    numpy.ndarray
        The fold of every sample (int).

    Examples
    --------
    >>> reversal_folds(np.array([0.0, 2.0, 4.0, 2.0, 0.0, 3.0, 1.0]), 0, 2).tolist()
    [0, 0, 0, 1, 1, 0, 1]
    """
    v = np.asarray(v, dtype=np.float64)
    sign = np.sign(np.diff(v[start:]))
    turns = np.zeros(v.size - start, dtype=np.int64)
    turns[2:] = sign[1:] != sign[:-1]  # a segment starts just after each turning point
    folds = np.full(v.size, -1, dtype=np.int64)
    folds[start:] = np.cumsum(turns) % n_folds
    return folds


#: Least share of the displacement's variance that a straight line in the voltage must
#: explain for a record to count as a response. Real records explain 0.95 and more; a
#: loop that turns back (a partial sum of PI weights below 0) still about 0.2; noise
#: about 1 / (number of samples).
MIN_EXPLAINED = 0.1
#: Least Fisher statistic ``(n - 2) R^2 / (1 - R^2)`` of that line: the share must also be
#: beyond chance (noise reaches 30 with a probability near 1e-5 at 20 samples, far less
#: with more), so that a short noise-only record is refused too.
MIN_F_STATISTIC = 30.0


def check_response(v, x, owner: str) -> float:
    """Refuse a record whose displacement does not respond to its input.

    The one check every fit goes through (PI, MPI, Preisach) before it identifies
    anything: the least-squares line ``x = a v + b`` (:func:`straight_line`) must rise
    (``a > 0``) and explain at least :data:`MIN_EXPLAINED` of the variance of ``x``,
    significantly (Fisher statistic at least :data:`MIN_F_STATISTIC`). A hysteretic
    actuator's loop is close to its line (R^2 of 0.95-0.98 on the real and simulated
    records of the tests); a record of sensor noise, of a constant, or of a column that
    is not the displacement explains next to nothing, and a short one that explains more
    by chance fails the F test. A line and not a monotone fit: a monotone fit explains
    much of any noise sorted by the input.

    Parameters
    ----------
    v, x : array_like
        Input (V) and displacement (µm) over the samples the fit uses.
    owner : str
        Names the fit in messages.

    Returns
    -------
    float
        The explained share R^2.

    Raises
    ------
    IdentificationError
        Naming what was found and what to record.

    Examples
    --------
    >>> v = np.linspace(0.0, 100.0, 50)
    >>> round(check_response(v, 0.3 * v + 2.0, "fit"), 6)
    1.0
    """
    v, x = as_signal_pair(v, x, ("v", "x"), owner)
    if np.ptp(x) == 0.0:
        raise IdentificationError(
            f"{owner}: the displacement 'x' is constant ({float(x[0])!r} µm); the sensor "
            "recorded no motion. Check the displacement column and the sensor."
        )
    if np.ptp(v) == 0.0:
        raise IdentificationError(
            f"{owner}: the input 'v' is constant ({float(v[0])!r} V); it shows no hysteresis "
            "to identify. Record the response to an input that sweeps the actuator's range."
        )
    vc = (v - v.mean()) / np.ptp(v)  # scaled: the products stay finite at any magnitude
    xc = (x - x.mean()) / np.ptp(x)
    r2 = float(np.dot(vc, xc) ** 2 / (np.dot(vc, vc) * np.dot(xc, xc)))
    slope = float(np.dot(vc, xc))
    f_stat = (v.size - 2) * r2 / (1.0 - r2) if r2 < 1.0 else np.inf
    if slope <= 0.0 and r2 >= MIN_EXPLAINED:
        raise IdentificationError(
            f"{owner}: the displacement 'x' falls as the voltage 'v' rises. The models "
            "describe an actuator whose displacement rises with its voltage: flip the sign "
            "of the displacement (a negative sensor gain) or check the columns."
        )
    if slope <= 0.0 or r2 < MIN_EXPLAINED or f_stat < MIN_F_STATISTIC:
        raise IdentificationError(
            f"{owner}: the displacement 'x' does not respond to the voltage 'v': a straight "
            f"line in v explains {100 * r2:.3g} % of its variance over {v.size} samples "
            f"(a response explains at least {100 * MIN_EXPLAINED:g} %, beyond chance). "
            "It looks like noise or the wrong column: check the displacement column, "
            "the sensor, and that the record sweeps the actuator's range."
        )
    return r2


def error_report(x, x_model, start: int = 0) -> dict:
    """Errors of a model output against the measured displacement over samples ``start..``.

    Parameters
    ----------
    x, x_model : ndarray
        Measured and modelled displacement in µm.
    start : int
        First sample scored.

    Returns
    -------
    dict
        ``rms_error_um``, ``max_error_um``, the same in percent of the measured displacement
        range (``rms_error_percent``, ``max_error_percent``), ``displacement_range_um``,
        ``n_samples`` (the record), ``n_used`` and ``first_used_sample``.
    """
    x, x_model = as_signal_pair(x, x_model, ("x", "x_model"), "error_report")
    start = check_int(start, "start", "error_report", minimum=0)
    if start >= x.size:
        raise IdentificationError(
            f"error_report: 'start' ({start}) leaves no sample of the {x.size} to score."
        )
    x = x[start:]
    err = x_model[start:] - x
    span = float(np.ptp(x))
    rms = float(np.sqrt(np.mean(err**2)))
    worst = float(np.abs(err).max())
    return {
        "rms_error_um": rms,
        "max_error_um": worst,
        "rms_error_percent": 100.0 * rms / span if span > 0 else float("nan"),
        "max_error_percent": 100.0 * worst / span if span > 0 else float("nan"),
        "displacement_range_um": span,
        "n_samples": int(x.size + start),
        "n_used": int(x.size),
        "first_used_sample": int(start),
    }


def straight_line(v, x) -> tuple[float, float]:
    """Least-squares line ``x = a v + b`` (a in µm/V, b in µm): the no-hysteresis baseline.

    Parameters
    ----------
    v : array_like
        Voltage, V.
    x : array_like
        Displacement, µm.

    Returns
    -------
    a : float
        The slope, µm/V.
    b : float
        The intercept, µm.

    Examples
    --------
    >>> a, b = straight_line([0.0, 1.0, 2.0], [1.0, 3.0, 5.0])
    >>> round(a, 9), round(b, 9)
    (2.0, 1.0)
    """
    v, x = as_signal_pair(v, x, ("v", "x"), "straight_line")
    v_mean, x_mean = float(v.mean()), float(x.mean())
    dv = v - v_mean
    spread = float(dv @ dv)
    a = float(dv @ (x - x_mean)) / spread if spread > 0 else 0.0
    return a, x_mean - a * v_mean


def holdout_report(model, v, x, n_fit: int, start: int = 0) -> dict:
    """Score a model fitted on ``v[:n_fit]`` on the rest of the record, against a line.

    The model is run over the whole record (so that its state is right when the held-out
    part begins) and scored on ``n_fit..`` only. The baseline is the straight line
    :func:`straight_line` fitted on the same samples as the model (``start..n_fit``).

    Parameters
    ----------
    model : HysteresisModel
        The model fitted on ``v[:n_fit]``.
    v : array_like
        The whole record's voltage, V.
    x : array_like
        The whole record's displacement, µm.
    n_fit : int
        The number of samples the model was fitted on.
    start : int, optional
        The first sample of the fit (after the start-up transient).

    Returns
    -------
    dict
        ``n_holdout``, ``model_rms_um``, ``line_rms_um`` and ``improvement`` (their ratio,
        > 1 when the model predicts better than the line).
    """
    v, x = as_signal_pair(v, x, ("v", "x"), "holdout_report")
    n_fit = check_int(n_fit, "n_fit", "holdout_report", minimum=1)
    start = check_int(start, "start", "holdout_report", minimum=0)
    if not start < n_fit < v.size:
        raise IdentificationError(
            f"holdout_report: need start < n_fit < {v.size} samples (a fit part and a held-out "
            f"part). Got start={start}, n_fit={n_fit}."
        )
    model_err = model.simulate(v)[n_fit:] - x[n_fit:]
    a, b = straight_line(v[start:n_fit], x[start:n_fit])
    line_err = a * v[n_fit:] + b - x[n_fit:]
    model_rms = float(np.sqrt(np.mean(model_err**2)))
    line_rms = float(np.sqrt(np.mean(line_err**2)))
    return {
        "n_holdout": int(v.size - n_fit),
        "model_rms_um": model_rms,
        "line_rms_um": line_rms,
        "improvement": line_rms / model_rms if model_rms > 0 else float("inf"),
    }
