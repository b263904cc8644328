"""``hystcomp compare``: the paper's experiment (Section V) on the simulated axis."""

from __future__ import annotations

import time
from typing import Any

import click

from hystcomp.cli import main


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
    from hystcomp.experiment.compare import CompareConfig
    from hystcomp.experiment.report import format_table
    from hystcomp.workflows.compare import compare_on_twin

    start = time.perf_counter()
    changes: dict[str, Any] = (
        {"seed": seed} if periods is None else {"seed": seed, "periods": periods}
    )
    config = CompareConfig.quick(**changes) if quick else CompareConfig(**changes)

    def progress(line: str) -> None:
        if not quiet:
            click.echo(f"hystcomp compare: {line}", err=True)

    run = compare_on_twin(out_dir, config, progress=progress, start=start)
    click.echo(format_table(run.comparison))
    progress(f"done in {run.seconds:.1f} s; wrote {len(run.files)} files into {out_dir}")
