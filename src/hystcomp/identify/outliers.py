"""Isolated input samples far outside the rest of a record: found, named and refused.

A hysteresis model learns its voltage range from the record's input (``min v .. max v``),
and that range is the compensator's clamp, the Preisach plane and the end the start-up
transient waits for (:func:`~hystcomp.identify.scoring.transient_end`). One wrong sample
(a glitch of the recorder, a cell edited by hand, a unit typed into a column) would set
all three: a record of 0 .. 120 V with one sample at -30 V made a model whose compensator
commanded -25.9 V, and one at 1000 V a PI compensator that commanded 120.9 V.

:func:`isolated_samples` finds such samples: at most :data:`MAX_RUN` consecutive samples
beyond every other sample of the record by more than :data:`OUTLIER_GAP` of the others'
span, which the input jumps to and back from, by more than :data:`JUMP_FACTOR` times its
ordinary sample-to-sample change. A measured input reaches its extremes by moving there;
one that spikes out and back in a sample or three is not a voltage the stage followed.

They are refused (:func:`check_isolated`), not left out: hystcomp cannot tell a glitch of
the recording (the stage never saw the voltage) from a real spike (the stage's memory was
wiped by it, and a model fitted without it would be wrong from there on), and either way
the displacement in the same row is suspect. The message names the row and the value, so
that correcting or deleting it is one edit, and the model's range stays the one the
record really covers.
"""

from __future__ import annotations

import numpy as np

from hystcomp.errors import InvalidSignalError

#: Most consecutive samples that make one isolated excursion.
MAX_RUN = 3
#: An isolated sample lies beyond every other sample by more than this share of their span.
OUTLIER_GAP = 0.05
#: ... and the input jumps to it (and back) by more than this many times its ordinary step,
#: the 99th percentile of ``|v[k+1] - v[k]|``: a sparsely sampled triangle, whose turning
#: sample may stand out by a whole step, is not refused.
JUMP_FACTOR = 10.0
#: Candidates examined at each end of the range (more isolated samples than this at one
#: end are not isolated: the record goes there).
CANDIDATES = 32


def isolated_samples(v) -> np.ndarray:
    """Indices of the isolated samples of ``v`` far outside the rest (see the module).

    Parameters
    ----------
    v : array_like
        A finite 1-D input signal (V).

    Returns
    -------
    ndarray of int
        Sorted indices; empty when every sample belongs to the bulk of the record.

    Examples
    --------
    >>> v = np.r_[-30.0, np.linspace(0.0, 100.0, 1000)]
    >>> isolated_samples(v).tolist()
    [0]
    >>> isolated_samples(np.linspace(0.0, 100.0, 1000)).tolist()
    []
    """
    v = np.asarray(v, dtype=np.float64)
    n = v.size
    if n < 2 * CANDIDATES + 2:  # too short to tell the bulk from an excursion
        return np.empty(0, dtype=np.int64)
    k = CANDIDATES
    low = np.argpartition(v, k)[: k + 1]
    low = low[np.argsort(v[low], kind="stable")]  # ascending
    high = np.argpartition(v, n - k - 1)[n - k - 1 :]
    high = high[np.argsort(-v[high], kind="stable")]  # descending
    span = float(v[high[k]] - v[low[k]])  # of the bulk, whatever the candidates are
    if not span > 0:
        return np.empty(0, dtype=np.int64)
    out = [*_beyond_gap(v[low], low, span), *_beyond_gap(v[high], high, span)]
    if not out:
        return np.empty(0, dtype=np.int64)
    step = float(np.percentile(np.abs(np.diff(v)), 99.0))
    found = np.unique(np.array(out, dtype=np.int64))
    return _confirmed(v, found, step)


def _beyond_gap(values: np.ndarray, indices: np.ndarray, span: float) -> list[int]:
    """The candidates (outermost first) beyond the innermost gap wider than
    :data:`OUTLIER_GAP` of ``span``."""
    gaps = np.abs(np.diff(values))  # sorted from the outside in
    wide = np.flatnonzero(gaps > OUTLIER_GAP * span)
    if wide.size == 0:
        return []
    return indices[: int(wide[-1]) + 1].tolist()


def _confirmed(v: np.ndarray, found: np.ndarray, step: float) -> np.ndarray:
    """Those of ``found`` in runs of at most :data:`MAX_RUN` that the input jumps into and
    out of by more than :data:`JUMP_FACTOR` times ``step``."""
    outside = np.zeros(v.size, dtype=bool)
    outside[found] = True
    keep: list[int] = []
    runs = np.split(found, np.flatnonzero(np.diff(found) > 1) + 1)
    for run in runs:
        first, last = int(run[0]), int(run[-1])
        if last - first + 1 > MAX_RUN:
            continue
        jumps = []
        if first > 0:
            jumps.append(abs(v[first] - v[first - 1]))
        if last + 1 < v.size:
            jumps.append(abs(v[last] - v[last + 1]))
        if jumps and min(jumps) > JUMP_FACTOR * step:
            keep.extend(range(first, last + 1))
    return np.array(keep, dtype=np.int64)


def bulk_range(v) -> tuple[float, float]:
    """``(min, max)`` of ``v`` without its :func:`isolated_samples`.

    Parameters
    ----------
    v : array_like
        The record's input, V.

    Returns
    -------
    tuple of (float, float)
        The range without isolated samples, V.

    Examples
    --------
    >>> v = np.r_[np.linspace(0.0, 100.0, 1000), 1000.0]
    >>> bulk_range(v)
    (0.0, 100.0)
    """
    v = np.asarray(v, dtype=np.float64)
    bad = isolated_samples(v)
    if bad.size:
        v = np.delete(v, bad)
    return float(v.min()), float(v.max())


def check_isolated(v, owner: str | None, *, row=None, source: str | None = None) -> None:
    """Refuse an input with :func:`isolated_samples` (see the module for why refused).

    Parameters
    ----------
    v : array_like
        The input voltage (V).
    owner : str or None
        Who checks, for the message (e.g. ``"fit_pi"``); None names no function.
    row : callable, optional
        ``row(k)`` names sample ``k`` for the user, e.g. ``"data row 41 (t = 2 s)"``;
        by default ``"v[k]"``.
    source : str, optional
        The record's name (a file), for the message.

    Raises
    ------
    InvalidSignalError
        Naming the first isolated sample, its value, the others' range and the fix.

    Examples
    --------
    >>> check_isolated(np.r_[np.linspace(0.0, 100.0, 1000), 1000.0], "fit")
    Traceback (most recent call last):
    ...
    hystcomp.errors.InvalidSignalError: fit: the input 'v' has an isolated sample far outside the rest: v[1000] is 1000 V, while every other sample lies in 0 .. 100 V. ...
    """
    v = np.asarray(v, dtype=np.float64)
    bad = isolated_samples(v)
    if bad.size == 0:
        return
    rest = np.delete(v, bad)
    lo, hi = float(rest.min()), float(rest.max())
    k = int(bad[0])
    where = f"v[{k}]" if row is None else row(k)
    more = f" ({bad.size - 1} more such sample{'s' if bad.size > 2 else ''} after it)"
    raise InvalidSignalError(
        ("" if owner is None else f"{owner}: ")
        + "the input 'v'"
        + (f" of {source}" if source else "")
        + f" has an isolated sample far outside the rest: {where} is {v[k]:.6g} V, while "
        f"every other sample lies in {lo:.6g} .. {hi:.6g} V"
        + (more if bad.size > 1 else "")
        + ". A spike that the input jumps to and back from is a glitch or a typo, not a "
        "voltage the stage followed, and it would set the model's voltage range (the "
        "compensator's clamp). Correct or delete that sample and identify again."
    )
