"""``hystcomp excite``: the paper's identification signals (t, v)."""

from __future__ import annotations

import click

from hystcomp import paper
from hystcomp.cli import main
from hystcomp.cli._options import (
    check_data_output,
    output_option,
    positive,
    quiet_option,
    voltage_range,
    write_signal,
)
from hystcomp.identify.excitation import DEFAULT_SAMPLE_RATE, SIGNAL_KINDS, excitation_signal


@main.command("excite")
@click.argument("model", type=click.Choice((*SIGNAL_KINDS, "multiaxis")))
@output_option(required=False, what="signal; CSV on standard output if omitted")
@click.option(
    "--fs",
    "sample_rate",
    type=float,
    default=DEFAULT_SAMPLE_RATE,
    show_default=True,
    metavar="HZ",
    callback=positive("Hz"),
    help="Sample rate in Hz.",
)
@click.option(
    "--voltage-range",
    nargs=2,
    type=float,
    default=paper.VOLTAGE_RANGE,
    show_default=True,
    metavar="LO HI",
    callback=voltage_range,
    help="Amplifier range in V; the paper's amplitudes are scaled from 0..120 V to it.",
)
@click.option(
    "--frequency",
    type=float,
    default=1.0,
    show_default=True,
    metavar="HZ",
    callback=positive("Hz"),
    help="Period rate.",
)
@click.option(
    "--axes",
    type=click.IntRange(1, 16),
    default=None,
    help="multiaxis: the number of axes N (columns t, v1..vN).",
)
@quiet_option
def excite(model, output, sample_rate, voltage_range, frequency, axes, quiet):
    """Write the identification input for MODEL: pi, mpi, preisach, rich, dynamics, multiaxis.

    pi, mpi: triangles of 30, 60, 90, 120 V at 1 Hz (Section IV-A); preisach: sinusoids of
    5, 10, ..., 120 V at 1 Hz (Section III-A); rich (not in the paper, one record for all
    three models): ramps at the slope of the 1 Hz major triangle (times --frequency) between
    turning points at many levels, decaying loops from each end of the range then random
    ones (about 14 s). Each starts and ends at the lower end of the range. dynamics (beyond
    the paper; with a hysteresis record, identify --dynamics-record fits both as a pair): a
    step to mid-range held 3 s (creep), three 1 s periods of a multisine of 1 Hz .. 5 kHz
    around it of a quarter of the range peak (+-30 V on 0..120 V), then triangles over 5-90
    % of the range at 1, 10, 100 and 200 Hz, which the fits leave out and the tracking
    estimates use (9.2 s; --frequency unused). Columns: t (s), v (V). multiaxis --axes N (beyond the paper): every
    axis sweeps its range with turning points of its own while the others move
    independently, which identifies the coupling between them; columns t, v1..vN.
    """
    if (model == "multiaxis") != (axes is not None):
        raise click.UsageError(
            "--axes N goes with 'excite multiaxis' (and only with it): give both or neither."
        )
    if output is not None:
        check_data_output(output, what="signal file")
    signal = {"sample_rate": sample_rate, "voltage_range": voltage_range, "frequency": frequency}
    if model == "multiaxis":
        from hystcomp.identify.multiaxis_excitation import multiaxis_sequence

        t, V = multiaxis_sequence(axes, **signal)
        table = {"t": t, **{f"v{i + 1}": V[:, i] for i in range(axes)}}
        what = f"{t.size} samples of {axes} axes at {sample_rate:g} Hz ({t[-1]:g} s)"
    else:
        t, v = excitation_signal(model, **signal)
        table, what = {"t": t, "v": v}, f"{t.size} samples at {sample_rate:g} Hz ({t[-1]:g} s)"
    write_signal(table, output, quiet, what)
