"""The figure of ``hystcomp evaluate --plot``: the tracking error over time, and the
measured displacement against the reference."""

from __future__ import annotations

from hystcomp.experiment import _layout as layout


def plot_evaluation(result, path) -> None:
    """Save the figure of an :class:`~hystcomp.workflows.evaluate.Evaluation`.

    Left: the error ``x - x_ref`` (µm) against time, every sample's extremes kept (a long
    run is drawn as its envelope, one column of pixels at a time, so peaks are never lost),
    with the rms of each span of the error-over-time table. Right: ``x`` against ``x_ref``
    with the line of perfect tracking; the hysteresis left shows as a loop.

    Parameters
    ----------
    result : Evaluation
        What :func:`~hystcomp.workflows.evaluate.evaluate` returned.
    path : str or path-like
        Output image, ``.png``, ``.pdf`` or ``.svg`` (written atomically).
    """
    path = layout.check_figure_path(path)
    fig = layout.new_figure((10.0, 4.2))
    layout.fixed_layout(fig, left=0.75, right=0.15, top=0.4, bottom=0.6, wgap=0.75, cols=2)
    ax_e, ax_x = fig.subplots(1, 2)
    t, e = result.t, result.e
    t_env, e_env = layout.envelope(t, e, layout.pixel_columns(fig, ax_e, layout.DPI))
    ax_e.plot(t_env, e_env, color="tab:blue", lw=0.6, label="error x - x_ref")
    for i, span in enumerate(result.spans):
        ax_e.plot(
            [span.t_start, span.t_end],
            [span.rms_um, span.rms_um],
            color="tab:red",
            lw=1.6,
            label="rms over the span" if i == 0 else None,
        )
    ax_e.axhline(0.0, color="0.3", lw=0.6)
    ax_e.set_title(
        f"(a) tracking error: rms {result.rms_um:.3g} µm, max {result.max_um:.3g} µm",
        y=layout.TITLE_Y,
    )
    ax_e.set_xlabel("time t (s)")
    ax_e.set_ylabel("error x - x_ref (µm)")
    ax_e.grid(alpha=0.3)
    ax_e.legend(loc="lower right", fontsize="small", framealpha=0.9)
    thin = layout.thin_slice(t.size, 20_000)
    lo, hi = float(result.x_ref.min()), float(result.x_ref.max())
    ax_x.plot([lo, hi], [lo, hi], color="0.55", lw=1.6, label="x = x_ref (perfect tracking)")
    ax_x.plot(result.x_ref[thin], result.x[thin], color="tab:blue", lw=0.7, label="measured x")
    loop = (
        f", hysteresis {result.hysteresis_pct:.2g} %" if result.hysteresis_pct is not None else ""
    )
    ax_x.set_title(f"(b) measured against reference{loop}", y=layout.TITLE_Y)
    ax_x.set_xlabel("reference x_ref (µm)")
    ax_x.set_ylabel("displacement x (µm)")
    ax_x.grid(alpha=0.3)
    ax_x.legend(loc="upper left")
    layout.save_figure(fig, path, dpi=layout.DPI)
