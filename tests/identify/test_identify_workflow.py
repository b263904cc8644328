"""The library functions behind ``hystcomp identify`` and ``excite``, and ``hystcomp calibrate``."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from hystcomp import presets
from hystcomp.cli import main
from hystcomp.errors import IdentificationError, InvalidParameterError, InvalidTypeError
from hystcomp.identify.dynamics import dynamics_excitation
from hystcomp.identify.excitation import (
    PREISACH_AMPLITUDES,
    excitation_signal,
    scaled_amplitudes,
    sinusoid_sequence,
    triangle_sequence,
)
from hystcomp.identify.scoring import coverage_warning, transient_end
from hystcomp.io.records import Record
from hystcomp.models.dynamics import LinearDynamics
from hystcomp.workflows.identify import (
    IdentificationResult,
    build_estimator,
    identify_record,
)
from hystcomp.workflows.pair import identify_dynamics_record

FS = 1000.0  # Hz


def _loops(seconds: float = 4.0) -> Record:
    """Loops with inner loops over 0..120 V every second, through the paper's MPI model."""
    t = np.arange(round(seconds * FS)) / FS
    v = 60.0 - 40.0 * np.cos(2 * np.pi * t) - 20.0 * np.cos(6 * np.pi * t)
    rng = np.random.default_rng(7)
    x = presets.paper_mpi().simulate(v) + rng.normal(0.0, 0.01, v.size)
    return Record(t, v, x, source="loops")


def test_a_record_in_gives_a_result_with_its_named_fields():
    rec = _loops()
    result = identify_record(rec, "pi", operators=8, holdout=0.25)
    assert isinstance(result, IdentificationResult)
    assert (result.kind, result.label, result.source) == ("pi", "PI", "loops")
    assert result.model.n_operators == 8
    assert (result.n_fit, result.start) == (3000, 0)  # the signal starts at an end (0 V)
    # The stored output is the fitted model's, and the errors are computed from it.
    np.testing.assert_array_equal(result.x_model, result.model.simulate(rec.v[:3000]))
    rms = float(np.sqrt(np.mean((rec.x[:3000] - result.x_model) ** 2)))
    assert result.fit["rms_error_um"] == pytest.approx(rms, rel=1e-9)
    assert result.fit["rms_error_um"] < 0.02 * np.ptp(rec.x)  # PI fits an MPI loop to 2 %
    assert result.holdout["n_holdout"] == 1000
    assert result.holdout["improvement"] > 2.0  # far better than a line on unseen loops
    assert result.tracking["ratio"] < 0.5
    assert result.warnings == []
    assert result.lines[0] == "PI model (8 plays) from loops"
    assert result.lines[2] == "  fitted on: samples 1..3000"
    assert result.lines[-1].startswith("  hold-out:  last 1000 samples (25 %): model rms ")
    assert result.lines[-1].endswith("x better")


def test_an_estimator_given_is_fitted_as_its_kind_would_be():
    rec = _loops(2.0)
    by_kind = identify_record(rec, "pi", operators=6, transient=0.5)
    by_estimator = identify_record(rec, build_estimator("pi", operators=6), transient=0.5)
    assert by_kind.start == by_estimator.start == 500  # 0.5 s at 1 kHz
    assert (
        by_kind.lines[2]
        == "  fitted on: samples 501..2000 (first 500 left out: start-up transient)"
    )
    np.testing.assert_allclose(by_kind.x_model, by_estimator.x_model, rtol=0, atol=1e-12)
    with pytest.raises(InvalidParameterError, match="only with a model kind"):
        identify_record(rec, build_estimator("pi"), operators=6)


def test_a_holdout_beyond_the_fitted_range_is_a_warning():
    _, v = triangle_sequence(sample_rate=FS)  # amplitudes grow: the end reaches 120 V
    rec = Record(np.arange(v.size) / FS, v, presets.paper_mpi().simulate(v))
    result = identify_record(rec, "pi", operators=8, holdout=0.3)
    coverage, beyond = result.warnings  # the fitted part stops on the fall from 90 V, at 36 V
    assert coverage.startswith("after its start-up transient the record never falls over more ")
    assert "than 67 % of its input range" in coverage
    assert beyond.startswith("the hold-out drives 0 .. 120 V, beyond the fitted")
    assert "hystcomp: warning" not in beyond  # the command line adds the prefix


def test_metres_read_as_micrometres_are_a_warning():
    """A record in m read as µm fits (it is clean, only tiny), but a reference in µm would
    then be out of reach at every sample: the result says so, as the command line does."""
    rec = _loops(2.0)
    metres = Record(rec.t, rec.v, rec.x * 1e-6, source="metres.csv")
    result = identify_record(metres, "pi", operators=4)
    assert result.warnings[0].startswith("the displacement in metres.csv spans ")
    assert "looks like metres read as µm; if it is, give --x-unit m" in result.warnings[0]
    assert identify_record(metres, "pi", operators=4, unit_check=False).warnings == []
    assert identify_record(rec, "pi", operators=4).warnings == []


def test_a_record_without_hysteresis_warns_that_a_line_does_as_well():
    rec = _loops(2.0)
    line = Record(rec.t, rec.v, 0.3 * rec.v, source="line")  # a straight line tracks exactly
    result = identify_record(line, "pi", operators=4)
    assert not result.tracking["ratio"] < 1.0
    assert len(result.warnings) == 1
    assert "no better than a straight line" in result.warnings[0]


@pytest.mark.parametrize(
    ("args", "options", "error", "match"),
    [
        (("pi",), {"degree": 3}, InvalidParameterError, "'degree' does not apply to kind='pi'"),
        (("preisach",), {"everett": "table", "degree": 3}, InvalidParameterError, "applies to"),
        (("nosuch",), {}, InvalidParameterError, "'kind' argument"),
        (("pi",), {"voltage_range": (0.0, 200.0)}, InvalidParameterError, "allow_extrapolation"),
        (("pi",), {"holdout": 0.9999}, IdentificationError, "leaves 0 of 2000 samples"),
        (("pi",), {"holdout": 1.5}, InvalidParameterError, "strictly between 0 and 1"),
        (("pi",), {"transient": -1.0}, InvalidParameterError, "'transient' argument"),
        ((object(),), {}, InvalidTypeError, "'model' argument"),
    ],
)
def test_bad_arguments_are_refused_with_a_message_naming_them(args, options, error, match):
    with pytest.raises(error, match=match):
        identify_record(_loops(2.0), *args, **options)


def test_a_wide_voltage_range_is_accepted_when_extrapolation_is_allowed():
    result = identify_record(
        _loops(2.0), "pi", operators=4, voltage_range=(0.0, 150.0), allow_extrapolation=True
    )
    assert result.model.voltage_range_ == (0.0, 150.0)
    said = (  # allowed, and said: the estimate stops at the record's range
        "the voltage range 0 150 V reaches beyond the record's input (0 .. 120 V), as "
        "allowed: the model extrapolates there, and the estimate above does not cover it. "
        "Check the tracking there before relying on it."
    )
    assert result.warnings == [said]
    inside = identify_record(
        _loops(2.0), "pi", operators=4, voltage_range=(0.0, 120.0), allow_extrapolation=True
    )
    assert inside.warnings == []


@pytest.mark.parametrize(
    ("ratio", "says"),
    [(0.79, None), (0.95, "barely better than a straight line (0.95x)"), (1.2, "no better than")],
)
def test_a_compensator_predicted_near_the_straight_line_is_warned_about(monkeypatch, ratio, says):
    """Within 0.8x of a line, a reference unlike the record can lose the margin: said, with
    the other models to try (the record has turning points across the range: no advice to
    record another)."""
    from hystcomp.workflows import identify as workflow

    def estimate(model, v, x, *, start=0):
        return {
            "tracking_rms_um": ratio,
            "baseline_rms_um": 1.0,
            "ratio": ratio,
            "held_out_rms_um": ratio,
            "flatters": False,
        }

    monkeypatch.setattr(workflow, "tracking_estimate", estimate)
    warnings = identify_record(_loops(2.0), "mpi", operators=4, deadzones=4).warnings
    if says is None:
        assert warnings == []
    else:
        assert len(warnings) == 1
        assert f"predicted to track {says}" in warnings[0]
        assert warnings[0].endswith("try the model pi or preisach.")
        assert warnings[0].kind == "line"
        assert (
            warnings[0]
            .worded({"model": "--model {others}"})
            .endswith("try --model pi or preisach.")
        )
        assert "excitation_signal('rich')" not in warnings[0]
        assert "--model" not in warnings[0]  # the library holds no command-line words


def test_a_record_must_be_a_record():
    with pytest.raises(InvalidTypeError, match="'record' argument"):
        identify_record(np.zeros((3, 10)), "pi")


def test_calibrate_prints_the_twins_figures():
    result = CliRunner().invoke(main, ["calibrate"])
    assert result.exit_code == 0, result.output
    lines = result.output.splitlines()
    assert lines[0].startswith("stroke: ")
    stroke = float(lines[0].split()[1])
    assert abs(stroke - 37.0) < 0.5  # the calibration target (µm at 120 V)
    assert "630.00 Hz" in lines[3]
    assert len(lines) == 9


def test_excitation_signal_is_the_papers_signal_scaled_to_the_range():
    t, v = excitation_signal("preisach", sample_rate=200.0, voltage_range=(-10.0, 50.0))
    amplitudes = scaled_amplitudes(PREISACH_AMPLITUDES, voltage_range=(-10.0, 50.0))
    t_ref, v_ref = sinusoid_sequence(amplitudes, sample_rate=200.0, v_min=-10.0)
    np.testing.assert_array_equal(t, t_ref)
    np.testing.assert_array_equal(v, v_ref)
    assert (float(v.min()), float(v.max())) == (-10.0, 50.0)
    with pytest.raises(InvalidParameterError, match="'kind' argument of excitation_signal"):
        excitation_signal("nosuch")


def test_dynamics_from_a_record_with_its_report_lines():
    true = LinearDynamics.from_parameters(
        sample_rate=20_000.0,
        resonance_hz=780.0,
        damping_ratio=0.05,
        creep_time_constants=[0.004, 0.04, 0.4, 2.0],
        creep_weights=[0.0075] * 4,
    )
    t, v = dynamics_excitation()
    x = 0.3 * true.simulate(v, initial=0.0) + 0.003 * np.random.default_rng(7).standard_normal(
        v.size
    )
    result = identify_dynamics_record(Record(t, v, x, source="stage"))
    assert result.model.resonance_hz_ == pytest.approx(780.0, rel=0.005)
    assert result.lines[0] == "linear dynamics (creep and first resonance) from stage"
    assert result.lines[2].startswith(f"  resonance: {result.model.resonance_hz_:.5g} Hz, ")
    assert len(result.lines) == 6
    assert result.warnings == []


def test_dynamics_report_a_rig_s_latency():
    true = LinearDynamics.from_parameters(
        sample_rate=20_000.0, resonance_hz=780.0, damping_ratio=0.05, delay_samples=3
    )
    t, v = dynamics_excitation()
    result = identify_dynamics_record(Record(t, v, 0.3 * true.simulate(v), source="late"))
    assert result.model.delay_samples_ == 3
    assert "  latency:   +3 samples beside the sample-and-hold's one (+150 µs)" in result.lines[3]
    assert result.warnings == []


def test_dynamics_without_a_resonance_are_a_warning():
    """A stage whose dynamics are a first-order lag (1.5 ms) has no resonance to find: the
    fit's damping ratio hits its bound, and the report says so rather than offering the
    inverse as if it fitted."""
    t, v = dynamics_excitation()
    fs = 20_000.0
    a = np.exp(-1.0 / (0.0015 * fs))
    x = np.empty_like(v)
    state = v[0]
    for k, u in enumerate(v):  # x[k] = a x[k-1] + (1 - a) v[k]
        state = a * state + (1.0 - a) * u
        x[k] = 0.3 * state
    result = identify_dynamics_record(Record(t, v, x, source="lag"))
    (warning,) = result.warnings
    assert "finds no resonance in it (the damping ratio is at its bound, 2)" in warning
    assert "compare compensate with and without the dynamics" in warning


@pytest.mark.parametrize("kind", ["mpi", "pi", "preisach", "rich"])
def test_the_excitations_cover_what_a_reference_does(kind):
    """hystcomp's own identification signals rise and fall over the whole range and turn
    inside it: no coverage warning."""
    _, v = excitation_signal(kind, sample_rate=FS)
    assert coverage_warning(v, transient_end(v)) is None


def test_a_record_that_drifts_across_the_range_once_is_a_warning():
    """A random walk from the top of the range down to its bottom: its rises stay short
    (minor loops wiped out), so the rising branches of the model are a guess; a single loop
    turns only at the ends. Both are said, with what to record instead."""
    rng = np.random.default_rng(3)
    steps = np.repeat(rng.normal(-0.4, 3.0, 400), 20)  # drifts down with small turns
    v = np.clip(120.0 + np.cumsum(steps) / 20.0, 0.0, 120.0)
    v = 120.0 * (v - v.min()) / np.ptp(v)
    rec = Record(np.arange(v.size) / FS, v, presets.paper_mpi().simulate(v))
    warning = identify_record(rec, "pi", operators=8).warnings[-1]
    assert warning.startswith("after its start-up transient the record never rises over more")
    assert warning.kind == "coverage"
    assert (
        "Record swings across the whole range in both directions "
        "(hystcomp.identify.excitation.excitation_signal('rich')" in warning
    )
    assert "(hystcomp excite rich, " in warning.worded({"excite_rich": "hystcomp excite rich"})
    loop = np.r_[np.linspace(0.0, 120.0, 500), np.linspace(120.0, 0.0, 500)]
    once = Record(np.arange(loop.size) / FS, loop, presets.paper_mpi().simulate(loop))
    warning = identify_record(once, "pi", operators=8).warnings[-1]
    assert warning.startswith("the record turns back only at the ends of its input range")


def test_the_coverage_warning_ignores_dither_and_a_start_mid_range():
    """Reversals smaller than 5 % of the span are no minor loops (a dithered single loop
    still warns), and a record that starts mid-range is judged from the swings it makes,
    not from where its start-up transient ends (the paper's triangles after a ramp from
    40 V do not warn)."""
    rng = np.random.default_rng(2)
    loop = np.r_[np.linspace(0.0, 120.0, 4000), np.linspace(120.0, 0.0, 4000)]
    dithered = loop + 2.0 * np.sin(np.arange(loop.size) / 3.0) + rng.normal(0.0, 0.2, loop.size)
    assert coverage_warning(dithered).startswith("the record turns back only at the ends")
    levels = [40.0, 120.0, 0.0, 60.0, 40.0, 120.0, 0.0]  # its one full rise wipes a loop out
    started_mid = np.interp(np.linspace(0, 6, 7000), np.arange(7), levels)
    assert transient_end(started_mid) < np.argmax(started_mid)  # on the rise, before the top
    assert coverage_warning(started_mid, transient_end(started_mid)) is None


def test_an_unknown_option_or_progress_is_refused_by_name():
    rec = _loops(1.0)
    with pytest.raises(InvalidParameterError, match="n_operators is called 'operators' here"):
        identify_record(rec, "pi", n_operators=4)
    with pytest.raises(InvalidTypeError, match="'progress' argument of identify_record"):
        identify_record(rec, "pi", progress=5)
