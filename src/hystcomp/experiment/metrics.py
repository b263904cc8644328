"""The paper's figures of merit (Section V): tracking errors and hysteresis percentages.

* Tracking error ``e = x - x_ref``: its rms and its largest magnitude, in µm (Table I).
* Hysteresis %: the largest vertical width between the ascending and the descending branch
  of the output plotted against the reference (or the input), divided by the displacement
  range, in percent; over the whole loop, and over the top quarter of the range, the
  paper's "saturation zone" (Fig. 9 and its text).

The caller passes whole periods (the paper does not say which periods it measures; we drop
the first, where the axis leaves its rest state; see :mod:`hystcomp.experiment.tracking`).
"""

from __future__ import annotations

import numpy as np

from hystcomp._validation import as_signal_pair, check_int
from hystcomp.errors import InvalidSignalError

#: The paper's "saturation zone": the top quarter of the displacement range.
SATURATION_ZONE = 0.75


def _pair(reference, output, min_samples):
    return as_signal_pair(
        reference, output, ("reference", "output"), "metrics", min_samples=min_samples
    )


def tracking_errors(reference, output) -> tuple[float, float]:
    """The rms and the maximum of ``|output - reference|``, in the signals' unit (µm).

    Parameters
    ----------
    reference : array_like
        The reference, µm.
    output : array_like
        The measured displacement, µm.

    Returns
    -------
    rms : float
        The rms error, µm.
    max : float
        The largest absolute error, µm.

    Examples
    --------
    >>> t = np.arange(1000) / 1000
    >>> rms, peak = tracking_errors(np.zeros(1000), 0.5 * np.sin(2 * np.pi * t))
    >>> round(rms, 6), round(peak, 6)
    (0.353553, 0.5)
    """
    ref, out = _pair(reference, output, 1)
    e = out - ref
    return float(np.sqrt(np.mean(e * e))), float(np.max(np.abs(e)))


def branch_means(reference, output, *, n_bins=None) -> tuple[np.ndarray, ...]:
    """Ascending and descending branches of a loop, averaged on a common grid.

    Each step between two samples belongs to the ascending or the descending branch as the
    reference rises or falls (steps of a flat reference are left out) and stands for its
    mid-point, so that the turning points weigh the same on both branches. The reference
    range is cut into ``n_bins`` equal bins and each branch is averaged in each bin, which
    removes the sensor noise and puts both branches on the same abscissa.

    Parameters
    ----------
    reference : array_like
        The loop's abscissa (the reference, or the input).
    output : array_like
        The loop's ordinate (the displacement).
    n_bins : int, optional
        The number of bins (from the number of samples if None).

    Returns
    -------
    centres, ascending, descending : ndarray
        Bin centres (reference unit) and the branch means (output unit); NaN where a
        branch has no step in a bin.
    """
    ref, out = _pair(reference, output, 4)
    step = np.diff(ref)
    rising, falling = step > 0, step < 0
    if not rising.any() or not falling.any():
        raise InvalidSignalError(
            "'reference' must rise and fall (a loop) to measure hysteresis. "
            "Pass at least one whole period of a periodic reference."
        )
    if n_bins is None:
        n_bins = int(np.clip(min(rising.sum(), falling.sum()) // 10, 8, 200))
    n_bins = check_int(n_bins, "n_bins", "branch_means", minimum=1)
    lo, hi = float(ref.min()), float(ref.max())
    mid_ref = 0.5 * (ref[1:] + ref[:-1])
    mid_out = 0.5 * (out[1:] + out[:-1])
    index = np.minimum(((mid_ref - lo) / (hi - lo) * n_bins).astype(np.int64), n_bins - 1)
    means = []
    for branch in (rising, falling):
        count = np.bincount(index[branch], minlength=n_bins)
        total = np.bincount(index[branch], weights=mid_out[branch], minlength=n_bins)
        means.append(np.where(count > 0, total / np.maximum(count, 1), np.nan))
    centres = lo + (np.arange(n_bins) + 0.5) * (hi - lo) / n_bins
    return centres, means[0], means[1]


def hysteresis_percent(reference, output, *, n_bins=None) -> tuple[float, float]:
    """Hysteresis of a loop in % of the displacement range: whole loop and saturation zone.

    Parameters
    ----------
    reference : array_like
        The abscissa: the reference (compensated system) or the input (uncompensated).
    output : array_like
        The measured displacement, one sample per reference sample, in µm.
    n_bins : int, optional
        Bins of the abscissa (see :func:`branch_means`); by default about ten samples of
        each branch per bin, between 8 and 200 bins.

    Returns
    -------
    whole, saturation_zone : float
        ``100 * max |descending - ascending| / range`` over every bin, and over the bins
        whose mid-line ``(ascending + descending) / 2`` lies in the top quarter of the range
        (the range is ``max(output) - min(output)``). A clockwise loop counts as much as a
        counterclockwise one.

    Examples
    --------
    A parallelogram loop: the descending branch 0.1 above the ascending one, range 1.1.

    >>> u = np.linspace(0.0, 1.0, 401)
    >>> ref = np.concatenate([u, u[::-1]])
    >>> out = np.concatenate([u, u[::-1] + 0.1])
    >>> [round(p, 3) for p in hysteresis_percent(ref, out)]
    [9.091, 9.091]
    """
    ref, out = _pair(reference, output, 4)
    _, ascending, descending = branch_means(ref, out, n_bins=n_bins)
    both = np.isfinite(ascending) & np.isfinite(descending)
    span = float(np.ptp(out))
    if not both.any() or span == 0.0:
        raise InvalidSignalError(
            "'output' must move and be seen on both branches of the loop to measure "
            "hysteresis. Pass at least one whole period with a moving output."
        )
    width = np.abs(descending[both] - ascending[both])
    middle = 0.5 * (descending[both] + ascending[both])
    top = middle >= float(out.min()) + SATURATION_ZONE * span
    whole = 100.0 * float(width.max()) / span
    zone = 100.0 * float(width[top].max()) / span if top.any() else 0.0
    return whole, zone
