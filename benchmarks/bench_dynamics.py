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
model's error alone and through the stage's resonance (:func:`coupling`).
"""

from __future__ import annotations

import time

import numpy as np

from hystcomp.experiment.compare import CompareConfig, run_comparison
from hystcomp.experiment.compare_dynamics import FAST_FREQUENCIES, STEP_FROM, STEP_HOLD
from hystcomp.experiment.references import triangle_reference
from hystcomp.experiment.tracking import period_samples
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


def run() -> list[dict]:
    """Measure and return one row per figure: name, value, unit, target, ok."""
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
    for row in run():
        print(f"{row['name']}: {row['value']:.4g} {row['unit']} (target {row['target']})")
