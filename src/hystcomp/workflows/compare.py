"""The paper's experiment on the simulated axis, run as ``hystcomp compare`` runs it.

:func:`compare_on_twin` runs :func:`hystcomp.experiment.compare.run_comparison` and writes its
tables, figures and report into a folder, using the machine as the command does: a second,
forked process (:mod:`hystcomp.experiment.background`) identifies the twin's dynamics and
draws half of the figures meanwhile, and Python's cycle collector is kept off the objects
that live for the whole run (:func:`collecting_garbage_less`). A folder it made is removed
again if the run fails or is interrupted.
"""

from __future__ import annotations

import contextlib
import functools
import gc
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hystcomp import _signals
from hystcomp.errors import InvalidParameterError
from hystcomp.io.atomic import forget_folder, track_new_folder

__all__ = ["CompareRun", "collecting_garbage_less", "compare_on_twin"]


@dataclass(frozen=True, eq=False)
class CompareRun:
    """What :func:`compare_on_twin` did.

    Attributes
    ----------
    comparison : hystcomp.experiment.compare.Comparison
        The measured comparison (Table I and the rest).
    files : list of Path
        The files written.
    seconds : float
        How long the run took, in s.
    """

    comparison: Any = field(repr=False)
    files: list[Path]
    seconds: float


def compare_on_twin(
    out_dir, config, *, progress: Callable[[str], None] | None = None, start=None
) -> CompareRun:
    """Run the paper's experiment on the twin and write its outputs into ``out_dir``.

    Parameters
    ----------
    out_dir : str
        The folder for the tables, figures and report (made if its parent exists).
    config : hystcomp.experiment.compare.CompareConfig
        The experiment's settings.
    progress : callable, optional
        ``progress(line)`` is called at each step, a point where a signal may stop the run.
    start : float, optional
        ``time.perf_counter()`` when the run began, for :attr:`CompareRun.seconds` [now].

    Returns
    -------
    CompareRun
        The measured comparison (tracking errors in µm), the files written and the
        run's duration (s).
    """
    from hystcomp.experiment import warmup
    from hystcomp.experiment.background import BackgroundJob, draw_in_background

    start = time.perf_counter() if start is None else start
    parent = os.path.dirname(os.path.abspath(out_dir)) if out_dir else "."
    if not os.path.isdir(parent):  # as every output refuses a file's missing folder
        raise InvalidParameterError(
            f"The 'out_dir' argument of compare_on_twin names the folder {out_dir!r}, which "
            f"cannot be made: its parent folder {parent!r} does not exist. Create it first or "
            "choose another folder."
        )

    def step(line: str) -> None:
        _signals.check()  # between the steps: a safe point to stop
        if progress is not None:
            progress(line)

    jobs: dict[str, BackgroundJob | None] = {}
    # a folder made for the outputs goes again if the run fails or is interrupted
    made = None if not out_dir or os.path.exists(out_dir) else Path(out_dir)
    failed = True
    try:
        # the second core: on a first run the kernels needed later, then on every run the
        # twin's dynamics (SciPy's optimisers and the fits), before matplotlib's import here
        jobs["dynamics"] = warmup.start(config)
        from hystcomp.experiment.compare import run_comparison
        from hystcomp.experiment.figures import (  # matplotlib, for a forked process
            BACKGROUND_FIGURES,
            write_figures,
        )
        from hystcomp.experiment.report import prepare_output_dir, write_outputs

        with collecting_garbage_less():  # after the imports: they stay frozen
            prepare_output_dir(out_dir)  # refuse a bad folder before the work
            if made is not None:
                track_new_folder(made)

            def draw_figures(table1) -> None:  # Table I measured: its figures, beside the rest
                jobs["figures"] = draw_in_background(
                    functools.partial(write_figures, names=BACKGROUND_FIGURES), table1
                )

            identified = jobs.get("dynamics")
            comparison = run_comparison(
                config,
                progress=step,
                table1=draw_figures,
                twin_dynamics=None if identified is None else identified.collect,
            )
            step(f"writing tables, figures and report into {out_dir}")
            files = write_outputs(comparison, out_dir, figures=jobs.get("figures"))
            failed = False
    finally:  # collected by now, unless the run failed: then ended here
        for job in jobs.values():
            if job is not None:
                job.cancel()
        if made is not None:  # a failed run leaves no empty folder behind
            forget_folder(made, remove=failed)
    return CompareRun(comparison, files, time.perf_counter() - start)


@contextlib.contextmanager
def collecting_garbage_less():
    """Keep Python's cycle collector off the objects that live for the whole run.

    The imports leave about a million objects (numba's, matplotlib's, SciPy's), and the
    experiment and its figures allocate many small objects that mostly live until the end.
    With the default thresholds the collector scans them again and again: it took 0.3-0.7 s
    of a 4 s run. :func:`gc.freeze` sets the imported objects aside meanwhile (the forked
    figure process then also leaves their memory pages shared), and a first generation of
    200,000 objects instead of 700 collects rarely, as mypy's command line does. The run's
    garbage is bounded (one experiment, six figures). The collector is as it was again when
    the block ends (it may run inside another program), its thresholds restored and every
    object in its oldest generation.

    Returns
    -------
    context manager
        Entered around the run; on exit the collector's thresholds are restored.
    """
    thresholds = gc.get_threshold()
    gc.freeze()
    gc.set_threshold(200_000, 30, 30)
    try:
        yield
    finally:  # the run's objects join the oldest generation unscanned, as if frozen
        gc.freeze()  # too: a young generation of 200,000 objects costs 50 ms to scan
        gc.set_threshold(*thresholds)
        gc.unfreeze()
