"""One wrong voltage sample far outside the record must not set a model's range."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

import hystcomp
from hystcomp import presets
from hystcomp.cli import main
from hystcomp.errors import InvalidSignalError
from hystcomp.identify.dynamics import dynamics_excitation
from hystcomp.identify.excitation import (
    random_turning_points,
    rich_sequence,
    sinusoid_sequence,
    triangle_sequence,
)
from hystcomp.identify.outliers import bulk_range, isolated_samples
from hystcomp.identify.scoring import transient_end
from hystcomp.io.records import Record, read_table, write_table
from hystcomp.workflows.identify import identify_record

FS = 2000.0  # Hz: the paper's triangles, 8001 samples


def _triangles():
    t, v = triangle_sequence(sample_rate=FS)
    return t, v


def _glitched(k: int, value: float) -> np.ndarray:
    v = _triangles()[1].copy()
    v[k] = value
    return v


@pytest.mark.parametrize(
    ("k", "value"), [(0, -30.0), (4000, -60.0), (4000, 1000.0), (8000, -8.0), (1234, 130.0)]
)
def test_a_glitch_is_found_by_its_index(k, value):
    v = _glitched(k, value)
    assert isolated_samples(v).tolist() == [k]
    assert bulk_range(v) == (0.0, 120.0)


def test_a_glitch_of_three_samples_is_one_and_of_four_is_the_record():
    v = _triangles()[1].copy()
    v[4000:4003] = 1000.0
    assert isolated_samples(v).tolist() == [4000, 4001, 4002]
    v[4003] = 1000.0  # four samples in a row: held, so the record went there
    assert isolated_samples(v).size == 0


def test_the_signals_hystcomp_writes_and_a_real_record_have_none():
    from hystcomp.io.records import read_record
    from tests.cli.test_cli_identify import REAL_RECORD

    signals = [
        _triangles()[1],
        sinusoid_sequence(sample_rate=FS)[1],
        rich_sequence(sample_rate=FS)[1],
        random_turning_points(sample_rate=FS)[1],
        dynamics_excitation()[1],
        read_record(REAL_RECORD, columns={"v": 1, "x": 5}, sample_rate=200.0).v,
    ]
    rng = np.random.default_rng(3)
    signals.append(_triangles()[1] + rng.normal(0.0, 0.5, 8001))  # a noisy command
    signals.append(np.tile(np.r_[np.linspace(0, 100, 8), np.linspace(100, 0, 8)[1:-1]], 10))
    lone = np.r_[np.linspace(0, 90, 20), 100.0, np.linspace(90, 0, 20), np.zeros(40)]
    signals.append(lone)  # a coarse triangle's peak stands out by one ordinary step
    for v in signals:
        assert isolated_samples(v).size == 0
        assert bulk_range(v) == (v.min(), v.max())


def test_the_start_up_transient_is_not_fooled_by_a_glitch():
    # the case: the fit dropped half the record, waiting for the glitch's "end"
    assert transient_end(_glitched(4000, -60.0)) == 0
    # a record starting mid-range: the transient ends at a true end, not at the glitch
    v = np.r_[np.linspace(60.0, 90.0, 500), -60.0, np.linspace(90.0, 120.0, 501)]
    v = np.r_[v, np.linspace(120.0, 0.0, 2000), np.linspace(0.0, 120.0, 2000)]
    k = transient_end(v)
    assert k > 500
    assert v[k] >= 118.8


@pytest.mark.parametrize(
    ("estimator", "owner"),
    [
        (hystcomp.PrandtlIshlinskii(n_operators=4), "fit_pi"),
        (hystcomp.ModifiedPrandtlIshlinskii(n_operators=4, n_deadzones=4), "fit_mpi"),
        (hystcomp.Preisach(grid_size=5), "identify_preisach"),
    ],
)
def test_every_fit_refuses_a_glitch_by_its_index(estimator, owner):
    v = _glitched(4000, -60.0)
    x = presets.paper_mpi().simulate(np.clip(v, 0.0, None))
    with pytest.raises(
        InvalidSignalError, match=rf"^{owner}: .* v\[4000\] is -60 V, .* 0 \.\. 120 V"
    ):
        estimator.fit(v, x)


def test_identify_names_the_data_row_and_writes_nothing(tmp_path):
    t, v = _triangles()
    x = presets.paper_mpi().simulate(v)
    v = v.copy()
    v[0] = -30.0
    write_table(tmp_path / "g.csv", {"t": t, "v": v, "x": x})
    (tmp_path / "g.json").write_text("old")
    result = CliRunner().invoke(
        main,
        [
            "identify",
            str(tmp_path / "g.csv"),
            "--model",
            "preisach",
            "-o",
            str(tmp_path / "g.json"),
        ],
    )
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output
    assert "data row 1 (t = 0 s) is -30 V, while every other sample lies in 0 .. 120 V" in (
        result.output
    )
    assert (tmp_path / "g.json").read_text() == "old"


def test_the_record_s_range_is_in_the_model_and_compensate_warns_beyond_it(tmp_path):
    t, v = _triangles()
    rec = Record(t, v, presets.paper_mpi().simulate(v), source="triangles")
    wide = identify_record(
        rec, "pi", operators=8, voltage_range=(0.0, 140.0), allow_extrapolation=True
    )
    model = wide.model
    assert model.voltage_range_ == (0.0, 140.0)  # the amplifier's range: the clamp
    assert model.covered_range() == (0.0, 120.0)  # what the record covered
    path = tmp_path / "m.json"
    hystcomp.save_model(model, path)
    assert hystcomp.load_model(path).covered_range() == (0.0, 120.0)
    reach = model.reachable_range()[1]
    tr = np.arange(2000) / 20_000.0
    write_table(
        tmp_path / "ref.csv", {"t": tr, "x": 0.5 * reach * (1 - np.cos(2 * np.pi * 10 * tr))}
    )
    out = tmp_path / "v.csv"
    result = CliRunner().invoke(
        main, ["compensate", str(path), str(tmp_path / "ref.csv"), "-o", str(out)]
    )
    assert result.exit_code == 0, result.output
    v_out = read_table(out, ("v",))["v"]
    beyond = int(np.count_nonzero(v_out > 120.0))
    assert beyond > 0
    assert (
        f"hystcomp: warning: {beyond} of 2000 samples command voltages beyond 0 .. 120 V, the "
        "range that the model's record covered"
    ) in result.output
    inside = identify_record(rec, "pi", operators=8).model
    assert inside.voltage_range_ == inside.covered_range() == (0.0, 120.0)
