"""The identification input of a multi-axis stage (N axes, each sweeping its range).

Every axis sweeps its whole range with turning points at many levels, as
:func:`~hystcomp.identify.excitation.rich_sequence` does for one axis, while the others move
independently of it: each axis has turning points of its own (its own seed), its sweeps in
another order, and its own ramp rate. That independence is what makes the coupling
identifiable (:mod:`hystcomp.identify.coupling`): an axis's displacement must not be a
function of another's input.
"""

from __future__ import annotations

import numpy as np

from hystcomp import paper
from hystcomp._validation import check_int, check_range, check_real
from hystcomp.errors import InvalidParameterError
from hystcomp.identify.excitation import (
    DEFAULT_SAMPLE_RATE,
    _ramps_through,
    rich_turning_points,
)

#: Most axes :func:`multiaxis_sequence` makes an input for.
MAX_AXES = 16
#: Ramp rate of axis ``i`` over that of axis 0: ``1 / (1 + RATE_STEP * i)``.
RATE_STEP = 0.29


def _axis_points(i: int, lo: float, hi: float) -> np.ndarray:
    """Axis ``i``'s turning points: :func:`rich_turning_points` of seed ``i``, its sweeps
    rotated by ``i`` (so that no two axes sweep the same way at the same time)."""
    points = rich_turning_points(v_min=lo, v_max=hi, seed=i)
    body = points[1:]
    n_sweep = (body.size - 34) // 4  # four sweeps, then 32 random points and two ends
    blocks = [body[j * n_sweep : (j + 1) * n_sweep] for j in range(4)] + [body[4 * n_sweep :]]
    shift = i % len(blocks)
    return np.concatenate([[lo], *(blocks[shift:] + blocks[:shift])])


def multiaxis_sequence(
    n_axes: int,
    *,
    rate: float | None = None,
    sample_rate: float = DEFAULT_SAMPLE_RATE,
    voltage_range=paper.VOLTAGE_RANGE,
    frequency: float = 1.0,
) -> tuple[np.ndarray, np.ndarray]:
    """An input that identifies N coupled axes (module notes).

    Axis ``i`` ramps through :func:`rich_turning_points` of seed ``i``, its sweeps rotated by
    ``i``; a faster axis goes on through random turning points until the slowest ends.

    Parameters
    ----------
    n_axes : int
        N, 1 to :data:`MAX_AXES`.
    rate : float, optional
        Ramp rate of axis 0 in V/s [twice the span times ``frequency``: the slope of the
        1 Hz major triangle]; axis ``i`` ramps :data:`RATE_STEP` slower per index.
    sample_rate : float, default 20000
        Hz.
    voltage_range : (float, float), default (0, 120)
        Every axis's amplifier range, V.
    frequency : float, default 1
        Scales the rates.

    Returns
    -------
    t : ndarray, shape (n,)
        s.
    V : ndarray, shape (n, N)
        V, every axis starting and ending at the low end of its range.

    Examples
    --------
    >>> t, V = multiaxis_sequence(2, sample_rate=500.0)
    >>> V.shape[1], float(V.min()), float(V.max()), V[0].tolist(), V[-1].tolist()
    (2, 0.0, 120.0, [0.0, 0.0], [0.0, 0.0])
    """
    owner = "multiaxis_sequence"
    n_axes = check_int(n_axes, "n_axes", owner, minimum=1, maximum=MAX_AXES)
    lo, hi = check_range(voltage_range, "voltage_range", owner)
    sample_rate = check_real(sample_rate, "sample_rate", owner, positive=True)
    frequency = check_real(frequency, "frequency", owner, positive=True)
    base = 2.0 * (hi - lo) * frequency if rate is None else check_real(rate, "rate", owner)
    if not base > 0:
        raise InvalidParameterError(f"The 'rate' parameter of {owner} must be > 0. Got {rate!r}.")
    signals = []
    for i in range(n_axes):
        step = base / (1.0 + RATE_STEP * i) / sample_rate
        signals.append(_ramps_through(_axis_points(i, lo, hi), step))
    n = max(v.size for v in signals)
    rng = np.random.default_rng(1000 + n_axes)
    out = []
    for i, v in enumerate(signals):
        step = base / (1.0 + RATE_STEP * i) / sample_rate
        while v.size < n:  # a faster axis goes on through random turning points
            v = np.r_[v[:-1], _ramps_through(np.r_[v[-1], rng.uniform(lo, hi, 8), lo], step)]
        out.append(v[:n])
    tail = int(np.ceil((hi - lo) / (base / sample_rate)))  # then every axis back to lo
    V = np.column_stack(
        [np.r_[v, v[-1] + (lo - v[-1]) * np.arange(1, tail + 1) / tail] for v in out]
    )
    return np.arange(V.shape[0]) / sample_rate, V
