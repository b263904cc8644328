"""benchmarks/run.py: one table from every bench_*.py module; --check decides the exit status."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

RUNNER = Path(__file__).resolve().parents[1] / "benchmarks" / "run.py"


@pytest.fixture
def runner():
    spec = importlib.util.spec_from_file_location("benchmark_runner", RUNNER)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture
def folder(tmp_path):
    (tmp_path / "bench_fast.py").write_text(
        "def run():\n"
        "    return [dict(name='speed', value=2.5, unit='ns', target='< 3', ok=True),\n"
        "            dict(name='info', value=1234567.0, unit='s', target=None, ok=None)]\n"
    )
    (tmp_path / "bench_slow.py").write_text(
        "def run():\n    return [dict(name='too slow', value=9.0, unit='x', target='<= 0.5', ok=False)]\n"
    )
    (tmp_path / "bench_broken.py").write_text("def run():\n    raise RuntimeError('no data')\n")
    (tmp_path / "helper.py").write_text("raise SystemExit('not a benchmark')\n")
    return tmp_path


def test_table_has_every_row_and_exit_status_needs_check(runner, folder, capsys):
    assert runner.main(["--dir", str(folder)]) == 0
    out = capsys.readouterr().out
    assert [line.split()[0] for line in out.splitlines()[2:6]] == ["broken", "fast", "fast", "slow"]
    assert "failed: RuntimeError: no data" in out
    speed = next(line for line in out.splitlines() if "speed" in line)
    assert speed.split() == ["fast", "speed", "2.5", "ns", "<", "3", "yes"]
    assert "1.235e+06" in out
    assert "2 targets missed: failed: RuntimeError: no data; too slow" in out
    assert runner.main(["--dir", str(folder), "--check"]) == 1


def test_pattern_selects_modules_and_check_passes_when_all_targets_are_met(runner, folder):
    assert [p.stem for p in runner.discover(folder, "fast")] == ["bench_fast"]
    assert runner.main(["fast", "--dir", str(folder), "--check"]) == 0
    assert runner.main(["nothing", "--dir", str(folder)]) == 2
