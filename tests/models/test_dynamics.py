"""The linear dynamics (creep, resonance): identification, stable inverse, composition, C."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import hystcomp
from hystcomp._lti import resonance_zoh
from hystcomp.cli import main
from hystcomp.errors import (
    HystcompWarning,
    IdentificationError,
    InvalidParameterError,
    InvalidTypeError,
)
from hystcomp.identify.dynamics import dynamics_excitation
from hystcomp.io.records import read_table, write_table
from hystcomp.models.dynamic_compensator import MAX_PREVIEW
from hystcomp.models.dynamics import DynamicCompensator, LinearDynamics
from hystcomp.models.hammerstein import HammersteinModel, fit_pair
from hystcomp.plant import Twin, creep_twin
from tests.codegen.test_codegen import CC, _compile, _run_c, _step_python, needs_cc
from tests.conftest import random_walk

FS = 20_000.0


def _stage(**changes):
    """A known linear stage: 780 Hz, zeta 0.05, 3 % creep on a grid unlike the fit's."""
    params = {
        "sample_rate": FS,
        "resonance_hz": 780.0,
        "damping_ratio": 0.05,
        "creep_time_constants": [0.004, 0.04, 0.4, 2.0],
        "creep_weights": [0.0075] * 4,
    }
    return LinearDynamics.from_parameters(**{**params, **changes})


def _pair(model, dynamics, **options):
    """The compensator of ``model`` and ``dynamics`` taken as one pair."""
    return HammersteinModel(model, dynamics).inverse(**options)


@pytest.fixture(scope="module")
def identified():
    """The known stage identified from its noisy answer (gain 0.3 µm/V) to the excitation."""
    true = _stage()
    _, v = dynamics_excitation()
    rng = np.random.default_rng(7)
    x = 0.3 * true.simulate(v, initial=0.0) + 0.003 * rng.standard_normal(v.size) - 5.0
    return true, LinearDynamics().fit(v, x, FS)


def test_identification_recovers_the_frequency_response(identified):
    true, fit = identified
    f = np.geomspace(1.0, 2.0 * 780.0, 200)
    error = np.abs(fit.frequency_response(f) / true.frequency_response(f) - 1.0)
    assert error.max() < 0.03  # 3 % of the response, 1 Hz to twice the resonance
    assert fit.resonance_hz_ == pytest.approx(780.0, rel=0.005)
    assert fit.damping_ratio_ == pytest.approx(0.05, rel=0.05)
    assert fit.fit_report_["fit_percent"] > 97.0


def test_identification_recovers_the_creep_after_a_step(identified):
    true, fit = identified
    for seconds in (0.01, 0.1, 1.0):
        assert fit.creep_fraction(seconds) == pytest.approx(true.creep_fraction(seconds), abs=0.002)


def test_unit_steady_state_gain(identified):
    _, fit = identified
    assert abs(fit.frequency_response([0.0])[0]) == pytest.approx(1.0, abs=1e-12)
    step = fit.simulate(np.r_[0.0, np.ones(400_000)], initial=0.0)
    assert step[-1] == pytest.approx(1.0, abs=1e-3)


def test_resonance_zoh_is_the_exact_discretisation():
    from scipy.linalg import expm

    for fn, zeta in [(630.0, 0.1), (780.0, 0.05), (300.0, 1.0), (300.0, 2.0)]:
        wn = 2 * np.pi * fn
        m = np.zeros((3, 3))
        m[0, 1] = 1.0
        m[1, :] = [-(wn**2), -2 * zeta * wn, wn**2]
        d = expm(m / FS)
        b, a = resonance_zoh(fn, zeta, FS)
        np.testing.assert_allclose(a, [1.0, -np.trace(d[:2, :2]), np.linalg.det(d[:2, :2])])
        np.testing.assert_allclose(b.sum() / a.sum(), 1.0, rtol=1e-12)


@pytest.mark.parametrize(
    ("f", "limit"), [(1.0, 0.005), (10.0, 0.005), (100.0, 0.005), (200.0, 0.015)]
)
def test_inverse_then_forward_is_the_identity_in_band(f, limit):
    dyn = _stage()
    inverse = dyn.inverse(rest=3.0)
    t = np.arange(round(2.0 * FS)) / FS
    x = 3.0 + 5.0 * np.sin(2 * np.pi * f * t)
    y = inverse.simulate(x)
    back = dyn.simulate(y, initial=3.0)
    inner = slice(round(0.1 * FS), -2 * inverse.preview)
    # of the amplitude: non-negative taps leave an error growing as f^4 (1.2 % at 200 Hz)
    assert np.abs(back - x)[inner].max() < limit * 5.0


def test_inverse_is_stable_for_any_resonance_and_creep():
    rng = np.random.default_rng(3)
    for _ in range(20):
        dyn = _stage(
            resonance_hz=rng.uniform(50.0, 9000.0),
            damping_ratio=rng.uniform(0.005, 3.0),
            creep_time_constants=[0.001, 0.01, 0.05, 0.2],
            creep_weights=rng.uniform(0.0, 0.5, 4),
        )
        y = dyn.inverse().simulate(np.r_[np.zeros(50), np.ones(40_000)])
        assert np.all(np.isfinite(y))
        assert abs(y[-1] - 1.0) < 0.05  # it settles: no growing mode
        assert np.abs(y).max() < 1e3


@pytest.mark.parametrize("kept_as", ["deepcopy", "pickle"])
def test_the_inverse_is_designed_once_per_resonance_and_band(kept_as, monkeypatch):
    import copy
    import pickle

    from hystcomp.models import dynamics as dynamics_module

    dyn = _stage()
    first = dyn.inverse()
    kept = copy.deepcopy(dyn) if kept_as == "deepcopy" else pickle.loads(pickle.dumps(dyn))
    designs = []
    original = dynamics_module.inverse_fir
    monkeypatch.setattr(
        dynamics_module, "inverse_fir", lambda *a: designs.append(a) or original(*a)
    )
    np.testing.assert_array_equal(kept.inverse().taps, first.taps)  # kept, not designed again
    assert designs == []
    kept.inverse(bandwidth_hz=500.0)  # another band: designed
    kept.resonance_hz_ = 700.0  # another resonance: designed, never the old design
    moved = kept.inverse()
    assert len(designs) == 2
    np.testing.assert_array_equal(moved.taps, _stage(resonance_hz=700.0).inverse().taps)
    assert dyn.inverse().taps is not first.taps  # each inverse owns its taps


def test_inverse_of_a_step_rises_monotonically_and_never_amplifies():
    rng = np.random.default_rng(5)
    for _ in range(20):
        dyn = _stage(
            resonance_hz=rng.uniform(50.0, 9000.0),
            damping_ratio=rng.uniform(0.005, 3.0),
            creep_time_constants=(),
            creep_weights=(),
        )
        inverse = dyn.inverse()
        assert inverse.taps.min() >= 0.0
        assert inverse.taps.sum() == pytest.approx(1.0, abs=1e-12)
        assert 0 <= inverse.preview <= MAX_PREVIEW
        y = inverse.simulate(np.r_[np.zeros(100), np.ones(2000)])
        assert np.diff(y).min() >= -1e-12  # no overshoot, no dip: no minor loop downstream
        f = np.linspace(0.0, 0.5 * FS, 501)
        gain = np.abs(
            np.exp(-2j * np.pi * np.outer(f / FS, np.arange(inverse.taps.size))) @ inverse.taps
        )
        assert gain.max() <= 1.0 + 1e-12


def _bench_dynamics():
    path = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_dynamics.py"
    spec = importlib.util.spec_from_file_location("bench_dynamics", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize(("resonance_hz", "damping_ratio"), [(630.0, 0.1), (780.0, 0.05)])
def test_the_inverse_is_the_best_monotone_one_on_slow_triangles(resonance_hz, damping_ratio):
    """docs/dynamics.md: the FIR is within 1 % of the best FIR with a monotone step response
    on a triangle at f_n / 6, and no FIR of that class beats the optimum; letting the step
    response turn back lowers the least error, and more so the further."""
    bench = _bench_dynamics()
    dyn = _stage(resonance_hz=resonance_hz, damping_ratio=damping_ratio)
    frequency = resonance_hz / 6.0
    ours = bench.fir_floor(dyn, 30.0, frequency)
    floors = [bench.best_floor(dyn, 30.0, frequency, turn) for turn in (0.0, 0.05, 0.5)]
    assert floors[0] * (1.0 - 1e-6) <= ours <= 1.01 * floors[0]
    assert floors[0] > 1.3 * floors[1] > 1.3 * floors[2]


def test_matching_leaves_its_centre_in_place_and_scales_about_it():
    dyn = _stage(creep_time_constants=[0.004, 0.4], creep_weights=[0.015, 0.015])
    gain = abs(dyn.frequency_response([1.0])[0])
    inverse = dyn.inverse(rest=0.0, match_hz=1.0, match_centre=10.0)
    held = inverse.simulate(np.r_[np.zeros(100), np.full(400_000, 10.0)])
    assert held[-1] == pytest.approx(10.0, abs=1e-9)
    top = inverse.simulate(np.r_[np.zeros(100), np.full(400_000, 20.0)])
    assert top[-1] == pytest.approx(10.0 + 10.0 * gain, abs=1e-9)
    assert gain < 0.995  # so that the two cases differ


@pytest.mark.parametrize("delay", [-1, 1, 3, 17])
def test_a_rig_s_latency_is_identified_and_looked_ahead_by_the_inverse(delay):
    """A record whose displacement answers `delay` samples later than the sample-and-hold
    (converters, filters; -1: in the same sample): the fit finds the latency and the
    resonance as without it, and the inverse looks that much further ahead, so that the
    stage still follows a 100 Hz sine in band. Before, one sample of latency made the fit
    fail ("the step of the record gives no displacement")."""
    _, v = dynamics_excitation()
    x_ref = 3.0 + 5.0 * np.sin(2 * np.pi * 100.0 * np.arange(round(0.5 * FS)) / FS)
    inner = slice(2000, -100)
    true = _stage(delay_samples=delay)
    x = 0.3 * true.simulate(v, initial=0.0) + 0.003 * np.random.default_rng(5).normal(size=v.size)
    fit = LinearDynamics().fit(v, x, FS)
    assert fit.delay_samples_ == delay
    assert fit.resonance_hz_ == pytest.approx(780.0, rel=0.005)
    inverse = fit.inverse(rest=3.0)
    assert inverse.preview == _stage().inverse().preview + delay
    back = true.simulate(inverse.simulate(x_ref), initial=3.0)
    # (a latency of 3 samples left in would cost 0.47 µm here)
    assert np.abs(back - x_ref)[inner].max() < 0.015 * 5.0
    # the inverse of the true model: the latency inverted exactly
    exact = {d: _stage(delay_samples=d) for d in (0, delay)}
    errors = [
        np.abs(m.simulate(m.inverse(rest=3.0).simulate(x_ref), initial=3.0) - x_ref)[inner]
        for m in exact.values()
    ]
    np.testing.assert_allclose(errors[1], errors[0], atol=1e-4)


def test_latency_in_simulate_and_the_frequency_response():
    plain, late = _stage(), _stage(delay_samples=4)
    u = np.r_[np.zeros(10), np.ones(200)]
    np.testing.assert_array_equal(late.simulate(u), np.r_[np.zeros(4), plain.simulate(u)[:-4]])
    early = _stage(delay_samples=-1).simulate(u)
    np.testing.assert_allclose(early[:-1], plain.simulate(u)[1:], rtol=0, atol=1e-15)
    f = np.array([10.0, 780.0, 3000.0])
    shift = np.exp(-2j * np.pi * f * 4 / FS)
    np.testing.assert_allclose(late.frequency_response(f), plain.frequency_response(f) * shift)
    with pytest.raises(InvalidParameterError, match=r"'delay_samples'.*<= 32"):
        _stage(delay_samples=33)


def test_model_file_round_trip(identified, tmp_path):
    _, fit = identified
    hystcomp.save_model(fit, tmp_path / "dyn.json")
    doc = json.loads((tmp_path / "dyn.json").read_text())
    assert (doc["format"], doc["version"], doc["kind"]) == ("hystcomp-model", 1, "dynamics")
    back = hystcomp.load_model(tmp_path / "dyn.json")
    assert isinstance(back, LinearDynamics)
    f = np.array([0.0, 10.0, 780.0, 3000.0])
    np.testing.assert_array_equal(back.frequency_response(f), fit.frequency_response(f))
    assert back.fit_report_ == fit.fit_report_
    # a file written before the latency existed reads as none
    del doc["parameters"]["delay_samples"]
    (tmp_path / "old.json").write_text(json.dumps(doc))
    assert hystcomp.load_model(tmp_path / "old.json").delay_samples_ == 0


def test_bad_parameters_are_refused():
    with pytest.raises(InvalidParameterError, match="resonance_hz"):
        _stage(resonance_hz=12_000.0)
    with pytest.raises(InvalidParameterError, match="weights >= 0"):
        _stage(creep_weights=[0.01, -0.01, 0.0, 0.0])
    # poles that double precision cannot resolve (a hand-edited file): refused, not a crash
    with pytest.raises(InvalidParameterError, match=r"'resonance_hz' .* at least 1e-06"):
        _stage(resonance_hz=1e-300)
    for zeta in (1e-300, 1e6):
        with pytest.raises(InvalidParameterError, match=r"'damping_ratio' .* 1e-06 \.\. 1000"):
            _stage(damping_ratio=zeta)
    for fn, zeta in ((0.02, 0.1), (630.0, 1e-6), (630.0, 1e3)):  # the ends work
        v = _pair(hystcomp.presets.paper_mpi(), _stage(resonance_hz=fn, damping_ratio=zeta))
        assert np.isfinite(v.simulate(np.linspace(5.0, 30.0, 500))).all()
    with pytest.raises(InvalidParameterError, match="bandwidth_hz"):
        _stage().inverse(bandwidth_hz=10_000.0)
    with pytest.raises(InvalidTypeError, match="LinearDynamics"):
        hystcomp.presets.paper_mpi().inverse(dynamics="dyn.json")
    with pytest.raises(IdentificationError, match=r"excitation_signal\('dynamics'\)"):
        LinearDynamics().fit(np.r_[np.zeros(10), np.ones(100)], np.zeros(110), FS)


# -- the compensator in series -----------------------------------------------------------


@pytest.fixture(params=["mpi", "preisach"])
def compensator(request):
    if request.param == "mpi":
        model = hystcomp.presets.paper_mpi()
    else:
        twin = Twin(creep_twin(sensor_noise=0.0))
        from hystcomp.identify.excitation import PI_AMPLITUDES, sinusoid_sequence

        _, v = sinusoid_sequence(PI_AMPLITUDES, sample_rate=FS)
        model = hystcomp.Preisach(everett="polynomial").fit(v, twin.run(v))
    return _pair(model, _stage(), slew_rate=2e5)


def _wild_reference(comp, n=8000):
    rng = np.random.default_rng(11)
    lo, hi = comp.dynamics_inverse.output_range
    span = hi - lo
    return random_walk(rng, n, lo - 0.3 * span, hi + 0.3 * span, span / 30)


def test_stepper_equals_batch(compensator):
    x = _wild_reference(compensator)
    batch = compensator.simulate(x)
    s = compensator.stepper()
    d = compensator.preview
    s.prime(x[:d])
    streamed = np.array([s.step(u) for u in np.r_[x[d:], np.full(d, x[-1])]])
    np.testing.assert_array_equal(streamed, batch)  # the same kernels: bit for bit
    s.reset()
    s.prime(x[:d])
    np.testing.assert_array_equal(s.step_block(np.r_[x[d:], np.full(d, x[-1])]), batch)
    # the generated C has no prime: it starts `preview` samples early, applying those
    # outputs (docs/c-export.md); the slew limit holds throughout, and once it no longer
    # binds on the start (a few samples here) the voltages are the batch run's
    s.reset()
    stepped = s.step_block(np.r_[x, np.full(d, x[-1])])
    assert np.abs(np.diff(np.r_[compensator.stepper().last_output, stepped])).max() <= (
        compensator.max_step * (1 + 1e-12)
    )
    np.testing.assert_allclose(stepped[d + 5 :], batch[5:], rtol=0, atol=1e-9)


def test_the_step_is_one_compiled_call_and_the_block_run_bit_for_bit(compensator):
    """``step`` calls the filter and the hysteresis compensator in one compiled kernel
    (behind the type test of the sample); it gives the block run's bits, counts a sample
    out of reach once, and holds on a non-finite reference."""
    from hystcomp._kernels import dynamics as dk
    from hystcomp._kernels._jit import step_function

    x = _wild_reference(compensator, n=6000)
    x[[100, 2000, 2001, 4000]] = [np.nan, np.inf, -np.inf, 1e308]  # the last one clamped
    s = compensator.stepper()
    assert s.step.func is step_function(dk.PAIR_STEPS[s._hyst.kernels.step], arrays=2)
    streamed = [s.step(u) for u in x]
    block = compensator.stepper()
    assert np.array_equal(streamed, block.step_block(x))
    assert (s.clamped_count, s.nonfinite_count) == (block.clamped_count, block.nonfinite_count)
    assert s.nonfinite_count == 3
    assert 500 < s.clamped_count < x.size - 500
    assert streamed[100] == streamed[99]  # held


def test_output_clamped_and_slew_limited(compensator):
    x = _wild_reference(compensator)
    v = compensator.simulate(x)
    lo, hi = compensator.voltage_range
    assert lo <= v.min()
    assert v.max() <= hi
    assert np.abs(np.diff(v)).max() <= compensator.max_step * (1 + 1e-12)
    assert compensator.max_step == pytest.approx(2e5 / FS)


def test_a_reference_out_of_reach_is_counted_once_per_sample():
    model = hystcomp.presets.paper_mpi()
    comp = _pair(model, _stage())
    low, high = comp.dynamics_inverse.output_range
    inside = np.full(3000, 0.5 * (low + high))
    assert comp.run(inside).clamped == 0
    for beyond in (low - 50.0, high + 50.0):
        result = comp.run(np.r_[inside, np.full(2000, beyond)])
        assert 1990 <= result.clamped <= 2000 + comp.preview  # the filter's look-ahead
        s = comp.stepper()
        s.prime(np.full(comp.preview, inside[0]))
        s.step_block(np.r_[inside[comp.preview :], np.full(2000 + comp.preview, beyond)])
        assert s.clamped_count == result.clamped


def test_nonfinite_reference_holds_the_voltage():
    comp = _pair(hystcomp.presets.paper_mpi(), _stage())
    s = comp.stepper()
    first = [s.step(u) for u in np.linspace(0.0, 10.0, 50)]
    held = s.step(np.nan)
    assert held == first[-1]
    assert s.nonfinite_count == 1
    copy = s.copy()
    assert copy.step(10.0) == s.step(10.0)


@needs_cc
@pytest.mark.skipif(CC is None, reason="no C compiler")
def test_c_matches_the_stepper(compensator, tmp_path):
    x = _wild_reference(compensator, n=6000)
    x[[100, 4100, 5000, 5001]] = [np.nan, np.nan, np.inf, -np.inf]
    drive = _compile(compensator, tmp_path, "stage_x")
    v_c, held = _run_c(drive, x, reset_at=4000)
    v_py = _step_python(compensator, x, reset_at=4000)
    np.testing.assert_allclose(v_c, v_py, rtol=0, atol=1e-9)
    assert held == 3
    header = (tmp_path / "stage_x.h").read_text()
    assert f"{compensator.preview} samples ahead" in header


@needs_cc
def test_c_without_creep_matches_the_stepper(tmp_path):
    dyn = LinearDynamics.from_parameters(sample_rate=FS, resonance_hz=630.0, damping_ratio=0.1)
    comp = _pair(hystcomp.presets.paper_mpi(), dyn)
    x = _wild_reference(comp, n=3000)
    drive = _compile(comp, tmp_path, "no_creep")
    v_c, _ = _run_c(drive, x)
    s = comp.stepper()
    np.testing.assert_allclose(v_c, [s.step(u) for u in x], rtol=0, atol=1e-9)
    assert comp.preview == 8  # half the taps' span, documented in docs/dynamics.md


@pytest.fixture(scope="module")
def creep_stage_pair():
    """The MPI model of the paper's triangles and the dynamics of a 780 Hz, zeta 0.05, 3 %
    creep stage, identified as one pair; the stage itself to track on."""
    from hystcomp.identify.excitation import triangle_sequence

    twin = Twin(creep_twin(resonance_hz=780.0, damping_ratio=0.05), seed=1)
    _, v_d = dynamics_excitation()
    _, v = triangle_sequence(sample_rate=FS)
    pair = fit_pair(
        hystcomp.ModifiedPrandtlIshlinskii(), v, twin.run(v), v_d, twin.run(v_d), sample_rate=FS
    )
    return twin, pair


def test_the_pair_finds_the_stage_s_dynamics_through_its_hysteresis(creep_stage_pair):
    """Behind the hysteresis model, the large multisine shows the stage's own resonance;
    the alternation ends within its rounds."""
    _, pair = creep_stage_pair
    assert pair.dynamics.resonance_hz_ == pytest.approx(780.0, rel=0.02)
    assert pair.dynamics.damping_ratio_ == pytest.approx(0.05, rel=0.2)
    assert 0.01 < pair.dynamics.creep_fraction(0.0) < 0.04  # 3 % over 1 ms .. 100 s
    assert pair.fit_report_["rounds"] <= 3
    assert pair.fit_report_["changes"][-1] < 1e-3


def test_the_pair_tracks_fast_triangles_and_never_slow_ones_worse(creep_stage_pair):
    """The targets of the pair on the creep stage: 100 Hz within 0.3x of the hysteresis
    inverse alone and 2x its 1 Hz error, 200 Hz within 0.35x, 1 Hz no worse than 1.1x the
    better of the two; after a step the creep drift is (nearly) gone."""
    from hystcomp.experiment.references import triangle_reference
    from hystcomp.experiment.tracking import run_tracking

    twin, pair = creep_stage_pair
    compensators = {"alone": pair.hysteresis_alone_.inverse(), "pair": pair.inverse()}
    rms = {}
    for name, comp in compensators.items():
        for f in (1.0, 100.0, 200.0):
            _, x_ref = triangle_reference(
                30.0, f, periods=2 if f == 1.0 else 6, sample_rate=FS, offset=1.5
            )
            rms[name, f] = run_tracking(comp, twin, x_ref, frequency=f).rms
    assert rms["pair", 100.0] <= 0.3 * rms["alone", 100.0]
    assert rms["pair", 100.0] <= 2.0 * rms["alone", 1.0]
    assert rms["pair", 200.0] <= 0.35 * rms["alone", 200.0]
    assert rms["pair", 1.0] <= 1.1 * min(rms["alone", 1.0], rms["pair", 1.0])
    n0, hold = round(0.1 * FS), round(3.0 * FS)
    for height in (8.0, 16.0, 24.0):
        x_ref = np.r_[np.full(n0, 3.0), np.full(hold, height)]
        drift, error = {}, {}
        for name, comp in compensators.items():
            e = (twin.run(comp.simulate(x_ref)) - x_ref)[n0 + round(0.02 * FS) :]
            drift[name] = np.mean(e[-200:]) - np.mean(e[:200])
            error[name] = np.mean(np.abs(e))
        assert abs(drift["alone"]) > 0.05  # the stage creeps
        assert abs(drift["pair"]) < 0.3 * abs(drift["alone"])
        assert error["pair"] < 0.9 * error["alone"]


def test_dynamics_identified_apart_are_warned_about_and_matched_at_1_hz():
    """model.inverse(dynamics=dyn): the two were not identified together; the composition
    still works as before (matched at 1 Hz), with a warning that says how to pair them."""
    dyn = _stage()
    with pytest.warns(HystcompWarning, match="identified apart.*identify_pair_record"):
        comp = hystcomp.presets.paper_mpi().inverse(dynamics=dyn)
    gain = abs(dyn.frequency_response([1.0])[0])
    paired = _pair(hystcomp.presets.paper_mpi(), dyn)
    assert comp.dynamics_inverse.taps.sum() == pytest.approx(gain)
    assert paired.dynamics_inverse.taps.sum() == pytest.approx(1.0)


# -- command line --------------------------------------------------------------------------


def test_cli_round_trip(tmp_path):
    run = CliRunner().invoke
    twin = Twin(creep_twin(resonance_hz=780.0, damping_ratio=0.05), seed=2)
    for kind in ("dynamics", "mpi"):
        assert run(main, ["excite", kind, "-o", str(tmp_path / f"{kind}.csv")]).exit_code == 0
        signal = read_table(tmp_path / f"{kind}.csv", ("v",))
        record = {"t": signal["t"], "v": signal["v"], "x": twin.run(signal["v"])}
        write_table(tmp_path / f"{kind}-rec.csv", record)
    pair_file = str(tmp_path / "pair.json")
    result = run(
        main,
        ["identify", str(tmp_path / "mpi-rec.csv"), "--model", "mpi", "--dynamics-record",
         str(tmp_path / "dynamics-rec.csv"), "-o", pair_file],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "paired with linear dynamics from" in result.output
    assert "resonance: 7" in result.output
    assert "H alone (µm)" in result.output
    pair = hystcomp.load_model(pair_file)
    assert isinstance(pair, HammersteinModel)
    estimates = pair.fit_report_["tracking_estimates"]
    assert set(estimates) == {"1", "10", "100", "200"}
    assert estimates["100"]["pair_um"] < 0.5 * estimates["100"]["alone_um"]
    t = np.arange(4000) / FS
    x_ref = 15.0 + 10.0 * np.sin(2 * np.pi * 100 * t)
    write_table(tmp_path / "ref.csv", {"t": t, "x": x_ref})
    args = ["compensate", pair_file, str(tmp_path / "ref.csv")]
    out = tmp_path / "v.csv"
    result = run(main, [*args, "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "samples of look-ahead" in result.output
    assert "warning" not in result.output  # a 100 Hz reference: the pair is the better
    np.testing.assert_allclose(read_table(out, ("v",))["v"], pair.inverse().simulate(x_ref))
    # a logger's time column: 1 µs of jitter on each 50 µs step is the same rate
    jitter = t + 1e-6 * np.random.default_rng(3).uniform(-1.0, 1.0, t.size)
    write_table(tmp_path / "jitter.csv", {"t": jitter, "x": 15.0 + np.zeros(t.size)})
    result = run(main, ["compensate", pair_file, str(tmp_path / "jitter.csv"), "-o", str(out)])
    assert result.exit_code == 0, result.output
    # out of reach with the dynamics: counted and warned about, refused with --strict
    far = 15.0 + 30.0 * np.sin(2 * np.pi * 10 * t)
    write_table(tmp_path / "far.csv", {"t": t, "x": far})
    far_args = ["compensate", pair_file, str(tmp_path / "far.csv"), "-o",
                str(tmp_path / "far-v.csv")]  # fmt: skip
    result = run(main, far_args)
    assert result.exit_code == 0, result.output
    low, high = pair.reachable_range()
    beyond = np.count_nonzero((far < low) | (far > high))
    counted = int(result.output.split("hystcomp: warning: ")[1].split(" of ")[0])
    assert 0.9 * beyond <= counted <= t.size
    assert f"{counted} clamped" in result.output
    (tmp_path / "far-v.csv").unlink()
    refused = run(main, [*far_args, "--strict"])
    assert refused.exit_code == 2
    assert "out of reach" in refused.output
    assert not (tmp_path / "far-v.csv").exists()
    # the pair's model at its own rate: simulate runs D[H[v]]
    sim = tmp_path / "sim.csv"
    result = run(main, ["simulate", pair_file, str(tmp_path / "dynamics-rec.csv"), "-o", str(sim)])
    assert result.exit_code == 0, result.output
    np.testing.assert_allclose(
        read_table(sim, ("x",))["x"],
        pair.simulate(read_table(tmp_path / "dynamics-rec.csv", ("v",))["v"]),
    )
    # the dynamics on their own, and put in series with a model identified apart: warned
    result = run(
        main,
        ["identify", str(tmp_path / "dynamics-rec.csv"), "--model", "dynamics", "-o",
         str(tmp_path / "dyn.json"), "--plot", str(tmp_path / "bode.png")],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "resonance: 7" in result.output
    assert (tmp_path / "bode.png").stat().st_size > 1000
    hystcomp.save_model(hystcomp.presets.paper_mpi(), tmp_path / "mpi.json")
    apart = ["compensate", str(tmp_path / "mpi.json"), str(tmp_path / "ref.csv"), "--dynamics",
             str(tmp_path / "dyn.json"), "-o", str(tmp_path / "apart.csv")]  # fmt: skip
    result = run(main, apart)
    assert result.exit_code == 0, result.output
    assert "hystcomp: warning: the hysteresis model and the dynamics were identified apart" in (
        result.output
    )
    (tmp_path / "apart.csv").unlink()
    refused = run(main, [*apart, "--strict"])
    assert refused.exit_code == 2
    assert "identified apart" in refused.output
    assert not (tmp_path / "apart.csv").exists()
    # a reference at another rate, a dynamics file as the model, a model as --dynamics, a
    # pair with --dynamics: exit 2, nothing written
    write_table(tmp_path / "slow.csv", {"t": 2 * t, "x": np.full(t.size, 10.0)})
    bad = run(main, ["compensate", pair_file, str(tmp_path / "slow.csv"), "-o",
                     str(tmp_path / "s.csv")])  # fmt: skip
    assert bad.exit_code == 2
    assert "10000 Hz" in bad.output
    bad = run(main, ["compensate", str(tmp_path / "dyn.json"), str(tmp_path / "ref.csv"),
                     "-o", str(tmp_path / "bad.csv")])  # fmt: skip
    assert bad.exit_code == 2
    assert "--dynamics" in bad.output
    bad = run(main, ["compensate", str(tmp_path / "mpi.json"), str(tmp_path / "ref.csv"),
                     "--dynamics", str(tmp_path / "mpi.json"), "-o", str(tmp_path / "b.csv")])  # fmt: skip
    assert bad.exit_code == 2
    assert "not linear dynamics" in bad.output
    bad = run(
        main, [*args, "--dynamics", str(tmp_path / "dyn.json"), "-o", str(tmp_path / "b.csv")]
    )
    assert bad.exit_code == 2
    assert "Drop --dynamics" in bad.output
    assert not (tmp_path / "b.csv").exists()
    result = run(main, ["export-c", pair_file, "-o", str(tmp_path / "c")])
    assert result.exit_code == 0, result.output
    assert "samples ahead" in (tmp_path / "c" / "hystcomp_compensator.h").read_text()
    result = run(main, ["export-c", pair_file, "--fs", "10000", "-o", str(tmp_path / "c2")])
    assert result.exit_code == 2
    assert "--fs" in result.output


def test_excite_dynamics_layout():
    from hystcomp.identify.dynamics import record_layout

    t, v = dynamics_excitation(sample_rate=10_000.0, voltage_range=(-10.0, 10.0))
    assert t[1] == pytest.approx(1e-4)
    assert v[0] == -10.0
    assert v[round(0.3 * 10_000)] == 0.0
    layout = record_layout(v, 10_000.0)
    assert (layout.step, layout.multisine, layout.periods) == (2000, 32000, 3)
    multisine = v[layout.multisine : layout.multisine + 3 * 10_000]
    assert np.abs(multisine).max() == pytest.approx(5.0)  # a quarter of the range
    assert [tri.frequency for tri in layout.triangles] == [1.0, 10.0, 100.0, 200.0]
    for tri in layout.triangles:  # over 5-90 % of the range, whole periods
        part = v[tri.start : tri.stop]
        assert (part.min(), part.max()) == pytest.approx((-9.0, 8.0))
        assert (tri.stop - tri.start) % tri.period == 0
    assert isinstance(_pair(hystcomp.presets.paper_mpi(), _stage()), DynamicCompensator)


def test_dynamics_of_a_low_voltage_amplifier_input_are_excited_and_identified():
    """A stage driven through a 0..3.6 V amplifier input (as the micromanipulator's record):
    the multisine scales with the range (0.9 V peak, as 30 V is on 0..120 V), and the
    model is found as on any other range."""
    _, v = dynamics_excitation(voltage_range=(0.0, 3.6))
    assert v[0] == 0.0
    assert np.abs(v[round(3.2 * FS) : round(6.2 * FS)] - 1.8).max() == pytest.approx(0.9)
    x = 13.0 * _stage().simulate(v, initial=0.0)  # µm: 13 µm/V of amplifier input
    fitted = LinearDynamics().fit(v, x, 20_000.0)
    assert fitted.resonance_hz_ == pytest.approx(_stage().resonance_hz_, rel=0.005)
    assert fitted.damping_ratio_ == pytest.approx(_stage().damping_ratio_, rel=0.05)


def test_twin_creep_rises_about_equally_per_decade():
    twin = Twin(creep_twin(sensor_noise=0.0, damping_ratio=0.7))
    v = np.r_[0.0, np.full(round(20.0 * FS), 60.0)]
    x = twin.run(v)
    at = {t: x[round(t * FS)] for t in (0.01, 0.1, 1.0, 10.0)}
    per_decade = np.diff([at[t] for t in sorted(at)]) / x[-1]
    assert np.all((0.003 < per_decade) & (per_decade < 0.006))  # 0.5 % a decade, +-40 %


def test_forward_filters_match_lfilter():
    from scipy.signal import lfilter

    from hystcomp import _lti

    u = random_walk(np.random.default_rng(4), 5000, -10.0, 10.0, 1.0)
    b, a = resonance_zoh(780.0, 0.05, FS)
    np.testing.assert_allclose(
        _lti.resonance((b, a), u), lfilter(np.r_[0.0, b], a, u), rtol=0, atol=1e-9
    )
    lag = np.exp(-1.0 / (FS * 0.01))
    np.testing.assert_allclose(
        _lti.lag(lag, u), lfilter([1.0 - lag], [1.0, -lag], u), rtol=0, atol=1e-9
    )


def test_identification_does_not_import_scipy_signal():
    """Its import alone took about 1 s of CPU in ``hystcomp compare``, ten times the fit."""
    import subprocess
    import sys

    code = (
        "import sys, numpy as np, hystcomp\n"
        "from hystcomp.identify.dynamics import dynamics_excitation\n"
        "t, v = dynamics_excitation(sample_rate=5000.0)\n"
        "dyn = hystcomp.LinearDynamics.from_parameters(sample_rate=5000.0, resonance_hz=600.0,"
        " damping_ratio=0.1, creep_time_constants=[0.01, 1.0], creep_weights=[0.01, 0.01])\n"
        "fit = hystcomp.LinearDynamics().fit(v, dyn.simulate(v), 5000.0)\n"
        "fit.inverse().simulate(v[:100])\n"
        "print('scipy.signal' in sys.modules)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "False"


def test_creep_fraction_and_frequency_response_refuse_what_is_not_a_time_or_a_frequency():
    dyn = LinearDynamics.from_parameters(
        sample_rate=20_000.0,
        resonance_hz=780.0,
        damping_ratio=0.05,
        creep_time_constants=[0.01, 0.1],
        creep_weights=[0.01, 0.02],
    )
    assert dyn.creep_fraction(0.0) == pytest.approx(0.03 / 1.03)
    for bad in (-1.0, float("nan"), float("inf")):
        with pytest.raises(InvalidParameterError):
            dyn.creep_fraction(bad)
    for bad in ([np.nan], [np.inf]):
        with pytest.raises(InvalidParameterError):
            dyn.frequency_response(bad)


def test_a_record_whose_displacement_does_not_move_is_refused_with_the_reason():
    _, v = dynamics_excitation(sample_rate=20_000.0, voltage_range=(0.0, 120.0))
    with pytest.raises(IdentificationError, match="does not move"):
        LinearDynamics().fit(v, np.full_like(v, 3.0), 20_000.0)


def test_the_compensator_runs_at_the_dynamics_rate():
    """Discrete-time dynamics run at their own rate only: inverse(dynamics=...) takes it
    (before, it kept 20 kHz, and a slew limit at 10 kHz was silently halved), refuses
    another, and to_control checks dt against it."""
    slow = _stage(sample_rate=10_000.0)
    model = hystcomp.presets.paper_mpi()
    assert _pair(model, slow, slew_rate=1000.0).max_step == pytest.approx(0.1)
    assert model.inverse(slew_rate=1000.0).max_step == pytest.approx(0.05)
    preisach = hystcomp.presets.paper_preisach()
    assert _pair(preisach, slow, slew_rate=1000.0).max_step == pytest.approx(0.1)
    with pytest.raises(InvalidParameterError, match="differs from the sample rate of its"):
        model.inverse(dynamics=slow, sample_rate=20_000.0)
    if importlib.util.find_spec("control") is not None:
        from hystcomp.control import to_control

        with pytest.raises(InvalidParameterError, match="the dynamics' sample time"):
            to_control(_pair(model, slow), 5e-5)


def test_a_reference_shorter_than_the_preview_is_held_past_its_end():
    comp = _pair(hystcomp.presets.paper_mpi(), _stage())
    d = comp.preview
    for n in (1, 3, d - 1):
        x = np.linspace(5.0, 8.0, n)
        s = comp.stepper()
        ahead = np.r_[x, np.full(d, x[-1])]
        s.prime(ahead[:d])
        np.testing.assert_array_equal(comp.simulate(x), s.step_block(ahead[d:]))


def test_a_latency_of_a_fraction_of_a_sample_keeps_the_fit_sane():
    """A latency of 2.5 samples (a sensor's sampling phase, a filter's group delay): the fit
    frees the fraction with the resonance, so the damping comes out right, and the step's
    creep is not traded against what is left of the ringing. Before, the damping came out
    half the true one and the creep at 57 to 99 % of the step, and the inverse made a
    100 Hz triangle 12 times worse than without it."""
    true = _stage()
    _, v = dynamics_excitation()
    y = 0.3 * true.simulate(v, initial=0.0)
    half = 0.5 * (y + np.r_[y[0], y[:-1]])  # half a sample later, by linear interpolation
    x = np.r_[np.full(2, half[0]), half[:-2]] + 0.003 * np.random.default_rng(9).normal(size=v.size)
    fit = LinearDynamics().fit(v, x, FS)
    assert fit.delay_samples_ in (2, 3)
    assert fit.resonance_hz_ == pytest.approx(780.0, rel=0.01)
    assert fit.damping_ratio_ == pytest.approx(0.05, rel=0.1)
    assert fit.creep_fraction(0.0) < 0.05  # the stage's is 3 %
    assert fit.fit_report_["fit_percent"] > 90.0
