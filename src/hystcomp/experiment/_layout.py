"""Figure layout shared by every figure module: fixed margins, thinned lines, a bare canvas.

A leaf of the figure modules (they all import it, it imports none of them).
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import (
    AutoLocator,
    FormatStrFormatter,
    LogLocator,
    MaxNLocator,
    NullFormatter,
)

from hystcomp.errors import InvalidParameterError
from hystcomp.io.atomic import atomic_path

#: The image formats a figure is saved in, by the output's suffix.
FORMATS = (".png", ".pdf", ".svg")
#: Resolution of a saved figure (dots per inch) where its module sets none of its own.
DPI = 150

#: ``set_title(..., y=TITLE_Y)``: the title just above the axes, where matplotlib's automatic
#: placement puts it when the tick labels are below them, without that placement (which
#: measures every y tick label once more).
TITLE_Y = 1.0

#: PNG encoding for every figure: the fastest zlib level, a few % larger files than the
#: default level 6 at a third less time.
PNG_OPTIONS = {"compress_level": 1}


#: At most this many major ticks on a linear axis. matplotlib's automatic choice puts up to
#: ten on a wide axes, and every tick is a set of lines and texts to create, lay out and
#: draw: with this the figures of ``hystcomp compare`` draw in two thirds of the time.
MAJOR_TICKS = 5

#: Minor ticks (and grid lines) of a log axis: at 2 and 5 times each power of ten.
LOG_MINOR_SUBS = (2.0, 5.0)


def thin_slice(n: int, points: int = 5000) -> slice:
    """Every k-th sample, so that a line has about ``points`` points (plots only)."""
    return slice(None, None, max(1, n // points))


def envelope(x: np.ndarray, y: np.ndarray, columns: int, *, log: bool = False):
    """``(x, y)`` reduced to the samples that draw the line as all of them do (plots only).

    The span of ``x`` (increasing) is cut into ``columns`` equal columns (equal in
    ``log(x)`` if ``log``), one per pixel of the axes; in each, the first, last, smallest
    and largest sample are kept, in their order (M4 decimation). A line through them
    covers the same pixels as the whole trace, noise and peaks included, at no more than
    four points per column: a 20 kHz record over seconds is drawn from a few thousand.
    """
    n = y.size
    if n <= 4 * columns:
        return x, y
    lo, hi = (math.log(x[0]), math.log(x[-1])) if log else (x[0], x[-1])
    bounds = np.linspace(lo, hi, columns + 1)[1:-1]
    starts = np.unique(np.r_[0, np.searchsorted(x, np.exp(bounds) if log else bounds)])
    starts = starts[starts < n]
    index = np.arange(n)
    column = np.repeat(np.arange(starts.size), np.diff(np.r_[starts, n]))
    parts = [starts, np.r_[starts[1:], n] - 1]
    for extreme in (np.minimum, np.maximum):
        at = extreme.reduceat(y, starts)[column] == y  # the column's extreme value
        parts.append(np.minimum.reduceat(np.where(at, index, n), starts))  # its first sample
    keep = np.unique(np.concatenate(parts))
    return x[keep], y[keep]


def pixel_columns(fig: Figure, ax, dpi: float) -> int:
    """Width of axes ``ax`` in pixels when ``fig`` is saved at ``dpi``."""
    return math.ceil(ax.get_position().width * fig.get_size_inches()[0] * dpi)


def new_figure(size) -> Figure:
    """A figure with its own Agg canvas (no global pyplot state)."""
    fig = Figure(figsize=size)
    FigureCanvasAgg(fig)
    return fig


def fixed_layout(fig: Figure, *, left, right, top, bottom, hgap=0.0, wgap=0.0, rows=1, cols=1):
    """Place a grid of ``rows`` x ``cols`` axes with margins and gaps given in inches.

    The space for tick labels, axis labels and titles is known in advance for these
    figures, so it is set once instead of measured (a constrained layout draws every text
    twice more).
    """
    width, height = fig.get_size_inches()
    axes_w = (width - left - right - (cols - 1) * wgap) / cols
    axes_h = (height - top - bottom - (rows - 1) * hgap) / rows
    fig.subplots_adjust(
        left=left / width,
        right=1.0 - right / width,
        top=1.0 - top / height,
        bottom=bottom / height,
        wspace=wgap / axes_w,
        hspace=hgap / axes_h,
    )


def check_figure_path(path, *, argument: str = "path", owner: str = "check_figure_path") -> Path:
    """``path`` as a Path if a figure can be saved there (by its suffix), else raise.

    Parameters
    ----------
    path : str or os.PathLike
        The figure's file.
    argument, owner : str
        The argument and the function that the refusal names.

    Returns
    -------
    pathlib.Path
        ``path``, checked.
    """
    path = Path(os.fspath(path))
    if path.suffix.lower() not in FORMATS:
        raise InvalidParameterError(
            f"The {argument!r} argument of {owner} must end in {', '.join(FORMATS)}; "
            f"got {str(path)!r}."
        )
    return path


def save_figure(fig: Figure, path: str | os.PathLike, *, dpi: float) -> None:
    """Save ``fig`` into ``path`` at ``dpi``, atomically, in the format of its suffix.

    Every axes of the figure, insets included, first gets at most :data:`MAJOR_TICKS`
    major ticks per linear axis (where the figure has not chosen its own), and on a log
    axis minor ticks at :data:`LOG_MINOR_SUBS` and its powers of ten as plain numbers. A
    PNG is written with :data:`PNG_OPTIONS`.
    """
    for ax in _every_axes(fig):
        for axis in (ax.xaxis, ax.yaxis):
            if axis.get_scale() == "log":
                axis.set_minor_locator(LogLocator(subs=LOG_MINOR_SUBS))
                axis.set_minor_formatter(NullFormatter())
                # plain numbers, not matplotlib's 10^n in mathtext, whose parser takes a
                # first figure 0.1-0.2 s to build
                axis.set_major_formatter(FormatStrFormatter("%g"))
            elif type(axis.get_major_locator()) is AutoLocator:
                axis.set_major_locator(MaxNLocator(nbins=MAJOR_TICKS, steps=[1, 2, 2.5, 5, 10]))
    path = Path(os.fspath(path))
    kind = path.suffix.lower().lstrip(".") or "png"
    options: dict[str, Any] = {"pil_kwargs": PNG_OPTIONS} if kind == "png" else {}
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=kind, dpi=dpi, **options)


def _every_axes(fig: Figure):
    stack: list[Any] = list(fig.axes)
    while stack:
        ax = stack.pop()
        stack.extend(ax.child_axes)
        yield ax
