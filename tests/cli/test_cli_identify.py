"""The excite, identify, simulate and compensate commands, and their exit codes."""

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import hystcomp
from hystcomp import presets
from hystcomp.cli import main
from hystcomp.identify.excitation import excitation_signal, triangle_sequence
from hystcomp.io.records import read_record, read_table, write_table
from hystcomp.plant import Twin

# A real record (MIT licence, see the README and LICENSE beside it).
REAL_RECORD = Path(__file__).parents[1] / "data" / "piezo-micromanipulator" / "Model_Vi_Do.dat"


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def assert_one_line_error(result, code=2):
    """Exit status ``code``, no traceback, one error line (click adds a usage hint above)."""
    assert result.exit_code == code, result.output
    assert "Traceback" not in result.output
    errors = [
        line
        for line in result.output.splitlines()
        if line.startswith(("Error:", "hystcomp: error:", "hystcomp: internal error:"))
    ]
    assert len(errors) == 1, result.output


def test_excite_writes_the_paper_signals(tmp_path):
    result = run("excite", "pi", "--fs", "4")
    assert result.exit_code == 0
    assert result.output.splitlines()[:4] == ["t,v", "0.0,0.0", "0.25,15.0", "0.5,30.0"]
    out = tmp_path / "mpi.csv"
    assert run("excite", "mpi", "-o", out, "--fs", "1000").exit_code == 0
    table = read_table(out, ("v",))
    assert table["v"].size == 4001
    assert table["v"].max() == 120.0
    result = run("excite", "preisach", "-o", tmp_path / "p.npz", "--voltage-range", "-150", "150")
    assert result.exit_code == 0
    v = read_table(tmp_path / "p.npz", ("v",))["v"]
    assert (v.min(), v.max()) == (-150.0, 150.0)
    assert v.size == 24 * 20_000 + 1  # 24 sinusoids of 1 s at 20 kHz


@pytest.mark.parametrize(
    ("kind", "operators", "tolerance"),
    [("pi", 8, 0.05), ("mpi", 16, 1e-6)],  # a PI cannot follow the MPI's saturation
)
def test_identify_simulate_compensate_round_trip(tmp_path, kind, operators, tolerance):
    true = presets.paper_mpi()
    assert run("excite", kind, "-o", tmp_path / "v.csv", "--fs", "2000").exit_code == 0
    t, v = (read_table(tmp_path / "v.csv", ("v",))[k] for k in "tv")
    write_table(tmp_path / "rec.csv", {"t": t, "v": v, "x": true.simulate(v)})
    args = ["identify", tmp_path / "rec.csv", "--model", kind, "--operators", operators]
    if kind == "mpi":  # the paper's MPI has negative play weights: eq. 19 as printed
        args += ["--regularization", "0", "--constraints", "paper"]
    result = run(*args, "-o", tmp_path / "m.json", "--plot", tmp_path / "fig.png")
    assert result.exit_code == 0, result.output
    assert "fit error: rms" in result.output
    assert "compensation (estimated): tracking rms" in result.output
    assert (tmp_path / "fig.png").stat().st_size > 10_000
    model = hystcomp.load_model(tmp_path / "m.json")
    assert model.kind == kind
    assert model.get_params().get("regularization", 0.0) == 0.0
    assert model.thresholds_.size == operators
    assert model.fit_report_["n_used"] == v.size

    assert (
        run("simulate", tmp_path / "m.json", tmp_path / "v.csv", "-o", tmp_path / "x.npz").exit_code
        == 0
    )
    sim = read_table(tmp_path / "x.npz", ("v", "x"))
    np.testing.assert_array_equal(sim["x"], model.simulate(v))

    x_ref = 5.0 + 25.0 * (1.0 - np.abs(1.0 - 2.0 * (t % 1.0)))  # 1 Hz triangle, 5..30 µm
    write_table(tmp_path / "ref.csv", {"t": t, "x": x_ref})
    result = run("compensate", tmp_path / "m.json", tmp_path / "ref.csv", "-o", tmp_path / "v2.csv")
    assert result.exit_code == 0
    out = read_table(tmp_path / "v2.csv", ("v",))
    tracking = np.abs(true.simulate(out["v"]) - x_ref).max()
    assert tracking < tolerance * 25.0


def test_simulate_on_a_record_with_x_reports_the_error_against_it(tmp_path):
    """A record of another experiment validates a model: simulate prints the model's error
    against its measured x (after the start-up transient) beside a straight line's."""
    true = presets.paper_mpi()
    model = presets.paper_pi()
    _, v = excitation_signal("rich", sample_rate=500.0)
    t = np.arange(v.size) / 500.0
    write_table(tmp_path / "rec.csv", {"t": t, "v": v, "x": true.simulate(v)})
    hystcomp.save_model(model, tmp_path / "m.json")
    result = run("simulate", tmp_path / "m.json", tmp_path / "rec.csv", "-o", tmp_path / "s.csv")
    assert result.exit_code == 0, result.output
    err = model.simulate(v) - true.simulate(v)  # the record starts at 0 V: no transient
    rms = float(np.sqrt(np.mean(err**2)))
    assert f"against the measured x of {tmp_path / 'rec.csv'}: model rms {rms:.4g} µm" in (
        result.output
    )
    assert f"max {np.abs(err).max():.4g} µm; a straight line fitted to it: rms" in result.output
    # a displacement in nm: warned about, and read right with --x-unit
    write_table(tmp_path / "nm.csv", {"t": t, "v": v, "x": 1e3 * true.simulate(v)})
    args = ["simulate", tmp_path / "m.json", tmp_path / "nm.csv", "-o", tmp_path / "s3.csv"]
    assert "looks like nanometres" in run(*args).output
    assert f"model rms {rms:.4g} µm" in run(*args, "--x-unit", "nm").output
    write_table(tmp_path / "v.csv", {"t": t, "v": v})
    result = run("simulate", tmp_path / "m.json", tmp_path / "v.csv", "-o", tmp_path / "s2.csv")
    assert result.exit_code == 0
    assert "against the measured x" not in result.output


@pytest.mark.parametrize("kind", ["pi", "mpi"])
def test_real_record_in_one_command_beats_a_straight_line(tmp_path, kind):
    out = tmp_path / "model.json"
    result = run(
        "identify", REAL_RECORD, "--model", kind, "--columns", "v=1,x=5", "--fs", 200,
        "--holdout", 0.5, "-o", out,
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    rec = read_record(REAL_RECORD, columns={"v": 1, "x": 5}, sample_rate=200.0)
    # the start-up transient ends where the input first comes within 1 % of its span to an
    # end of its range (the record starts mid-range, at 1.8 V)
    tol = 0.01 * np.ptp(rec.v)
    start = int(np.argmax((rec.v <= rec.v.min() + tol) | (rec.v >= rec.v.max() - tol)))
    assert 0 < start < 100
    assert f"first {start} left out: start-up transient" in result.output
    # the printed figure, recomputed from the saved model on the held-out half: the model's
    # rms error against that of a straight line fitted to the same samples as the model
    printed = float(re.search(r"([\d.]+)x better", result.output).group(1))
    model = hystcomp.load_model(out)
    n_fit = len(rec) - round(0.5 * len(rec))
    model_rms = np.sqrt(np.mean((model.simulate(rec.v)[n_fit:] - rec.x[n_fit:]) ** 2))
    slope, intercept = np.polyfit(rec.v[start:n_fit], rec.x[start:n_fit], 1)
    line_rms = np.sqrt(np.mean((slope * rec.v[n_fit:] + intercept - rec.x[n_fit:]) ** 2))
    assert line_rms / model_rms == pytest.approx(printed, rel=0.01)
    assert line_rms / model_rms > 3.0
    assert model_rms < 0.01 * np.ptp(rec.x[start:])  # 1 % of the 45 µm stroke
    if kind == "mpi":  # x_0 is the smallest settled displacement: the sensor's offset
        assert model.output_offset_ == pytest.approx(rec.x[start:n_fit].min(), abs=0.05)
    model.inverse()  # invertible


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (["identify", "missing.csv", "--model", "pi", "-o", "m.json"], "does not exist"),
        (["identify", "rec.csv", "--model", "pi"], "Missing option '-o'"),
        (
            ["identify", "rec.csv", "--model", "bogus", "-o", "m.json"],
            "Invalid value for '--model'",
        ),
        (["identify", "rec.csv", "--model", "pi", "--holdout", "1", "-o", "m.json"], "between 0"),
        (
            ["identify", "rec.csv", "--model", "pi", "--deadzones", "3", "-o", "m.json"],
            "--deadzones",
        ),
        (
            ["identify", "rec.csv", "--model", "pi", "--operators", "0", "-o", "m.json"],
            "between 1 and",
        ),
        (["identify", "rec.csv", "--model", "pi", "--plot", "f.jpg", "-o", "m.json"], "--plot"),
        (
            ["identify", "rec.csv", "--model", "pi", "--regularization", "0.1", "-o", "m.json"],
            "--regularization does not apply to --model pi",
        ),
        (
            ["identify", "rec.csv", "--model", "mpi", "--regularization", "-1", "-o", "m.json"],
            "must be 'auto' or a number from 0 to 1e+12; got '-1'",
        ),
        (
            ["identify", "rec.csv", "--model", "mpi", "--regularization", "best", "-o", "m.json"],
            "must be 'auto' or a number from 0 to 1e+12; got 'best'",
        ),
        (
            ["identify", "rec.csv", "--model", "pi", "--degree", "2", "-o", "m.json"],
            "--degree does not apply to --model pi",
        ),
        (
            ["identify", "rec.csv", "--model", "preisach", "--degree", "0", "-o", "m.json"],
            "--degree",
        ),
        (["identify", "rec.csv", "--model", "pi", "--columns", "v=", "-o", "m.json"], "columns"),
        (["identify", "flat.csv", "--model", "mpi", "-o", "m.json"], "is constant"),
        (["simulate", "m.json", "rec.csv", "-o", "x.csv"], "Model file 'm.json' does not exist"),
        (["excite", "pi", "--fs", "-5"], "--fs"),
        (["compensate", "rec.csv", "rec.csv", "-o", "x.csv"], "not valid JSON"),
    ],
)
def test_bad_usage_and_bad_input_exit_2_in_one_line(tmp_path, monkeypatch, args, match):
    monkeypatch.chdir(tmp_path)
    v = np.r_[np.linspace(0, 10, 50), np.linspace(10, 0, 50)]
    write_table("rec.csv", {"t": np.arange(100) / 100, "v": v, "x": 2 * v})
    write_table("flat.csv", {"t": np.arange(100) / 100, "v": np.ones(100), "x": v})
    result = run(*args)
    assert_one_line_error(result)
    assert match in result.output


def test_preisach_through_every_command(tmp_path):
    """excite -> (paper's eq. 6 model as the rig) -> identify -> simulate -> compensate."""
    true = presets.paper_preisach(zero_diagonal=True)  # the form that identify fits
    assert run("excite", "preisach", "-o", tmp_path / "v.csv", "--fs", "500").exit_code == 0
    t, v = (read_table(tmp_path / "v.csv", ("v",))[k] for k in "tv")
    write_table(tmp_path / "rec.csv", {"t": t, "v": v, "x": true.simulate(v) - 120.0})
    args = ["identify", tmp_path / "rec.csv", "--model", "preisach", "--degree", "3"]
    args += ["--fit", "reversal-curves"]  # the paper's fit: eq. 5 to the reversal curves
    result = run(*args, "-o", tmp_path / "m.json")
    assert result.exit_code == 0, result.output
    assert result.output.startswith("Preisach model from")
    model = hystcomp.load_model(tmp_path / "m.json")
    assert model.kind == "preisach"
    assert model.output_offset_ == pytest.approx(-120.0, abs=1e-3)
    alpha, beta = np.meshgrid(np.linspace(0.0, 120.0, 7), np.linspace(0.0, 120.0, 7))
    plane = alpha >= beta
    np.testing.assert_allclose(
        model.everett_function(alpha[plane], beta[plane]),
        true.everett_function(alpha[plane], beta[plane]),
        atol=1e-3,
    )
    assert run("simulate", tmp_path / "m.json", tmp_path / "v.csv", "-o", tmp_path / "x.csv")
    np.testing.assert_allclose(read_table(tmp_path / "x.csv", ("x",))["x"], model.simulate(v))

    t = np.arange(20_001) / 20_000.0
    x_ref = -115.0 + 25.0 * (1.0 - np.abs(1.0 - 2.0 * (t % 1.0)))  # 1 Hz triangle, 5..30 µm
    write_table(tmp_path / "ref.csv", {"t": t, "x": x_ref})
    args = ["compensate", tmp_path / "m.json", tmp_path / "ref.csv", "-o", tmp_path / "v2.csv"]
    assert run(*args).exit_code == 0
    v2 = read_table(tmp_path / "v2.csv", ("v",))["v"]
    assert np.abs(model.simulate(v2) - x_ref)[1000:].max() < 0.005 * 25.0
    assert run(*args, "--voltage-range", 20, 60).exit_code == 0
    v3 = read_table(tmp_path / "v2.csv", ("v",))["v"]
    assert (v3.min(), v3.max()) == (20.0, 60.0)
    # the exact inverse: no one-sample lag, so it tracks the model more closely than eq. 10
    assert run(*args, "--method", "exact").exit_code == 0
    v4 = read_table(tmp_path / "v2.csv", ("v",))["v"]
    np.testing.assert_array_equal(v4, model.inverse(method="exact").simulate(x_ref))
    assert np.abs(model.simulate(v4) - x_ref)[1000:].max() < 1e-6


def test_constraints_paper_is_the_papers_preisach_fit_of_eq_5(tmp_path):
    """Eq. 6 as printed (X(v, v) != 0) is recovered by the paper's fit, coefficient by
    coefficient; the default holds X(v, v) = 0 and so cannot be."""
    true = presets.paper_preisach()
    assert run("excite", "preisach", "-o", tmp_path / "v.csv", "--fs", "500").exit_code == 0
    v = read_table(tmp_path / "v.csv", ("v",))["v"]
    write_table(
        tmp_path / "rec.csv", {"t": np.arange(v.size) / 500.0, "v": v, "x": true.simulate(v)}
    )
    args = ["identify", tmp_path / "rec.csv", "--model", "preisach", "--degree", "3"]
    args += ["--fit", "reversal-curves"]
    assert run(*args, "--constraints", "paper", "-o", tmp_path / "paper.json").exit_code == 0
    assert run(*args, "-o", tmp_path / "physical.json").exit_code == 0
    printed = hystcomp.load_model(tmp_path / "paper.json")
    np.testing.assert_allclose(printed.theta_, true.theta_, rtol=1e-3, atol=1e-9)
    held = hystcomp.load_model(tmp_path / "physical.json")
    assert abs(float(held.everett_function(120.0, 120.0))) < 1e-9
    assert abs(float(printed.everett_function(120.0, 120.0))) > 1e-3


def test_compensate_method_is_for_preisach_models_only(tmp_path):
    hystcomp.save_model(presets.paper_mpi(), tmp_path / "m.json")
    write_table(tmp_path / "ref.csv", {"t": np.arange(10) / 100.0, "x": np.linspace(1, 9, 10)})
    out = tmp_path / "v.csv"
    out.write_text("precious")
    args = ["compensate", tmp_path / "m.json", tmp_path / "ref.csv", "-o", out]
    result = run(*args, "--method", "exact")
    assert result.exit_code == 2
    assert "'--method': applies to Preisach models only" in result.output
    assert "m.json is MPI, whose inverse is analytic" in result.output
    assert out.read_text() == "precious"


def test_failed_identify_keeps_the_existing_model_file(tmp_path):
    out = tmp_path / "m.json"
    out.write_text("precious")
    write_table(tmp_path / "flat.csv", {"t": np.arange(3.0), "v": np.ones(3), "x": np.ones(3)})
    assert run("identify", tmp_path / "flat.csv", "--model", "pi", "-o", out).exit_code == 2
    assert out.read_text() == "precious"


def test_internal_fault_exits_1(tmp_path, monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("boom")

    monkeypatch.setattr("hystcomp.cli.identify.read_record", broken)
    result = run("identify", "x.csv", "--model", "pi", "-o", tmp_path / "m.json")
    assert_one_line_error(result, code=1)
    assert "internal error: RuntimeError: boom" in result.output


def test_python_dash_m_runs_the_command():
    src = Path(hystcomp.__file__).parents[1]
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(src), os.environ.get("PYTHONPATH", "")]),
    }
    result = subprocess.run(
        [sys.executable, "-m", "hystcomp", "excite", "--help"],
        capture_output=True,
        text=True,
        env=env,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    assert "identification input" in result.stdout


def test_mpi_regularization_reaches_the_fit_and_the_model_file(tmp_path):
    _, v = triangle_sequence(sample_rate=2000)
    x = Twin(seed=5).run(np.repeat(v, 10))[::10]  # the twin runs at 20 kHz
    write_table(tmp_path / "rec.csv", {"t": np.arange(v.size) / 2000, "v": v, "x": x})
    files = {}
    for value in ("0", "0.01"):
        files[value] = tmp_path / f"m{value}.json"
        args = ["identify", tmp_path / "rec.csv", "--model", "mpi", "--regularization", value]
        assert run(*args, "-o", files[value]).exit_code == 0
    plain, tamed = (hystcomp.load_model(files[k]) for k in ("0", "0.01"))
    assert tamed.get_params()["regularization"] == 0.01
    # the penalty on the changes of slope of S takes them down
    assert np.sum(tamed.deadzone_weights_[1:] ** 2) < 0.75 * np.sum(
        plain.deadzone_weights_[1:] ** 2
    )
    # by default the value is chosen, printed, and kept in the file with the choice
    result = run("identify", tmp_path / "rec.csv", "--model", "mpi", "-o", tmp_path / "auto.json")
    assert result.exit_code == 0, result.output
    auto = hystcomp.load_model(tmp_path / "auto.json")
    chosen = auto.fit_report_["regularization"]
    assert auto.get_params()["regularization"] == "auto"
    assert f"regularization: {chosen:g} (auto" in result.output
    assert auto.fit_report_["rms_error_um"] <= plain.fit_report_["rms_error_um"]
    chose = auto.fit_report_["initial_memory"]
    assert f"initial memory: {chose} (the better predicted tracking" in result.output
    # --initial-memory gives the start instead, into the fit, the file and the compensator
    other = {"virgin": "descended", "descended": "virgin"}[chose]
    given = run(*args[:4], "--initial-memory", other, "-o", tmp_path / "given.json")
    assert given.exit_code == 0, given.output
    assert f"  initial memory: {other} (given)" in given.output
    forced = hystcomp.load_model(tmp_path / "given.json")
    assert forced.get_params()["initial_memory"] == other
    assert forced.fit_report_["initial_memory"] == other
    ramp = np.linspace(0.0, 60.0, 50)  # from rest, not to the top: the start still shows
    assert np.abs(forced.simulate(ramp) - auto.simulate(ramp)).max() > 0.1


@pytest.mark.parametrize(
    ("argv", "status"),
    [(["--version"], 0), (["excite", "nope"], 2), (["excite", "pi", "-o", "{tmp}/e.csv"], 0)],
)
def test_the_program_flushes_then_ends_with_the_commands_status(
    monkeypatch, tmp_path, capsys, argv, status
):
    import os

    from hystcomp import _program

    ended = []
    monkeypatch.setattr(os, "_exit", ended.append)  # the real one would end pytest
    monkeypatch.setattr(sys, "argv", ["hystcomp", *(a.format(tmp=tmp_path) for a in argv)])
    _program.command_line()
    assert ended == [status]
    err = capsys.readouterr().err
    assert err.startswith("hystcomp: error:") if status else "Traceback" not in err
    assert (tmp_path / "e.csv").exists() == ("pi" in argv)
