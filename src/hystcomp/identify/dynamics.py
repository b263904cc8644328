"""Identification of the linear dynamics (creep, one or two resonances) of a hysteretic stage.

The stage is a Hammerstein system, ``x = D[H[v]]``: a rate-independent hysteresis ``H``
followed by linear dynamics ``D`` (Croft, Shed and Devasia 2001; the paper's Fig. 2 puts
the piezo dynamics after the hysteresis). ``D`` is identified *behind* ``H``: the input of
the fit is ``u = H[v]``, the output of a hysteresis model, not the voltage (the workflow
:mod:`hystcomp.workflows.pair` alternates this fit with the fit of ``H`` in front of ``D``).

The record is the stage's answer to :func:`dynamics_excitation` (``hystcomp excite
dynamics``), at the amplitudes tracking uses::

    rest at v_min (REST s) | step to mid-range, held HOLD s | multisine around mid-range,
    PERIODS x 1 s, peak AMPLITUDE_FRACTION of the range | triangles over 5-90 % of the
    range at 1, 10, 100 and 200 Hz (each reached by a ramp at its own slope)

Why large signal: the minor loops of a small multisine around one operating point have the
gain and phase of the hysteresis, not of the dynamics (on a Preisach stage with narrow
minor loops, a +-4 V multisine let a one-mode model explain 24 % of the frequency
response). Driven over most of the range, the stage's hysteresis is what its hysteresis
model describes, and ``X / H[V]`` is ``D``. The triangles are held out of every fit: the
workflow estimates on them how well the compensators track at those rates.

The fit, in five short stages:

1. The frequency response ``X(f) / U(f)`` at the multisine's lines, from the average of
   its periods after the first (``u`` is periodic with ``v`` after one period, as a
   rate-independent ``H[v]`` is); the resonance of :class:`~hystcomp.LinearDynamics`
   fitted to the lines above 20 Hz by nonlinear least squares
   (``scipy.optimize.least_squares``), with a free complex factor that takes up what is
   left of the hysteresis's gain and phase (with ``u = v``, all of it).
2. The creep from the step and hold: with the resonance known, the step response is linear
   in the weights of creep modes with time constants fixed on a log grid (two per decade
   from 1 ms to the hold's length); non-negative least squares (``scipy.optimize.nnls``).
3. The multisine part again, with the step's continuing creep removed, and the resonance
   fitted again with the creep in the model.
4. A second mode, above the first and within the multisine's band, in parallel with it,
   the latency freed again with the two (:mod:`hystcomp.identify.modes`): kept when it
   explains the lines clearly better (:func:`~hystcomp.identify.modes.keeps_second_mode`;
   its residual at most a quarter of one mode's), and then the creep fitted again with
   both. The latency is then the two modes' fit's: a second mode's phase, which one mode
   cannot follow, is not taken for latency.
5. The fit report: fit % and largest magnitude error in the frequency domain up to twice
   the highest mode, rms error of the step response, the number of modes (``modes``) and
   the ratio that decided it (``residual_ratio``), and the measured frequency response
   (for the Bode figure).

Only the *shape* of the dynamics is identified: the model is normalised to unit
steady-state gain (the end of the hold; modes slower than the hold show as a part of the
slowest mode), and the hysteresis model holds the static map. Deviation from the usual
subspace or ARX fits (e.g. ``nfoursid``): a physical structure with few parameters keeps
the inverse stable by construction and costs no extra dependency.

Records of the former layout (a +-1/30 range multisine to the end, no triangles) are still
read.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from hystcomp import paper
from hystcomp._lti import (
    creep_fraction,
    creep_response,
    frequency_response,
    lag,
    modal,
    output,
    resonance_response,
    resonance_zoh,
)
from hystcomp._notice import Notice
from hystcomp._validation import MAX_SIGNAL_SAMPLES, as_signal_pair, check_real
from hystcomp.errors import IdentificationError, InvalidParameterError
from hystcomp.identify.modes import fit_modes, keeps_second_mode


class DynamicsFit(NamedTuple):
    """What :func:`fit_dynamics` found: the model's parameters and the fit report."""

    parameters: dict
    report: dict


#: Layout of the excitation (s, V, Hz).
REST = 0.2
HOLD = 3.0
PERIOD = 1.0
PERIODS = 3
BIAS_FRACTION = 0.5
#: The multisine's peak, as a fraction of the voltage range's span: 30 V on 0..120 V, so
#: that it sweeps 25-75 % of the range, and its lines near a resonance (of zeta 0.02 and
#: up) drive the stage within its stroke. Lines of equal amplitude: a spectrum falling
#: with frequency, as a reference's harmonics do, left the lines near a resonance to the
#: hysteresis model's error, which is broadband (a one-mode fit explained 51 % of a
#: Preisach stage's response with lines falling as 1 / f above 100 Hz, 98 % flat).
AMPLITUDE_FRACTION = 0.25
F_MIN, F_MAX = 1.0, 5000.0
N_LINES = 120
#: The held-out triangles: (frequency in Hz, periods), over TRIANGLE_SPAN of the range.
TRIANGLES = ((1.0, 2), (10.0, 4), (100.0, 20), (200.0, 20))
TRIANGLE_SPAN = (0.05, 0.90)
#: Lines used to fit the resonance, Hz (from), and how far the step's start is skipped for creep.
FIT_FROM_HZ = 20.0
#: Time constants of the resonance's decay left out at the start of the step for the creep.
RINGING_DECAYS = 4.0
#: A creep mode settled beyond this share of its step where the fit's samples start is
#: left out of the fit (its share goes to the direct term).
SETTLED = 0.1
#: Samples of the step response (log-spaced in time) on which the creep is fitted.
CREEP_SAMPLES = 2000
#: Largest damping ratio the fit considers: a resonance damped beyond it is not one.
MAX_DAMPING = 2.0
#: Latencies (whole samples beyond the sample-and-hold's one) that the fit tries and a
#: model may have: the inverse looks that far ahead, on top of the FIR's own look-ahead.
DELAY_RANGE = (-1, 32)


class Triangle(NamedTuple):
    """A held-out triangle of the record: ``frequency`` (Hz), samples ``start .. stop``
    (the first period included) and the samples of one ``period``."""

    frequency: float
    start: int
    stop: int
    period: int


class Layout(NamedTuple):
    """Where the parts of a dynamics record lie (sample indices)."""

    step: int
    multisine: int
    periods: int
    n_period: int
    triangles: tuple[Triangle, ...]


def dynamics_excitation(
    *,
    sample_rate: float = paper.SAMPLE_RATE,
    voltage_range: tuple[float, float] = paper.VOLTAGE_RANGE,
    amplitude: float | None = None,
    seed: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """``(t, v)`` of the identification signal of the linear dynamics (see the module).

    A rest at the low end of ``voltage_range`` (:data:`REST` s), a step to the middle of
    the range held :data:`HOLD` s (creep), :data:`PERIODS` periods of a 1 s multisine of
    ``amplitude`` V peak around the middle (by default :data:`AMPLITUDE_FRACTION` of the
    range's span: 30 V on 0..120 V, 0.9 V on 0..3.6 V): :data:`N_LINES` log-spaced
    frequencies from 1 Hz to 5 kHz (at most 0.4 ``sample_rate``) rounded to whole Hz, the
    duplicates dropped (96 lines at 20 kHz), Schroeder phases for a low crest factor; then the triangles of :data:`TRIANGLES` over
    :data:`TRIANGLE_SPAN` of the range (those with fewer than 20 samples a period left
    out), each reached by a ramp at its own slope. 9.2 s in all.

    Parameters
    ----------
    sample_rate : float, optional
        Samples per second, Hz.
    voltage_range : tuple of (float, float), optional
        The amplifier's range, V.
    amplitude : float, optional
        The multisine's peak amplitude, V (a share of the range's span if None).
    seed : int, optional
        Not used by the signal, which is deterministic; kept for a uniform signature with the other
        excitations.

    Returns
    -------
    t : numpy.ndarray
        Time, s, from 0.
    v : numpy.ndarray
        Voltage, V.

    Examples
    --------
    >>> t, v = dynamics_excitation()
    >>> t.size, float(v.min()), float(v[round(1.0 * 20_000)])   # rest, then the step to 60 V
    (183298, 0.0, 60.0)
    >>> ms = v[round(3.2 * 20_000):round(6.2 * 20_000)]          # the multisine, +-30 V
    >>> round(float(np.abs(ms - 60.0).max()), 9)
    30.0
    >>> round(float(v[round(6.5 * 20_000):].min()), 9), round(float(v.max()), 9)  # 5-90 %
    (6.0, 108.0)
    """
    owner = "dynamics_excitation"
    fs = check_real(sample_rate, "sample_rate", owner, positive=True)
    lo, hi = voltage_range
    if amplitude is None:
        amplitude = AMPLITUDE_FRACTION * (hi - lo)
    amplitude = check_real(amplitude, "amplitude", owner, positive=True)
    if amplitude > (1.0 - BIAS_FRACTION) * (hi - lo):
        raise InvalidParameterError(
            f"The 'amplitude' parameter of {owner} must keep the multisine inside the voltage "
            f"range {lo:g} .. {hi:g} V (at most {(1.0 - BIAS_FRACTION) * (hi - lo):g} V about "
            f"its middle). Got {amplitude:g} V; use a smaller amplitude, or leave it out for "
            f"{AMPLITUDE_FRACTION:.3g} of the range."
        )
    seconds = _duration(fs, lo, hi, amplitude)
    if seconds * fs > MAX_SIGNAL_SAMPLES:
        raise InvalidParameterError(
            f"The 'sample_rate' parameter of {owner} makes the {seconds:.3g} s signal "
            f"{seconds * fs:.3g} samples long, more than {MAX_SIGNAL_SAMPLES:.0e}. Got {fs:g} Hz; "
            f"use at most {MAX_SIGNAL_SAMPLES / seconds:g} Hz."
        )
    v = np.concatenate([part for _, part in _parts(fs, lo, hi, amplitude)])
    return np.arange(v.size) / fs, v


def _duration(fs: float, lo: float, hi: float, amplitude: float) -> float:
    """Seconds of :func:`dynamics_excitation`, from its layout alone (cheap)."""
    seconds = REST + HOLD + PERIODS * PERIOD
    a, b = lo + TRIANGLE_SPAN[0] * (hi - lo), lo + TRIANGLE_SPAN[1] * (hi - lo)
    level = lo + BIAS_FRACTION * (hi - lo)
    for f, periods in _triangles(fs):
        seconds += abs(level - a) / (2.0 * (b - a) * f) + periods / f
        level = a
    return seconds


def _triangles(fs: float) -> list[tuple[float, int]]:
    """The triangles of :data:`TRIANGLES` that the sample rate draws (20 samples a period)."""
    return [(f, n) for f, n in TRIANGLES if fs / f >= 20.0]


def _parts(fs: float, lo: float, hi: float, amplitude: float) -> list[tuple[str, np.ndarray]]:
    """The excitation's parts, labelled: ``rest``, ``hold``, ``multisine``, and for each
    triangle ``ramp`` then ``triangle <f>``."""
    n_period = round(PERIOD * fs)
    lines = multisine_lines(fs)
    phases = -np.pi * np.arange(lines.size) * (np.arange(lines.size) + 1) / lines.size
    spectrum = np.zeros(n_period // 2 + 1, dtype=complex)  # one period is PERIOD s
    spectrum[np.round(lines * PERIOD).astype(int)] = np.exp(1j * phases)
    period = np.fft.irfft(spectrum, n_period)
    period *= amplitude / np.abs(period).max()
    bias = lo + BIAS_FRACTION * (hi - lo)
    parts = [
        ("rest", np.full(round(REST * fs), float(lo))),
        ("hold", np.full(round(HOLD * fs), bias)),
        ("multisine", bias + np.tile(period, PERIODS)),
    ]
    a, b = lo + TRIANGLE_SPAN[0] * (hi - lo), lo + TRIANGLE_SPAN[1] * (hi - lo)
    level = bias
    for f, periods in _triangles(fs):
        n = round(fs / f)
        slope = 2.0 * (b - a) / n  # V a sample
        ramp = max(1, math.ceil(abs(level - a) / slope))
        parts.append(("ramp", np.linspace(level, a, ramp + 1)[1:]))
        phase = np.arange(n * periods) % n / n
        parts.append((f"triangle {f:g}", a + (b - a) * (1.0 - np.abs(1.0 - 2.0 * phase))))
        level = a
    return parts


def multisine_lines(sample_rate: float) -> np.ndarray:
    """The multisine's lines in Hz (integers: one period is 1 s).

    Parameters
    ----------
    sample_rate : float
        The record's sample rate, Hz (lines stop at 0.4 of it).

    Returns
    -------
    numpy.ndarray
        The frequencies, Hz, whole numbers, rising.
    """
    top = min(F_MAX, 0.4 * sample_rate)
    return np.unique(np.round(np.geomspace(F_MIN, top, N_LINES)))


def creep_grid(hold: float) -> np.ndarray:
    """Creep time constants (s): two per decade from 1 ms to the hold's length.

    Parameters
    ----------
    hold : float
        The length of the record's hold, s.

    Returns
    -------
    numpy.ndarray
        The candidate time constants, s, rising.
    """
    decades = math.log10(hold / 1e-3)
    return np.geomspace(1e-3, hold, max(2, round(2 * decades) + 1))


def fit_dynamics(v, x, sample_rate: float, *, u=None) -> DynamicsFit:
    """Identify the linear dynamics from the answer ``x`` (µm) to :func:`dynamics_excitation`.

    :meth:`hystcomp.LinearDynamics.fit` delegates here.

    Parameters
    ----------
    v, x : array_like
        The record: command (V) and displacement (µm), one sample each per ``1/sample_rate``.
    sample_rate : float
        Hz.
    u : array_like, optional
        The input of ``D``: a hysteresis model's output ``H[v]`` (µm), for a fit behind
        ``H`` (see the module). By default ``v`` itself, whose local gain and phase the fit
        then takes as the hysteresis's, as a small-signal record has them.

    Returns
    -------
    DynamicsFit
        The parameters of :meth:`~hystcomp.LinearDynamics.from_parameters` and the fit
        report (see the module's notes).

    Raises
    ------
    IdentificationError
        If the record does not have the layout of :func:`dynamics_excitation`.
    """
    owner = "fit_dynamics"
    fs = check_real(sample_rate, "sample_rate", owner, positive=True)
    v, x = as_signal_pair(v, x, ("v", "x"), owner)  # too short: the layout says what to record
    u = v if u is None else as_signal_pair(v, u, ("v", "u"), owner)[1]
    layout = record_layout(v, fs)
    step, multisine, n_period, periods = (
        layout.step,
        layout.multisine,
        layout.n_period,
        layout.periods,
    )
    if np.ptp(x[step:]) <= 1e-9 * max(1.0, float(np.max(np.abs(x)))):
        raise IdentificationError(
            f"The displacement 'x' does not move after the step of the dynamics excitation "
            f"(constant at {x[step]:.6g} µm): nothing to identify. Check that the column "
            "is the displacement sensor's and that the actuator was driven."
        )
    hold = (multisine - step) / fs
    lines = multisine_lines(fs)
    bins = np.round(lines * n_period / fs).astype(int)

    taus = creep_grid(hold)
    lags = np.exp(-1.0 / (fs * taus))
    x0 = float(np.mean(x[max(0, step - round(0.1 * fs)) : step]))
    # the rig's latency first: the lines, each advanced by d samples, fit best at the right d
    measured = _frf(u, x, multisine, n_period, periods, bins)
    tau, (fn, zeta) = _fit_delay(measured, lines, fs)
    delay = int(np.clip(round(tau), *DELAY_RANGE))  # the model's, in whole samples
    advance = np.exp(2j * np.pi * lines * tau / fs)  # the fit's: the fraction too
    rise = x[step + delay : multisine] - x0  # the answer to the step, from its own start
    weights, step_fit = _fit_creep(rise, ((fn, zeta, 1.0),), fs, lags)
    # the step's creep goes on through the multisine: take it out and fit again
    ramp = np.r_[np.zeros(step), np.ones(v.size - step)]
    drift = step_fit * output(ramp, 0.0, fs, ((fn, zeta, 1.0),), lags, weights, delay)
    clean = _frf(u, x - drift, multisine, n_period, periods, bins)  # its latency in
    measured = clean * advance
    fn, zeta, _ = _fit_resonance(measured, lines, fs, lags, weights, guess=(fn, zeta))
    modes: tuple[tuple[float, float, float], ...] = ((fn, zeta, 1.0),)
    # a second mode, kept where it explains the lines clearly better; its latency then
    use = lines >= FIT_FROM_HZ
    creep = creep_response(lags, weights, np.exp(-2j * np.pi * lines[use] / fs))
    one, two = fit_modes(
        lines[use],
        clean[use],
        fs,
        creep,
        (fn, zeta),
        tau,
        delay_range=DELAY_RANGE,
        max_damping=MAX_DAMPING,
    )
    if keeps_second_mode(one, two, float(lines.max())):
        modes, tau = two.modes, two.tau
        delay = int(np.clip(round(tau), *DELAY_RANGE))
        advance = np.exp(2j * np.pi * lines * tau / fs)
        rise = x[step + delay : multisine] - x0
        measured = clean * advance
    weights, step_fit = _fit_creep(rise, modes, fs, lags)
    parameters = {
        "sample_rate": fs,
        "resonance_hz": modes[0][0],
        "damping_ratio": modes[0][1],
        "creep_time_constants": taus.tolist(),
        "creep_weights": weights.tolist(),
        "delay_samples": delay,
    }
    if len(modes) > 1:
        parameters["second_resonance_hz"] = modes[1][0]
        parameters["second_damping_ratio"] = modes[1][1]
        parameters["second_mode_gain"] = modes[1][2]
    report = _report(parameters, modes, lags, measured, lines, rise, step_fit)
    report["modes"] = len(modes)
    report["residual_ratio"] = two.residual / one.residual  # two modes' over one's
    raw = measured / advance  # as the rig answered, its latency in
    report["input"] = "voltage" if u is v else "hysteresis model"
    report["measured_response"] = {
        "hz": lines.tolist(),
        "real": raw.real.tolist(),
        "imag": raw.imag.tolist(),
    }
    return DynamicsFit(parameters, report)


def record_layout(v, sample_rate: float) -> Layout:
    """Where the parts of :func:`dynamics_excitation` lie in a record's command ``v``.

    The step is the first change of ``v``, the multisine the first change after it; the
    multisine's periods are those that repeat the first (a record of the former layout
    holds the multisine to its end). The triangles are those of the excitation for the
    record's voltage range (its rest and its mid-range level), kept where the command
    follows them (within 1 % of the range); a record without them has none.

    Parameters
    ----------
    v : array_like
        The record's command, V.
    sample_rate : float
        The record's sample rate, Hz.

    Returns
    -------
    Layout
        The sample indices of the step, the multisine, its periods and the triangles.

    Raises
    ------
    IdentificationError
        If the record does not have the layout of :func:`dynamics_excitation`.
    """
    v = np.asarray(v, dtype=np.float64)
    fs = float(sample_rate)
    n_period = round(PERIOD * fs)
    moved = np.flatnonzero(v != v[0])
    if moved.size == 0:
        raise IdentificationError(
            Notice(
                "The record's voltage never moves. Record the answer to {excite_dynamics} (a "
                "step, a hold, then a multisine)."
            )
        )
    step = int(moved[0])
    after = np.flatnonzero(v[step:] != v[step])
    multisine = step + int(after[0]) if after.size else v.size
    hold = (multisine - step) / fs
    if hold < 0.1 or (v.size - multisine) < 2 * n_period:
        raise IdentificationError(
            Notice(
                "The record does not have the layout of {excite_dynamics}: found a "
                f"hold of {hold:.3g} s (at least 0.1 s needed) and "
                f"{(v.size - multisine) / fs:.3g} s of multisine (at least {2 * PERIOD:g} s: "
                f"two periods of {PERIOD:g} s). Record the answer to {{excite_dynamics}} "
                "{same_rate}."
            )
        )
    first = v[multisine : multisine + n_period]
    span = float(np.ptp(v))
    periods = 1
    while multisine + (periods + 1) * n_period <= v.size:
        this = v[multisine + periods * n_period : multisine + (periods + 1) * n_period]
        if np.max(np.abs(this - first)) > 1e-6 * span:
            break
        periods += 1
    if periods < 2:
        raise IdentificationError(
            Notice(
                "The record does not have the layout of {excite_dynamics}: its multisine "
                f"does not repeat after {PERIOD:g} s. Record the answer to {{excite_dynamics}} "
                "{same_rate}."
            )
        )
    lo = float(v[0])
    hi = lo + (float(v[step]) - lo) / BIAS_FRACTION
    triangles = []
    at = multisine + periods * n_period
    if hi > lo and at < v.size:
        expected = _parts(fs, lo, hi, AMPLITUDE_FRACTION * (hi - lo))[3:]
        for label, part in expected:
            stop = at + part.size
            if stop > v.size or np.max(np.abs(v[at:stop] - part)) > 0.01 * (hi - lo):
                break
            if label.startswith("triangle"):
                f = float(label.split()[1])
                triangles.append(Triangle(f, at, stop, round(fs / f)))
            at = stop
    return Layout(step, multisine, periods, n_period, tuple(triangles))


def _frf(v, x, start, n_period, periods, bins) -> np.ndarray:
    """``X/V`` at ``bins``, from the average of the periods after the first."""
    vv = v[start + n_period : start + periods * n_period].reshape(periods - 1, n_period).mean(0)
    xx = x[start + n_period : start + periods * n_period].reshape(periods - 1, n_period).mean(0)
    return np.fft.rfft(xx)[bins] / np.fft.rfft(vv)[bins]


def _fit_delay(measured, lines, fs) -> tuple[float, tuple[float, float]]:
    """``(tau, (f_n, zeta))``: the latency in samples (a fraction of a sample too; the
    model keeps the nearest whole number in :data:`DELAY_RANGE`) whose removal lets the
    resonance fit the lines best, and that fit.

    A latency adds a phase that grows with frequency, which the free complex gain of
    :func:`_fit_resonance` cannot take up, and leaves the magnitude as it is. So the
    resonance is first fitted to the magnitude alone, the slope of the phase left over
    gives the latency, the complex fits at it, at its neighbours and at the rig's usual 0
    decide, and a last fit frees the latency with the resonance.
    """
    from scipy.optimize import least_squares

    use = lines >= FIT_FROM_HZ
    f, g = lines[use], measured[use]
    z1 = np.exp(-2j * np.pi * f / fs)

    def at(fn, zeta):
        b, a = resonance_zoh(fn, zeta, fs)
        return resonance_response(b, a, z1)

    def residual(theta):
        r = np.log(np.abs(g)) - np.log(np.abs(at(*np.exp(theta))))
        return r - r.mean()

    theta0, bounds = _start(f, g, fs, None)
    fn, zeta = np.exp(least_squares(residual, theta0, bounds=bounds).x)
    left = np.angle(g / at(fn, zeta))
    # lines close enough that the largest latency turns the phase by less than pi between them
    close = np.r_[True, np.diff(f) < fs / (2.0 * (DELAY_RANGE[1] + 1))]
    close = np.cumprod(close).astype(bool)
    slope = np.polyfit(f[close], np.unwrap(left[close]), 1)[0] if close.sum() > 2 else 0.0
    estimate = float(
        np.clip(-slope * fs / (2.0 * np.pi), DELAY_RANGE[0] - 0.5, DELAY_RANGE[1] + 0.5)
    )
    guess = round(estimate)
    z = np.exp(2j * np.pi * lines / fs)  # one sample of advance at each line
    none = np.zeros(0)
    # whole samples, and the estimate itself: a rig's latency need not be whole samples (a
    # sensor's sampling phase, a filter's group delay), and the resonance fitted with a
    # fraction of a sample of phase left in would come out too lightly damped
    fits = {
        d: _fit_resonance(measured * z**d, lines, fs, none, none, guess=None)
        for d in sorted({0.0, guess - 1.0, float(guess), guess + 1.0, estimate})
        if DELAY_RANGE[0] - 0.5 <= d <= DELAY_RANGE[1] + 0.5
    }
    best = min(fits, key=lambda k: fits[k][2])

    # then the latency free with the resonance, from the best: a fraction of a sample too
    def delayed(theta):
        m = at(*np.exp(theta[:2])) * np.exp(-2j * np.pi * f * theta[2] / fs)
        gain = np.vdot(m, g) / np.vdot(m, m)
        r = (gain * m - g) / np.abs(g)
        return np.r_[r.real, r.imag]

    start = np.r_[np.log(fits[best][:2]), best]
    low = np.r_[np.log([1.0, 1e-4]), max(best - 1.0, DELAY_RANGE[0] - 0.5)]
    high = np.r_[np.log([0.45 * fs, MAX_DAMPING]), min(best + 1.0, DELAY_RANGE[1] + 0.5)]
    theta = least_squares(delayed, np.clip(start, low + 1e-9, high - 1e-9), bounds=(low, high)).x
    fn, zeta = np.exp(theta[:2])
    return float(theta[2]), (float(fn), float(zeta))


def _start(f, g, fs, guess):
    """Start and bounds of the resonance fits, in logs: the peak of the lines, and a damping
    ratio from its height, unless a ``guess`` is given."""
    if guess is None:
        peak = f[np.argmax(np.abs(g))]
        ratio = np.abs(g).max() / np.abs(g[0])
        guess = (peak, min(0.7, max(1e-3, 0.5 / ratio)))
    bounds = (np.log([1.0, 1e-4]), np.log([0.45 * fs, MAX_DAMPING]))
    return np.clip(
        np.log(np.asarray(guess, dtype=np.float64)), bounds[0] + 1e-9, bounds[1] - 1e-9
    ), bounds


def _fit_resonance(measured, lines, fs, lags, weights, guess):
    """``(f_n, zeta, cost)`` of the resonance, the local gain eliminated (relative complex
    error; ``cost`` its half sum of squares)."""
    from scipy.optimize import least_squares

    use = lines >= FIT_FROM_HZ
    f, g = lines[use], measured[use]
    z1 = np.exp(-2j * np.pi * f / fs)
    creep = creep_response(lags, weights, z1)

    def residual(theta):
        fn, zeta = np.exp(theta)
        m = creep * resonance_response(*resonance_zoh(fn, zeta, fs), z1)
        gain = np.vdot(m, g) / np.vdot(m, m)
        r = (gain * m - g) / np.abs(g)
        return np.r_[r.real, r.imag]

    theta0, bounds = _start(f, g, fs, guess)
    result = least_squares(residual, theta0, bounds=bounds, x_scale=1.0)
    fn, zeta = np.exp(result.x)
    return float(fn), float(zeta), float(result.cost)


def _fit_creep(rise, modes, fs, lags):
    """Non-negative creep weights and the step's final height from the step response
    (``modes`` as in :func:`hystcomp._lti.modal_tf`)."""
    from scipy.optimize import nnls

    # the ringing is left out: a slightly wrong resonance there would outweigh the creep
    decay = max(fs / (2.0 * np.pi * fn * zeta) for fn, zeta, _ in modes)
    start = min(rise.size // 2, round(RINGING_DECAYS * decay))
    # samples spaced evenly in log time: each decade of creep weighs the same, and it is fast
    rows = np.unique(np.geomspace(start + 1, rise.size, CREEP_SAMPLES).astype(int) - 1)
    unit = np.ones(rise.size)
    # a mode settled to within 1 % where the samples start is nearly the unit column: the
    # least squares would trade a large weight of it against the direct term to take up
    # what a slightly wrong resonance leaves of the ringing (a creep of 36 % of the step
    # in 3 ms came of it); such modes are left at 0, their share in the direct term. 1 %
    # was not enough: a mode 98.5 % settled took 4 % of a stage's step behind one
    # hysteresis model and 0 % behind another (a 1.5 kHz stage, 4 % creep from 0.1 s on)
    seen = lags ** (start + 1) > SETTLED
    columns = [modal(modes, fs, unit)[rows]]
    columns += [modal(modes, fs, lag(a, unit))[rows] for a in lags[seen]]
    solved, _ = nnls(np.column_stack(columns), rise[rows])
    coef = np.zeros(lags.size + 1)
    coef[0] = solved[0]
    coef[1:][seen] = solved[1:]
    if not coef[0] > 0:
        raise IdentificationError(
            Notice(
                "The step of the record gives no displacement that the model can follow: "
                "check that x answers v, that the record is the answer to {excite_dynamics}, "
                f"and that the rig's latency is within {DELAY_RANGE[1]} samples."
            )
        )
    weights = coef[1:] / coef[0]
    return weights, float(coef.sum())


def _report(parameters, modes, lags, measured, lines, rise, step_fit) -> dict:
    """Fit % and largest magnitude error (dB) up to twice the highest mode; step rms error."""
    fs = parameters["sample_rate"]
    weights = np.asarray(parameters["creep_weights"])
    top = min(2.0 * max(hz for hz, _, _ in modes), lines.max())
    use = (lines >= FIT_FROM_HZ) & (lines <= top)
    m = frequency_response(lines[use], fs, modes, lags, weights)
    g = measured[use]
    gain = np.vdot(m, g) / np.vdot(m, m)
    fit = 100.0 * (1.0 - np.linalg.norm(gain * m - g) / np.linalg.norm(g - g.mean()))
    db = np.abs(20.0 * np.log10(np.abs(gain * m) / np.abs(g)))
    unit = np.r_[0.0, np.ones(rise.size - 1)]
    step_model = step_fit * output(unit, 0.0, fs, modes, lags, weights)
    step_rms = float(np.sqrt(np.mean((step_model - rise) ** 2)))
    after_1s = creep_fraction(1.0, parameters["creep_time_constants"], weights)
    return {
        "fit_percent": float(fit),
        "max_magnitude_error_db": float(db.max()),
        "fit_band_hz": [float(FIT_FROM_HZ), float(top)],
        "step_rms_um": step_rms,
        "step_height_um": float(step_fit),
        "creep_after_1s_percent": 100.0 * after_1s,
        # what the free complex factor took up: the hysteresis's local gain (µm/V) and
        # phase behind a fit on the voltage; what a hysteresis model left (about 1, 0 deg)
        # behind a fit on its output
        "input_gain": float(abs(gain)),
        "input_phase_deg": float(np.degrees(np.angle(gain))),
    }
