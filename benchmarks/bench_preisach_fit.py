"""Preisach compensation identified from any record: tracking error / uncompensated error.

For each simulated actuator (the twin, and twins whose hysteresis is changed so that no
model family matches any of them), record its answer to three kinds of identification
signal: the paper's PI/MPI triangles (``hystcomp excite pi``: first-order curves from 4
maxima only), the paper's Preisach sinusoids (``hystcomp excite preisach``: 24 maxima) and
a band-limited random voltage (random turning points over 0..120 V). Identify a Preisach
model from each, compensate a 1 Hz triangle of 0 .. 90 % of the measured stroke with its
inverse (eq. 10), drive the actuator and score the rms tracking error over the periods after
the first, divided by the uncompensated one (a straight line ``v = x_ref / k_lin`` with the
least-squares gain of the triangle record, as in Table I). Target: below 0.25 everywhere.

Fits: the default (``fit_method="auto"``: the paper's reversal curves for the sinusoids,
least squares with a non-negative density otherwise; cubic Everett polynomial, eq. 5) and
least squares with a 25 x 25 table.

Run alone with ``python benchmarks/bench_preisach_fit.py`` (about a minute).
"""

from __future__ import annotations

from hystcomp import Preisach
from hystcomp.experiment.baseline import LinearCompensator, linear_gain
from hystcomp.experiment.references import triangle_reference
from hystcomp.experiment.tracking import run_tracking
from hystcomp.identify.excitation import (
    random_turning_points,
    sinusoid_sequence,
    triangle_sequence,
)
from hystcomp.plant import Twin, TwinParameters

TARGET = 0.25
ACTUATORS = {
    "twin": TwinParameters(),
    "twin, 18 % hysteresis": TwinParameters(hysteresis_amplitude=3.5),
    "twin, slow Bouc-Wen turn": TwinParameters(bouc_wen_rate=3.0),
    "twin, all changed": TwinParameters(
        hysteresis_amplitude=4.0, bouc_wen_rate=3.0, anhysteretic=(30.0, 20.0, -10.0)
    ),
}
FITS = {
    "default (auto, cubic)": {},
    "least-squares table": {"fit_method": "least-squares", "everett": "table"},
}


def records() -> dict:
    """The three identification signals (V) at the twin's 20 kHz."""
    return {
        "triangles (excite pi)": triangle_sequence()[1],
        "sinusoids (excite preisach)": sinusoid_sequence()[1],
        "random turning points": random_turning_points()[1],
    }


def panel(actuators=ACTUATORS, fits=FITS, seed: int = 0) -> list[dict]:
    """One row per actuator, record and fit: the tracking rms ratio and the fit used."""
    rows = []
    signals = records()
    for actuator, params in actuators.items():
        twin = Twin(params, seed=seed)
        measured = {name: twin.run(v) for name, v in signals.items()}
        v_tri = signals["triangles (excite pi)"]
        x_tri = measured["triangles (excite pi)"]
        baseline = LinearCompensator(linear_gain(v_tri, x_tri), twin.voltage_range)
        _, x_ref = triangle_reference(0.9 * float(x_tri.max()), 1.0, periods=3)
        uncompensated = run_tracking(baseline, twin, x_ref, frequency=1.0).rms
        for record, v in signals.items():
            for fit, options in fits.items():
                model = Preisach(**options).fit(v, measured[record])
                rms = run_tracking(model.inverse(), twin, x_ref, frequency=1.0).rms
                rows.append(
                    {
                        "actuator": actuator,
                        "record": record,
                        "fit": fit,
                        "used": model.fit_report_["fit"],
                        "ratio": rms / uncompensated,
                        "rms_um": rms,
                        "uncompensated_um": uncompensated,
                    }
                )
    return rows


def run() -> list[dict]:
    """The panel as benchmark rows: name, value, unit, target, ok."""
    return [
        {
            "name": f"{r['actuator']} / {r['record']} / {r['fit']} [{r['used']}]",
            "value": r["ratio"],
            "unit": "x uncompensated rms",
            "target": f"< {TARGET}",
            "ok": r["ratio"] < TARGET,
        }
        for r in panel()
    ]


if __name__ == "__main__":
    for row in panel():
        print(
            f"{row['actuator']:26s} {row['record']:28s} {row['fit']:22s} {row['used']:16s} "
            f"{row['ratio']:.3f}  ({row['rms_um']:.3f} / {row['uncompensated_um']:.3f} µm)"
        )
