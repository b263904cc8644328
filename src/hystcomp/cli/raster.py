"""``hystcomp raster``: an AFM raster on the simulated scanner, three ways."""

from __future__ import annotations

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
    """Parse, run :func:`hystcomp.experiment.raster.raster_experiment`, print, write."""
    from hystcomp.experiment.raster import check_raster_folder, raster_experiment, write_raster

    if out_dir is not None:
        check_raster_folder(out_dir)
    label = f"identifying the {experiment['n_axes']}-axis scanner and scanning"
    with opts.progress(label, quiet).ticking():
        result = raster_experiment(**experiment)
    click.echo("\n".join(result.table()))
    if out_dir is not None:
        opts.wrote(write_raster(result, out_dir))
