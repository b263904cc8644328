"""Reference trajectories of the paper's tracking experiment (Section V, Figs. 9-10).

Triangles from 0 up to an amplitude and back, at 1, 10 and 50 Hz. The paper does not give
their amplitude; we take 90 % of the largest displacement measured in the identification
record (:data:`REFERENCE_FRACTION`): the top quarter of that range is the saturation zone
where the methods differ (Fig. 9), and the 10 % left above it keep every compensator away
from the amplifier's rail, so that a small model error is not turned into clipping.
"""

from __future__ import annotations

import numpy as np

from hystcomp import paper
from hystcomp._validation import check_int, check_real
from hystcomp.errors import InvalidParameterError
from hystcomp.identify.excitation import DEFAULT_SAMPLE_RATE, triangle_sequence

FREQUENCIES = paper.FREQUENCIES  # Hz, Table I
REFERENCE_FRACTION = 0.9  # of the stroke measured during identification


def triangle_reference(
    amplitude: float,
    frequency: float,
    *,
    periods: int = 3,
    sample_rate: float = DEFAULT_SAMPLE_RATE,
    offset: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """A triangle ``offset -> offset + amplitude -> offset`` repeated ``periods`` times.

    Parameters
    ----------
    amplitude : float
        Peak-to-peak displacement in µm (> 0).
    frequency : float
        In Hz; a period must hold at least 4 samples.
    periods : int, default 3
        Whole periods (the metrics leave the first one out, so at least 2).
    sample_rate : float, default 20000
        In Hz.
    offset : float, default 0
        The lowest reference, in µm.

    Returns
    -------
    t, x_ref : ndarray
        Time in s and reference in µm, ``periods * period_samples + 1`` samples (the last
        closes the final period).

    Examples
    --------
    >>> t, x = triangle_reference(10.0, 1000.0, periods=2, sample_rate=4000.0)
    >>> x.tolist()
    [0.0, 5.0, 10.0, 5.0, 0.0, 5.0, 10.0, 5.0, 0.0]
    """
    owner = "triangle_reference"
    amplitude = check_real(amplitude, "amplitude", owner, positive=True)
    frequency = check_real(frequency, "frequency", owner, positive=True)
    sample_rate = check_real(sample_rate, "sample_rate", owner, positive=True)
    periods = check_int(periods, "periods", owner, minimum=2)
    offset = check_real(offset, "offset", owner)
    if period_samples(frequency, sample_rate) < 4:
        raise InvalidParameterError(
            f"The 'frequency' parameter of {owner} must leave at least 4 samples per period. "
            f"Got {frequency:g} Hz at {sample_rate:g} Hz; lower it or raise the sample rate."
        )
    return triangle_sequence(
        [amplitude] * periods, frequency=frequency, sample_rate=sample_rate, v_min=offset
    )


def period_samples(frequency: float, sample_rate: float = DEFAULT_SAMPLE_RATE) -> int:
    """Samples in one period of a reference at ``frequency`` (as the excitation rounds it).

    Parameters
    ----------
    frequency : float
        The reference's frequency, Hz.
    sample_rate : float, optional
        Samples per second, Hz.

    Returns
    -------
    int
        Samples per period.
    """
    return round(sample_rate / frequency)
