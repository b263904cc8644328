"""The io package: atomic outputs are a leaf, and every public name is re-exported."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from pathlib import Path

import pytest

import hystcomp
import hystcomp.io
from hystcomp.io import atomic, models, records

ATOMIC = Path(atomic.__file__)


def _fresh(code: str) -> list[str]:
    """The modules a fresh interpreter has loaded after ``code`` (with this hystcomp)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(Path(hystcomp.__file__).parents[1]), env.get("PYTHONPATH", "")]
    )
    done = subprocess.run(
        [sys.executable, "-c", f"{code}\nimport sys\nprint('\\n'.join(sys.modules))"],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return done.stdout.split()


def test_atomic_outputs_import_nothing_of_the_models_or_records():
    tree = ast.parse(ATOMIC.read_text(encoding="utf-8"))
    imported = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            imported |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module == "hystcomp":  # its modules
            imported |= {f"hystcomp.{alias.name}" for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            imported.add(node.module or "")
    ours = {name for name in imported if name.split(".")[0] == "hystcomp"}
    assert ours == {"hystcomp.errors", "hystcomp._validation", "hystcomp._signals"}
    assert all(name.split(".")[0] in sys.stdlib_module_names for name in imported - ours)


def test_writing_a_file_loads_no_model_no_reader_and_no_compiled_code():
    loaded = _fresh("from hystcomp.io import atomic_path, check_output_path")
    heavy = [
        m
        for m in loaded
        if m.startswith(("hystcomp.models", "hystcomp.io.records", "hystcomp.io.models"))
        or m.split(".")[0] in {"numba", "scipy"}
    ]
    assert heavy == []


def test_reading_a_record_loads_no_model_class():
    loaded = _fresh("from hystcomp.io import read_record")
    assert "hystcomp.io.records" in loaded
    assert [m for m in loaded if m.startswith(("hystcomp.models", "hystcomp.io.models"))] == []


def test_every_public_name_of_the_package_is_its_module_s_object():
    homes = (atomic, models, records)
    for name in hystcomp.io.__all__:
        value = getattr(hystcomp.io, name)
        assert any(getattr(home, name, None) is value for home in homes), name
    eager = set(hystcomp.io.__all__) - set(hystcomp.io._LAZY)
    assert eager == {
        name
        for name, value in vars(atomic).items()
        if not name.startswith("_") and getattr(value, "__module__", None) == atomic.__name__
    }
    assert set(hystcomp.io._LAZY) <= set(hystcomp.io.__all__)
    assert set(hystcomp.io.__all__) <= set(dir(hystcomp.io))
    assert hystcomp.io.load_model is models.load_model
    assert hystcomp.io.MODEL_KINDS is models.MODEL_KINDS
    assert hystcomp.io.atomic_paths is atomic.atomic_paths
    assert hystcomp.Record is records.Record
    assert hystcomp.read_record is records.read_record
    assert hystcomp.save_model is models.save_model
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        hystcomp.io.nothing  # noqa: B018
