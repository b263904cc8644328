"""``hystcomp raster``: an AFM raster on the simulated scanner, three ways."""

from __future__ import annotations

from pathlib import Path

import click

from hystcomp.cli import main
from hystcomp.cli._options import progress, quiet_option


@main.command("raster")
@click.option(
    "--axes",
    "n_axes",
    type=click.IntRange(2, 3),
    default=2,
    show_default=True,
    help="XY, or XYZ (a Z axis following the sample's topography).",
)
@click.option(
    "--model",
    "family",
    type=click.Choice(["auto", "pi", "mpi", "preisach"]),
    default="auto",
    show_default=True,
    help="Each axis's model family, per-axis and coupled alike.",
)
@click.option(
    "--lines",
    type=click.IntRange(4, 1024),
    default=64,
    show_default=True,
    help="Lines per frame (10 Hz each).",
)
@click.option(
    "--out", "out_dir", default=None, metavar="DIR", help="Write raster.csv and raster.png."
)
@click.option("--jobs", "n_jobs", type=int, default=None, help="Axes fitted in parallel [1].")
@quiet_option
def raster(n_axes, family, lines, out_dir, n_jobs, quiet):
    """An AFM raster on the simulated scanner: uncompensated, per-axis, coupled.

    Identifies the simulated raster scanner (hystcomp.plant.raster_scanner: axes of different
    hysteresis, coupled by 2 to 8 %, each with its own resonance) from its answer to
    'hystcomp excite multiaxis', then scans a frame (the fast axis a 10 Hz triangle over
    10-80 % of its stroke, the slow axis a ramp over 10-80 %), retraces and scans again,
    three ways: a straight line per axis, a hysteresis compensator per axis that ignores
    the coupling, and the coupled model. Prints each axis's rms tracking error on the
    second frame; with --out, writes raster.csv and raster.png (the image of a checkerboard
    grating in each case).
    """
    from hystcomp.experiment.raster import METHODS, plot_raster, raster_experiment

    outputs = []
    if out_dir is not None:
        from hystcomp.io.atomic import check_output_path

        folder = Path(out_dir)
        if folder.exists() and not folder.is_dir():
            raise click.BadParameter("exists and is not a folder.", param_hint="--out")
        if not folder.parent.is_dir():
            raise click.BadParameter("has no existing parent folder.", param_hint="--out")
        outputs = [folder / "raster.csv", folder / "raster.png"]
        if folder.is_dir():
            for path in outputs:
                check_output_path(path)
    with progress(f"identifying the {n_axes}-axis scanner and scanning", quiet).ticking():
        result = raster_experiment(n_axes=n_axes, family=family, lines=lines, n_jobs=n_jobs)
    for line in result.table():
        click.echo(line)
    if not outputs:
        return
    from hystcomp.io.atomic import atomic_paths

    folder.mkdir(exist_ok=True)
    rows = ["axis,method,rms_um,ratio_to_uncompensated"]
    for i in range(n_axes):
        for method in METHODS:
            rms = result.rms_um[method][i]
            rows.append(f"{'xyz'[i]},{method},{rms!r},{rms / result.rms_um['uncompensated'][i]!r}")
    with atomic_paths(*outputs) as (tmp_csv, tmp_png):
        tmp_csv.write_text("\n".join(rows) + "\n", encoding="utf-8")
        plot_raster(result, tmp_png)
    for path in outputs:
        click.echo(f"  wrote {path}")
