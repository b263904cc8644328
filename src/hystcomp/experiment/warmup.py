"""The second core's work while ``hystcomp compare`` starts: kernels, then the dynamics.

numba compiles a kernel at its first call and keeps the result in its on-disk cache; a
later first call, in any process, loads it from there in milliseconds. On a first run
(an empty cache) ``compare`` spends about 11 s of CPU compiling, one kernel after the
other, and on every run it imports SciPy's optimisers (0.3 s) for the twin's linear
dynamics alone. So ``hystcomp compare`` forks one process first (:func:`start`) that

1. on a first run, compiles into the same cache the kernels the experiment needs later:
   the Everett function's, the play chain's (PI and MPI fits and their inverses)
   (:func:`compile_later_kernels`). Meanwhile the first process compiles the twin's and
   the Preisach model's run, which it needs first; when it reaches the others, it loads
   them;
2. on every run, measures the identification records again (the same seeded twin), and
   identifies the MPI and Preisach models with the twin's linear dynamics as pairs and
   designs their inverses (:func:`~hystcomp.experiment.compare_dynamics.identify_twin_pairs`),
   which the first process takes when it reaches the dynamics part (:func:`prepare`).

Nothing the experiment computes depends on which process compiled a kernel (the cache
holds the same machine code) or identified the dynamics (the same computation, pickled).
"""

from __future__ import annotations

import sys
from pathlib import Path

from hystcomp._kernels import chain
from hystcomp.experiment.background import BackgroundJob
from hystcomp.plant.parameters import TwinParameters


def compile_later_kernels() -> None:
    """Call the kernels that ``compare`` needs after the twin's, on small inputs.

    Through the public calls that ``compare`` makes (a PI and an MPI fit with their
    defaults, their compensators), so that every kernel is compiled for the argument types
    it meets there; those of the dynamics follow in :func:`prepare`.
    """
    from hystcomp import presets
    from hystcomp.identify.excitation import triangle_sequence
    from hystcomp.models.mpi import ModifiedPrandtlIshlinskii
    from hystcomp.models.pi import PrandtlIshlinskii

    # first the Everett function's kernel, which the first process needs soon after the
    # twin's (to fit the Preisach model), then the play chain's
    presets.paper_preisach().everett_function([1.0], [0.0])
    _, v = triangle_sequence(sample_rate=400.0)
    x = presets.paper_mpi().simulate(v)
    for model in (PrandtlIshlinskii(), ModifiedPrandtlIshlinskii()):
        model.fit(v, x).inverse().simulate(x)


def prepare(config, compile_first: bool):
    """The job of :func:`start`: :func:`compile_later_kernels` if ``compile_first``, then
    :func:`~hystcomp.experiment.compare.twin_pairs` for ``config`` (the
    twin's kernel after the others: the first process compiles it first, so that here it
    is loaded).

    Parameters
    ----------
    config : CompareConfig
        The comparison's settings.
    compile_first : bool
        Whether to compile the later kernels first.

    Returns
    -------
    tuple of (Record, dict)
        What :func:`~hystcomp.experiment.compare_dynamics.identify_twin_pairs` returns.
    """
    from hystcomp.experiment.compare import twin_pairs

    if compile_first:
        compile_later_kernels()
    return twin_pairs(config)


def load_shared(twin: TwinParameters) -> None:
    """Load here what a process forked next would load again: numba's compiler context
    (its start, 0.3 s, which imports SciPy's BLAS wrappers) and the twin's kernel, by
    running the twin for one sample. ``hystcomp compare`` calls it before it forks the
    process that identifies the twin's dynamics, which both need.

    Parameters
    ----------
    twin : TwinParameters
        The twin's parameters.
    """
    from hystcomp.plant.twin import Twin

    Twin(twin).run_noiseless([0.0])


def start(config) -> BackgroundJob | None:
    """Fork the process of :func:`prepare` for ``config`` (a
    :class:`~hystcomp.experiment.compare.CompareConfig`), or None where the platform does
    not fork (Linux only, as :class:`~hystcomp.experiment.background.BackgroundJob`).

    Its result is what :func:`~hystcomp.experiment.compare_dynamics.identify_twin_pairs`
    returns. It compiles first only if the cache lacks the play chain's batch kernel (a
    first run); otherwise this process first loads what both need (:func:`load_shared`).

    Parameters
    ----------
    config : CompareConfig
        The comparison whose dynamics part the job prepares (no job if ``config.dynamics``
        is off).

    Returns
    -------
    BackgroundJob or None
        The running job, or None where the platform does not fork.
    """
    if not sys.platform.startswith("linux") or not config.dynamics:
        return None
    compile_first = not _in_cache(chain.chain_run)
    if not compile_first:
        load_shared(config.twin)
    return BackgroundJob.start(prepare, config, compile_first)


def _in_cache(kernel) -> bool:
    """Whether numba's on-disk cache holds compiled code of ``kernel`` (a data file named
    after it, as numba names them: ``<module>.<name>-<line>.py<version>.<n>.nbc``); never
    where kernels are not cached (:func:`hystcomp._kernels._jit.caching`)."""
    path = kernel.stats.cache_path
    if path is None:
        return False
    folder = Path(path)
    return any(folder.glob(f"*.{kernel.py_func.__name__}-*.nbc"))
