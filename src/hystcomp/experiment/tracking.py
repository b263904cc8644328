"""Tracking runs: a compensator drives the twin along a reference (the paper's Section V).

``x_ref -> compensator -> v -> twin -> x``; the error ``e = x - x_ref`` and the hysteresis
of ``x`` against ``x_ref`` are measured over the whole periods after the first (the axis
leaves its rest state during the first one). For the uncompensated baseline ``v`` is
proportional to ``x_ref``, so its loop against ``x_ref`` is its loop against the input,
rescaled, as the paper measures it.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from hystcomp._validation import as_signal, check_real
from hystcomp.errors import InvalidParameterError, InvalidTypeError
from hystcomp.experiment.metrics import hysteresis_percent, tracking_errors
from hystcomp.experiment.references import period_samples
from hystcomp.plant import Twin


@dataclasses.dataclass(frozen=True, eq=False)
class TrackingResult:
    """One tracking run. Signals cover the whole run; the figures of merit do not.

    Attributes
    ----------
    method : str
        Name of the compensation method.
    frequency : float
        Reference frequency in Hz.
    t, x_ref, v, x, e : ndarray
        Time (s), reference (µm), voltage (V), measured displacement (µm), error (µm).
    rms, max : float
        Rms and largest ``|e|`` in µm over the periods after the first (Table I).
    hysteresis_pct, saturation_zone_pct : float
        Hysteresis of ``x`` against ``x_ref`` over the same periods, whole loop and top
        quarter, in % of the displacement range (Fig. 9).
    period : int
        Samples per period of the reference.
    """

    method: str
    frequency: float
    t: np.ndarray
    x_ref: np.ndarray
    v: np.ndarray
    x: np.ndarray
    e: np.ndarray
    rms: float
    max: float
    hysteresis_pct: float
    saturation_zone_pct: float
    period: int

    @property
    def window(self) -> slice:
        """The measured samples: the whole periods after the first."""
        return slice(self.period, self.period * (self.t.size // self.period))


def check_compensator(compensator, name: str = "compensator"):
    """A compensator: anything with ``simulate(x_ref) -> v`` and a ``voltage_range`` (V).

    Parameters
    ----------
    compensator : object
        The compensator.
    name : str, optional
        How the message names it.

    Returns
    -------
    object
        ``compensator``, unchanged.
    """
    if not callable(getattr(compensator, "simulate", None)) or not hasattr(
        compensator, "voltage_range"
    ):
        raise InvalidTypeError(
            f"{name!r} must have a simulate(x_ref) method and a voltage_range, like "
            f"model.inverse() or LinearCompensator. Got {type(compensator).__name__}."
        )
    return compensator


def run_tracking(compensator, twin: Twin, x_ref, *, frequency: float, method: str = ""):
    """Drive ``twin`` with ``compensator`` along the periodic reference ``x_ref``.

    Parameters
    ----------
    compensator : object
        ``simulate(x_ref) -> v`` (V) and ``voltage_range``; its output must stay in range.
    twin : Twin
        The simulated axis (its noise generator advances).
    x_ref : array_like
        Reference in µm, at the twin's sample rate, at least two whole periods.
    frequency : float
        The reference's frequency in Hz (sets the period).
    method : str
        A name for the result.

    Returns
    -------
    TrackingResult
    """
    check_compensator(compensator)
    if not isinstance(twin, Twin):
        raise InvalidTypeError(f"'twin' must be a hystcomp.plant.Twin. Got {type(twin).__name__}.")
    x_ref = as_signal(x_ref, "x_ref")
    frequency = check_real(frequency, "frequency", "run_tracking", positive=True)
    n = period_samples(frequency, twin.sample_rate)
    periods = x_ref.size // n
    if periods < 2:
        raise InvalidParameterError(
            f"'x_ref' must hold at least two periods at {frequency:g} Hz ({2 * n} samples at "
            f"{twin.sample_rate:g} Hz): the first one is left out. Got {x_ref.size} samples."
        )
    v = _voltage(compensator, x_ref)
    x = twin.run(v)
    window = slice(n, n * periods)
    rms, peak = tracking_errors(x_ref[window], x[window])
    whole, zone = hysteresis_percent(x_ref[window], x[window])
    return TrackingResult(
        method=method,
        frequency=frequency,
        t=twin.time(x_ref.size),
        x_ref=x_ref,
        v=v,
        x=x,
        e=x - x_ref,
        rms=rms,
        max=peak,
        hysteresis_pct=whole,
        saturation_zone_pct=zone,
        period=n,
    )


def _voltage(compensator, x_ref: np.ndarray) -> np.ndarray:
    """The compensator's voltage, checked: one finite sample per reference sample, in range."""
    v = np.asarray(compensator.simulate(x_ref), dtype=np.float64)
    lo, hi = (float(a) for a in compensator.voltage_range)
    name = type(compensator).__name__
    if v.shape != x_ref.shape or not np.all(np.isfinite(v)):
        raise InvalidParameterError(
            f"The {name} returned {v.shape[0] if v.ndim else 0} voltage samples "
            f"(finite: {bool(np.all(np.isfinite(v)))}) for {x_ref.size} reference samples; "
            "a compensator must return one finite voltage per reference sample."
        )
    slack = 1e-9 * max(1.0, abs(lo), abs(hi))
    if v.min() < lo - slack or v.max() > hi + slack:
        raise InvalidParameterError(
            f"The {name} drove the voltage to {v.min():g}..{v.max():g} V, outside its range "
            f"{lo:g}..{hi:g} V; a compensator must clamp its output to protect the piezo."
        )
    return v


def error_rows(comparison) -> list[dict]:
    """The rows of Table I's CSV, and of the dynamics part's: rms and max tracking error, µm.

    Parameters
    ----------
    comparison : Comparison or DynamicsComparison
        Either part's results: ``results[frequency][method]`` has ``rms`` and ``max``.

    Returns
    -------
    list of dict
        One row per frequency and method.
    """
    return [
        {"frequency_hz": f, "method": m, "rms_um": r.rms, "max_um": r.max}
        for f, by_method in comparison.results.items()
        for m, r in by_method.items()
    ]
