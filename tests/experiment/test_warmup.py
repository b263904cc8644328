"""The warm-up process of a first ``compare``: it compiles what the experiment then loads."""

import json
import os
import subprocess
import sys

import pytest

from hystcomp import presets
from hystcomp._kernels import chain
from hystcomp.experiment import warmup

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="fork on Linux")

_COMPARE = """
import json
from hystcomp._kernels import chain, dynamics, preisach
from hystcomp.experiment.compare import CompareConfig, run_comparison
run_comparison(CompareConfig.quick())
kernels = [getattr(m, n) for m in (chain, dynamics) for n in dir(m)] + [preisach.everett_many]
print(json.dumps({
    k.py_func.__name__: [len(k.stats.cache_hits), len(k.stats.cache_misses)]
    for k in kernels if hasattr(k, "stats") and (k.stats.cache_hits or k.stats.cache_misses)
}))
"""


def _python(code, cache):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    done = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    return done.stdout


@pytest.mark.slow
def test_compare_loads_every_kernel_the_warmup_compiled(tmp_path):
    _python(
        "from hystcomp.experiment.warmup import prepare; "
        "from hystcomp.experiment.compare import CompareConfig; "
        "prepare(CompareConfig.quick(), True)",
        tmp_path,
    )
    counts = json.loads(_python(_COMPARE, tmp_path).splitlines()[-1])
    assert {"everett_many", "chain_run", "regressor_rows", "inverse_run"} <= set(counts)
    missed = {name: c for name, c in counts.items() if c[1]}
    assert not missed  # compiled by compare itself: the warm-up called it differently


def test_the_job_compiles_first_only_on_a_first_run(monkeypatch):
    from hystcomp.experiment.compare import CompareConfig

    started, loaded = [], []
    monkeypatch.setattr(warmup.BackgroundJob, "start", lambda *args: started.append(args))
    monkeypatch.setattr(warmup, "load_shared", loaded.append)
    presets.paper_mpi().simulate([0.0, 1.0])  # chain_run: compiled or loaded, now cached
    assert warmup._in_cache(chain.chain_run)
    config = CompareConfig(seed=7)
    warmup.start(config)
    assert started == [(warmup.prepare, config, False)]
    assert loaded == [config.twin]  # numba's context and the twin kernel, before the fork
    monkeypatch.setattr(warmup, "_in_cache", lambda kernel: False)
    warmup.start(config)
    assert started[1] == (warmup.prepare, config, True)
    assert loaded == [config.twin]
    assert warmup.start(CompareConfig(dynamics=False)) is None  # nothing to do beside it
