"""``hystcomp excite``: the paper's identification signals (t, v), and beyond the paper's."""

from __future__ import annotations

import click

from hystcomp import paper
from hystcomp.cli import _options as opts
from hystcomp.cli import command
from hystcomp.identify.excitation import DEFAULT_SAMPLE_RATE, SIGNAL_KINDS, excitation_signal
from hystcomp.io.multiaxis import axis_table
from hystcomp.io.records import check_data_output


@command("excite")
@click.argument("model", type=click.Choice((*SIGNAL_KINDS, "multiaxis")))
@click.option("-o", "--output", metavar="FILE")
@click.option("--fs", "sample_rate", default=DEFAULT_SAMPLE_RATE, show_default=True, **opts.HZ)
@click.option("--voltage-range", default=paper.VOLTAGE_RANGE, show_default=True, **opts.RANGE)
@click.option("--frequency", default=1.0, show_default=True, **opts.HZ)
@click.option("--axes", type=click.IntRange(1, 16))
@opts.quiet
def excite(model, output, axes, quiet, **signal):
    """``hystcomp excite``: parse, make the signal, write it (or print it as CSV)."""
    if (model == "multiaxis") != (axes is not None):
        raise click.UsageError(
            "--axes N goes with 'excite multiaxis' (and only with it): give both or neither."
        )
    if output is not None:
        check_data_output(output, what="signal file")
    if model == "multiaxis":
        from hystcomp.identify.multiaxis_excitation import multiaxis_sequence

        t, v = multiaxis_sequence(axes, **signal)
    else:
        t, v = excitation_signal(model, **signal)
    each = f" of {axes} axes" if axes else ""
    what = f"{t.size} samples{each} at {signal['sample_rate']:g} Hz ({t[-1]:g} s)"
    opts.write_signal(axis_table(t, v=v), output, quiet, what)
