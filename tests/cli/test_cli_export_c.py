"""``hystcomp export-c``: files, prefix, exit codes, and no damage on failure."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from click.testing import CliRunner

import hystcomp
from hystcomp.cli import main
from hystcomp.io.records import read_table, write_table
from tests.codegen.test_codegen import build_preisach, needs_cc
from tests.conftest import random_walk


@pytest.fixture
def model_file(tmp_path):
    path = tmp_path / "mpi.json"
    hystcomp.save_model(hystcomp.presets.paper_mpi(), path)
    return path


def _export(*args):
    return CliRunner().invoke(main, ["export-c", *map(str, args)])


def test_writes_header_and_source_with_the_default_prefix(model_file, tmp_path):
    out = tmp_path / "c"
    result = _export(model_file, "-o", out)
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in out.iterdir()) == [
        "hystcomp_compensator.c",
        "hystcomp_compensator.h",
    ]
    header = (out / "hystcomp_compensator.h").read_text()
    assert (
        "double hystcomp_compensator_step(hystcomp_compensator_state *s, double x_ref);" in header
    )
    assert f"from {model_file}" in header
    assert "inverse Modified Prandtl-Ishlinskii" in header


def test_prefix_names_files_type_and_functions(model_file, tmp_path):
    result = _export(model_file, "-o", tmp_path, "--prefix", "stage_x")
    assert result.exit_code == 0, result.output
    header = (tmp_path / "stage_x.h").read_text()
    for name in ("stage_x_state", "stage_x_init(", "stage_x_reset(", "stage_x_step("):
        assert name in header
    assert '#include "stage_x.h"' in (tmp_path / "stage_x.c").read_text()


@pytest.mark.parametrize("prefix", ["9lives", "stage-x", "_hidden", "a b"])
def test_invalid_prefix_exits_2_and_writes_nothing(model_file, tmp_path, prefix):
    out = tmp_path / "c"
    result = _export(model_file, "-o", out, "--prefix", prefix)
    assert result.exit_code == 2
    assert "prefix must be a C identifier" in result.output
    assert "Traceback" not in result.output
    assert not out.exists()


def test_slew_rate_and_sample_rate_are_baked_in(model_file, tmp_path):
    result = _export(model_file, "-o", tmp_path, "--slew-rate", "50000", "--fs", "10000")
    assert result.exit_code == 0, result.output
    source = (tmp_path / "hystcomp_compensator.c").read_text()
    assert "v = s->last + 5.0;" in source  # 50 000 V/s at 10 kHz: 5 V per sample
    assert "every 100 us" in source


@pytest.mark.parametrize("option", [["--slew-rate", "-1"], ["--slew-rate", "1e5", "--fs", "0"]])
def test_bad_slew_options_exit_2(model_file, tmp_path, option):
    result = _export(model_file, "-o", tmp_path, *option)
    assert result.exit_code == 2
    assert re.search(
        r"Invalid value for '--(slew-rate|fs)': must be a (finite )?number > 0", result.output
    )


def test_missing_model_file_exits_2(tmp_path):
    result = _export(tmp_path / "nope.json", "-o", tmp_path)
    assert result.exit_code == 2
    assert "does not exist" in result.output


def test_output_folder_without_parent_exits_2(model_file, tmp_path):
    result = _export(model_file, "-o", tmp_path / "a" / "b")
    assert result.exit_code == 2
    assert "is not an existing folder" in result.output


def test_failure_leaves_existing_files_untouched(tmp_path):
    # a model whose inverse does not exist: the command fails after the files were planned
    path = tmp_path / "bad.json"
    doc = hystcomp.io.model_to_dict(hystcomp.presets.paper_pi())
    doc["parameters"]["weights"] = (-np.asarray(doc["parameters"]["weights"])).tolist()
    path.write_text(json.dumps(doc))
    existing = tmp_path / "hystcomp_compensator.c"
    existing.write_text("precious")
    result = _export(path, "-o", tmp_path)
    assert result.exit_code == 2
    assert "not invertible" in result.output
    assert existing.read_text() == "precious"
    assert not (tmp_path / "hystcomp_compensator.h").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.json", "hystcomp_compensator.c"]


def test_write_failure_exits_2_and_leaves_the_other_file(model_file, tmp_path):
    (tmp_path / "hystcomp_compensator.h").write_text("precious")
    (tmp_path / "hystcomp_compensator.c").mkdir()  # in the way: the .c cannot be written
    result = _export(model_file, "-o", tmp_path)
    assert result.exit_code == 2
    assert "Cannot write the output" in result.output
    assert "hystcomp_compensator.c" in result.output
    assert (tmp_path / "hystcomp_compensator.h").read_text() == "precious"
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]


@needs_cc
@pytest.mark.parametrize("method", [None, "multiplicative", "exact"])
def test_preisach_model_from_identify_exports_and_runs_as_python(method, tmp_path, rng):
    """excite -> (eq. 6, zero diagonal, as the rig) -> identify -> export-c -> cc -> step."""
    rig = hystcomp.presets.paper_preisach(zero_diagonal=True)
    assert _export_run("excite", "preisach", "-o", tmp_path / "v.csv", "--fs", "500") == 0
    t, v = (read_table(tmp_path / "v.csv", ("v",))[k] for k in "tv")
    write_table(tmp_path / "rec.csv", {"t": t, "v": v, "x": rig.simulate(v) - 120.0})
    model_file = tmp_path / "preisach.json"
    args = ["identify", tmp_path / "rec.csv", "--model", "preisach", "-o", model_file]
    assert _export_run(*args) == 0
    out = tmp_path / "c"
    options = [] if method is None else ["--method", method]
    result = _export(model_file, "-o", out, "--prefix", "stage_x", "--slew-rate", "2e5", *options)
    assert result.exit_code == 0, result.output
    header = (out / "stage_x.h").read_text()
    assert ("exact inverse" in header) == (method == "exact")
    assert f"from {model_file}" in header
    # the compiled code steps as the model file's compensator does in Python
    model = hystcomp.load_model(model_file)
    comp = model.inverse(method=method or "multiplicative", slew_rate=2e5, sample_rate=20_000)
    x_ref = -120.0 + random_walk(rng, 20_000, -5.0, 45.0, 0.4)
    x_ref[rng.choice(x_ref.size, 10, replace=False)] = np.nan
    v_c, _, held = build_preisach(out, "stage_x")(x_ref)
    stepper = comp.stepper()
    np.testing.assert_allclose(v_c, stepper.step_block(x_ref), rtol=0, atol=1e-9)
    assert held == stepper.nonfinite_count == 10


def test_method_for_a_pi_model_exits_2_and_writes_nothing(model_file, tmp_path):
    out = tmp_path / "c"
    result = _export(model_file, "-o", out, "--method", "exact")
    assert result.exit_code == 2
    assert "'--method': applies to Preisach models only" in result.output
    assert "is MPI, whose inverse is analytic" in result.output
    assert "Drop --method" in result.output
    assert not out.exists()


def test_unknown_method_exits_2(tmp_path):
    path = tmp_path / "preisach.json"
    hystcomp.save_model(hystcomp.presets.paper_preisach(), path)
    result = _export(path, "-o", tmp_path, "--method", "newton")
    assert result.exit_code == 2
    assert "'newton' is not one of 'multiplicative', 'exact'" in result.output


def _export_run(*args):
    return CliRunner().invoke(main, [str(a) for a in args]).exit_code
