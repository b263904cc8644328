"""The compiled float formatter writes exactly what ``repr`` writes."""

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from hystcomp.io._floattext import format_rows


def _reprs(values):
    return [repr(float(v)) for v in values]


def test_every_kind_of_float64_as_repr(rng):
    bits = rng.integers(0, 2**64, size=50_000, dtype=np.uint64, endpoint=False)
    anything = bits.view(np.float64)  # every exponent, subnormals, nan and inf included
    lab = np.concatenate(
        [
            np.arange(5000) / 2e4,  # times
            rng.standard_normal(5000) * 50.0,  # volts
            np.round(rng.standard_normal(5000), 3),  # few digits
            rng.integers(-(10**6), 10**6, 5000).astype(float),
            rng.standard_normal(5000) * 10.0 ** rng.integers(-30, 30, 5000),
        ]
    )
    edges = [0.0, -0.0, 5e-324, 2.2250738585072014e-308, 1.7976931348623157e308, 0.1, 0.3]
    edges += [1e-4, 9.999999999999999e-05, 1e15, 1e16, 1e16 - 2, 1e22, 1e23, 2.0**53 + 2]
    edges += [148464748120430784.0, 123456789012345678.0, 0.5, 1.5, 100.0, 2 / 3]
    for values in (anything, lab, np.array(edges)):
        lines = format_rows(values[:, None]).decode().splitlines()
        assert lines == _reprs(values)


@given(st.lists(st.floats(allow_nan=False), min_size=1, max_size=12))
def test_rows_and_columns_as_csv(values):
    table = np.array(values).reshape(1, -1)
    assert format_rows(table).decode() == ",".join(_reprs(values)) + "\n"
