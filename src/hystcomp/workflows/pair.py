"""Hysteresis and dynamics identified as one pair, and how well the pair will track.

:func:`identify_pair_record` identifies the hysteresis model alone from its record (as
:func:`hystcomp.workflows.identify.identify_record` fits it), then the pair
(:func:`hystcomp.models.hammerstein.fit_pair`) from both records, then estimates the
tracking of both compensators on the triangles of the dynamics record, which neither fit
saw (:func:`tracking_estimates`).

:func:`dynamics_alone` fits the dynamics behind a hysteresis model of the dynamics record's
own, for a user who pairs them with a hysteresis model later (the dynamics given to
:func:`hystcomp.workflows.compensate.compensate_reference`), which is then warned about.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hystcomp._notice import Notice
from hystcomp.errors import InvalidParameterError, InvalidTypeError
from hystcomp.identify.dynamics import MAX_DAMPING, TRIANGLE_SPAN, record_layout
from hystcomp.identify.scoring import turning_indices
from hystcomp.io.records import uneven_sampling
from hystcomp.models.dynamics import LinearDynamics
from hystcomp.models.hammerstein import HammersteinModel, fit_pair
from hystcomp.models.mpi import ModifiedPrandtlIshlinskii
from hystcomp.workflows.identify import IdentificationResult, identify_record

__all__ = [
    "DynamicsResult",
    "PairResult",
    "dynamics_alone",
    "dynamics_lines",
    "identify_dynamics_record",
    "identify_pair_record",
    "predicted_worse",
    "reference_rate",
    "tracking_estimates",
]

#: Least share (%) of the frequency response the dynamics must explain to be used without a
#: warning (Benchmarks, "The H+D pair").
MIN_DYNAMICS_FIT = 80.0
#: The pair is said to track worse than the hysteresis model alone where its estimate is
#: above this multiple of the other's (the estimates' own scatter stays within it).
WORSE = 1.1


@dataclass(frozen=True, eq=False)
class PairResult:
    """What :func:`identify_pair_record` found.

    The hysteresis model's own result stays apart from the pair's, with its lines first.

    Attributes
    ----------
    model : HammersteinModel
        The pair, with ``fit_report_["tracking_estimates"]``.
    hysteresis : IdentificationResult
        The hysteresis model alone, as
        :func:`~hystcomp.workflows.identify.identify_record` fits it from the hysteresis
        record (its report and warnings).
    estimates : dict
        ``{frequency (Hz): {"alone_um": rms, "pair_um": rms}}``: see
        :func:`tracking_estimates`.
    lines : list of str
        The pair's report (after the hysteresis model's own lines).
    warnings : list of str
        The pair's warnings (after the hysteresis model's).
    """

    model: HammersteinModel
    hysteresis: IdentificationResult
    estimates: dict
    lines: list[str] = field(repr=False)
    warnings: list[str] = field(default_factory=list)


def tracking_estimates(pair, alone, v, x) -> dict:
    """Estimated tracking rms (µm) of the pair and of its hysteresis model alone.

    For each triangle of the dynamics record ``(v, x)`` (see
    :func:`hystcomp.identify.dynamics.record_layout`), of frequency ``f``::

        estimate(C, f)^2 = e_model(C, f)^2 + e_stage(f)^2

    ``e_model`` is what compensator ``C`` leaves on the pair as a model of the stage: a
    triangle over :data:`~hystcomp.identify.dynamics.TRIANGLE_SPAN` of the pair's reach at
    ``f`` through ``C`` and then ``D[H[.]]``. It holds the dynamics that the hysteresis
    model alone does not invert, and what the pair's own inverse cannot (its band limit).
    ``e_stage`` is how far the pair is from the stage: its forward error on that triangle
    of the record, which neither fit saw. How close the estimate comes to the measured
    tracking: (Benchmarks, "The H+D pair").

    Parameters
    ----------
    pair : hystcomp.models.hammerstein.HammersteinModel
        The fitted pair ``D[H[v]]``.
    alone : hystcomp.models.base.HysteresisModel
        The hysteresis model fitted alone (its compensator ignores the dynamics).
    v : array_like
        The dynamics record's voltage (V), sampled at the pair's dynamics rate.
    x : array_like
        The dynamics record's displacement (µm).

    Returns
    -------
    dict
        ``{f (Hz): {"alone_um": rms, "pair_um": rms}}`` (µm), empty if the record has no
        triangles (a record of the former layout).
    """
    dynamics = pair.dynamics
    fs = dynamics.sample_rate_
    triangles = record_layout(v, fs).triangles
    if not triangles:
        return {}
    lo, hi = pair.voltage_range_
    # the reach once swung over the range (a model whose loops stay open at rest no longer
    # comes back to its first value)
    swept = pair.hysteresis.simulate(np.array([lo, hi, lo, hi]))
    bottom, top = float(swept[2]), float(swept[3])
    a, b = TRIANGLE_SPAN
    compensators = {
        "alone_um": alone.inverse(sample_rate=fs),
        "pair_um": pair.inverse(),
    }
    forward = pair.simulate(v) - x
    out = {}
    for tri in triangles:
        e_stage = _rms(forward[tri.start + tri.period : tri.stop])
        periods = max(2, round(TRIANGLE_SECONDS * tri.frequency))
        phase = np.arange(periods * tri.period) % tri.period / tri.period
        x_ref = bottom + (top - bottom) * (a + (b - a) * (1.0 - np.abs(1.0 - 2.0 * phase)))
        out[tri.frequency] = {
            k: float(
                np.hypot(_rms((pair.simulate(c.simulate(x_ref)) - x_ref)[tri.period :]), e_stage)
            )
            for k, c in compensators.items()
        }
    return out


#: Seconds of the triangles simulated by :func:`tracking_estimates` (two periods at least).
TRIANGLE_SECONDS = 0.3


def _rms(e) -> float:
    return float(np.sqrt(np.mean(np.square(e))))


def identify_pair_record(
    record, dynamics_record, model, *, hysteresis=None, **options
) -> PairResult:
    """Identify a hysteresis model and the linear dynamics as one pair, and report.

    Parameters
    ----------
    record : hystcomp.io.records.Record
        The hysteresis record: time (s), voltage (V), displacement (µm), e.g. the answer to
        ``excitation_signal('mpi')`` or ``'rich'``.
    dynamics_record : hystcomp.io.records.Record
        The answer to ``excitation_signal('dynamics')``, at the rate the compensator will
        run.
    model : {'pi', 'mpi', 'preisach'} or estimator
        As in :func:`~hystcomp.workflows.identify.identify_record`.
    hysteresis : IdentificationResult, optional
        ``model`` already identified from ``record`` (by
        :func:`~hystcomp.workflows.identify.identify_record`, as
        :func:`~hystcomp.workflows.auto.identify_best` does): it is the pair's first round,
        not fitted again.
    **options
        Those of :func:`~hystcomp.workflows.identify.identify_record` (no ``holdout``), for
        the hysteresis model's identification when it is not given.

    Returns
    -------
    PairResult
        The pair (with its tracking estimates in ``fit_report_``), the hysteresis model's
        own identification, and the report lines and warnings.
    """
    uneven = uneven_sampling(dynamics_record.t, f"the dynamics record {dynamics_record.source}")
    if uneven:
        raise InvalidParameterError(uneven)
    if hysteresis is None:
        hysteresis = identify_record(record, model, **options)
    estimator = hysteresis.model
    fs = dynamics_record.sample_rate
    pair = fit_pair(
        estimator,
        record.v,
        record.x,
        dynamics_record.v,
        dynamics_record.x,
        sample_rate=fs,
        hysteresis_rate=record.sample_rate,
        alone=estimator,
    )
    estimates = tracking_estimates(pair, estimator, dynamics_record.v, dynamics_record.x)
    pair.fit_report_["tracking_estimates"] = {f"{f:g}": e for f, e in estimates.items()}
    dyn = pair.dynamics
    rounds = pair.fit_report_["rounds"]
    lines = [
        (
            f"paired with linear dynamics from {dynamics_record.source}: x = D[H[v]], identified "
            f"together ({rounds} round{'s' if rounds > 1 else ''}: D behind H, H in front of D)"
        )
    ]
    lines += dynamics_lines(dyn, dynamics_record)
    warnings = dynamics_warnings(dyn)
    if estimates:
        lines.append(
            "  tracking (estimated on the dynamics record's triangles, which neither fit saw):"
        )
        lines.append(f"  {'f (Hz)':>10}  {'H alone (µm)':>13}  {'pair (µm)':>10}")
        worse = []
        for f, e in estimates.items():
            lines.append(f"  {f:>10g}  {e['alone_um']:>13.4g}  {e['pair_um']:>10.4g}")
            if e["pair_um"] > WORSE * e["alone_um"]:
                worse.append(f"{f:g} Hz ({e['pair_um']:.3g} vs {e['alone_um']:.3g} µm)")
        if worse:
            warnings.append(
                Notice(
                    "the pair is predicted to track worse than the hysteresis model alone at "
                    + ", ".join(worse)
                    + "; compensate warns when a reference runs at those rates. Check the "
                    "dynamics record ({excite_dynamics}, at the rate you compensate), or "
                    "compensate such references with the hysteresis model alone.",
                    kind="pair-worse",
                )
            )
    else:
        warnings.append(
            Notice(
                "the dynamics record holds no triangles (a record of an older "
                "{excite_dynamics}), so the pair's tracking cannot be estimated; record the "
                "answer to {excite_dynamics} again.",
                kind="no-triangles",
            )
        )
    return PairResult(pair, hysteresis, estimates, lines, warnings)


def dynamics_lines(dyn: LinearDynamics, record) -> list[str]:
    """The report of a dynamics model: record, resonance, latency, creep, fit.

    Parameters
    ----------
    dyn : hystcomp.models.dynamics.LinearDynamics
        The fitted dynamics (with their ``fit_report_``).
    record : hystcomp.io.records.Record
        The record they were fitted to: time (s), voltage (V), displacement (µm).

    Returns
    -------
    list of str
        One line each: the record's length and rate (Hz, s), the resonance (Hz), the
        latency (samples, µs), the creep (%, s), the fit (%, dB) and the step error (µm).
    """
    report = dyn.fit_report_
    lo, hi = report["fit_band_hz"]
    taus = dyn.creep_time_constants_
    lines = [
        (
            f"  record:    {len(record)} samples at {record.sample_rate:.6g} Hz "
            f"({record.t[-1] - record.t[0]:.4g} s)"
        ),
        f"  resonance: {dyn.resonance_hz_:.5g} Hz, damping ratio {dyn.damping_ratio_:.3g}",
    ]
    if dyn.second_mode_gain_ is not None:  # found where it explains the response clearly better
        ratio = report.get("residual_ratio")
        why = "" if ratio is None else f"; two modes leave {ratio:.2g} of one mode's residual"
        lines.append(
            f"  second mode: {dyn.second_resonance_hz_:.5g} Hz, damping ratio "
            f"{dyn.second_damping_ratio_:.3g}, {100 * dyn.second_mode_gain_:.3g} % of the "
            f"static gain, in parallel with the first{why}"
        )
    delay = dyn.delay_samples_
    if delay:  # the rig's latency, beyond the sample-and-hold's one sample
        lines.append(
            f"  latency:   {delay:+d} sample{'s' if abs(delay) > 1 else ''} beside the "
            f"sample-and-hold's one ({1e6 * delay / record.sample_rate:+.4g} µs); the inverse "
            "looks that much further ahead"
        )
    lines.append(
        f"  creep:     {100 * dyn.creep_fraction(0.0):.3g} % of the final displacement, "
        f"{100 * dyn.creep_fraction(1.0):.3g} % of it after 1 s "
        f"({taus.size} modes, {taus[0]:.3g} .. {taus[-1]:.3g} s)"
    )
    modes = "two modes" if dyn.second_mode_gain_ is not None else "one mode"
    lines.append(
        f"  fit, {lo:.4g} .. {hi:.4g} Hz: {report['fit_percent']:.3g} % "
        f"(frequency response, {modes}), largest magnitude error "
        f"{report['max_magnitude_error_db']:.3g} dB"
    )
    lines.append(
        f"  step:      rms error {report['step_rms_um']:.4g} µm on a step of "
        f"{report['step_height_um']:.4g} µm"
    )
    return lines


def dynamics_warnings(dyn: LinearDynamics) -> list[str]:
    """A warning when the dynamics follow their record too poorly to be inverted safely."""
    report = dyn.fit_report_
    lo, hi = report["fit_band_hz"]
    resonance = dyn.damping_ratio_ < 0.99 * MAX_DAMPING
    if report["fit_percent"] >= MIN_DYNAMICS_FIT and resonance:
        return []
    found = (
        ""
        if resonance
        else f" and finds no resonance in it (the damping ratio is at its bound, {MAX_DAMPING:g})"
    )
    return [
        (
            f"the model explains {report['fit_percent']:.3g} % of the frequency response "
            f"from {lo:.4g} to {hi:.4g} Hz{found}; stages with one resonance give "
            f"{MIN_DYNAMICS_FIT:g} % and more. Its inverse may make tracking worse (a "
            "hysteresis that changes with the rate, or more modes than two, does this): "
            "compare compensate with and without the dynamics on a test reference first."
        )
    ]


@dataclass(frozen=True, eq=False)
class DynamicsResult:
    """What :func:`identify_dynamics_record` found.

    Attributes
    ----------
    model : hystcomp.models.dynamics.LinearDynamics
        The fitted dynamics.
    source : str
        Where the record came from.
    lines : list of str
        The report, one line each.
    warnings : list of str
        Each a sentence (without the command line's ``hystcomp: warning:`` prefix): when
        the model follows the record too poorly for its inverse to be trusted.
    """

    model: LinearDynamics
    source: str
    lines: list[str] = field(repr=False)
    warnings: list[str] = field(default_factory=list)


def identify_dynamics_record(record) -> DynamicsResult:
    """Fit the linear dynamics (creep, first resonance, a second mode if the record shows
    one) to a record and report the fit.

    Beyond the paper: the record is the answer to
    :func:`~hystcomp.identify.dynamics.dynamics_excitation`; the fit is
    :func:`dynamics_alone`.

    Parameters
    ----------
    record : hystcomp.io.records.Record
        The measured record: time (s), voltage (V), displacement (µm), evenly sampled (an
        uneven record is refused, as the fit assumes one sample rate).

    Returns
    -------
    DynamicsResult
        The fitted model and the report lines (resonance in Hz, creep in %, fit errors).
    """
    for name in ("t", "v", "x", "source", "sample_rate"):
        if not hasattr(record, name):
            raise InvalidTypeError(
                "The 'record' argument of identify_dynamics_record must be a "
                f"hystcomp.io.records.Record (t, v, x); got {type(record).__name__}."
            )
    uneven = uneven_sampling(record.t, f"the record {record.source}")
    if uneven:
        raise InvalidParameterError(uneven)
    model = dynamics_alone(record)
    lines = [f"linear dynamics (creep and first resonance) from {record.source}"]
    lines += dynamics_lines(model, record)
    return DynamicsResult(model, str(record.source), lines, dynamics_warnings(model))


def dynamics_alone(record) -> LinearDynamics:
    """The linear dynamics of the answer to ``excitation_signal('dynamics')``, on their own.

    ``D`` is fitted behind a hysteresis model (MPI) of the record itself, fitted on its
    1 Hz triangles (from the ramp before them, which sets the model's memory), the two
    alternated as in :func:`~hystcomp.models.hammerstein.fit_pair`: the large-signal
    record drives the stage through its hysteresis, which a fit on the voltage would take
    for dynamics. The hysteresis model is not kept. A record of the former layout (a small
    multisine, no triangles) is fitted on the voltage, as it was.

    Parameters
    ----------
    record : hystcomp.io.records.Record
        The dynamics record: time (s), voltage (V), displacement (µm).

    Returns
    -------
    hystcomp.models.dynamics.LinearDynamics
        The fitted dynamics, at the record's sample rate.
    """
    v, x = record.v, record.x
    triangles = record_layout(v, record.sample_rate).triangles
    if not triangles:
        return LinearDynamics().fit(v, x, record.sample_rate)
    slow = triangles[0]
    start = slow.start - 1  # the ramp's last sample, at the triangle's low end
    part = slice(start, slow.stop)
    fs = record.sample_rate
    pair = fit_pair(ModifiedPrandtlIshlinskii(), v, x, v, x, sample_rate=fs, fit_on=part)
    return pair.dynamics


def reference_rate(x_ref, sample_rate: float) -> float:
    """The rate (Hz) of a reference: one over twice the mean time between its turns.

    Turns smaller than 5 % of its span are not counted; a reference that never turns back
    (a ramp, a step, a hold) has rate 0.

    Parameters
    ----------
    x_ref : array_like
        The reference displacement (µm).
    sample_rate : float
        Its sample rate (Hz).

    Returns
    -------
    float
        The rate (Hz), 0.0 for a reference that never turns back.

    Examples
    --------
    >>> t = np.arange(20_000) / 20_000.0
    >>> round(reference_rate(np.abs(((10.0 * t) % 1.0) - 0.5), 20_000.0), 3)
    10.0
    """
    x = np.asarray(x_ref, dtype=np.float64)
    span = float(np.ptp(x)) if x.size else 0.0
    if span <= 0.0:
        return 0.0
    idx, _ = turning_indices(x, 0.05 * span)
    turns = idx[:-1]  # the last is where the reference ends, not a turn
    if turns.size < 2:
        return 0.0
    return 0.5 * (turns.size - 1) * sample_rate / float(turns[-1] - turns[0])


def _estimate_rows(report) -> list[tuple[float, float, float]]:
    """``(frequency, alone, pair)`` of a fit report's tracking estimates, sorted; a model
    file's report is not validated, so anything else than positive finite numbers is no
    estimate."""
    found = report.get("tracking_estimates") if isinstance(report, dict) else None
    rows = []
    for f, e in found.items() if isinstance(found, dict) else ():
        try:
            row = (float(f), float(e["alone_um"]), float(e["pair_um"]))
        except (TypeError, ValueError, KeyError, OverflowError):
            continue
        if all(np.isfinite(row)) and min(row) > 0.0:
            rows.append(row)
    return sorted(rows)


def predicted_worse(pair: HammersteinModel, x_ref, sample_rate: float):
    """``(rate, alone_um, pair_um)`` if the pair is predicted to track ``x_ref`` worse than
    its hysteresis model alone, else None.

    The estimates of :func:`tracking_estimates` (in the pair's file) are interpolated in
    the logarithm of the frequency at the reference's :func:`reference_rate`, held at the
    ends of the frequencies estimated (a step or a hold is the slowest).

    Parameters
    ----------
    pair : hystcomp.models.hammerstein.HammersteinModel
        The pair, with ``fit_report_["tracking_estimates"]`` (as its model file holds it).
    x_ref : array_like
        The reference displacement (µm).
    sample_rate : float
        The reference's sample rate (Hz).

    Returns
    -------
    tuple of float or None
        ``(rate (Hz), alone_um, pair_um)``, the estimates in µm rms, if the pair is
        predicted to track worse than the hysteresis model alone; None if it is not, or if
        the pair holds no estimates.
    """
    rows = _estimate_rows(getattr(pair, "fit_report_", None))
    if not rows:
        return None
    f, alone, paired = (np.array(c) for c in zip(*rows, strict=True))
    rate = reference_rate(x_ref, sample_rate)
    at = np.log(np.clip(rate, f[0], f[-1]))
    a = float(np.exp(np.interp(at, np.log(f), np.log(alone))))
    p = float(np.exp(np.interp(at, np.log(f), np.log(paired))))
    return (rate, a, p) if p > WORSE * a else None
