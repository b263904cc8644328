"""Figure helpers: the envelope per pixel column draws what the whole trace draws."""

import numpy as np
import pytest

from hystcomp.experiment._layout import envelope


def _naive_columns(x, y, columns, log):
    """Per column (a loop over columns): the first, last, smallest and largest sample."""
    u = np.log(x) if log else x
    edges = np.linspace(u[0], u[-1], columns + 1)
    keep = set()
    for c in range(columns):
        inside = np.flatnonzero((u >= edges[c]) & ((u < edges[c + 1]) | (c == columns - 1)))
        if inside.size:
            part = y[inside]
            keep |= {inside[0], inside[-1], inside[np.argmin(part)], inside[np.argmax(part)]}
    return np.array(sorted(keep))


@pytest.mark.parametrize("log", [False, True])
def test_envelope_keeps_each_columns_first_last_and_extremes(log):
    rng = np.random.default_rng(3)
    x = (1 + np.arange(30_000)) / 20_000.0
    y = np.sin(40 * x) + 0.05 * rng.standard_normal(x.size)
    xe, ye = envelope(x, y, 300, log=log)
    expected = _naive_columns(x, y, 300, log)
    np.testing.assert_array_equal(xe, x[expected])
    np.testing.assert_array_equal(ye, y[expected])
    assert xe.size <= 4 * 300
    assert ye.max() == y.max()
    assert ye.min() == y.min()


def test_a_short_trace_is_kept_whole():
    x = np.arange(10.0)
    xe, ye = envelope(x, x**2, 100)
    assert xe is x
    assert np.array_equal(ye, x**2)
