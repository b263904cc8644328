"""Bad input gets a clean answer: tampered model files, bad rates and prefixes, a bare
``hystcomp``, unfitted models, samples of the wrong type, and an honest hold-out line."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

import hystcomp
from hystcomp import presets
from hystcomp.cli import main
from hystcomp.codegen import check_prefix, generate_c
from hystcomp.errors import (
    InvalidParameterError,
    InvalidSignalError,
    InvalidTypeError,
    ModelFileError,
    NotFittedError,
)
from hystcomp.io.models import model_from_dict, model_to_dict
from hystcomp.io.records import write_table
from hystcomp.workflows.identify import _verdict


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def _table_preisach():
    model = presets.paper_preisach()
    grid = np.linspace(0.0, 120.0, 7)
    a, b = np.meshgrid(grid, grid, indexing="ij")
    table = model.everett_function(a, b)
    return hystcomp.Preisach.from_parameters(table=np.tril(table), voltage_range=(0.0, 120.0))


TAMPERED = [
    ("preisach", "degree", 5),
    ("preisach", "degree", 3.5),
    ("preisach", "degree", "3"),
    ("preisach", "degree", True),
    ("preisach", "everett", "table"),
    ("preisach", "zero_diagonal", "yes"),
    ("preisach", "max_extrema", 2),
    ("preisach", "grid_size", "x"),
    ("preisach-table", "grid_size", 9),
    ("preisach-table", "everett", "polynomial"),
    ("preisach", "fit_method", "zzz"),
    ("preisach", "fit_method", None),
    ("pi", "n_operators", 15),
    ("pi", "n_operators", 16.0),
    ("pi", "margin", "0.001"),
    ("pi", "transient", -1),
    ("pi", "voltage_range", [5, 1]),
    ("mpi", "n_deadzones", 3),
    ("mpi", "regularization", "most"),
]


def _document(kind):
    model = {
        "pi": presets.paper_pi,
        "mpi": presets.paper_mpi,
        "preisach": presets.paper_preisach,
        "preisach-table": _table_preisach,
    }[kind]()
    doc = model_to_dict(model)
    model_from_dict(json.loads(json.dumps(doc)))  # untampered, it loads
    return doc


@pytest.mark.parametrize(("kind", "name", "value"), TAMPERED)
def test_a_tampered_hyperparameter_is_refused_when_the_file_is_read(kind, name, value):
    doc = _document(kind)
    doc["hyperparameters"][name] = value
    with pytest.raises(ModelFileError, match=name):
        model_from_dict(doc, source="m.json")


@pytest.mark.parametrize("value", [5, 3.5, "3"])
@pytest.mark.parametrize("command", ["compensate", "simulate", "export-c"])
def test_cli_exits_2_on_a_preisach_file_whose_degree_disagrees(tmp_path, command, value):
    doc = _document("preisach")
    doc["hyperparameters"]["degree"] = value
    (tmp_path / "m.json").write_text(json.dumps(doc))
    write_table(tmp_path / "in.csv", {"t": [0.0, 1.0, 2.0], "x": [1.0, 2.0, 3.0], "v": [1.0] * 3})
    if command == "export-c":
        result = run("export-c", tmp_path / "m.json", "-o", tmp_path / "c")
    else:
        result = run(command, tmp_path / "m.json", tmp_path / "in.csv", "-o", tmp_path / "o.csv")
    assert result.exit_code == 2, result.output
    assert "hystcomp: error:" in result.output
    assert "'degree'" in result.output
    assert "internal error" not in result.output


def test_fit_checks_the_same_hyperparameters():
    v = np.linspace(0.0, 100.0, 200)
    with pytest.raises(InvalidTypeError, match="'degree'"):
        hystcomp.Preisach(degree="3").fit(v, v)
    with pytest.raises(InvalidParameterError, match="'margin'"):
        hystcomp.PrandtlIshlinskii(margin=2.0).fit(v, v)


@pytest.mark.parametrize("fs", ["0", "-5", "nan", "inf", "-inf"])
def test_export_c_accepts_only_a_positive_finite_rate(tmp_path, fs):
    hystcomp.save_model(presets.paper_pi(), tmp_path / "m.json")
    result = run("export-c", tmp_path / "m.json", "-o", tmp_path / "c", "--fs", fs)
    assert result.exit_code == 2, result.output
    assert "--fs" in result.output
    assert not (tmp_path / "c").exists()


@pytest.mark.parametrize("rate", [0.0, -1.0, math.nan, math.inf])
def test_generate_c_refuses_a_bad_rate(rate):
    with pytest.raises(InvalidParameterError, match="sample_rate"):
        generate_c(presets.paper_pi().inverse(), sample_rate=rate)


@pytest.mark.parametrize("prefix", ["math", "stdio", "stdlib", "string", "Math", "float", "int"])
def test_a_prefix_that_shadows_a_header_or_is_a_keyword_is_refused(tmp_path, prefix):
    with pytest.raises(InvalidParameterError, match=repr(prefix)):
        check_prefix(prefix)
    hystcomp.save_model(presets.paper_pi(), tmp_path / "m.json")
    result = run("export-c", tmp_path / "m.json", "-o", tmp_path / "c", "--prefix", prefix)
    assert result.exit_code == 2
    assert not (tmp_path / "c").exists()
    assert check_prefix("math_comp") == "math_comp"


def test_bare_hystcomp_prints_usage_and_commands():
    result = CliRunner().invoke(main, [], prog_name="hystcomp")
    assert result.exit_code == 2  # as click does for a group called without a command
    assert result.stderr.startswith("Usage: hystcomp [OPTIONS] COMMAND")
    assert "Commands:" in result.stderr
    assert "compensate" in result.stderr
    assert "error" not in result.stderr
    assert result.stdout == ""


def test_saving_an_unfitted_model_says_it_is_not_fitted(tmp_path):
    for model in (hystcomp.Preisach(), hystcomp.PrandtlIshlinskii()):
        with pytest.raises(NotFittedError, match="no parameters yet"):
            hystcomp.save_model(model, tmp_path / "m.json")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("make", [presets.paper_pi, presets.paper_preisach])
def test_step_takes_one_real_number(make):
    stepper = make().inverse().stepper()
    for bad in ("1.0", b"1", True, np.bool_(True), np.ones(1), None, [1.0]):
        with pytest.raises(InvalidTypeError, match="one sample, a real number"):
            stepper.step(bad)
    reference = make().inverse().stepper()
    for good in (1.0, 2, np.float64(3.0), np.float32(4.0), np.int64(5)):
        assert stepper.step(good) == reference.step(float(good))


@pytest.mark.parametrize("make", [presets.paper_pi, presets.paper_preisach])
def test_step_block_refuses_two_dimensions_and_text(make):
    stepper = make().inverse().stepper()
    with pytest.raises(InvalidSignalError, match=r"1-D block .* shape \(2, 3\)"):
        stepper.step_block(np.ones((2, 3)))
    with pytest.raises(InvalidTypeError, match="real numbers"):
        stepper.step_block(["1.0", "2.0"])
    assert stepper.step_block(2.0).shape == (1,)
    assert stepper.step_block([1, 2, 3]).shape == (3,)


def test_holdout_verdict_reads_worse_below_one():
    assert _verdict(2.5) == "2.5x better"
    assert _verdict(0.879) == "1.14x worse"
    assert _verdict(1.0) == "1x better"


def test_none_for_a_signal_is_named_a_type_error():
    from hystcomp.errors import InvalidTypeError

    with pytest.raises(InvalidTypeError, match="'v' must be a 1-D array of real numbers"):
        hystcomp.PrandtlIshlinskii().fit(None, None)


@pytest.mark.parametrize("make", [
    lambda: hystcomp.PrandtlIshlinskii(n_operators=257),
    lambda: hystcomp.ModifiedPrandtlIshlinskii(n_deadzones=1000),
])  # fmt: skip
def test_a_fit_with_more_operators_than_it_can_solve_in_time_is_refused_at_once(make):
    v = np.r_[np.linspace(0.0, 120.0, 500), np.linspace(120.0, 0.0, 500)]
    with pytest.raises(InvalidParameterError, match="at most 256"):
        make().fit(v, presets.paper_mpi().simulate(v))
