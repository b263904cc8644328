"""The documentation runs as written: the README's Python block, the tutorial, the examples."""

from __future__ import annotations

import os
import re
import runpy
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import hystcomp
from hystcomp import presets
from hystcomp.identify.excitation import triangle_sequence
from hystcomp.plant import Twin

ROOT = Path(__file__).resolve().parents[1]


def blocks(path: Path, language: str) -> list[str]:
    """The fenced code blocks of ``language`` in a Markdown file, in order."""
    text = path.read_text(encoding="utf-8")
    return re.findall(rf"^```{language}\n(.*?)^```", text, flags=re.MULTILINE | re.DOTALL)


def _env() -> dict:
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), env.get("PATH", "")])
    env["MPLBACKEND"] = "Agg"
    return env


def test_readme_python_blocks_run_each_on_its_own(tmp_path, monkeypatch):
    codes = blocks(ROOT / "README.md", "python")
    assert len(codes) >= 3
    monkeypatch.chdir(tmp_path)
    spaces = []
    for i, code in enumerate(codes):
        namespace: dict = {}  # a fresh namespace: no block leans on another's names
        exec(compile(code, f"README.md, Python block {i + 1}", "exec"), namespace)  # noqa: S102
        spaces.append(namespace)
    first = next(ns for ns in spaces if "comp" in ns)
    assert (tmp_path / "model.json").is_file()
    model, x_ref, v = first["model"], first["x_ref"], first["v"]
    # the fit error it prints is the model's error on the record, recomputed here
    _, v_rec = triangle_sequence()
    x_rec = Twin(seed=0).run(v_rec)
    rms = float(np.sqrt(np.mean((model.simulate(v_rec) - x_rec) ** 2)))
    assert model.fit_report_["rms_error_um"] == pytest.approx(rms, rel=0.01)
    assert rms < 0.01 * np.ptp(x_rec)  # an MPI follows the axis within 1 % of its stroke
    # the compensator inverts the model: the model driven by its voltage follows x_ref,
    # clamped to what the model reaches, inside the amplifier's 0..120 V
    lo, hi = model.reachable_range()
    assert v.min() >= 0.0
    assert v.max() <= 120.0
    assert np.abs(first["x"] - np.clip(x_ref, lo, hi)).max() < 0.01 * (hi - lo)
    assert first["v_k"] == v[0]  # the streaming step gives the batch's first voltage
    scored = next(ns for ns in spaces if "run" in ns)
    assert 0.0 < scored["run"].rms_um < 0.2 < scored["run"].max_um < 1.0  # µm, as in docs/cli.md
    twin = next(ns for ns in spaces if "twin" in ns)
    assert twin["x"].shape == twin["v"].shape
    # the axis is calibrated to the paper's stroke over 0..120 V: X(120, 0) of eq. (6)
    stroke = float(presets.paper_preisach().everett_function(120.0, 0.0))
    assert np.ptp(twin["x"]) == pytest.approx(stroke, rel=0.03)


def test_user_guide_first_python_block_runs(tmp_path, monkeypatch):
    code = next(b for b in blocks(ROOT / "docs" / "guide.md", "python") if "import hystcomp" in b)
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    exec(compile(code, "docs/guide.md", "exec"), namespace)  # noqa: S102 - our own guide
    # the file it saves is the model it fitted, whose fit error is its error on the record
    model, v, x = namespace["model"], namespace["v"], namespace["x"]
    loaded = hystcomp.load_model(tmp_path / "model.json")
    np.testing.assert_array_equal(loaded.simulate(v), model.simulate(v))
    rms = float(np.sqrt(np.mean((model.simulate(v) - x) ** 2)))
    assert model.fit_report_["rms_error_um"] == pytest.approx(rms, rel=0.01)
    assert rms < 0.01 * np.ptp(x)  # an MPI follows the axis within 1 % of its stroke


@pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler (cc)")
def test_tutorial_from_record_to_c_runs_block_by_block(tmp_path):
    (tmp_path / "tests").symlink_to(ROOT / "tests")
    steps = blocks(ROOT / "docs" / "tutorial.md", "bash")
    assert len(steps) >= 6
    for step in steps:
        done = subprocess.run(
            ["bash", "-euo", "pipefail", "-c", step],
            cwd=tmp_path,
            env=_env(),
            capture_output=True,
            text=True,
            check=False,
        )
        assert done.returncode == 0, f"{step}\n{done.stdout}\n{done.stderr}"
    assert (tmp_path / "firmware" / "stage_x").is_file()


def test_closed_loop_example_quick(tmp_path, capsys):
    module = runpy.run_path(str(ROOT / "examples" / "closed_loop_feedforward.py"))
    results = module["main"](tmp_path, quick=True)
    rows = results[50.0]
    # at 50 Hz, the loop's crossover, the feedforward removes most of the loop's error;
    # the loop's own lag there adds a little to the feedforward's (0.66 against 0.57 µm)
    assert rows["feedforward"][0] < 0.15 * rows["feedback"][0]
    assert rows["both"][0] < 0.3 * rows["feedback"][0]
    assert (tmp_path / "closed_loop_feedforward.png").stat().st_size > 10_000
    assert "feedforward cuts the loop's rms error" in capsys.readouterr().out


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler 'cc' on this machine")
@pytest.mark.parametrize("model", ["mpi", "preisach"])
def test_record_to_c_example(tmp_path, capsys, monkeypatch, model):
    module = runpy.run_path(str(ROOT / "examples" / "record_to_c.py"))
    monkeypatch.chdir(tmp_path.parent)  # a relative --out, as its default is
    found = module["main"](["--model", model, "--out", tmp_path.name])
    # the compiled C follows the Python stepper to rounding, inside the record's voltage range
    assert found["difference"] < 1e-12
    assert found["v_c"].min() >= 0.0
    assert found["v_c"].max() <= 3.6
    assert np.ptp(found["v_c"]) > 2.0  # it really drives the stage over most of its range
    assert found["result"].holdout["improvement"] > 5  # the hold-out beats a straight line
    assert sorted(p.name for p in (tmp_path / "c").glob("stage.*")) == ["stage.c", "stage.h"]
    assert "largest difference" in capsys.readouterr().out
