"""Accuracy and cost of the inverse of the linear dynamics (beyond the paper).

On the compare twin (630 Hz, zeta 0.1, 3 % creep) and on a stage with a 780 Hz mode,
zeta 0.05 and 3 % creep, the whole ``compare`` experiment is run with its dynamics part;
the rows are ratios measured in the same run:

* rms of the 100 Hz (200 Hz) triangle over the 1 Hz rms of the same compensator, with the
  inverse of the dynamics (targets <= 1.5 and <= 2.5) and without it (for information);
* mean |error| from 20 ms to 3 s after a step, with over without the dynamics (target
  < 0.3), and how far the error drifts over that time (the creep left), with over without;
* the linear floor: the rms that the inverse of the identified dynamics leaves at 100 and
  200 Hz on the stage's own linear part alone (creep and resonance, no hysteresis), over
  MPI's 1 Hz rms (information: what the dynamics inverse costs, whatever the hysteresis
  model; a perfect hysteresis inverse in front of the twin leaves the same);
* the same step ratio for the exact Preisach inverse (information: the default inverse of
  the Preisach model overshoots the voltage on a fast rise by itself, a minor loop that
  the dynamics cannot undo);
* the extra time of the dynamics part of ``compare`` (identification, 1..200 Hz runs, the
  step) as a fraction of the rest of the run (information: ``compare`` must stay fast).

Run alone with ``python benchmarks/bench_dynamics.py``; ``--heights`` prints the step's
ratio at several heights instead (:func:`step_heights`), ``--coupling`` the hysteresis
model's error alone and through the stage's resonance (:func:`coupling`), ``--floor`` the
least error that any linear inverse whose step response turns back by at most a given
fraction leaves on the triangles (:func:`best_floor`), ``--turns`` the rows with targets
when hystcomp's FIR is allowed to turn back (:func:`turning_fir`), ``--ideal`` the
tracking with the best linear inverse for each triangle instead (:func:`ideal_tracking`).
"""

from __future__ import annotations

import copy
import time

import numpy as np

from hystcomp.experiment.compare import CompareConfig, run_comparison
from hystcomp.experiment.compare_dynamics import FAST_FREQUENCIES, STEP_FROM, STEP_HOLD
from hystcomp.experiment.references import triangle_reference
from hystcomp.experiment.tracking import period_samples
from hystcomp.models.dynamic_compensator import MAX_PREVIEW, band_fit
from hystcomp.models.dynamics import MATCH_HZ, LinearDynamics
from hystcomp.plant import Twin, creep_twin

STAGES = {
    "compare twin (630 Hz, zeta 0.1, 3 % creep)": creep_twin(),
    "stage 780 Hz, zeta 0.05, 3 % creep": creep_twin(resonance_hz=780.0, damping_ratio=0.05),
}


def _row(name, value, unit="x", target=None, ok=None):
    return {"name": name, "value": float(value), "unit": unit, "target": target, "ok": ok}


def _exact_step_ratio(c, params) -> float:
    """The step's mean |error| with over without the dynamics, exact Preisach inverse."""
    twin = Twin(params, seed=c.config.seed)
    fs = twin.sample_rate
    n0 = round(0.1 * fs)
    x_ref = np.r_[np.zeros(n0), np.full(round(STEP_HOLD * fs), 0.5 * c.reference_amplitude)]
    window = slice(n0 + round(STEP_FROM * fs), None)
    model = c.models["preisach"]
    err = [
        np.mean(np.abs(twin.run(comp.simulate(x_ref)) - x_ref)[window])
        for comp in (
            model.inverse(method="exact", dynamics=c.dynamics.dynamics),
            model.inverse(method="exact"),
        )
    ]
    return err[0] / err[1]


def _stage_dynamics(params) -> LinearDynamics:
    """The stage's own linear part (creep and resonance) as a :class:`LinearDynamics`."""
    n_creep = len(params.creep_time_constants)
    return LinearDynamics.from_parameters(
        sample_rate=float(params.sample_rate),
        resonance_hz=params.resonance_hz,
        damping_ratio=params.damping_ratio,
        creep_time_constants=params.creep_time_constants,
        creep_weights=[params.creep_gain / n_creep] * n_creep,
    )


def _triangle(c, params, frequency):
    """``compare``'s triangle at ``frequency`` and the window it measures."""
    fs = float(params.sample_rate)
    periods = max(c.config.periods, round(c.config.periods * frequency / 10.0))
    _, x_ref = triangle_reference(c.reference_amplitude, frequency, periods=periods, sample_rate=fs)
    return x_ref, slice(period_samples(frequency, fs), None)


def _rms(e) -> float:
    return float(np.sqrt(np.mean(e**2)))


def _linear_floor(c, params, frequency) -> float:
    """rms (µm) of ``D[D_id^-1[x_ref]] / |D(1 Hz)| - x_ref`` on ``compare``'s triangle at
    ``frequency``, over the periods that ``compare`` measures: ``D`` the stage's own creep
    and resonance, ``D_id^-1`` the inverse of the identified model matched at 1 Hz as in
    ``with_dynamics`` (a hysteresis model identified at 1 Hz holds the gain ``|D(1 Hz)|``)."""
    stage = _stage_dynamics(params)
    x_ref, window = _triangle(c, params, frequency)
    r = c.dynamics.dynamics.inverse(match_hz=MATCH_HZ).simulate(x_ref)
    x = stage.simulate(r, initial=0.0) / abs(stage.frequency_response([MATCH_HZ])[0])
    return _rms((x - x_ref)[window])


def coupling(c, params, method, frequency) -> tuple[float, float]:
    """``(rms e_h, rms D[e_h])`` in µm: the hysteresis error of ``method``'s compensator with
    the dynamics, ``e_h = H_stage[v] - |D(1 Hz)| r`` (``r`` what ``D^-1`` asks of the
    hysteresis inverse, ``v`` the voltage), alone and through the stage's own creep and
    resonance ``D``, on ``compare``'s triangle at ``frequency`` (docs/dynamics.md)."""
    stage = _stage_dynamics(params)
    x_ref, window = _triangle(c, params, frequency)
    dyn = c.dynamics.dynamics
    v = c.models[method].inverse(dynamics=dyn).simulate(x_ref)
    r = dyn.inverse(match_hz=MATCH_HZ).simulate(x_ref)
    e_h = Twin(params).hysteresis(v) - abs(stage.frequency_response([MATCH_HZ])[0]) * r
    return _rms(e_h[window]), _rms(stage.simulate(e_h, initial=0.0)[window])


#: How far (fractions of the step) the step response of the inverses of :func:`best_floor`
#: may fall back from its highest value so far: 0 is a monotone rise (non-negative taps).
FALL_BACKS = (0.0, 0.05, 0.2, 0.5, 1.0)
#: The same for the band fit of ``--turns``, measured with the hysteresis.
TURNS = (0.0, 0.02, 0.05)


def _harmonics(dynamics, peak_to_peak, frequency, lead):
    """``(m, target)``: the real and imaginary parts of ``R(z) z^lead`` on the odd harmonics
    ``k f`` of a triangle of ``peak_to_peak`` µm, weighted by their amplitudes
    ``4 P / (pi^2 k^2)``, and the weighted 1 (``m @ g - target`` is the error of the FIR ``g``
    with those leads, real parts over imaginary parts)."""
    b, a = dynamics.resonance()
    fs = dynamics.sample_rate_
    k = np.arange(1, int(0.5 * fs / frequency), 2)
    amp = 4.0 * peak_to_peak / (np.pi**2 * k**2)
    z = np.exp(2j * np.pi * k * frequency / fs)
    n = a.size - 1  # R(z) in powers of z, one mode's (b0 z + b1) / (z^2 + a1 z + a2) or two
    r = sum(c * z ** (n - 1 - j) for j, c in enumerate(b)) / sum(
        c * z ** (n - j) for j, c in enumerate(a)
    )
    m = r[:, None] * z[:, None] ** np.asarray(lead)
    return np.vstack([m.real, m.imag]) * np.r_[amp, amp][:, None], np.r_[amp, np.zeros_like(amp)]


def _rms_of_harmonics(e) -> float:
    return float(np.sqrt(np.sum(e**2) / 2.0))


def fir_floor(dynamics, peak_to_peak, frequency) -> float:
    """The rms (µm) that ``dynamics.inverse()``'s FIR leaves on a triangle through the
    resonance of ``dynamics`` (creep inverted exactly), as :func:`best_floor` measures it."""
    inverse = dynamics.inverse()
    m, target = _harmonics(
        dynamics, peak_to_peak, frequency, inverse.preview - np.arange(inverse.taps.size)
    )
    return _rms_of_harmonics(m @ inverse.taps - target)


def _turning_taps(design, target, fall_back):
    """The taps ``g`` (unit sum) that minimise ``|design @ g - target|`` among those whose
    step response never turns back by more than ``fall_back`` (a fraction of the step: it
    stays within that of its running maximum, ``s = u - d`` with ``u`` rising and
    ``0 <= d <= fall_back``): a quadratic program in the rises of ``u`` and in ``d``
    (``quadprog``). ``fall_back = 0`` is a monotone rise, non-negative taps."""
    import quadprog

    n = design.shape[1]
    rises = np.eye(n) - np.eye(n, k=-1)  # taps g = p - rises @ d, p >= 0 the rises of u
    fit = np.hstack([design, -design @ rises])
    hess = fit.T @ fit
    hess += 1e-10 * np.trace(hess) / n * np.eye(2 * n)
    constraints = np.vstack(
        [
            np.r_[np.ones(n), np.zeros(n - 1), -1.0],  # s[-1] = sum(p) - d[-1] = 1
            np.eye(2 * n),  # p >= 0, d >= 0
            np.hstack([np.zeros((n, n)), -np.eye(n)]),  # d <= fall_back
        ]
    )
    # (an exact 0 makes d >= 0 and d <= 0 a degenerate pair that quadprog refuses)
    bounds = np.r_[1.0, np.zeros(2 * n), np.full(n, -max(fall_back, 1e-9))]
    x = quadprog.solve_qp(hess, fit.T @ target, constraints.T, bounds, 1)[0]
    return x[:n] - rises @ x[n:]


def best_floor(dynamics, peak_to_peak, frequency, fall_back, half=MAX_PREVIEW) -> float:
    """The least rms (µm) that a linear inverse of the resonance leaves on a triangle.

    Over every FIR of ``2 half + 1`` taps (look-ahead up to ``half``) with unit sum whose
    step response never turns back by more than ``fall_back`` (:func:`_turning_taps`), the
    one that minimises the error ``|1 - R G|`` on the harmonics of a triangle of
    ``peak_to_peak`` µm at ``frequency`` (:func:`_harmonics`), ``R`` the resonance of
    ``dynamics``. The creep is taken as inverted exactly: given the stage's own dynamics,
    this is what the best such inverse leaves with a perfect hysteresis inverse.
    """
    m, target = _harmonics(dynamics, peak_to_peak, frequency, np.arange(half, -half - 1, -1))
    return _rms_of_harmonics(m @ _turning_taps(m, target, fall_back) - target)


def ideal_tracking(c, params, method, frequency, fall_back) -> float:
    """rms (µm) of ``method`` + dynamics on ``compare``'s triangle at ``frequency``, its FIR
    replaced by the best one of :func:`best_floor` for that very triangle, designed on the
    stage's *own* resonance (for ``--ideal``): what the hysteresis model leaves behind the
    best linear inverse that knows the reference and the stage."""
    from unittest import mock

    lead = np.arange(MAX_PREVIEW, -MAX_PREVIEW - 1, -1)
    m, target = _harmonics(_stage_dynamics(params), c.reference_amplitude, frequency, lead)
    g = _turning_taps(m, target, fall_back)
    kept = np.flatnonzero(np.abs(g) > 1e-12 * np.abs(g).max())
    design = (g[kept[0] : kept[-1] + 1], int(lead[kept[0]]))
    dyn = copy.deepcopy(c.dynamics.dynamics)  # its kept FIR designs are not ours to change
    dyn.__dict__.pop("_fir_designs", None)
    with mock.patch("hystcomp.models.dynamics.inverse_fir", return_value=design):
        comp = c.models[method].inverse(dynamics=dyn)
    x_ref, window = _triangle(c, params, frequency)
    x = Twin(params, seed=c.config.seed).run(comp.simulate(x_ref))
    return _rms((x - x_ref)[window])


def turning_fir(fall_back):
    """A stand-in for :func:`hystcomp.models.dynamic_compensator.inverse_fir`: the same band
    fit, with the step response allowed to turn back by ``fall_back`` (for ``--turns``)."""

    def design(resonance, bandwidth_hz, sample_rate):
        m, target, lead = band_fit(resonance, bandwidth_hz, sample_rate)
        g = _turning_taps(m, target, fall_back)
        kept = np.flatnonzero(np.abs(g) > 1e-12 * np.abs(g).max())
        taps = g[kept[0] : kept[-1] + 1]
        return taps / taps.sum(), int(lead[kept[0]])

    return design


#: Step heights (fractions of the reference's peak) of :func:`step_heights`.
HEIGHTS = (0.2, 0.35, 0.5, 0.65, 0.8)


def step_heights(c, params, method) -> dict:
    """``{height: (ratio, error with)}``: a step from rest to ``height`` of the peak, held
    :data:`STEP_HOLD` s, mean |error| from :data:`STEP_FROM` s with over without the
    dynamics, and the error with them (µm); as ``compare``'s step, at other heights."""
    twin = Twin(params, seed=c.config.seed)
    fs = twin.sample_rate
    n0 = round(0.1 * fs)
    window = slice(n0 + round(STEP_FROM * fs), None)
    model = c.models[method]
    out = {}
    for height in HEIGHTS:
        x_ref = np.r_[np.zeros(n0), np.full(round(STEP_HOLD * fs), height * c.reference_amplitude)]
        with_, without = (
            float(np.mean(np.abs(twin.run(comp.simulate(x_ref)) - x_ref)[window]))
            for comp in (model.inverse(dynamics=c.dynamics.dynamics), model.inverse())
        )
        out[height] = (with_ / without, with_)
    return out


def run(timing=True) -> list[dict]:
    """Measure and return one row per figure: name, value, unit, target, ok (without the
    timing row if not ``timing``)."""
    rows = []
    for stage, params in STAGES.items():
        c = run_comparison(CompareConfig(twin=params))
        dc = c.dynamics
        for method in ("preisach", "mpi"):
            label = f"{method} + dynamics"
            base = dc.results[1.0][label].rms
            for f, limit in ((100.0, 1.5), (200.0, 2.5)):
                ratio = dc.results[f][label].rms / base
                rows.append(
                    _row(
                        f"{stage}: {label}, rms {f:g} Hz / 1 Hz",
                        ratio,
                        "x",
                        f"<= {limit:g}",
                        ratio <= limit,
                    )
                )
                plain = dc.results[f][method].rms / c.results[1.0][method].rms
                rows.append(_row(f"{stage}: {method} alone, rms {f:g} Hz / 1 Hz", plain))
            step = dc.step_error[label] / dc.step_error[method]
            rows.append(
                _row(
                    f"{stage}: {method}, step mean |error| with / without dynamics",
                    step,
                    "x",
                    "< 0.3",
                    step < 0.3,
                )
            )
            drift = abs(dc.step_drift[label]) / abs(dc.step_drift[method])
            rows.append(_row(f"{stage}: {method}, step |drift| 20 ms..3 s with / without", drift))
        base = dc.results[1.0]["mpi + dynamics"].rms
        for f in FAST_FREQUENCIES:
            floor = _linear_floor(c, params, f) / base
            rows.append(_row(f"{stage}: linear floor at {f:g} Hz / MPI's 1 Hz rms", floor))
        rows.append(
            _row(
                f"{stage}: preisach (exact inverse), step mean |error| with / without dynamics",
                _exact_step_ratio(c, params),
            )
        )
    if not timing:
        return rows
    start = time.perf_counter()
    run_comparison(CompareConfig(dynamics=False))
    plain = time.perf_counter() - start
    start = time.perf_counter()
    run_comparison(CompareConfig())
    full = time.perf_counter() - start
    rows.append(_row("compare: extra time of the dynamics part / the rest", (full - plain) / plain))
    return rows


if __name__ == "__main__":
    import sys

    if "--heights" in sys.argv:  # the step at several heights (docs/dynamics.md)
        for stage, params in STAGES.items():
            c = run_comparison(CompareConfig(twin=params))
            for method in ("mpi", "preisach"):
                cells = step_heights(c, params, method)
                print(
                    f"{stage}: {method}, step with / without dynamics (error with, µm): "
                    + ", ".join(f"{h:g}: {r:.2f} ({e:.3f})" for h, (r, e) in cells.items())
                )
        sys.exit()
    if "--coupling" in sys.argv:  # the hysteresis error through the resonance (docs/dynamics.md)
        for stage, params in STAGES.items():
            c = run_comparison(CompareConfig(twin=params))
            for method in ("mpi", "preisach"):
                cells = [coupling(c, params, method, f) for f in (1.0, *FAST_FREQUENCIES)]
                print(
                    f"{stage}: {method}, rms e_h / rms D[e_h] (µm) at 1, 100, 200 Hz: "
                    + ", ".join(f"{e:.3f} / {d:.3f}" for e, d in cells)
                )
        sys.exit()
    if "--floor" in sys.argv:  # the best linear inverse of each class (docs/dynamics.md)
        for stage, params in STAGES.items():
            c = run_comparison(CompareConfig(twin=params))
            base = c.dynamics.results[1.0]["mpi + dynamics"].rms
            stage_dyn = _stage_dynamics(params)
            for f in FAST_FREQUENCIES:
                cells = [best_floor(stage_dyn, c.reference_amplitude, f, d) for d in FALL_BACKS]
                print(
                    f"{stage}: {f:g} Hz, least rms (µm), step response turning back by at most "
                    + ", ".join(f"{d:g}: {e:.3f}" for d, e in zip(FALL_BACKS, cells, strict=True))
                    + f"; hystcomp's FIR {fir_floor(stage_dyn, c.reference_amplitude, f):.3f}"
                    + f" (MPI's 1 Hz rms {base:.3f})"
                )
        sys.exit()
    if "--ideal" in sys.argv:  # the best linear inverse for each triangle (docs/dynamics.md)
        for stage, params in STAGES.items():
            c = run_comparison(CompareConfig(twin=params))
            for method in ("mpi", "preisach"):
                base = c.dynamics.results[1.0][f"{method} + dynamics"].rms
                for d in (0.0, 1.0):
                    cells = [ideal_tracking(c, params, method, f, d) for f in FAST_FREQUENCIES]
                    print(
                        f"{stage}: {method}, the best inverse turning back by at most {d:g}, "
                        + ", ".join(
                            f"{f:g} Hz {e:.3f} µm ({e / base:.2f}x)"
                            for f, e in zip(FAST_FREQUENCIES, cells, strict=True)
                        )
                        + f" (1 Hz rms {base:.3f})"
                    )
        sys.exit()
    if "--turns" in sys.argv:  # the same band fit, allowed to turn back (docs/dynamics.md)
        from unittest import mock

        for turn in TURNS:
            with mock.patch("hystcomp.models.dynamics.inverse_fir", turning_fir(turn)):
                for row in run(timing=False):
                    if row["target"] or "linear floor" in row["name"]:
                        print(f"turns back {turn:g}: {row['name']}: {row['value']:.3g}")
        sys.exit()
    for row in run():
        print(f"{row['name']}: {row['value']:.4g} {row['unit']} (target {row['target']})")
