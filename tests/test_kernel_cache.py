"""Kernels run without numba's on-disk cache where no folder is writable, with one note."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np

import hystcomp
from hystcomp._kernels._jit import NO_CACHE_NOTE, caching
from hystcomp.io.records import read_table, write_table


def test_here_kernels_are_cached():
    assert caching() is True


def test_without_a_cache_folder_a_command_runs_and_says_so_in_one_line(tmp_path):
    # numba's locators all failing, as on a read-only install with an unwritable home
    # folder (the locator that only works inside IPython is the only one left)
    hystcomp.save_model(hystcomp.presets.paper_pi(), tmp_path / "pi.json")
    t = np.arange(100) / 20_000.0
    write_table(tmp_path / "ref.csv", {"t": t, "x": np.linspace(1.0, 20.0, 100)})
    env = {**os.environ, "NUMBA_CACHE_LOCATOR_CLASSES": "IPythonCacheLocator"}
    env.pop("NUMBA_CACHE_DIR", None)
    args = ["compensate", "pi.json", "ref.csv", "-o", "v.csv"]
    done = subprocess.run(
        [sys.executable, "-m", "hystcomp", *args],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert done.stderr == NO_CACHE_NOTE  # one line, naming the fix
    assert "NUMBA_CACHE_DIR" in NO_CACHE_NOTE
    assert NO_CACHE_NOTE.count("\n") == 1
    v = read_table(tmp_path / "v.csv", ("v",))["v"]
    expected = hystcomp.presets.paper_pi().inverse().simulate(np.linspace(1.0, 20.0, 100))
    np.testing.assert_array_equal(v, expected)  # the same kernels, compiled in the run
