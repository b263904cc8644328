"""The notebook tutorial runs, cell by cell, as the docs render it (tools/mkdocs_notebooks.py)."""

from __future__ import annotations

import importlib.util
import re
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOK = ROOT / "docs" / "notebooks" / "record_to_c.py"


def _hook():
    spec = importlib.util.spec_from_file_location(
        "mkdocs_notebooks", ROOT / "tools" / "mkdocs_notebooks.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_py_percent_cells_are_split_as_jupytext_writes_them():
    text = "# header\n# %% [markdown]\n# # Title\n#\n# Text.\n\n# %%\nx = 1\n\n# %%\nprint(x)\n"
    assert _hook().cells(text) == [
        ("markdown", "# Title\n\nText."),
        ("code", "x = 1"),
        ("code", "print(x)"),
    ]


def test_the_notebook_runs_from_a_record_to_c(tmp_path):
    hook = _hook()
    results = hook.run(NOTEBOOK, tmp_path)
    kinds = [kind for kind, *_ in results]
    assert kinds.count("code") >= 6
    assert kinds.count("markdown") >= 5
    printed = "".join(out for _, _, out, _ in results)
    # the compensator tracked the 20 µm cosine on the simulated stage to about 0.1 µm rms
    rms = float(re.search(r"tracking error: rms ([0-9.]+) µm", printed)[1])
    assert 0.0 < rms < 0.2
    estimated = float(re.search(r"tracking \(estimated\): rms ([0-9.]+) µm", printed)[1])
    assert rms < 2.0 * estimated  # the estimate the fit printed held
    figures = [png for *_, shown in results for png in shown]
    assert len(figures) == 1
    assert figures[0][:8] == b"\x89PNG\r\n\x1a\n"
    assert (tmp_path / "firmware" / "stage_x.c").is_file()
    assert (tmp_path / "model.json").is_file()
    if shutil.which("cc") is not None:
        difference = float(re.search(r"largest difference ([0-9.e+-]+) V", printed)[1])
        assert difference < 1e-9
    # and the page the docs show: every code cell, then what it printed
    page = hook.MARKER.sub("PAGE", "<!-- notebook: notebooks/record_to_c.py -->")
    assert page == "PAGE"


@pytest.mark.parametrize(
    "marker", ["<!-- notebook: notebooks/x.py -->", "<!--notebook:notebooks/x.py-->"]
)
def test_the_docs_marker_names_the_notebook(marker):
    assert _hook().MARKER.fullmatch(marker)[1] == "notebooks/x.py"
