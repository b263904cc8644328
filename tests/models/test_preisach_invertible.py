"""A Preisach model whose branches do not all rise has no compensator, whatever the method."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from click.testing import CliRunner

import hystcomp
from hystcomp import presets
from hystcomp.cli import main
from hystcomp.codegen import export_c
from hystcomp.errors import NotInvertibleError
from hystcomp.io.records import write_table
from hystcomp.models.preisach import Preisach

NODES = np.linspace(0.0, 120.0, 25)  # 5 V apart, as the default fit's table


def _table() -> np.ndarray:
    """X on the default grid, of the paper's model with X(v, v) = 0 (every branch rises)."""
    model = presets.paper_preisach(zero_diagonal=True)
    return np.tril(model.everett_function(NODES[:, None], NODES[None, :]))


def _falling() -> np.ndarray:
    table = _table()
    table[12, 0] = table[13, 0] = table[8, 0] - 5.0  # the ascending branch from 0 V falls
    return table


CASES = {
    "zero": (lambda: np.zeros((25, 25)), r"major loop does not rise .* = 0 µm \(table\[24, 0\]\)"),
    "negated": (lambda: -_table(), r"major loop does not rise .* = -36\.\d+ µm"),
    "falling": (
        _falling,
        (
            r"descending branch from 65 V turns back up by 11\.\d µm as the voltage falls "
            r"from 5 to 0 V \(table\[13, 1\] = .*, table\[13, 0\] = 4\.87.*correct table\[13, 0\]"
        ),
    ),
}


def test_the_paper_s_model_and_its_table_have_compensators():
    # the checks pass where every branch rises, as the least-squares fit's always do
    for model in (
        presets.paper_preisach(),
        presets.paper_preisach(zero_diagonal=True),
        Preisach.from_parameters(table=_table()),
    ):
        for method in ("multiplicative", "exact"):
            assert model.inverse(method=method).voltage_range == (0.0, 120.0)


@pytest.mark.parametrize("name", sorted(CASES))
def test_every_method_and_every_gain_refuses_it(name):
    make, match = CASES[name]
    model = Preisach.from_parameters(table=make())
    for options in ({}, {"method": "exact"}, {"rho": 0.3}, {"method": "exact", "slew_rate": 1e3}):
        with pytest.raises(NotInvertibleError, match=match) as info:
            model.inverse(**options)
        assert info.value.index is None
    assert model.simulate(np.array([0.0, 120.0])).size == 2  # the forward model still runs


@pytest.mark.parametrize("name", sorted(CASES))
@pytest.mark.parametrize("method", ["multiplicative", "exact"])
def test_compensate_and_export_c_exit_2_and_write_nothing(tmp_path, name, method):
    make, match = CASES[name]
    path = tmp_path / "p.json"
    hystcomp.save_model(Preisach.from_parameters(table=make()), path)
    t = np.arange(200) / 20_000.0
    write_table(tmp_path / "ref.csv", {"t": t, "x": 15.0 * (1.0 - np.cos(2 * np.pi * 10 * t))})
    (tmp_path / "v.csv").write_text("old")
    runner = CliRunner()
    args = [str(path), str(tmp_path / "ref.csv"), "--method", method, "-o", str(tmp_path / "v.csv")]
    result = runner.invoke(main, ["compensate", *args])
    assert result.exit_code == 2, result.output
    assert result.output.count("hystcomp: error:") == 1
    assert "Traceback" not in result.output
    assert re.search(match, " ".join(result.output.split()))
    assert (tmp_path / "v.csv").read_text() == "old"
    folder = tmp_path / "fw"
    result = runner.invoke(main, ["export-c", str(path), "--method", method, "-o", str(folder)])
    assert result.exit_code == 2, result.output
    assert re.search(match, " ".join(result.output.split()))
    assert not folder.exists()  # not even an empty folder


def test_the_defect_names_the_voltages_of_a_polynomial():
    # X = 0.3 (alpha - beta) - 0.002 (alpha - beta)^2: every branch rises, then falls past 75 V
    model = Preisach.from_parameters(theta=[-0.3, 0.3, -0.002, 0.004, -0.002])
    with pytest.raises(
        NotInvertibleError, match=r"ascending branch from 0 V turns back down .* V \(X\("
    ):
        model.inverse(method="exact")


def test_a_model_file_s_table_that_was_edited_is_refused_in_python_too(tmp_path):
    path = tmp_path / "p.json"
    hystcomp.save_model(Preisach.from_parameters(table=_table()), path)
    doc = json.loads(path.read_text())
    doc["parameters"]["table"] = _falling().tolist()
    path.write_text(json.dumps(doc))
    model = hystcomp.load_model(path)
    with pytest.raises(NotInvertibleError):
        export_c(model.inverse(method="exact"), tmp_path / "fw")
    assert not (tmp_path / "fw").exists()
