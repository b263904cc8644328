"""Fig. 8 of the paper: a model against the measured loop, before and after identification."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from hystcomp.errors import InvalidParameterError
from hystcomp.experiment._layout import TITLE_Y, _thin, fixed_layout, new_figure, save_figure

FORMATS = (".png", ".pdf", ".svg")


def plot_identification(v, x, before, after, path, *, model_name: str = "model") -> None:
    """Save a Fig. 8-style figure: measured and modelled displacement against voltage.

    Left panel: the model before identification (its initial guess); right panel: the
    identified model. The paper does not say what its initial weights were; the command
    line uses the least-squares straight line ``x = a v + b``, i.e. all the weight on the
    zero-threshold play (and, for MPI, on the zero-threshold dead-zone): the best model
    without hysteresis.

    Parameters
    ----------
    v, x : array_like
        Input voltage (V) and measured displacement (µm).
    before, after : array_like
        Model displacement (µm) before and after identification, for the same samples.
    path : str or path-like
        Output image, ``.png``, ``.pdf`` or ``.svg`` (written atomically).
    model_name : str
        Name of the identified model, for the titles (e.g. ``"MPI"``).
    """
    path = Path(os.fspath(path))
    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        raise InvalidParameterError(
            f"Cannot save a figure as {str(path)!r}: use a name ending in {', '.join(FORMATS)}."
        )
    v, x = np.asarray(v, dtype=np.float64), np.asarray(x, dtype=np.float64)
    fig = new_figure((10.0, 4.2))
    fixed_layout(fig, left=0.75, right=0.15, top=0.4, bottom=0.6, wgap=0.3, cols=2)
    axes = fig.subplots(1, 2, sharey=True)
    panels = [
        ("(a) before identification (straight line)", before),
        (f"(b) after identification ({model_name})", after),
    ]
    for ax, (title, model_x) in zip(axes, panels, strict=True):
        model_x = np.asarray(model_x, dtype=np.float64)
        rms = float(np.sqrt(np.mean((model_x - x) ** 2)))
        thin = _thin(v.size)  # the drawn lines only; the rms is over every sample
        ax.plot(v[thin], x[thin], color="0.55", lw=1.6, label="measured")
        label = f"model (rms error {rms:.3g} µm)"
        ax.plot(v[thin], model_x[thin], color="tab:red", lw=0.9, label=label)
        ax.set_title(title, y=TITLE_Y)
        ax.set_xlabel("voltage v (V)")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper left")
    axes[0].set_ylabel("displacement x (µm)")
    save_figure(fig, path, dpi=150)
