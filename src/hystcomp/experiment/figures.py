"""Figures of the comparison: the paper's Figs. 9 and 10 here, Figs. 5 and 8 from their modules.

Every figure is drawn on its own :class:`~matplotlib.figure.Figure` (no global pyplot
state) and saved through :func:`hystcomp.io.atomic.atomic_path`, so a failure never leaves a
broken image. The margins are fixed in inches (``_layout.fixed_layout``) rather than computed
by matplotlib's constrained layout, which measures every label again and doubled the cost of
drawing a figure; lines are thinned to a few thousand points (``_layout.thin_slice``), time
series to their envelope per pixel column (``_layout.envelope``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from hystcomp.experiment import _layout as layout
from hystcomp.experiment.fig_identification import plot_identification
from hystcomp.experiment.fig_preisach import plot_preisach_loops
from hystcomp.experiment.metrics import SATURATION_ZONE
from hystcomp.paper import LABELS, METHODS

COLOURS = {"uncompensated": "0.45", "preisach": "tab:green", "pi": "tab:blue", "mpi": "tab:red"}


#: Resolution of the saved figures (dots per inch).
DPI = 130


def figure_9(results: dict, path: Path) -> None:
    """Fig. 9: measured displacement against the reference at one frequency, four methods.

    ``results`` maps each method to its :class:`~hystcomp.experiment.tracking.TrackingResult`;
    the inset zooms on the saturation zone (top quarter of the reference range).

    Parameters
    ----------
    results : dict
        Each method's tracking result at one frequency.
    path : pathlib.Path
        The figure's file.
    """
    fig = layout.new_figure((7.5, 6.0))
    layout.fixed_layout(fig, left=0.75, right=0.15, top=0.4, bottom=0.6)
    ax = fig.add_subplot()
    top = max(float(r.x_ref.max()) for r in results.values())
    zone = SATURATION_ZONE * top
    inset = ax.inset_axes((0.52, 0.06, 0.45, 0.42))
    low_y, high_y = np.inf, -np.inf
    for method in METHODS:
        r = results[method]
        w = r.window
        ref, x = r.x_ref[w], r.x[w]
        near = ref >= zone
        low_y, high_y = min(low_y, float(x[near].min())), max(high_y, float(x[near].max()))
        ref, x = ref[layout.thin_slice(ref.size)], x[layout.thin_slice(x.size)]
        style: dict[str, Any] = {"color": COLOURS[method], "lw": 0.9}
        label = f"{LABELS[method]} ({r.saturation_zone_pct:.1f} % in the saturation zone)"
        ax.plot(ref, x, label=label, **style)
        inset.plot(ref, x, **style)
    for axis in (ax, inset):
        axis.plot([0.0, top], [0.0, top], color="k", lw=0.6, ls="--")
        axis.grid(alpha=0.3)
    ax.plot([], [], color="k", lw=0.6, ls="--", label="ideal (x = x_ref)")
    inset.set_xlim(zone, top)
    inset.set_ylim(low_y, high_y)
    inset.set_title("saturation zone", fontsize=8, y=layout.TITLE_Y)
    inset.tick_params(labelsize=7)
    ax.indicate_inset_zoom(inset, edgecolor="0.3")
    ax.set_xlabel("reference x_ref (µm)")
    ax.set_ylabel("measured displacement x (µm)")
    frequency = next(iter(results.values())).frequency
    ax.set_title(f"Hysteresis compensation, {frequency:g} Hz triangle (twin)", y=layout.TITLE_Y)
    ax.legend(loc="upper left", fontsize=8)
    layout.save_figure(fig, path, dpi=DPI)


def figure_10(results: dict, path: Path) -> None:
    """Fig. 10: tracking (left) and tracking error (right) against time, one row per frequency.

    ``results[frequency][method]`` are tracking results; the measured window is shown.

    Parameters
    ----------
    results : dict
        ``results[frequency][method]``, each a tracking result.
    path : pathlib.Path
        The figure's file.
    """
    frequencies = sorted(results)
    fig = layout.new_figure((11.0, 3.0 * len(frequencies) + 0.3))
    layout.fixed_layout(
        fig, left=0.75, right=0.15, top=0.75, bottom=0.55, hgap=0.85, wgap=0.9,
        rows=len(frequencies), cols=2,
    )  # fmt: skip
    axes = fig.subplots(len(frequencies), 2, squeeze=False)
    columns = layout.pixel_columns(fig, axes[0, 0], DPI)
    for row, f in zip(axes, frequencies, strict=True):
        first = results[f][METHODS[0]]
        w = first.window
        t = first.t[w]
        ref = layout.envelope(t, first.x_ref[w], columns)
        row[0].plot(*ref, color="k", lw=0.8, ls="--", label="reference")
        for method in METHODS:
            r = results[f][method]
            style = {"color": COLOURS[method], "lw": 0.8, "label": LABELS[method]}
            row[0].plot(*layout.envelope(t, r.x[w], columns), **style)
            row[1].plot(*layout.envelope(t, r.e[w], columns), **style)
        row[0].set_ylabel("displacement (µm)")
        row[1].set_ylabel("tracking error e (µm)")
        row[0].set_title(f"{f:g} Hz: tracking", y=layout.TITLE_Y)
        row[1].set_title(f"{f:g} Hz: tracking error e = x - x_ref", y=layout.TITLE_Y)
        for ax in row:
            ax.set_xlabel("time (s)")
            ax.grid(alpha=0.3)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", ncols=len(labels), frameon=False)
    layout.save_figure(fig, path, dpi=DPI)


def _fig9(comparison, path: Path) -> None:
    figure_9(comparison.results[min(comparison.results)], path)


def _fig10(comparison, path: Path) -> None:
    figure_10(comparison.results, path)


def _fig5(comparison, path: Path) -> None:
    rec = comparison.record_loops
    plot_preisach_loops(comparison.models["preisach"], path, measured=(rec.v, rec.x))


def _fig8(kind: str):
    def draw(comparison, path: Path) -> None:
        rec = comparison.record_pi
        slope, intercept = np.polyfit(rec.v, rec.x, 1)  # "before": the best straight line
        after = comparison.models[kind].simulate(rec.v)
        plot_identification(
            rec.v, rec.x, slope * rec.v + intercept, after, path, model_name=LABELS[kind]
        )

    return draw


#: Every figure of the paper's experiment: file name -> ``draw(comparison, path)``.
FIGURES = {
    "fig9_compensation.png": _fig9,
    "fig10_tracking.png": _fig10,
    "fig5_preisach.png": _fig5,
    "fig8_pi.png": _fig8("pi"),
    "fig8_mpi.png": _fig8("mpi"),
}

#: The figures ``hystcomp compare`` draws in a second process, while the first goes on with
#: the dynamics part and then draws the others: about as much drawing each.
BACKGROUND_FIGURES = ("fig10_tracking.png", "fig5_preisach.png", "fig8_pi.png")


def write_figures(comparison, out_dir: Path, names=None) -> dict[str, str | None]:
    """Draw the figures ``names`` (default every one) into ``out_dir``; returns
    ``{file name: None if drawn, else why not}``.

    Figs. 9 and 10 (:func:`figure_9`, :func:`figure_10`), Fig. 5
    (:func:`~hystcomp.experiment.fig_preisach.plot_preisach_loops`) and Fig. 8 for PI and
    MPI (:func:`~hystcomp.experiment.fig_identification.plot_identification`), in the order
    of :data:`FIGURES`; every one is drawn, so every value is None.

    Parameters
    ----------
    comparison : Comparison
        The comparison's results.
    out_dir : pathlib.Path
        The folder to draw into.
    names : sequence of str, optional
        The file names to draw (every one of :data:`FIGURES` if None).

    Returns
    -------
    dict
        ``{file name: None if drawn, else why not}``.
    """
    notes: dict[str, str | None] = {}
    for name, draw in FIGURES.items():
        if names is None or name in names:
            draw(comparison, out_dir / name)
            notes[name] = None
    return notes
