"""Figures of the linear dynamics: the Bode plot of an identified model, a step and hold."""

from __future__ import annotations

import numpy as np

from hystcomp.experiment._layout import (
    TITLE_Y,
    envelope,
    fixed_layout,
    new_figure,
    pixel_columns,
    save_figure,
)


def plot_bode(model, path, *, measured=None) -> None:
    """Bode plot of ``model`` (magnitude in dB, phase in degrees) from 1 Hz to 0.45 fs.

    ``measured`` is an optional ``(frequencies, response)`` pair drawn as dots; by default
    the response measured at the multisine's lines when the model was identified (its
    ``fit_report_``), divided by the fit's free complex gain (the hysteresis model's gain
    and phase that the fit took up), so that it lies on the model where the model fits.

    Parameters
    ----------
    model : LinearDynamics
        A fitted model.
    path : str or pathlib.Path
        The figure's file.
    measured : tuple of numpy.ndarray, optional
        ``(frequencies, response)`` drawn as dots.
    """
    if measured is None:
        measured = measured_response(model)
    f = np.geomspace(1.0, 0.45 * model.sample_rate_, 600)
    d = model.frequency_response(f)
    fig = new_figure((6.4, 5.2))
    mag, phase = fig.subplots(2, 1, sharex=True)
    mag.semilogx(f, 20 * np.log10(np.abs(d)), label="model D (unit steady-state gain)")
    phase.semilogx(f, np.degrees(np.unwrap(np.angle(d))))
    if measured is not None:
        fm, g = measured
        behind = (getattr(model, "fit_report_", {}) or {}).get("input") == "hysteresis model"
        label = "measured, X / H[V]" if behind else "measured, X / V"
        mag.semilogx(fm, 20 * np.log10(np.abs(g)), ".", ms=3, label=label)
        phase.semilogx(fm, np.degrees(np.unwrap(np.angle(g))), ".", ms=3)
    mag.set_ylabel("magnitude (dB)")
    phase.set_ylabel("phase (deg)")
    phase.set_xlabel("frequency (Hz)")
    second = (
        ""
        if model.second_mode_gain_ is None
        else f" + {model.second_resonance_hz_:.4g} Hz, zeta {model.second_damping_ratio_:.3g}"
        f" ({100 * model.second_mode_gain_:.2g} %)"
    )
    mag.set_title(
        f"Linear dynamics: {model.resonance_hz_:.4g} Hz, zeta {model.damping_ratio_:.3g}"
        f"{second}, creep {100 * model.creep_fraction(0.0):.2g} %"
    )
    mag.grid(True, which="both", alpha=0.3)
    phase.grid(True, which="both", alpha=0.3)
    mag.legend(loc="lower left")
    fig.tight_layout()
    save_figure(fig, path, dpi=fig.dpi)


def measured_response(model):
    """``(frequencies, response)`` measured at identification, on the model's scale, or None.

    Parameters
    ----------
    model : LinearDynamics
        A fitted model.

    Returns
    -------
    tuple of numpy.ndarray or None
        ``(frequencies, response)``: Hz and complex, or None if the fit report has none.
    """
    report = getattr(model, "fit_report_", {}) or {}
    found = report.get("measured_response")
    if not isinstance(found, dict) or not found.get("hz"):
        return None
    g = np.asarray(found["real"], dtype=float) + 1j * np.asarray(found["imag"], dtype=float)
    gain = report.get("input_gain", 1.0) * np.exp(
        1j * np.radians(report.get("input_phase_deg", 0.0))
    )
    return np.asarray(found["hz"], dtype=float), g / gain


def plot_step(t, x_ref, runs: dict, path) -> None:
    """Step and hold: the tracking error of each run (``{label: x}``) after the step.

    Left, the first 10 ms (the resonance); right, 10 ms to the end on a log time axis,
    zoomed on the creep (each trace reduced to its envelope per pixel column,
    :func:`~hystcomp.experiment._layout.envelope`: it looks the same, drawn from a few
    thousand points instead of every sample). Each panel has its legend. Runs with the
    inverse of the dynamics are dashed; in the first 10 ms the resonance makes the runs of
    one kind alike, so each run is drawn thinner than the one before and every one shows.

    Parameters
    ----------
    t : array_like
        Time, s.
    x_ref : array_like
        The step reference, µm.
    runs : dict
        ``{label: x}``, each run's displacement, µm.
    path : str or pathlib.Path
        The figure's file.
    """
    fig = new_figure((9.0, 4.0))
    fixed_layout(fig, left=0.746, right=0.15, top=0.683, bottom=0.61, wgap=0.786, cols=2)
    fast, slow = fig.subplots(1, 2)
    start = int(np.flatnonzero(np.diff(x_ref))[0]) + 1
    after = t[start:] - t[start]
    early = after <= 0.01
    late = after >= 0.01
    columns = pixel_columns(fig, slow, fig.dpi)
    for i, (label, x) in enumerate(runs.items()):
        e = (x - x_ref)[start:]
        style = {
            "label": _label(label),
            "ls": "--" if "dynamics" in label else "-",
            "lw": max(3.2 - 0.7 * i, 0.9),
        }
        fast.plot(1e3 * after[early], e[early], **style)
        slow.semilogx(*envelope(after[late], e[late], columns, log=True), **style)
    for ax in (fast, slow):
        ax.axhline(0.0, color="k", lw=0.5)
        ax.grid(True, which="both", alpha=0.3)
        ax.set_ylabel("tracking error (µm)")
    fast.set_xlabel("time after the step (ms)")
    slow.set_xlabel("time after the step (s)")
    fast.set_title("the first 10 ms", y=TITLE_Y)
    slow.set_title("creep: 10 ms to the end", y=TITLE_Y)
    fast.legend(loc="upper right", fontsize="small")
    slow.legend(loc="lower right", fontsize="small")
    fig.suptitle("Step and hold on the simulated axis with creep")
    save_figure(fig, path, dpi=fig.dpi)


def _label(key: str) -> str:
    """A run's name as the other figures write it: ``"mpi + dynamics"`` -> ``"MPI +
    dynamics"``."""
    names = {"mpi": "MPI", "pi": "PI", "preisach": "Preisach"}
    return " ".join(names.get(word, word) for word in key.split(" "))
