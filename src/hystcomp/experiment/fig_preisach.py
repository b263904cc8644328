"""Fig. 5 of the paper: the Preisach model's loops for 1 Hz sinusoids of growing amplitude."""

from __future__ import annotations

import os

from hystcomp._validation import as_signal, check_real
from hystcomp.errors import InvalidParameterError, InvalidSignalError
from hystcomp.experiment._layout import TITLE_Y, fixed_layout, new_figure, save_figure
from hystcomp.identify.excitation import scaled_amplitudes, sinusoid_sequence
from hystcomp.paper import FIG5_AMPLITUDES


def plot_preisach_loops(
    model,
    path: str | os.PathLike,
    *,
    amplitudes=None,
    frequency: float = 1.0,
    sample_rate: float = 2_000.0,
    measured=None,
) -> None:
    """Draw the model's response to sinusoids of growing amplitude (Fig. 5) into a PNG.

    Parameters
    ----------
    model : Preisach
        A fitted model (any forward model with ``simulate`` and ``voltage_range_`` works).
    path : str or path
        The PNG to write (atomically).
    amplitudes : sequence of float, optional
        Amplitudes in V, each sinusoid starting from ``v_min``; default Fig. 5's
        30, 60, 90, 120 V scaled to the model's voltage range.
    frequency, sample_rate : float
        Of the sinusoids, in Hz (the model is static: the rate only sets the resolution).
    measured : (v, x), optional
        A record in V and µm to draw underneath, e.g. the identification data.
    """
    lo, hi = model.voltage_range_
    if amplitudes is None:
        amplitudes = scaled_amplitudes(FIG5_AMPLITUDES, voltage_range=(lo, hi))
    amplitudes = [
        check_real(a, "amplitudes", "plot_preisach_loops", positive=True) for a in amplitudes
    ]
    if not amplitudes:
        raise InvalidParameterError(
            "The 'amplitudes' parameter of plot_preisach_loops must hold at least one "
            "amplitude in V. Got an empty sequence."
        )
    _, v = sinusoid_sequence(amplitudes, frequency=frequency, sample_rate=sample_rate, v_min=lo)
    x = model.simulate(v)
    per_period = round(sample_rate / frequency)

    fig = new_figure((6.4, 4.8))
    fixed_layout(fig, left=0.75, right=0.15, top=0.4, bottom=0.6)
    ax = fig.add_subplot()
    if measured is not None:
        v_meas, x_meas = (
            as_signal(measured[0], "measured v"),
            as_signal(measured[1], "measured x"),
        )
        if v_meas.size != x_meas.size:
            raise InvalidSignalError(
                f"'measured' must be (v, x) of the same length. Got {v_meas.size} and "
                f"{x_meas.size} samples."
            )
        ax.plot(v_meas, x_meas, color="0.6", lw=2.5, label="measured")
    for i, amplitude in enumerate(amplitudes):
        seg = slice(i * per_period, (i + 1) * per_period + 1)
        ax.plot(v[seg], x[seg], lw=1.2, label=f"model, {amplitude:g} V")
    # plain text, as in the other figures: mathtext would build its parser (0.4 s) for this
    ax.set_xlabel("voltage v_px (V)")
    ax.set_ylabel("displacement x_p (µm)")
    ax.set_title(f"Preisach model, {frequency:g} Hz sinusoids of growing amplitude", y=TITLE_Y)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left")
    save_figure(fig, path, dpi=120)
