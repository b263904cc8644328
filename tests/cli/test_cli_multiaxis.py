"""The commands on N-axis files and models: excite, identify, compensate, simulate, export-c."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from hystcomp.cli import main
from hystcomp.io.multiaxis import read_axes
from hystcomp.io.records import write_table
from hystcomp.plant.scanner import Scanner, raster_scanner

FS = 2000.0


def _run(*args):
    result = CliRunner().invoke(main, [str(a) for a in args])
    return result.exit_code, result.stdout, result.stderr


@pytest.fixture(scope="module")
def stage(tmp_path_factory):
    """An excitation, the 2-axis scanner's record of it (upper-case names), and a model."""
    folder = tmp_path_factory.mktemp("multiaxis")
    code, out, err = _run(
        "excite", "multiaxis", "--axes", 2, "--fs", FS, "--frequency", 2, "-o", folder / "sig.csv"
    )
    assert code == 0, err
    assert "2 axes" in out
    sig = read_axes(folder / "sig.csv", ("v",))
    base = raster_scanner(2)
    scanner = Scanner(base.axes, base.coupling, sample_rate=FS)
    X = scanner.run(sig["v"])
    table = {"t": sig["t"], "V1": sig["v"][:, 0], "V2": sig["v"][:, 1]}
    table.update({"X1": X[:, 0], "X2": X[:, 1]})
    write_table(folder / "rec.csv", table)
    code, out, err = _run(
        "identify", folder / "rec.csv", "--model", "pi", "-o", folder / "m.json", "-q"
    )
    assert code == 0, err
    return folder, scanner, out


def test_identify_reports_the_coupling_and_each_axis(stage):
    folder, scanner, out = stage
    assert "2-axis model" in out
    assert "axis 1: PI" in out
    assert "axis 2: PI" in out
    doc = json.loads((folder / "m.json").read_text())
    assert doc["kind"] == "multiaxis"
    m = np.array(doc["coupling"])
    assert np.allclose(m, scanner.coupling, atol=0.01)  # 2.5-6 % identified within 1 %


def test_compensate_writes_one_voltage_per_axis_and_the_references(stage, tmp_path):
    folder, scanner, _ = stage
    n = 400
    t = np.arange(n) / FS
    ref = {"t": t, "x1": 10 + 6 * np.sin(2 * np.pi * 5 * t), "x2": np.linspace(5, 15, n)}
    write_table(tmp_path / "ref.csv", ref)
    code, _out, err = _run(
        "compensate", folder / "m.json", tmp_path / "ref.csv", "-o", tmp_path / "v.csv"
    )
    assert code == 0, err
    assert err == ""
    got = read_axes(tmp_path / "v.csv", ("v",))
    header = (tmp_path / "v.csv").read_text().splitlines()[0]
    assert header == "t,v1,v2,x1_ref,x2_ref"
    assert got["v"].min() >= 0.0
    assert got["v"].max() <= 120.0
    # the scanner driven by it follows the reference far better than a straight line would
    X = scanner.run_noiseless(got["v"])
    err_rms = np.sqrt(
        np.mean((X[n // 4 :] - np.column_stack([ref["x1"], ref["x2"]])[n // 4 :]) ** 2)
    )
    assert err_rms < 0.5


def test_a_reference_out_of_reach_is_warned_per_axis_and_refused_with_strict(stage, tmp_path):
    folder, _, _ = stage
    n = 200
    write_table(
        tmp_path / "far.csv",
        {"t": np.arange(n) / FS, "x1": np.linspace(5, 60, n), "x2": np.full(n, 8.0)},
    )
    code, _, err = _run(
        "compensate", folder / "m.json", tmp_path / "far.csv", "-o", tmp_path / "v.csv"
    )
    assert code == 0
    assert err.startswith("hystcomp: warning: axis 1:")
    assert "axis 2" not in err
    code, _, err = _run(
        "compensate", folder / "m.json", tmp_path / "far.csv", "-o", tmp_path / "w.csv", "--strict"
    )
    assert code == 2
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "w.csv").exists()


def test_a_reference_with_the_wrong_number_of_axes_is_refused(stage, tmp_path):
    folder, _, _ = stage
    write_table(
        tmp_path / "one.csv",
        {"t": [0.0, 1.0], "x1": [1.0, 2.0], "x2": [1.0, 2.0], "x3": [1.0, 1.0]},
    )
    (tmp_path / "v.csv").write_text("keep\n")
    code, _, err = _run(
        "compensate", folder / "m.json", tmp_path / "one.csv", "-o", tmp_path / "v.csv"
    )
    assert code == 2
    assert "3 axes" in err
    assert (tmp_path / "v.csv").read_text() == "keep\n"  # nothing overwritten


def test_simulate_runs_the_model_on_n_voltages(stage, tmp_path):
    folder, _, _ = stage
    code, _, err = _run("simulate", folder / "m.json", folder / "sig.csv", "-o", tmp_path / "x.csv")
    assert code == 0, err
    assert (tmp_path / "x.csv").read_text().splitlines()[0] == "t,v1,v2,x1,x2"


def test_export_c_writes_one_state_for_all_axes(stage, tmp_path):
    folder, _, _ = stage
    code, _, err = _run("export-c", folder / "m.json", "-o", tmp_path / "c", "--prefix", "xy")
    assert code == 0, err
    header = (tmp_path / "c" / "xy.h").read_text()
    assert "void xy_step(xy_state *s, const double *x_ref, double *v);" in header
    assert sorted(p.name for p in (tmp_path / "c").iterdir()) == [
        "xy.c",
        "xy.h",
        "xy_axis1.c",
        "xy_axis1.h",
        "xy_axis2.c",
        "xy_axis2.h",
    ]


def test_options_that_do_not_apply_are_refused(stage, tmp_path):
    folder, _, _ = stage
    code, _, err = _run("identify", folder / "rec.csv", "--holdout", 0.3, "-o", tmp_path / "m.json")
    assert code == 2
    assert "--holdout does not apply to an N-axis record" in err
    code, _, err = _run("excite", "multiaxis", "-o", tmp_path / "s.csv")
    assert code == 2
    assert "--axes" in err
    code, _, err = _run(
        "identify", folder / "rec.csv", "--columns", "v1=2,v1=3", "-o", tmp_path / "m.json"
    )
    assert code == 2
    assert not (tmp_path / "m.json").exists()


def test_axes_driven_together_are_refused_with_what_to_record(tmp_path):
    n = 2000
    v = 60 + 50 * np.sin(np.linspace(0, 12 * np.pi, n))
    x = 0.25 * v
    write_table(
        tmp_path / "same.csv", {"t": np.arange(n) / FS, "v1": v, "v2": v, "x1": x, "x2": 0.9 * x}
    )
    code, _, err = _run(
        "identify", tmp_path / "same.csv", "--model", "pi", "-o", tmp_path / "m.json"
    )
    assert code == 2
    assert "move together" in err
    assert "hystcomp excite multiaxis" in err
    assert not (tmp_path / "m.json").exists()


def test_voltage_range_may_only_narrow_every_axis(stage, tmp_path):
    folder, _, _ = stage
    n = 200
    ref = {"t": np.arange(n) / FS, "x1": np.linspace(2, 28, n), "x2": np.full(n, 8.0)}
    write_table(tmp_path / "ref.csv", ref)
    args = ["compensate", folder / "m.json", tmp_path / "ref.csv", "-o", tmp_path / "v.csv"]
    code, _, err = _run(*args, "--voltage-range", 10, 100, "--slew-rate", 2e4)
    assert code == 0, err
    v = read_axes(tmp_path / "v.csv", ("v",))["v"]
    assert v.min() >= 10.0
    assert v.max() <= 100.0
    assert np.abs(np.diff(v, axis=0)).max() <= 2e4 / FS + 1e-9  # the slew limit, per axis
    assert "axis 1" in err  # 28 µm needs more than 100 V: told
    code, _, err = _run(*args, "--voltage-range", -10, 100)
    assert code == 2
    assert "may only narrow" in err
