"""``hystcomp compare``: the paper's experiment (Section V) on the simulated axis."""

from __future__ import annotations

import contextlib
import functools
import gc
import os
import time
from pathlib import Path
from typing import Any

import click

from hystcomp import _signals
from hystcomp.cli import main
from hystcomp.io.atomic import forget_folder, track_new_folder


@main.command("compare")
@click.option(
    "--out",
    "out_dir",
    default="compare-out",
    show_default=True,
    type=click.Path(),  # text: click would read an empty path as "."
    help="Folder for table1.csv, hysteresis.csv, the figures and report.md.",
)
@click.option(
    "--seed", default=0, show_default=True, type=click.IntRange(min=0), help="Noise seed."
)
@click.option(
    "--periods",
    default=None,
    type=click.IntRange(min=2),
    help="Periods of each tracking reference (the first is not measured). [default: 3, 2 with --quick]",
)
@click.option("--quick", is_flag=True, help="A short run: 2 periods, four Preisach sinusoids.")
@click.option(
    "--quiet",
    "-q",
    is_flag=True,
    help="No status lines ('hystcomp compare: ...') on standard error; the table and the "
    "files are the same.",
)
def compare(out_dir: str, seed: int, periods: int | None, quick: bool, quiet: bool) -> None:
    """Identify the Preisach, PI and MPI models on the twin and compare the four methods.

    Runs the paper's identification signals on the simulated axis, identifies the models,
    tracks triangles at 1, 10 and 50 Hz with each method, prints Table I and writes the
    tables, figures and a report into OUT. Beyond the paper, it also identifies the axis's
    linear dynamics and tracks 1 to 200 Hz triangles and a step with the MPI and Preisach
    compensators in series with their inverse (dynamics.csv, step_creep.png). The axis has
    3 % creep. Units: µm, V, s.
    """
    from hystcomp.experiment import warmup
    from hystcomp.experiment.background import BackgroundJob, draw_in_background
    from hystcomp.experiment.compare import CompareConfig, run_comparison

    start = time.perf_counter()
    parent = os.path.dirname(os.path.abspath(out_dir)) if out_dir else "."
    if not os.path.isdir(parent):  # as every -o refuses a file's missing folder
        raise click.BadParameter(
            f"the folder {out_dir!r} cannot be made: its parent folder {parent!r} does not "
            "exist. Create it first or choose another --out.",
            param_hint="'--out'",
        )
    changes: dict[str, Any] = (
        {"seed": seed} if periods is None else {"seed": seed, "periods": periods}
    )
    config = CompareConfig.quick(**changes) if quick else CompareConfig(**changes)
    jobs: dict[str, BackgroundJob | None] = {}
    # a folder made for the outputs goes again if the run fails or is interrupted
    made = None if not out_dir or os.path.exists(out_dir) else Path(out_dir)
    failed = True
    try:
        # the second core: on a first run the kernels needed later, then on every run the
        # twin's dynamics (SciPy's optimisers and the fits), before matplotlib's import here
        jobs["dynamics"] = warmup.start(config)
        from hystcomp.experiment.figures import (  # matplotlib, for a forked process
            BACKGROUND_FIGURES,
            write_figures,
        )
        from hystcomp.experiment.report import format_table, prepare_output_dir, write_outputs

        with _collecting_garbage_less():  # after the imports: they stay frozen
            prepare_output_dir(out_dir)  # refuse a bad --out before the work
            if made is not None:
                track_new_folder(made)

            def progress(line: str) -> None:
                _signals.check()  # between the steps: a safe point to stop
                if not quiet:
                    click.echo(f"hystcomp compare: {line}", err=True)

            def draw_figures(table1) -> None:  # Table I measured: its figures, beside the rest
                jobs["figures"] = draw_in_background(
                    functools.partial(write_figures, names=BACKGROUND_FIGURES), table1
                )

            identified = jobs.get("dynamics")
            comparison = run_comparison(
                config,
                progress=progress,
                table1=draw_figures,
                twin_dynamics=None if identified is None else identified.collect,
            )
            progress(f"writing tables, figures and report into {out_dir}")
            files = write_outputs(comparison, out_dir, figures=jobs.get("figures"))
            click.echo(format_table(comparison))
            seconds = time.perf_counter() - start
            progress(f"done in {seconds:.1f} s; wrote {len(files)} files into {out_dir}")
            failed = False
    finally:  # collected by now, unless the run failed: then ended here
        for job in jobs.values():
            if job is not None:
                job.cancel()
        if made is not None:  # a failed run leaves no empty folder behind
            forget_folder(made, remove=failed)


@contextlib.contextmanager
def _collecting_garbage_less():
    """Keep Python's cycle collector off the objects that live for the whole command.

    The imports above leave about a million objects (numba's, matplotlib's, SciPy's), and
    the experiment and its figures allocate many small objects that mostly live until the
    end. With the default thresholds the collector scans them again and again: it took
    0.3-0.7 s of a 4 s run. :func:`gc.freeze` sets the imported objects aside meanwhile
    (the forked figure process then also leaves their memory pages shared), and a first
    generation of 200,000 objects instead of 700 collects rarely, as mypy's command line
    does. The command's garbage is bounded (one experiment, six figures). The collector is
    as it was again when the command returns (it may run inside another program), its
    thresholds restored and every object in its oldest generation.
    """
    thresholds = gc.get_threshold()
    gc.freeze()
    gc.set_threshold(200_000, 30, 30)
    try:
        yield
    finally:  # the command's objects join the oldest generation unscanned, as if frozen
        gc.freeze()  # too: a young generation of 200,000 objects costs 50 ms to scan
        gc.set_threshold(*thresholds)
        gc.unfreeze()
