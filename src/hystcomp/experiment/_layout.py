"""Figure layout shared by every figure module: fixed margins, thinned lines, a bare canvas.

A leaf of the figure modules (they all import it, it imports none of them).
"""

from __future__ import annotations

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure


def _thin(n: int, points: int = 5000) -> slice:
    """Every k-th sample, so that a line has about ``points`` points (plots only)."""
    return slice(None, None, max(1, n // points))


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
