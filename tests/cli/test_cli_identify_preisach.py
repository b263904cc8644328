"""``hystcomp identify --model preisach`` with --fit, --everett and --grid, on any record."""

import json
import re

import numpy as np
import pytest

import hystcomp
from hystcomp import presets
from hystcomp.identify.excitation import triangle_sequence
from hystcomp.io.records import read_table, write_table
from tests.cli.test_cli_identify import REAL_RECORD, assert_one_line_error, run


def test_the_real_record_predicts_its_second_half_far_better_than_a_line(tmp_path):
    out = tmp_path / "m.json"
    args = ["identify", REAL_RECORD, "--model", "preisach", "--columns", "v=1,x=5"]
    result = run(*args, "--fs", "200", "--holdout", "0.5", "-o", out)
    assert result.exit_code == 0, result.output
    assert "25 x 25 table, least squares over the record" in result.output
    assert "compensation (estimated)" in result.output
    model = hystcomp.load_model(out)
    assert model.fit_report_["fit"] == "least-squares"
    assert model.fit_report_["first_used_sample"] == 0  # the CLI cut the transient (44 samples)
    assert model.fit_report_["tracking_rms_um"] < model.fit_report_["baseline_tracking_rms_um"]
    better = float(result.output.split("µm: ")[1].split("x better")[0])
    assert better > 1 / 0.3  # the model's hold-out error is < 0.3x the straight line's
    cubic = tmp_path / "c.json"
    result = run(*args, "--fs", "200", "--holdout", "0.5", "--degree", "3", "-o", cubic)
    assert result.exit_code == 0, result.output
    assert "degree-3 polynomial, least squares" in result.output  # --degree: the polynomial
    assert float(result.output.split("µm: ")[1].split("x better")[0]) < better


def test_fit_choices_and_the_table_go_into_the_model_file(tmp_path):
    _, v = triangle_sequence(sample_rate=500.0)
    x = presets.paper_preisach(zero_diagonal=True).simulate(v) - 20.0
    write_table(tmp_path / "rec.csv", {"t": np.arange(v.size) / 500.0, "v": v, "x": x})
    base = ["identify", tmp_path / "rec.csv", "--model", "preisach"]
    paper = ["--fit", "reversal-curves", "--everett", "polynomial"]
    result = run(*base, *paper, "-o", tmp_path / "paper.json")
    assert result.exit_code == 0, result.output
    assert "polynomial, reversal curves from 4 maxima (paper, Section III-A)" in result.output
    result = run(*base, "--fit", "reversal-curves", "-o", tmp_path / "rc.json")
    assert result.exit_code == 0, result.output
    assert "25 x 25 table, reversal curves from 4 maxima\n" in result.output
    result = run(*base, "--everett", "table", "--grid", "13", "-o", tmp_path / "t.json")
    assert result.exit_code == 0, result.output
    assert "13 x 13 table, least squares" in result.output
    doc = json.loads((tmp_path / "t.json").read_text())
    assert doc["hyperparameters"]["fit_method"] == "least-squares"
    assert np.array(doc["parameters"]["table"]).shape == (13, 13)
    model = hystcomp.load_model(tmp_path / "t.json")
    assert model.fit_report_["density_min"] >= -1e-9
    # the file serves the other commands: the exact inverse of the table model
    ref = tmp_path / "ref.csv"
    write_table(ref, {"t": np.arange(200) / 500.0, "x": np.linspace(-15.0, 10.0, 200)})
    out = tmp_path / "v.csv"
    assert (
        run("compensate", tmp_path / "t.json", ref, "--method", "exact", "-o", out).exit_code == 0
    )
    v_comp = read_table(out, ("v",))["v"]
    np.testing.assert_allclose(model.simulate(v_comp), np.linspace(-15.0, 10.0, 200), atol=1e-6)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--everett", "polynomial", "--grid", "9"], r"--grid applies to --everett table"),
        (["--everett", "table", "--degree", "4"], r"--degree applies to --everett polynomial"),
        (["--fit", "paper"], r"'paper' is not one of 'auto', 'reversal-curves', 'least-squares'"),
        (["--everett", "table", "--grid", "1"], r"--grid.*1 is not in the range 2<=x<=41"),
    ],
)
def test_bad_preisach_options_are_refused_before_any_work(tmp_path, extra, message):
    args = ["identify", tmp_path / "missing.csv", "--model", "preisach", *extra]
    result = run(*args, "-o", tmp_path / "m.json")
    assert_one_line_error(result)
    assert not (tmp_path / "m.json").exists()
    assert re.search(message, result.output), result.output


@pytest.mark.parametrize("option", [["--fit", "least-squares"], ["--everett", "table"]])
def test_preisach_options_do_not_apply_to_pi(tmp_path, option):
    result = run("identify", tmp_path / "x.csv", "--model", "pi", *option, "-o", tmp_path / "m")
    assert_one_line_error(result)
    assert f"{option[0]} does not apply to --model pi" in result.output


def test_eq_10_overshooting_a_step_is_warned_about_and_exact_is_not(tmp_path):
    """The paper's structure corrects with a constant gain: on a step it overshoots, and the
    stage keeps a minor loop the model never saw. compensate says so, with the way out; a
    triangle from rest, whose voltage turns where the reference does, is not warned about
    (the paper's free fit, whose X(v, v) steps at each reversal, rings there: it is warned
    about, with reason)."""
    model = presets.paper_preisach(zero_diagonal=True)  # no step of X(v, v) at reversals
    hystcomp.save_model(model, tmp_path / "p.json")
    t = np.arange(8000) / 20_000.0
    stairs = 2.0 + 6.0 * np.floor(t / 0.1)  # from rest, four steps of 6 µm
    write_table(tmp_path / "stairs.csv", {"t": t, "x": stairs})
    rest = float(model.simulate([0.0])[0])
    triangle = rest + 15.0 * (1.0 - np.abs(2.0 * (t * 5.0 % 1.0) - 1.0))  # from rest, to 62 V
    write_table(tmp_path / "tri.csv", {"t": t, "x": triangle})
    args = ["compensate", tmp_path / "p.json"]
    result = run(*args, tmp_path / "stairs.csv", "-o", tmp_path / "v.csv")
    assert result.exit_code == 0, result.output
    warned = re.search(
        r"hystcomp: warning: the paper's multiplicative structure \(eq\. 10\) turns the voltage "
        r"back where the reference does not, (\d+) times? \(the largest by ([\d.]+) V, at t = "
        r"([\d.]+) s\): it overshoots where the model is steeper than its gain rho.*"
        r"--method exact inverts the model without it\.",
        result.output,
    )
    assert warned, result.output
    v = read_table(tmp_path / "v.csv", ("v",))["v"]
    at = round(float(warned[3]) * 20_000.0)  # the largest: at a step, and as large as said
    assert at in (4000, 4001, 6000, 6001)
    assert min(abs(v[at] - v[at - 1]), abs(v[at + 1] - v[at])) == pytest.approx(
        float(warned[2]), abs=0.01
    )
    assert float(warned[2]) > 1.2  # more than 1 % of the 0..120 V range
    assert int(warned[1]) >= 2
    exact = run(*args, tmp_path / "stairs.csv", "--method", "exact", "-o", tmp_path / "e.csv")
    assert "warning" not in exact.output
    plain = run(*args, tmp_path / "tri.csv", "-o", tmp_path / "w.csv")
    assert "multiplicative structure" not in plain.output
