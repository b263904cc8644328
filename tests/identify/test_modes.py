"""A second resonance mode: identified where the record shows one, and only there."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from hystcomp.cli import main
from hystcomp.identify.dynamics import dynamics_excitation
from hystcomp.identify.excitation import triangle_sequence
from hystcomp.identify.modes import RESIDUAL_RATIO, ModalFit, keeps_second_mode
from hystcomp.io.records import Record, write_table
from hystcomp.models.dynamics import LinearDynamics
from hystcomp.models.hammerstein import fit_pair
from hystcomp.models.mpi import ModifiedPrandtlIshlinskii
from hystcomp.plant import Twin, creep_twin
from hystcomp.workflows.pair import identify_dynamics_record

FS = 20_000.0
#: The linear part of the dynamics panel's two-mode stage (narrow1200): 1200 Hz and a
#: weaker 3100 Hz mode, 8 % of the static gain, in parallel; 3 % creep.
TWO_MODES = {
    "sample_rate": FS,
    "resonance_hz": 1200.0,
    "damping_ratio": 0.05,
    "second_resonance_hz": 3100.0,
    "second_damping_ratio": 0.03,
    "second_mode_gain": 0.08,
    "creep_time_constants": [0.004, 0.04, 0.4, 2.0],
    "creep_weights": [0.0075] * 4,
}


def _record(true: LinearDynamics, seed: int = 7):
    """``(t, v, x)``: the stage's noisy answer (0.3 µm/V, 3 nm rms) to the excitation."""
    t, v = dynamics_excitation(sample_rate=true.sample_rate_)
    noise = 0.003 * np.random.default_rng(seed).standard_normal(v.size)
    return t, v, 0.3 * true.simulate(v, initial=0.0) + noise


@pytest.mark.parametrize("delay", [0, 3])
def test_a_known_two_mode_stage_is_identified(delay):
    """Both modes within 1 % (damping ratios and the share within 3 %), the latency the
    stage's, and the response within 2 % up to twice the second mode. With one mode the
    fit was 1183 Hz, zeta 0.033, a latency one sample short (the second mode's phase
    taken for latency), 72 % of the response explained, and up to 4x off in the band."""
    true = LinearDynamics.from_parameters(**TWO_MODES, delay_samples=delay)
    _, v, x = _record(true)
    fit = LinearDynamics().fit(v, x, FS)
    report = fit.fit_report_
    assert report["modes"] == 2
    assert report["residual_ratio"] < 0.1
    assert fit.delay_samples_ == delay
    assert fit.resonance_hz_ == pytest.approx(1200.0, rel=0.01)
    assert fit.damping_ratio_ == pytest.approx(0.05, rel=0.03)
    assert fit.second_resonance_hz_ == pytest.approx(3100.0, rel=0.01)
    assert fit.second_damping_ratio_ == pytest.approx(0.03, rel=0.03)
    assert fit.second_mode_gain_ == pytest.approx(0.08, rel=0.03)
    f = np.geomspace(1.0, 6200.0, 300)
    error = np.abs(fit.frequency_response(f) / true.frequency_response(f) - 1.0)
    assert error.max() < 0.02
    assert report["fit_percent"] > 97.0
    assert report["fit_band_hz"][1] == pytest.approx(5000.0)  # twice 3.1 kHz, the lines' top
    assert fit.creep_fraction(0.1) == pytest.approx(true.creep_fraction(0.1), abs=0.002)


@pytest.mark.parametrize(
    ("fs", "hz", "zeta", "delay"),
    [(20_000.0, 780.0, 0.05, 0), (20_000.0, 1500.0, 0.02, 2), (10_000.0, 300.0, 0.1, 1),
     (5000.0, 630.0, 0.1, 0), (20_000.0, 400.0, 0.7, 0)],
)  # fmt: skip
def test_a_single_mode_stage_keeps_one_mode(fs, hz, zeta, delay):
    true = LinearDynamics.from_parameters(
        sample_rate=fs,
        resonance_hz=hz,
        damping_ratio=zeta,
        creep_time_constants=[0.004, 0.04, 0.4, 2.0],
        creep_weights=[0.0075] * 4,
        delay_samples=delay,
    )
    _, v, x = _record(true)
    fit = LinearDynamics().fit(v, x, fs)
    assert fit.fit_report_["modes"] == 1
    assert fit.second_resonance_hz_ is None
    assert "second_resonance_hz" not in fit.parameters()
    assert fit.fit_report_["residual_ratio"] > 2.0 * RESIDUAL_RATIO  # (0.78 and up measured)
    assert fit.resonance_hz_ == pytest.approx(hz, rel=0.005)
    assert fit.delay_samples_ == delay


def test_the_simulated_axis_keeps_one_mode_behind_its_hysteresis():
    """The twin (creep_twin: 630 Hz, zeta 0.1, Bouc-Wen hysteresis), identified as a pair
    with MPI: its hysteresis leaves a residual that a second mode does not take up (two modes
    leave 0.99 of one mode's)."""
    twin = Twin(creep_twin(), seed=3)
    _, v_d = dynamics_excitation()
    _, v = triangle_sequence(sample_rate=FS)
    pair = fit_pair(ModifiedPrandtlIshlinskii(), v, twin.run(v), v_d, twin.run(v_d), sample_rate=FS)
    report = pair.dynamics.fit_report_
    assert report["modes"] == 1
    assert report["residual_ratio"] > 2.0 * RESIDUAL_RATIO
    assert pair.dynamics.resonance_hz_ == pytest.approx(630.0, rel=0.03)


def _fit(residual, second=(3000.0, 0.03, 0.08)):
    one = ModalFit(((1200.0, 0.05, 1.0),), 0.0, 0.5)
    modes = ((1200.0, 0.05, 1.0 - second[2]), second)
    return one, ModalFit(modes, 0.0, residual)


def test_the_rule_for_two_modes():
    """Kept when the residual falls to a quarter of one mode's or below, the second mode a
    resonance (zeta < 0.5) within the band with at least 0.5 % of the static gain."""
    assert keeps_second_mode(*_fit(0.5 * RESIDUAL_RATIO), 5000.0)
    assert keeps_second_mode(*_fit(0.5 * RESIDUAL_RATIO - 1e-9), 5000.0)
    assert not keeps_second_mode(*_fit(0.5 * RESIDUAL_RATIO + 1e-3), 5000.0)
    assert not keeps_second_mode(*_fit(0.01, (3000.0, 0.6, 0.08)), 5000.0)  # no resonance
    assert not keeps_second_mode(*_fit(0.01, (6000.0, 0.03, 0.08)), 5000.0)  # beyond the band
    assert not keeps_second_mode(*_fit(0.01, (3000.0, 0.03, 0.001)), 5000.0)  # too small
    one, _ = _fit(0.01)
    assert not keeps_second_mode(one, one._replace(residual=0.0), 5000.0)  # one mode only


def test_the_reports_say_how_many_modes(tmp_path):
    """identify --model dynamics prints the second mode, and the fit line says how many
    modes the model holds; a single-mode stage's report has no second-mode line."""
    true = LinearDynamics.from_parameters(**TWO_MODES)
    t, v, x = _record(true)
    result = identify_dynamics_record(Record(t, v, x, source="stage"))
    lines = "\n".join(result.lines)
    assert result.model.second_resonance_hz_ == pytest.approx(3100.0, rel=0.01)
    assert f"  second mode: {result.model.second_resonance_hz_:.5g} Hz, damping ratio" in lines
    assert "% of the static gain, in parallel with the first" in lines
    assert "(frequency response, two modes)" in lines
    assert result.warnings == []
    write_table(tmp_path / "rec.csv", {"t": t, "v": v, "x": x})
    out = CliRunner().invoke(
        main, ["identify", str(tmp_path / "rec.csv"), "--model", "dynamics", "-o",
               str(tmp_path / "dyn.json")],
    )  # fmt: skip
    assert out.exit_code == 0, out.output
    assert "  second mode: 3" in out.output
    one = LinearDynamics.from_parameters(
        **{k: val for k, val in TWO_MODES.items() if not k.startswith("second_")}
    )
    t, v, x = _record(one)
    result = identify_dynamics_record(Record(t, v, x, source="stage"))
    assert not any("second mode" in line for line in result.lines)
    assert "(frequency response, one mode)" in "\n".join(result.lines)


@pytest.mark.slow
def test_the_two_mode_stage_of_the_dynamics_panel_meets_the_pair_s_targets():
    """``narrow1200`` (benchmarks/dynamics_panel.py), as ``bench_dynamics_panel.py`` runs it:
    with two modes found behind each hysteresis model, the pair tracks a 100 Hz triangle at
    most 0.3x and a 200 Hz one at most 0.35x as far off as the hysteresis model alone
    (measured 0.19x and 0.22x for MPI, 0.21x and 0.20x for Preisach; with one mode it was
    0.60x and 0.64x, 0.50x and 0.57x), within 15 % of the pair built on the stage's true
    linear part."""
    from benchmarks.bench_dynamics_panel import (
        ESTIMATORS,
        WITH,
        identify_true,
        panel_table,
        records,
    )
    from benchmarks.dynamics_panel import stage

    st = stage("narrow1200")
    recs = records(st)
    for cls in ESTIMATORS.values():
        pair = fit_pair(cls(), *recs["pi"], *recs["dynamics"], sample_rate=st.sample_rate)
        assert pair.dynamics.fit_report_["modes"] == 2
        assert pair.dynamics.second_resonance_hz_ == pytest.approx(3100.0, rel=0.01)
        assert pair.dynamics.delay_samples_ == 0
    cells = panel_table(("narrow1200",))["narrow1200"]
    bound = panel_table(("narrow1200",), identify_true)["narrow1200"]
    for model in ESTIMATORS:
        alone, paired = cells[model], cells[model + WITH]
        assert paired["100 Hz"] <= 0.3 * alone["100 Hz"], (model, alone, paired)
        assert paired["200 Hz"] <= 0.35 * alone["200 Hz"], (model, alone, paired)
        for f in ("100 Hz", "200 Hz"):
            assert paired[f] <= 1.15 * bound[model + WITH][f], (model, f, paired, bound)


@pytest.mark.slow
def test_the_single_mode_stages_of_the_dynamics_panel_keep_one_mode():
    """Every other tuning stage of the dynamics panel, behind MPI and Preisach as the pair
    fits them: one mode, two modes leaving at least 0.6 of one mode's residual (measured
    0.65 and up)."""
    from benchmarks.bench_dynamics_panel import ESTIMATORS, records
    from benchmarks.dynamics_panel import DYNAMICS_STAGES, stage

    for name in DYNAMICS_STAGES:
        if name == "narrow1200":
            continue
        st = stage(name)
        recs = records(st)
        for label, cls in ESTIMATORS.items():
            pair = fit_pair(cls(), *recs["pi"], *recs["dynamics"], sample_rate=st.sample_rate)
            report = pair.dynamics.fit_report_
            assert report["modes"] == 1, (name, label, report["residual_ratio"])
            assert report["residual_ratio"] > 0.6, (name, label, report["residual_ratio"])
