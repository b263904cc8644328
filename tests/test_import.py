"""Importing hystcomp compiles nothing: kernels compile (or load from disk) on first use."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import hystcomp

PROBE = """
import pkgutil, sys
import numba.core.dispatcher
import hystcomp
for info in pkgutil.walk_packages(hystcomp.__path__, "hystcomp."):
    if not info.name.endswith("__main__"):
        __import__(info.name)
kernels = [
    obj
    for name, module in list(sys.modules.items())
    if name.startswith("hystcomp")
    for obj in vars(module).values()
    if isinstance(obj, numba.core.dispatcher.Dispatcher)
]
print(len(kernels), sum(len(k.signatures) for k in kernels))
"""


def test_importing_every_module_compiles_no_kernel():
    env = dict(os.environ)
    src = str(Path(hystcomp.__file__).parents[1])  # the hystcomp under test
    env["PYTHONPATH"] = os.pathsep.join([src, env.get("PYTHONPATH", "")])
    done = subprocess.run(
        [sys.executable, "-c", PROBE], env=env, capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stderr
    n_kernels, n_compiled = map(int, done.stdout.split())
    assert n_kernels >= 8  # the probe sees the chain kernels at least
    assert n_compiled == 0
