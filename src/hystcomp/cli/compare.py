"""``hystcomp compare``: the paper's experiment (Section V) on the simulated axis."""

from __future__ import annotations

import time
from typing import Any

import click

from hystcomp.cli import command


@command("compare")
@click.option("--out", "out_dir", default="compare-out", show_default=True, type=click.Path())
@click.option("--seed", default=0, show_default=True, type=click.IntRange(min=0))
@click.option("--periods", type=click.IntRange(min=2))
@click.option("--quick", is_flag=True)
@click.option("--quiet", "-q", is_flag=True)
def compare(out_dir: str, seed: int, periods: int | None, quick: bool, quiet: bool) -> None:
    """Parse, run :func:`hystcomp.workflows.compare.compare_on_twin`, print."""
    from hystcomp.experiment.compare import CompareConfig
    from hystcomp.experiment.report import format_table
    from hystcomp.workflows.compare import compare_on_twin

    start = time.perf_counter()
    changes: dict[str, Any] = {"seed": seed} | ({} if periods is None else {"periods": periods})
    config = (CompareConfig.quick if quick else CompareConfig)(**changes)

    def progress(line: str) -> None:
        if not quiet:
            click.echo(f"hystcomp compare: {line}", err=True)

    run = compare_on_twin(out_dir, config, progress=progress, start=start)
    click.echo(format_table(run.comparison))
    progress(f"done in {run.seconds:.1f} s; wrote {len(run.files)} files into {out_dir}")
