"""hystcomp.evaluate and ``hystcomp evaluate``: a run's tracking against its reference."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

import hystcomp
from hystcomp import presets
from hystcomp.cli import main
from hystcomp.errors import InvalidParameterError, InvalidTypeError
from hystcomp.experiment.metrics import hysteresis_percent
from hystcomp.io.records import read_record, write_table
from hystcomp.plant import Twin
from hystcomp.workflows.evaluate import Evaluation

FS = 2000.0


def _triangle(n=4000, amplitude=20.0, periods=4):
    t = np.arange(n) / FS
    phase = (t * periods * FS / n) % 1.0
    return t, amplitude * (1.0 - np.abs(2.0 * phase - 1.0))


def test_known_errors_and_hysteresis_are_measured():
    t, x_ref = _triangle()
    rng = np.random.default_rng(0)
    e = 0.05 * rng.standard_normal(t.size) + 0.02
    e[1234] = 0.9  # one spike: the maximum
    run = hystcomp.evaluate({"t": t, "x": x_ref}, {"t": t, "x": x_ref + e})
    assert isinstance(run, Evaluation)
    assert run.rms_um == pytest.approx(np.sqrt(np.mean(e**2)), rel=1e-12)
    assert run.max_um == pytest.approx(0.9)
    assert run.mean_um == pytest.approx(np.mean(e), rel=1e-12)
    assert run.range_um == pytest.approx(np.ptp(x_ref))
    assert run.interpolated is False
    assert run.samples == t.size
    assert run.outside == 0
    assert run.hysteresis_pct == pytest.approx(hysteresis_percent(x_ref, x_ref + e)[0])
    # the error over time: ten spans covering the run, the spike in the fourth
    assert len(run.spans) == 10
    assert run.spans[0].t_start == t[0]
    assert run.spans[-1].t_end == t[-1]
    assert max(run.spans, key=lambda s: s.max_um) is run.spans[3]


def test_a_loop_of_known_width_and_a_reference_without_one():
    u = np.linspace(0.0, 10.0, 1001)
    x_ref = np.concatenate([u, u[::-1]])
    x = np.concatenate([u, u[::-1] + 0.5])  # the falling branch 0.5 µm above: 5 % of 10 µm
    t = np.arange(x.size) / FS
    run = hystcomp.evaluate({"t": t, "x": x_ref}, {"t": t, "x": x})
    assert run.hysteresis_pct == pytest.approx(100 * 0.5 / 10.5, rel=1e-3)
    ramp = hystcomp.evaluate({"t": t, "x": t}, {"t": t, "x": t + 0.1})
    assert ramp.hysteresis_pct is None
    assert ramp.max_um == pytest.approx(0.1)


def test_matched_by_time_interpolated_outside_counted_and_skipped():
    t_ref = np.arange(0, 2001) / 1000.0  # 0 .. 2 s at 1 kHz
    x_ref = 3.0 * t_ref  # a ramp: linear interpolation is exact
    t = 0.5 + np.arange(3000) / 1000.0 + 0.0004  # 0.5004 .. 3.4994 s, off the grid
    x = 3.0 * t + 0.25
    run = hystcomp.evaluate({"t": t_ref, "x": x_ref}, {"t": t, "x": x})
    assert run.interpolated
    assert run.t[-1] <= 2.0
    assert run.outside == int(np.count_nonzero(t > 2.0))
    np.testing.assert_allclose(run.e, 0.25, rtol=0, atol=1e-12)
    skipped = hystcomp.evaluate({"t": t_ref, "x": x_ref}, {"t": t, "x": x}, skip=1.0)
    assert skipped.t[0] >= t[0] + 1.0
    assert skipped.samples == run.samples - 1000
    with pytest.raises(InvalidParameterError, match="shares fewer than two instants"):
        hystcomp.evaluate({"t": t_ref, "x": x_ref}, {"t": t + 10.0, "x": x})
    with pytest.raises(InvalidParameterError, match="'skip' parameter of evaluate"):
        hystcomp.evaluate({"t": t_ref, "x": x_ref}, {"t": t, "x": x}, skip=-1.0)
    with pytest.raises(InvalidParameterError, match="must hold columns 't'"):
        hystcomp.evaluate({"time": t_ref, "x": x_ref}, {"t": t, "x": x})
    with pytest.raises(InvalidTypeError, match="'measured' parameter of evaluate"):
        hystcomp.evaluate({"t": t_ref, "x": x_ref}, 3.0)


def test_records_and_dataframes_are_taken(tmp_path):
    t, x_ref = _triangle()
    frame = pd.DataFrame({"t": t, "v": x_ref / 0.2, "x": x_ref + 0.1})
    run = hystcomp.evaluate(pd.DataFrame({"t": t, "x": x_ref}), frame)
    assert run.max_um == pytest.approx(0.1)
    np.testing.assert_array_equal(run.v, frame["v"].to_numpy())
    path = tmp_path / "run.csv"
    write_table(path, {"t": t, "v": x_ref / 0.2, "x": x_ref - 0.1})
    run = hystcomp.evaluate({"t": t, "x": x_ref}, read_record(path))
    assert run.mean_um == pytest.approx(-0.1)
    assert run.measured == str(path)


@pytest.fixture(scope="module")
def compensated_run(tmp_path_factory):
    """compensate, then the twin as the stage: a reference file and a measured file."""
    folder = tmp_path_factory.mktemp("evaluate")
    model = presets.paper_mpi()
    fs = 20_000.0
    t = np.arange(int(0.5 * fs)) / fs
    x_ref = 12.0 * (1.0 - np.cos(2 * np.pi * 4.0 * t))  # 4 Hz, 0 .. 24 µm
    write_table(folder / "reference.csv", {"t": t, "x": x_ref})
    v = model.inverse().simulate(x_ref)
    x = Twin(seed=1).run(v)
    write_table(folder / "measured.csv", {"t": t, "v": v, "x": x})
    return folder, t, x_ref, x


def test_cli_prints_the_figures_and_json(compensated_run):
    folder, t, x_ref, x = compensated_run
    ref, measured = folder / "reference.csv", folder / "measured.csv"
    result = CliRunner().invoke(main, ["evaluate", str(ref), str(measured), "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.output)
    e = x - x_ref
    assert data["rms_um"] == pytest.approx(np.sqrt(np.mean(e**2)), rel=1e-12)
    assert data["max_um"] == pytest.approx(np.abs(e).max(), rel=1e-12)
    assert data["samples"] == t.size
    assert len(data["spans"]) == 10
    assert data["hysteresis_pct"] > 0
    text = CliRunner().invoke(main, ["evaluate", str(ref), str(measured), "--skip", "0.25"])
    assert text.exit_code == 0, text.output
    late = np.sqrt(np.mean(e[t >= 0.25] ** 2))
    assert f"rms {late:.4g} µm" in text.output
    assert "the first 0.25 s left out" in text.output
    assert "error over time:" in text.output
    assert len([line for line in text.output.splitlines() if " .. " in line]) >= 10


def test_cli_plot_and_refusals(compensated_run, tmp_path):
    folder, *_ = compensated_run
    ref, measured = folder / "reference.csv", folder / "measured.csv"
    png = tmp_path / "tracking.png"
    result = CliRunner().invoke(main, ["evaluate", str(ref), str(measured), "--plot", str(png)])
    assert result.exit_code == 0, result.output
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert png.stat().st_size > 20_000
    bad = CliRunner().invoke(main, ["evaluate", str(ref), str(measured), "--plot", "a.txt"])
    assert bad.exit_code == 2
    assert "--plot" in bad.output
    # a failing run leaves an existing figure as it was
    before = png.read_bytes()
    empty = tmp_path / "empty.csv"
    empty.write_text("t,x\n")
    failed = CliRunner().invoke(main, ["evaluate", str(ref), str(empty), "--plot", str(png)])
    assert failed.exit_code == 2
    assert "Traceback" not in failed.output
    assert png.read_bytes() == before
    far = tmp_path / "far.csv"
    write_table(far, {"t": np.arange(10) + 100.0, "x": np.zeros(10)})
    failed = CliRunner().invoke(main, ["evaluate", str(ref), str(far)])
    assert failed.exit_code == 2
    assert "shares fewer than two instants" in failed.output
