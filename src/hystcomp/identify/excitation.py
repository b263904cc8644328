"""The paper's identification signals (Section III-A for Preisach, Section IV-A for PI/MPI),
and two that are not in the paper, for fits that take any record: ramps between random
turning points (:func:`random_turning_points`) and the same after decaying loops from each
end of the range (:func:`rich_sequence`, ``hystcomp excite rich``).

All signals start at the lower end of the voltage range, with the piezo at rest there.
"""

from __future__ import annotations

import itertools

import numpy as np

from hystcomp import paper
from hystcomp._validation import MAX_SIGNAL_SAMPLES, as_vector, check_range, check_real
from hystcomp.errors import InvalidParameterError

DEFAULT_SAMPLE_RATE = paper.SAMPLE_RATE  # Hz, the paper's rig (Section II)
PI_AMPLITUDES = paper.PI_AMPLITUDES  # V, Section IV-A (ii)
PREISACH_AMPLITUDES = paper.PREISACH_AMPLITUDES  # V, Section III-A (i)
MIN_SAMPLES_PER_PERIOD = 4  # fewer cannot draw a triangle or a sinusoid


def _periods(owner, shape, amplitudes, sample_rate, frequency, v_min):
    """``(t, v)``: one period of ``v_min + A * shape(phase)`` per amplitude ``A``, then
    ``v_min`` (``shape`` maps the phase of a period, in [0, 1), to 0 .. 1 and back to 0),
    after checking the arguments of ``owner``."""
    amplitudes = as_vector(amplitudes, "amplitudes", owner)
    if np.any(amplitudes < 0):
        raise InvalidParameterError(
            f"The 'amplitudes' parameter of {owner} must hold amplitudes >= 0 V (each period "
            f"rises from v_min by its amplitude). Got {amplitudes.min()!r}."
        )
    v_min = check_real(v_min, "v_min", owner)
    sample_rate = check_real(sample_rate, "sample_rate", owner, positive=True)
    frequency = check_real(frequency, "frequency", owner, positive=True)
    if sample_rate / frequency > MAX_SIGNAL_SAMPLES:
        raise InvalidParameterError(
            f"{owner}: one period at {frequency:g} Hz is {sample_rate / frequency:.3g} samples "
            f"at {sample_rate:g} Hz, more than {MAX_SIGNAL_SAMPLES:.0e}. Raise the frequency or "
            "lower the sample rate."
        )
    n = round(sample_rate / frequency)
    if n < MIN_SAMPLES_PER_PERIOD:
        raise InvalidParameterError(
            f"{owner}: a sample rate of {sample_rate:g} Hz gives {n} samples per period at "
            f"{frequency:g} Hz; at least {MIN_SAMPLES_PER_PERIOD} are needed. Raise the sample "
            "rate or lower the frequency."
        )
    if n * amplitudes.size + 1 > MAX_SIGNAL_SAMPLES:
        raise InvalidParameterError(
            f"{owner}: {amplitudes.size} periods of {n} samples ({sample_rate:g} Hz at "
            f"{frequency:g} Hz) make {n * amplitudes.size + 1} samples, more than "
            f"{MAX_SIGNAL_SAMPLES:.0e}. Lower the sample rate or raise the frequency."
        )
    unit = shape(np.arange(n) / n)
    v = np.concatenate([a * unit for a in amplitudes] + [np.zeros(1)]) + v_min
    return np.arange(v.size) / sample_rate, v


def triangle_sequence(
    amplitudes=PI_AMPLITUDES,
    *,
    frequency: float = 1.0,
    sample_rate: float = DEFAULT_SAMPLE_RATE,
    v_min: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Triangles ``v_min -> v_min + A -> v_min``, one period per amplitude, then ``v_min``.

    With the defaults this is the PI/MPI identification signal of Section IV-A (ii):
    triangles of 30, 60, 90 and 120 V at 1 Hz, 80,001 samples at 20 kHz.

    Parameters
    ----------
    amplitudes : sequence of float, optional
        The triangles' heights above ``v_min``, V.
    frequency : float, optional
        Periods per second, Hz.
    sample_rate : float, optional
        Samples per second, Hz.
    v_min : float, optional
        The level each triangle starts and ends at, V.

    Returns
    -------
    t, v : ndarray
        Time in s (from 0) and voltage in V.

    Examples
    --------
    >>> t, v = triangle_sequence([10.0, 20.0], sample_rate=4.0)
    >>> v.tolist()
    [0.0, 5.0, 10.0, 5.0, 0.0, 10.0, 20.0, 10.0, 0.0]
    """
    return _periods(
        "triangle_sequence",
        lambda phase: 1.0 - np.abs(1.0 - 2.0 * phase),  # 0 -> 1 -> 0
        amplitudes, sample_rate, frequency, v_min,
    )  # fmt: skip


def sinusoid_sequence(
    amplitudes=PREISACH_AMPLITUDES,
    *,
    frequency: float = 1.0,
    sample_rate: float = DEFAULT_SAMPLE_RATE,
    v_min: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Sinusoids ``v_min + A (1 - cos 2 pi f t) / 2``, one period per amplitude, then ``v_min``.

    With the defaults this is the Preisach identification signal of Section III-A (i):
    1 Hz sinusoids of amplitude 5, 10, ..., 120 V, each starting from ``v_min``, so that each
    descent from ``v_min + A`` traces a first-order descending curve.

    Parameters
    ----------
    amplitudes : sequence of float, optional
        The sinusoids' peak-to-peak amplitudes above ``v_min``, V.
    frequency : float, optional
        Hz.
    sample_rate : float, optional
        Samples per second, Hz.
    v_min : float, optional
        The level each sinusoid starts and ends at, V.

    Returns
    -------
    t, v : ndarray
        Time in s and voltage in V.
    """
    return _periods(
        "sinusoid_sequence",
        lambda phase: 0.5 * (1.0 - np.cos(2.0 * np.pi * phase)),
        amplitudes, sample_rate, frequency, v_min,
    )  # fmt: skip


def scaled_amplitudes(
    amplitudes, paper_range=paper.VOLTAGE_RANGE, voltage_range=paper.VOLTAGE_RANGE
):
    """The paper's amplitudes rescaled from 0..120 V to another ``voltage_range``.

    Parameters
    ----------
    amplitudes : sequence of float
        The paper's amplitudes, V on 0..120 V.
    paper_range : tuple of (float, float), optional
        The range they are given for, V.
    voltage_range : tuple of (float, float), optional
        The amplifier's range they are wanted for, V.

    Returns
    -------
    tuple of float
        The amplitudes for ``voltage_range``, V.
    """
    lo, hi = check_range(voltage_range, "voltage_range", "scaled_amplitudes")
    paper_range = check_range(paper_range, "paper_range", "scaled_amplitudes")
    amplitudes = as_vector(amplitudes, "amplitudes", "scaled_amplitudes")
    scale = (hi - lo) / (paper_range[1] - paper_range[0])
    return tuple(float(a) * scale for a in amplitudes)


def random_turning_points(
    n_turns: int = 60,
    *,
    seed: int = 0,
    rate: float = 240.0,
    sample_rate: float = DEFAULT_SAMPLE_RATE,
    voltage_range=paper.VOLTAGE_RANGE,
) -> tuple[np.ndarray, np.ndarray]:
    """A random voltage: ramps at ``rate`` between random turning points.

    Not one of the paper's signals: a record with nested minor loops of every size, such as
    an actuator meets in use, from which all three models can be identified (PI/MPI by
    eqs. 16-19, Preisach by least squares, :mod:`hystcomp.identify.preisach_lsq`). The
    turning points are ``v_max``, ``v_min`` (a major loop, so the record covers the whole
    range at once), then uniform over ``voltage_range`` (:func:`uniform_turning_points`, which
    :func:`rich_sequence` ends with too); the signal starts and ends at ``v_min``. Ramps run
    at ``rate`` V/s (240 V/s: the slope of the paper's 120 V triangle at 1 Hz), as in
    :func:`rich_sequence`.

    Ramps rather than half-cosine sweeps of random duration: a PI model fitted to ramps
    tracks better, MPI and Preisach models alike (Benchmarks, "Excitation signals").

    Parameters
    ----------
    n_turns : int, default 60
        Turning points after the start (>= 8); the default makes a record of about 10 s.
    seed : int, default 0
        Seed of the random generator (the signal is reproducible from it).
    rate : float, default 240
        Ramp slope in V/s.
    sample_rate : float, default 20000
        In Hz.
    voltage_range : (float, float), default (0, 120)
        In V.

    Returns
    -------
    t, v : ndarray
        Time in s and voltage in V.

    Examples
    --------
    >>> t, v = random_turning_points(8, sample_rate=100.0)
    >>> float(v.min()), float(v.max()), float(v[0]), float(v[-1])
    (0.0, 120.0, 0.0, 0.0)
    """
    owner = "random_turning_points"
    if not isinstance(n_turns, int | np.integer) or isinstance(n_turns, bool) or n_turns < 8:
        raise InvalidParameterError(
            f"The 'n_turns' parameter of {owner} must be an int >= 8. Got {n_turns!r} instead."
        )
    if not isinstance(seed, int | np.integer) or isinstance(seed, bool) or seed < 0:
        raise InvalidParameterError(
            f"The 'seed' parameter of {owner} must be an int >= 0. Got {seed!r} instead."
        )
    lo, hi = check_range(voltage_range, "voltage_range", owner)
    rng = np.random.default_rng(seed)
    points = np.r_[lo, hi, lo, _uniform_points(rng, lo, hi, n_turns - 3), lo]
    return _ramps(points, rate, sample_rate, owner)


def _uniform_points(rng, v_min: float, v_max: float, n: int) -> np.ndarray:
    """``n`` turning points uniform in ``v_min .. v_max`` (V): the random part of both
    :func:`random_turning_points` and :func:`rich_sequence`."""
    return rng.uniform(v_min, v_max, n)


def _ramps(points, rate, sample_rate, owner) -> tuple[np.ndarray, np.ndarray]:
    """``(t, v)``: ramps at ``rate`` V/s through ``points``, sampled at ``sample_rate``."""
    rate = check_real(rate, "rate", owner, positive=True)
    sample_rate = check_real(sample_rate, "sample_rate", owner, positive=True)
    step = rate / sample_rate
    if float(np.sum(np.abs(np.diff(points)))) / step > MAX_SIGNAL_SAMPLES:
        raise InvalidParameterError(
            f"{owner}: a rate of {rate:g} V/s at {sample_rate:g} Hz makes more than "
            f"{MAX_SIGNAL_SAMPLES:.0e} samples. Raise the rate or lower the sample rate."
        )
    v = _ramps_through(points, step)
    return np.arange(v.size) / sample_rate, v


def _ramps_through(points, step: float) -> np.ndarray:
    """Straight ramps of at most ``step`` V per sample through ``points`` (V), ending on the
    last point: each ramp takes the fewest samples that keep its steps within ``step``.

    Examples
    --------
    >>> _ramps_through(np.array([0.0, 2.0, 1.0]), 1.0).tolist()
    [0.0, 1.0, 2.0, 1.0]
    """
    pieces = []
    for lo, hi in itertools.pairwise(points):
        n = max(1, int(np.ceil(abs(hi - lo) / step)))
        pieces.append(lo + (hi - lo) * np.arange(n) / n)
    return np.r_[np.concatenate(pieces), points[-1]]


def rich_turning_points(
    *, v_min: float = 0.0, v_max: float = paper.VOLTAGE_RANGE[1], seed: int = 0
) -> np.ndarray:
    """Turning points of :func:`rich_sequence`: decaying oscillations from both ends, then random.

    Four sweeps, each from an end of the range: ``v_max`` then down-up oscillations whose
    amplitude decays from the span to 3 % of it (nested minor loops near the top, each
    descent a reversal curve from a new level); the same from ``v_min`` upwards; then twice
    16 turning points drawn uniformly in the range. It ends at ``v_min``.

    Parameters
    ----------
    v_min : float, optional
        The lower end of the range, V.
    v_max : float, optional
        The upper end of the range, V.
    seed : int, optional
        The seed of the random turning points.

    Returns
    -------
    numpy.ndarray
        The turning points, V, from ``v_min`` back to ``v_min``.

    Examples
    --------
    >>> p = rich_turning_points()
    >>> float(p[0]), float(p[-1]), float(p.min()), float(p.max())
    (0.0, 0.0, 0.0, 120.0)
    """
    rng = np.random.default_rng(seed)
    span = v_max - v_min
    points = [v_min]
    decay = span * np.geomspace(1.0, 0.03, 12)
    for from_top in (True, False, True, False):
        end = v_max if from_top else v_min
        points.append(end)
        sign = -1.0 if from_top else 1.0
        level = end
        for amplitude in decay * rng.uniform(0.7, 1.0, decay.size):
            level = float(np.clip(level + sign * amplitude, v_min, v_max))
            points.append(level)
            sign = -sign
    points += [*list(_uniform_points(rng, v_min, v_max, 32)), v_max, v_min]
    return np.asarray(points, dtype=np.float64)


def rich_sequence(
    *,
    rate: float = 240.0,
    sample_rate: float = DEFAULT_SAMPLE_RATE,
    v_min: float = 0.0,
    v_max: float = paper.VOLTAGE_RANGE[1],
    seed: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """An identification signal for all three models: ramps between :func:`rich_turning_points`.

    Not in the paper. The paper's triangles (Section IV-A) visit only four reversal levels
    and its sinusoids (Section III-A) only descents from rest; this signal reverses at many
    levels in both directions (decaying loops from each end, then random turning points), so
    a model fitted to it has seen the minor loops a tracking reference produces. Ramps run at
    ``rate`` V/s (240 V/s: the slope of the paper's 120 V triangle at 1 Hz).

    Parameters
    ----------
    rate : float, optional
        The ramps' slope, V/s.
    sample_rate : float, optional
        Samples per second, Hz.
    v_min, v_max : float, optional
        The voltage range the ramps span, V.
    seed : int, optional
        Passed to :func:`rich_turning_points`, which draws the last 32 turns from it.

    Returns
    -------
    t, v : ndarray
        Time in s and voltage in V, starting and ending at ``v_min``.

    Examples
    --------
    >>> t, v = rich_sequence(sample_rate=1000.0)
    >>> float(v[0]), float(v[-1]), float(v.max())
    (0.0, 0.0, 120.0)
    """
    owner = "rich_sequence"
    v_min, v_max = check_range((v_min, v_max), "voltage range (v_min, v_max)", owner)
    points = rich_turning_points(v_min=v_min, v_max=v_max, seed=seed)
    return _ramps(points, rate, sample_rate, owner)


#: The kinds :func:`excitation_signal` knows.
SIGNAL_KINDS = ("mpi", "pi", "preisach", "rich", "dynamics")


def excitation_signal(
    kind: str,
    *,
    sample_rate: float = DEFAULT_SAMPLE_RATE,
    voltage_range=paper.VOLTAGE_RANGE,
    frequency: float = 1.0,
) -> tuple[np.ndarray, np.ndarray]:
    """The identification input for a model kind, as ``hystcomp excite`` writes it.

    Parameters
    ----------
    kind : {'pi', 'mpi', 'preisach', 'rich', 'dynamics'}
        ``'pi'``, ``'mpi'``: :func:`triangle_sequence` of :data:`PI_AMPLITUDES`
        (Section IV-A); ``'preisach'``: :func:`sinusoid_sequence` of
        :data:`PREISACH_AMPLITUDES` (Section III-A), both scaled from 0..120 V to
        ``voltage_range`` (:func:`scaled_amplitudes`); ``'rich'`` (not in the paper):
        :func:`rich_sequence` at the slope of the major triangle; ``'dynamics'`` (beyond the
        paper): :func:`hystcomp.identify.dynamics.dynamics_excitation`.
    sample_rate : float, optional
        Samples per second (Hz).
    voltage_range : (float, float), optional
        Amplifier range in V.
    frequency : float, optional
        Period rate in Hz (the rich signal's slope scales with it; unused by ``'dynamics'``).

    Returns
    -------
    t, v : ndarray
        Time in s and voltage in V.

    Examples
    --------
    >>> t, v = excitation_signal("pi", sample_rate=100.0)
    >>> t.size, float(v.max())
    (401, 120.0)
    """
    lo, hi = check_range(voltage_range, "voltage_range", "excitation_signal")
    if kind == "dynamics":
        from hystcomp.identify.dynamics import dynamics_excitation

        return dynamics_excitation(sample_rate=sample_rate, voltage_range=(lo, hi))
    if kind == "rich":
        return rich_sequence(
            rate=2.0 * (hi - lo) * frequency, sample_rate=sample_rate, v_min=lo, v_max=hi
        )
    amplitudes: tuple[float, ...]
    if kind in ("pi", "mpi"):
        shape, amplitudes = triangle_sequence, PI_AMPLITUDES
    elif kind == "preisach":
        shape, amplitudes = sinusoid_sequence, PREISACH_AMPLITUDES
    else:
        raise InvalidParameterError(
            f"The 'kind' argument of excitation_signal must be one of {', '.join(SIGNAL_KINDS)}; "
            f"got {kind!r}."
        )
    return shape(
        scaled_amplitudes(amplitudes, voltage_range=(lo, hi)),
        frequency=frequency,
        sample_rate=sample_rate,
        v_min=lo,
    )
