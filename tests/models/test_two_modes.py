"""Linear dynamics with a second resonance mode: the model, its file, its inverse, its C."""

from __future__ import annotations

import json

import numpy as np
import pytest

import hystcomp
from hystcomp._lti import modal_tf
from hystcomp.errors import InvalidParameterError
from hystcomp.models.dynamics import LinearDynamics
from hystcomp.models.hammerstein import HammersteinModel
from tests.codegen.test_codegen import _compile, _run_c, _step_python, needs_cc
from tests.conftest import random_walk

FS = 20_000.0
#: The second mode of the dynamics panel's two-mode stage (narrow1200).
SECOND = {"second_resonance_hz": 3100.0, "second_damping_ratio": 0.03, "second_mode_gain": 0.08}


def _model(**changes):
    """1200 Hz, zeta 0.05, 3 % creep; with ``SECOND`` for two modes."""
    params = {
        "sample_rate": FS,
        "resonance_hz": 1200.0,
        "damping_ratio": 0.05,
        "creep_time_constants": [0.01, 0.1, 1.0],
        "creep_weights": [0.01, 0.01, 0.01],
    }
    return LinearDynamics.from_parameters(**{**params, **changes})


def test_two_modes_are_the_two_one_mode_models_in_parallel():
    """``R = (1 - g) R1 + g R2``, each of unit static gain: the output and the frequency
    response are the weighted sums of the one-mode models' (same creep, same latency)."""
    two = _model(**SECOND, delay_samples=2)
    first = _model(delay_samples=2)
    second = _model(resonance_hz=3100.0, damping_ratio=0.03, delay_samples=2)
    g = SECOND["second_mode_gain"]
    u = random_walk(np.random.default_rng(1), 4000, -10.0, 10.0, 1.0)
    np.testing.assert_allclose(
        two.simulate(u), (1 - g) * first.simulate(u) + g * second.simulate(u), rtol=0, atol=1e-12
    )
    f = np.array([0.0, 10.0, 1200.0, 2500.0, 3100.0, 9000.0])
    np.testing.assert_allclose(
        two.frequency_response(f),
        (1 - g) * first.frequency_response(f) + g * second.frequency_response(f),
        rtol=1e-12,
    )
    assert abs(two.frequency_response([0.0])[0]) == pytest.approx(1.0, abs=1e-12)
    # the peaks of the panel's stage: 8.9 at 1.2 kHz and 1.3 at 3.1 kHz
    peaks = np.abs(two.frequency_response([1200.0, 3100.0]) / two.frequency_response([0.0]))
    assert peaks == pytest.approx([8.9, 1.3], abs=0.1)


def test_the_transfer_function_of_the_modes_is_their_sum():
    from scipy.signal import lfilter

    two = _model(**SECOND, creep_time_constants=(), creep_weights=())
    b, a = two.resonance()
    assert (b.size, a.size) == (4, 5)
    u = random_walk(np.random.default_rng(2), 3000, -5.0, 5.0, 0.5)
    np.testing.assert_allclose(
        lfilter(np.r_[0.0, b], a, u), two.simulate(u, initial=0.0), rtol=0, atol=1e-9
    )
    # one mode of share 1: the one-mode model's own (b, a)
    one = _model()
    for ours, theirs in zip(modal_tf(one.modes, FS), one.resonance(), strict=True):
        np.testing.assert_array_equal(ours, theirs)
    assert one.modes == ((1200.0, 0.05, 1.0),)
    assert two.modes[1] == (3100.0, 0.03, 0.08)
    assert two.modes[0][2] == pytest.approx(0.92)


def test_the_second_mode_is_checked_like_the_first():
    for missing in SECOND:
        partial = {k: v for k, v in SECOND.items() if k != missing}
        with pytest.raises(InvalidParameterError, match=rf"without '{missing}'; give all three"):
            _model(**partial)
    with pytest.raises(InvalidParameterError, match=r"'second_resonance_hz' .* above"):
        _model(**{**SECOND, "second_resonance_hz": 900.0})
    with pytest.raises(InvalidParameterError, match=r"'second_resonance_hz' .* Nyquist"):
        _model(**{**SECOND, "second_resonance_hz": 10_000.0})
    for zeta in (1e-300, 1e6):
        with pytest.raises(InvalidParameterError, match=r"'second_damping_ratio' .* 1e-06"):
            _model(**{**SECOND, "second_damping_ratio": zeta})
    for gain in (0.0, 1.0, -0.1, 1.5):
        with pytest.raises(InvalidParameterError, match=r"'second_mode_gain' .* in \(0, 1\)"):
            _model(**{**SECOND, "second_mode_gain": gain})
    with pytest.raises(InvalidParameterError, match="second_mode_gain"):
        _model(**{**SECOND, "second_mode_gain": float("nan")})


def test_model_files_old_and_new(tmp_path):
    two = _model(**SECOND, delay_samples=1)
    hystcomp.save_model(two, tmp_path / "two.json")
    doc = json.loads((tmp_path / "two.json").read_text())
    assert doc["parameters"]["second_resonance_hz"] == 3100.0
    back = hystcomp.load_model(tmp_path / "two.json")
    assert back.modes == two.modes
    f = np.array([0.0, 100.0, 1200.0, 3100.0])
    np.testing.assert_array_equal(back.frequency_response(f), two.frequency_response(f))
    assert "second_resonance_hz=3100" in repr(back)
    # a model of one mode writes no second mode: the file it always wrote
    hystcomp.save_model(_model(), tmp_path / "one.json")
    one = json.loads((tmp_path / "one.json").read_text())
    assert not any(key.startswith("second_") for key in one["parameters"])
    assert "second" not in repr(_model())
    # a file written before the second mode existed (or with it null) reads as one mode
    for value in ("absent", None):
        params = {k: v for k, v in doc["parameters"].items() if not k.startswith("second_")}
        if value is None:
            params.update(dict.fromkeys(SECOND))
        (tmp_path / "old.json").write_text(json.dumps({**doc, "parameters": params}))
        old = hystcomp.load_model(tmp_path / "old.json")
        assert old.second_resonance_hz_ is None
        assert old.modes == ((1200.0, 0.05, 1.0),)
    # and a pair keeps it
    pair = HammersteinModel(hystcomp.presets.paper_mpi(), two)
    hystcomp.save_model(pair, tmp_path / "pair.json")
    assert hystcomp.load_model(tmp_path / "pair.json").dynamics.modes == two.modes


def test_the_inverse_takes_both_modes_and_stays_monotone():
    """The FIR is designed on the whole ``R``: non-negative taps summing to 1 (a monotone
    step, no gain above 1), and the two-mode stage follows sines in band better than with
    the FIR of its first mode alone."""
    two, first = _model(**SECOND), _model()
    inverse = two.inverse(rest=3.0)
    assert inverse.taps.min() >= 0.0
    assert inverse.taps.sum() == pytest.approx(1.0, abs=1e-12)
    assert inverse.preview == first.inverse().preview  # the look-ahead: the first mode's
    assert not np.array_equal(inverse.taps, first.inverse().taps)
    t = np.arange(round(1.0 * FS)) / FS
    inner = slice(round(0.1 * FS), -200)
    for f, limit in ((100.0, 0.002), (200.0, 0.007)):
        x = 3.0 + 5.0 * np.sin(2 * np.pi * f * t)
        errors = [
            np.abs(two.simulate(d.inverse(rest=3.0).simulate(x), initial=3.0) - x)[inner].max()
            for d in (two, first)
        ]
        assert errors[0] < limit * 5.0
        assert errors[0] < 0.95 * errors[1]


def test_a_monotone_step_without_creep():
    inverse = _model(**SECOND, creep_time_constants=(), creep_weights=()).inverse()
    y = inverse.simulate(np.r_[np.zeros(100), np.ones(2000)])
    assert np.diff(y).min() >= -1e-12
    f = np.linspace(0.0, 0.5 * FS, 501)
    gain = np.abs(
        np.exp(-2j * np.pi * np.outer(f / FS, np.arange(inverse.taps.size))) @ inverse.taps
    )
    assert gain.max() <= 1.0 + 1e-12


def test_the_design_is_kept_per_second_mode(monkeypatch):
    from hystcomp.models import dynamics as dynamics_module

    two = _model(**SECOND)
    first = two.inverse().taps
    designs = []
    original = dynamics_module.inverse_fir
    monkeypatch.setattr(
        dynamics_module, "inverse_fir", lambda *a: designs.append(a) or original(*a)
    )
    np.testing.assert_array_equal(two.inverse().taps, first)
    assert designs == []
    two.second_mode_gain_ = 0.2  # another second mode: designed again, never the old design
    moved = two.inverse().taps
    assert len(designs) == 1
    np.testing.assert_array_equal(
        moved, _model(**{**SECOND, "second_mode_gain": 0.2}).inverse().taps
    )


@needs_cc
def test_c_matches_the_stepper_for_two_modes(tmp_path):
    comp = HammersteinModel(
        hystcomp.presets.paper_mpi(), _model(**SECOND, delay_samples=1)
    ).inverse(slew_rate=2e5)
    rng = np.random.default_rng(11)
    lo, hi = comp.dynamics_inverse.output_range
    x = random_walk(rng, 6000, lo - 0.3 * (hi - lo), hi + 0.3 * (hi - lo), (hi - lo) / 30)
    x[[100, 4100, 5000]] = [np.nan, np.inf, -np.inf]
    drive = _compile(comp, tmp_path, "two_modes")
    v_c, held = _run_c(drive, x, reset_at=4000)
    v_py = _step_python(comp, x, reset_at=4000)
    np.testing.assert_allclose(v_c, v_py, rtol=0, atol=1e-9)
    assert held == 2  # the non-finite samples after the reset, each held
    assert f"{comp.preview} samples ahead" in (tmp_path / "two_modes.h").read_text()
