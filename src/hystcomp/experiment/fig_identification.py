"""Fig. 8 of the paper: a model against the measured loop, before and after identification.

A short record (the paper's 4 s of triangles) is drawn whole, as the paper draws it. A long
one (many loops laid over each other draw a solid band) or one with a hold-out is drawn as
an excerpt and the whole: the loops of a few cycles at the end of the fitted part (and at
the start of the hold-out, the prediction), and below them the model's error against time
over the whole record, every sample's extremes kept (each pixel column's smallest and
largest value), the hold-out in its own colour and the excerpts shaded.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hystcomp.errors import InvalidParameterError
from hystcomp.experiment._layout import (
    DPI,
    FORMATS,
    TITLE_Y,
    check_figure_path,
    envelope,
    fixed_layout,
    new_figure,
    pixel_columns,
    save_figure,
    thin_slice,
)

__all__ = [
    "FORMATS",
    "check_figure_output",
    "plot_identification",
    "plot_identification_result",
    "plot_identified",
    "turning_points",
]

#: Turning points of the input above which a record is drawn as excerpts (about 6 loops).
LONG_TURNS = 12
#: Turning points (half-cycles) in an excerpt: two whole loops.
EXCERPT_TURNS = 4
#: Colours of the measured loop, the fitted model and its prediction on the hold-out.
MEASURED, FITTED, PREDICTED = "0.55", "tab:red", "tab:green"


def turning_points(v, tolerance: float = 0.02) -> np.ndarray:
    """Indices where the input turns back by more than ``tolerance`` of its range (the
    extremes of each half-cycle), in order.

    Parameters
    ----------
    v : array_like
        The input.
    tolerance : float, optional
        The least reversal counted, a share of the input's range.

    Returns
    -------
    numpy.ndarray
        The indices, rising.

    Examples
    --------
    >>> turning_points(np.array([0.0, 1.0, 2.0, 1.0, 0.0, 1.0, 3.0, 2.0]))
    array([2, 4, 6])
    """
    v = np.asarray(v, dtype=np.float64)
    step = tolerance * float(np.ptp(v)) if v.size else 0.0
    turns: list[int] = []
    k_ext, rising = 0, None  # the running extreme and the direction towards it
    for k in range(1, v.size):
        if rising is None:
            if abs(v[k] - v[0]) > step:
                rising, k_ext = bool(v[k] > v[0]), k
            continue
        if (v[k] > v[k_ext]) == rising and v[k] != v[k_ext]:
            k_ext = k
        elif abs(v[k] - v[k_ext]) > step:
            turns.append(k_ext)
            rising, k_ext = not rising, k
    return np.array(turns, dtype=np.int64)


def _excerpt(turns: np.ndarray, lo: int, hi: int, at_end: bool) -> slice:
    """A window of :data:`EXCERPT_TURNS` half-cycles inside samples ``lo .. hi``: the last
    ones (``at_end``) or the first; the whole span if it holds fewer."""
    inside = turns[(turns > lo) & (turns < hi)]
    if inside.size <= EXCERPT_TURNS:
        return slice(lo, hi)
    if at_end:
        return slice(int(inside[-EXCERPT_TURNS - 1]), hi)
    return slice(lo, int(inside[EXCERPT_TURNS]) + 1)


def plot_identification(
    v, x, before, after, path, *, model_name: str = "model", t=None, fit_end=None
) -> None:
    """Save a Fig. 8-style figure: measured and modelled displacement against voltage.

    Left panel: the model before identification (its initial guess); right panel: the
    identified model. The paper does not say what its initial weights were; the command
    line uses the least-squares straight line ``x = a v + b``, i.e. all the weight on the
    zero-threshold play (and, for MPI, on the zero-threshold dead-zone): the best model
    without hysteresis. A long record (more than :data:`LONG_TURNS` turning points) or one
    with a hold-out is drawn as excerpts of two loops over the model's error against time
    (the module's notes).

    Parameters
    ----------
    v, x : array_like
        Input voltage (V) and measured displacement (µm).
    before, after : array_like
        Model displacement (µm) before and after identification, for the same samples
        (``after`` over the hold-out too: the model's prediction there).
    path : str or path-like
        Output image, ``.png``, ``.pdf`` or ``.svg`` (written atomically).
    model_name : str
        Name of the identified model, for the titles (e.g. ``"MPI"``).
    t : array_like, optional
        Time of each sample (s); by default the sample index.
    fit_end : int, optional
        The first sample of the hold-out (the samples before it were fitted); None: no
        hold-out.
    """
    path = check_figure_path(path)
    v, x = np.asarray(v, dtype=np.float64), np.asarray(x, dtype=np.float64)
    before = np.asarray(before, dtype=np.float64)
    after = np.asarray(after, dtype=np.float64)
    n = v.size
    fit_end = n if fit_end is None else int(fit_end)
    turns = turning_points(v)
    if turns.size <= LONG_TURNS and fit_end >= n:
        _whole(v, x, before, after, path, model_name)
    else:
        time = np.arange(n, dtype=np.float64) if t is None else np.asarray(t, dtype=np.float64)
        _excerpts(v, x, before, after, path, model_name, time, fit_end, turns, t is not None)


def _rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - b) ** 2))) if a.size else float("nan")


def _whole(v, x, before, after, path: Path, model_name: str) -> None:
    """The paper's Fig. 8: every sample's loop, before and after (a short record)."""
    fig = new_figure((10.0, 4.2))
    fixed_layout(fig, left=0.75, right=0.15, top=0.4, bottom=0.6, wgap=0.3, cols=2)
    axes = fig.subplots(1, 2, sharey=True)
    panels = [
        ("(a) before identification (straight line)", before),
        (f"(b) after identification ({model_name})", after),
    ]
    thin = thin_slice(v.size)  # the drawn lines only; the rms is over every sample
    for ax, (title, model_x) in zip(axes, panels, strict=True):
        ax.plot(v[thin], x[thin], color=MEASURED, lw=1.6, label="measured")
        label = f"model (rms error {_rms(model_x, x):.3g} µm)"
        ax.plot(v[thin], model_x[thin], color=FITTED, lw=0.9, label=label)
        ax.set_title(title, y=TITLE_Y)
        ax.set_xlabel("voltage v (V)")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper left")
    axes[0].set_ylabel("displacement x (µm)")
    save_figure(fig, path, dpi=DPI)


def _excerpts(v, x, before, after, path, model_name, t, fit_end, turns, seconds) -> None:
    """Loops of excerpts (top) over the error against time of the whole record (bottom)."""
    n = v.size
    held = fit_end < n
    fitted = _excerpt(turns, 0, fit_end, at_end=True)
    predicted = _excerpt(turns, fit_end, n, at_end=False) if held else None
    fig = new_figure((10.0, 7.8))
    fixed_layout(
        fig, left=0.75, right=0.15, top=0.4, bottom=0.6, wgap=0.3, hgap=1.0, rows=2, cols=2
    )
    grid = fig.add_gridspec(2, 2)
    ax_a = fig.add_subplot(grid[0, 0])
    ax_b = fig.add_subplot(grid[0, 1], sharey=ax_a)
    ax_e = fig.add_subplot(grid[1, :])
    unit = "s" if seconds else "samples"
    span = f"t = {t[fitted.start]:.4g} .. {t[fitted.stop - 1]:.4g} {unit}"
    for ax, model_x, title in (
        (ax_a, before, "(a) before identification (straight line)"),
        (ax_b, after, f"(b) after identification ({model_name})"),
    ):
        ax.plot(v[fitted], x[fitted], color=MEASURED, lw=1.6, label=f"measured, {span}")
        ax.plot(v[fitted], model_x[fitted], color=FITTED, lw=0.9, label="model, fitted")
        ax.set_title(title, y=TITLE_Y)
        ax.set_xlabel("voltage v (V)")
        ax.grid(alpha=0.3)
    if predicted is not None:
        hold_span = f"t = {t[predicted.start]:.4g} .. {t[predicted.stop - 1]:.4g} {unit}"
        ax_b.plot(v[predicted], x[predicted], color=MEASURED, lw=1.6, ls=":")
        ax_b.plot(
            v[predicted],
            after[predicted],
            color=PREDICTED,
            lw=0.9,
            ls="--",
            label=f"model, predicted on the hold-out ({hold_span})",
        )
    ax_a.set_ylabel("displacement x (µm)")
    ax_b.tick_params(labelleft=False)  # the scale of (a)
    for ax in (ax_a, ax_b):
        ax.legend(loc="upper left", fontsize="small")
    # (c) the error of the identified model over the whole record, fitted and held out
    columns = pixel_columns(fig, ax_e, DPI)
    e = after - x
    parts = [(slice(0, fit_end), FITTED, "fitted")]
    if held:
        parts.append((slice(fit_end, n), PREDICTED, "hold-out (predicted)"))
    for part, colour, what in parts:
        label = f"{what}: rms {_rms(after[part], x[part]):.3g} µm"
        ax_e.plot(*envelope(t[part], e[part], columns), color=colour, lw=0.6, label=label)
    for window in (fitted, predicted):
        if window is not None:
            ax_e.axvspan(t[window.start], t[window.stop - 1], color="0.85", zorder=0)
    if held:
        ax_e.axvline(t[fit_end], color="k", lw=0.8, ls="--")
    ax_e.axhline(0.0, color="k", lw=0.5)
    ax_e.set_title(
        "(c) the identified model's error over the whole record (shaded: the loops above)",
        y=TITLE_Y,
    )
    ax_e.set_xlabel(f"time t ({unit})")
    ax_e.set_ylabel("model - measured (µm)")
    ax_e.grid(alpha=0.3)
    ax_e.legend(loc="upper right", fontsize="small")
    save_figure(fig, path, dpi=DPI)


def plot_identification_result(record, result, path) -> None:
    """The figure of ``hystcomp identify --plot``: :func:`plot_identification` of what
    :func:`~hystcomp.workflows.identify.identify_record` found, from the end of the
    start-up transient to the end of the record, the hold-out (if any) predicted by the
    identified model.

    Parameters
    ----------
    record : Record
        The record identified.
    result : IdentificationResult
        What the identification found.
    path : str or pathlib.Path
        The figure's file.
    """
    from hystcomp.identify.scoring import straight_line

    kept = slice(result.start, len(record))
    v, x = record.v[kept], record.x[kept]
    a, b = straight_line(
        record.v[result.start : result.n_fit], record.x[result.start : result.n_fit]
    )
    after = result.model.simulate(record.v)[kept]  # from the model's start, as the fit ran
    plot_identification(
        v,
        x,
        a * v + b,
        after,
        path,
        model_name=result.label,
        t=record.t[kept],
        fit_end=result.n_fit - result.start if result.n_fit < len(record) else None,
    )


def plot_identified(record, found, path) -> None:
    """The figure of ``hystcomp identify --plot`` for what
    :func:`~hystcomp.workflows.record.identify_model` found: the hysteresis model's
    (:func:`plot_identification_result`), or the Bode plot of linear dynamics alone
    (:func:`~hystcomp.experiment.fig_dynamics.plot_bode`).

    Parameters
    ----------
    record : Record
        The record identified.
    found : ModelResult
        What the identification found.
    path : str or pathlib.Path
        The figure's file.
    """
    if found.hysteresis is None:
        from hystcomp.experiment.fig_dynamics import plot_bode

        return plot_bode(found.model, path)
    plot_identification_result(record, found.hysteresis, path)


def check_figure_output(plot, *, inputs=(), output=None) -> Path:
    """Refuse, before any work, a figure of an unknown format (:data:`FORMATS`), one that
    would overwrite an input, or one at the path of the command's other output.

    Parameters
    ----------
    plot : str or os.PathLike
        The figure's file.
    inputs : sequence of str or os.PathLike
        Files the same command reads (:func:`hystcomp.io.atomic.check_output_path`).
    output : str or os.PathLike, optional
        The command's other output, written beside the figure.

    Returns
    -------
    pathlib.Path
        ``plot``, checked.
    """
    from hystcomp.io.atomic import check_output_path

    path = check_figure_path(plot, argument="plot", owner="check_figure_output")
    check_output_path(path, inputs=inputs, what="figure")
    if output is not None and path.resolve() == Path(output).resolve():
        raise InvalidParameterError(
            f"The 'plot' argument of check_figure_output must not be the other output, "
            f"{str(output)!r}; name another file."
        )
    return path
