"""``hystcomp export-c``: files, prefix, exit codes, and no damage on failure."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

import hystcomp
from hystcomp.cli import main


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
    assert "must be a finite number > 0" in result.output


def test_missing_model_file_exits_2(tmp_path):
    result = _export(tmp_path / "nope.json", "-o", tmp_path)
    assert result.exit_code == 2
    assert "does not exist" in result.output


def test_output_folder_without_parent_exits_2(model_file, tmp_path):
    result = _export(model_file, "-o", tmp_path / "a" / "b")
    assert result.exit_code == 2
    assert "must be an existing folder" in result.output


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
