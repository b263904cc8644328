"""Kernels compiled on the second core while ``hystcomp compare`` starts (a first run).

numba compiles a kernel at its first call and keeps the result in its on-disk cache; a
later first call, in any process, loads it from there in milliseconds. On a first run
(an empty cache) ``compare`` spends about 11 s of CPU compiling, one kernel after the
other on one core, while the second core idles until the figures are drawn. So
``hystcomp compare`` forks a process first (:func:`start`) that compiles, into the same
cache, the kernels the experiment needs later: the Everett function's, the play chain's
(PI and MPI fits and their inverses) and the linear dynamics'
(:func:`compile_later_kernels`). Meanwhile the first process compiles the twin's and the
Preisach model's run, which it needs first; when it reaches the others, it loads them.
Once the cache holds them, no compiling process is started: on such a run the second core
identifies the twin's linear dynamics instead, from the start
(:func:`~hystcomp.experiment.compare_dynamics.designed_twin_dynamics`, after
:func:`load_shared`).

Nothing the experiment computes depends on which process compiled a kernel: the cache
holds the same machine code.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import signal
import sys
import warnings
from pathlib import Path

import numpy as np

from hystcomp._kernels import chain
from hystcomp.experiment.background import FORK_WARNING, detach_output
from hystcomp.plant.parameters import TwinParameters


def compile_later_kernels() -> None:
    """Call the kernels that ``compare`` needs after the twin's, on small inputs.

    Through the public calls that ``compare`` makes (a PI and an MPI fit with their
    defaults, their compensators, an MPI compensator with an inverse of the dynamics, the
    twin), so that every kernel is compiled for the argument types it meets there.
    """
    from hystcomp import presets
    from hystcomp.identify.dynamics import dynamics_excitation
    from hystcomp.identify.excitation import triangle_sequence
    from hystcomp.models.dynamics import LinearDynamics
    from hystcomp.models.mpi import ModifiedPrandtlIshlinskii
    from hystcomp.models.pi import PrandtlIshlinskii
    from hystcomp.plant.twin import Twin

    # first the Everett function's kernel, which the first process needs soon after the
    # twin's (to fit the Preisach model), then the play chain's and the dynamics' kernels
    presets.paper_preisach().everett_function([1.0], [0.0])
    _, v = triangle_sequence(sample_rate=400.0)
    x = presets.paper_mpi().simulate(v)
    models = [PrandtlIshlinskii(), ModifiedPrandtlIshlinskii()]
    for model in models:
        model.fit(v, x).inverse().simulate(x)
    # the twin last: the first process compiles it first, so that here it is loaded
    twin = Twin(seed=0)
    fs = twin.sample_rate
    _, u = dynamics_excitation(sample_rate=fs, voltage_range=twin.voltage_range)
    dynamics = LinearDynamics().fit(u, twin.run(u), fs)
    models[1].inverse(dynamics=dynamics).simulate(np.linspace(0.0, float(x.max()), 100))


def load_shared(twin: TwinParameters) -> None:
    """Load here what a process forked next would load again: numba's compiler context
    (its start, 0.3 s, which imports SciPy's BLAS wrappers) and the twin's kernel, by
    running the twin for one sample. ``hystcomp compare`` calls it before it forks the
    process that identifies the twin's dynamics, which both need."""
    from hystcomp.plant.twin import Twin

    Twin(twin).run_noiseless([0.0])


def start(job=compile_later_kernels):
    """Fork a daemon process that runs ``job`` (and ends), or None if there is no need.

    Nothing is started if the cache already holds the play chain's batch kernel (a run
    after the first: loading the kernels would cost the second process as much as the
    first, about 0.5 s of CPU for numba's start, on a core that the figures need), nor
    where the platform does not fork (Linux only, as
    :class:`~hystcomp.experiment.background.BackgroundJob`). The process is not
    waited for: its only output is the kernel cache, and a kernel that it has not compiled
    yet when this process needs it is compiled here as it would be without it.
    """
    if not sys.platform.startswith("linux") or _in_cache(chain.chain_run):
        return None
    try:
        context = multiprocessing.get_context("fork")
        process = context.Process(target=_run, args=(job,), daemon=True, name="hystcomp-warmup")
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", FORK_WARNING, DeprecationWarning)
            process.start()
    except (OSError, ValueError):
        return None
    return process


def _in_cache(kernel) -> bool:
    """Whether numba's on-disk cache holds compiled code of ``kernel`` (a data file named
    after it, as numba names them: ``<module>.<name>-<line>.py<version>.<n>.nbc``)."""
    folder = Path(kernel.stats.cache_path)
    return any(folder.glob(f"*.{kernel.py_func.__name__}-*.nbc"))


def _run(job) -> None:
    # Ctrl-C or SIGTERM end it at once and silently (not the caller's handlers, which it
    # inherits): numba writes each cache file whole, under a temporary name first
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    detach_output()  # it may outlive the caller: not with the caller's pipes
    with contextlib.suppress(Exception):  # a failure here only costs the caller time
        job()
