"""Choosing the model family by predicted tracking (``hystcomp identify --model auto``), and
the tracking estimate it ranks by."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

import hystcomp
from hystcomp import presets
from hystcomp.cli import main
from hystcomp.errors import IdentificationError
from hystcomp.identify.compensation import swing_mask, tracking_estimate
from hystcomp.identify.excitation import rich_sequence, triangle_sequence
from hystcomp.io.records import Record, write_table
from hystcomp.plant import Twin
from hystcomp.workflows.auto import identify_best

FS = 2000.0


def _record(v, x, source="stage") -> Record:
    return Record(np.arange(v.size) / FS, v, x, source=source)


@pytest.fixture(scope="module")
def saturating():
    """The paper's MPI model as a stage (its loops saturate at the top): from the paper's
    triangles, at 2 kHz, with 5 nm of sensor noise."""
    _, v = triangle_sequence(sample_rate=FS)
    x = presets.paper_mpi().simulate(v) + 0.005 * np.random.default_rng(3).normal(size=v.size)
    return v, x


def test_the_estimate_is_near_zero_for_a_model_of_its_own_data_and_larger_for_a_line(saturating):
    v, x = saturating
    model = presets.paper_mpi()
    est = tracking_estimate(model, v, x)
    # the model is the stage: what is left is the sensor's noise, and its inverse is exact
    assert est["swing_rms_um"] == pytest.approx(0.005, rel=0.2)
    assert est["inverse_rms_um"] < 1e-9
    assert est["tracking_rms_um"] == pytest.approx(np.hypot(est["swing_rms_um"], 0.0))
    assert est["baseline_rms_um"] > 50 * est["tracking_rms_um"]
    assert est["ratio"] == pytest.approx(est["tracking_rms_um"] / est["baseline_rms_um"])
    assert np.isnan(est["held_out_rms_um"])  # a preset: no fit, no cross-validation
    assert not est["flatters"]


def test_the_estimate_counts_what_the_inverse_itself_misses(saturating):
    """The paper's Preisach compensator (eq. 10) lags a sample: on its own model its error
    is that lag, which the estimate adds; the exact inverse has none."""
    model = presets.paper_preisach()
    v, _ = saturating
    x = model.simulate(v)
    est = tracking_estimate(model, v, x)
    assert est["swing_rms_um"] < 1e-9
    assert est["inverse_rms_um"] > 1e-4  # the one-sample lag over a 20,000-sample period


def test_swings_are_the_stretches_over_half_the_range():
    v = np.r_[np.linspace(0.0, 10.0, 11), np.linspace(9.0, 2.0, 8), np.linspace(3.0, 10.0, 8)]
    mask = swing_mask(v)
    assert mask[:11].all()  # 0 -> 10
    assert mask[10:18].all()  # 10 -> 2: 80 %
    assert not mask[20:].any() or mask[18:].all()  # 2 -> 10 is 80 % too
    assert not swing_mask(np.r_[np.linspace(0.0, 10.0, 11), np.linspace(9.0, 7.0, 3)])[12:].any()


def test_auto_keeps_the_family_predicted_best_and_says_why(saturating):
    """An MPI stage (the paper's model): neither PI (no saturation) nor a Preisach model (an
    output saturation breaks the congruency of its minor loops) follows its loops; auto
    ranks MPI first by a margin and keeps it; the ranking is printed."""
    v, x = saturating
    chosen = identify_best(_record(v, x), operators=8, deadzones=8)
    kinds = [k for k, _ in chosen.ranking]
    assert sorted(kinds) == ["mpi", "pi", "preisach"]
    assert chosen.best.kind == kinds[0] == "mpi"
    estimates = [e["tracking_rms_um"] for _, e in chosen.ranking]
    assert estimates == sorted(estimates)
    assert chosen.margin > 2.0
    assert chosen.margin == pytest.approx(estimates[1] / estimates[0])
    assert chosen.results["pi"].model.n_operators == 8  # the family options reached them
    assert chosen.results["mpi"].model.n_deadzones == 8
    assert chosen.lines[0].startswith("auto: the family whose compensator")
    assert chosen.lines[1].split()[0] == "MPI"
    assert chosen.lines[1].endswith(": chosen")
    assert "x the" in chosen.lines[3]


def test_auto_names_a_better_family_for_references_that_turn_inside_the_range(monkeypatch):
    from hystcomp.workflows import auto

    ranking = [
        ("preisach", {"tracking_rms_um": 0.03, "held_out_rms_um": 0.65}),
        ("mpi", {"tracking_rms_um": 0.11, "held_out_rms_um": 0.15}),
        ("pi", {"tracking_rms_um": 1.8, "held_out_rms_um": 2.3}),
    ]
    assert auto._held_out_best(ranking) == ("mpi", 0.15, 0.65)
    ranking[1][1]["held_out_rms_um"] = 0.5  # within 1.5x: not worth a word
    assert auto._held_out_best(ranking) is None


def test_auto_refuses_when_no_family_can_be_fitted():
    t = np.arange(100) / FS
    with pytest.raises(IdentificationError, match="No model family could be identified"):
        identify_best(Record(t, np.full(100, 5.0), np.zeros(100), source="flat"))


def test_identify_uses_auto_by_default_and_writes_the_choice(tmp_path):
    _, v = rich_sequence(sample_rate=FS)
    x = Twin(seed=1).hysteresis(v)
    write_table(tmp_path / "rec.csv", {"t": np.arange(v.size) / FS, "v": v, "x": x})
    result = CliRunner().invoke(
        main, ["identify", str(tmp_path / "rec.csv"), "-o", str(tmp_path / "m.json")]
    )
    assert result.exit_code == 0, result.output
    lines = result.output.splitlines()
    assert lines[0].startswith("auto: the family whose compensator is predicted")
    chosen = next(line.split()[0] for line in lines[1:4] if line.endswith(": chosen"))
    model = hystcomp.load_model(tmp_path / "m.json")
    assert {"PI": "pi", "MPI": "mpi", "Preisach": "preisach"}[chosen] == model.kind
    assert f"{chosen} model" in result.output
    assert "cross-validated:" in result.output
    # an option of one family goes to it alone under auto; a fixed family still refuses it
    result = CliRunner().invoke(
        main,
        ["identify", str(tmp_path / "rec.csv"), "--grid", "13", "-o", str(tmp_path / "g.json")],
    )
    assert result.exit_code == 0, result.output
    bad = CliRunner().invoke(
        main,
        ["identify", str(tmp_path / "rec.csv"), "--model", "pi", "--grid", "13", "-o",
         str(tmp_path / "b.json")],
    )  # fmt: skip
    assert bad.exit_code == 2
    assert "--grid does not apply to --model pi" in bad.output
