"""``hystcomp raster``: an AFM raster on the simulated scanner, three ways.

The work is :func:`hystcomp.experiment.raster.raster_experiment`.
"""

from __future__ import annotations

from pathlib import Path

import click

from hystcomp.cli import _options as opts
from hystcomp.cli import command

FAMILIES = click.Choice(["auto", "pi", "mpi", "preisach"])


@command("raster")
@click.option("--axes", "n_axes", type=click.IntRange(2, 3), default=2, show_default=True)
@click.option("--model", "family", type=FAMILIES, default="auto", show_default=True)
@click.option("--lines", type=click.IntRange(4, 1024), default=64, show_default=True)
@click.option("--out", "out_dir", metavar="DIR")
@click.option("--jobs", "n_jobs", type=int)
@opts.quiet
def raster(out_dir, quiet, **experiment):
    """``hystcomp raster``: parse, run the experiment, print, write."""
    from hystcomp.experiment.raster import plot_raster, raster_experiment
    from hystcomp.io.atomic import check_output_path

    folder = Path(out_dir or ".")
    if out_dir is not None and folder.exists() and not folder.is_dir():
        raise click.BadParameter("exists and is not a folder.", param_hint="--out")
    if out_dir is not None and not folder.parent.is_dir():
        raise click.BadParameter("has no existing parent folder.", param_hint="--out")
    for path in (
        (folder / "raster.csv", folder / "raster.png") if out_dir and folder.is_dir() else ()
    ):
        check_output_path(path)
    label = f"identifying the {experiment['n_axes']}-axis scanner and scanning"
    with opts.progress(label, quiet).ticking():
        result = raster_experiment(**experiment)
    for line in result.table():
        click.echo(line)
    if out_dir is not None:
        folder.mkdir(exist_ok=True)
        text = result.csv_text()
        writers = {folder / "raster.csv": lambda tmp: tmp.write_text(text, encoding="utf-8")}
        opts.write_files({**writers, folder / "raster.png": lambda tmp: plot_raster(result, tmp)})
