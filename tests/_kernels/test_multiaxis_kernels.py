"""The mixing kernel of the multi-axis models against a plain NumPy product."""

from __future__ import annotations

import numpy as np
import pytest

from hystcomp._kernels.multiaxis import mix_rows


@pytest.mark.parametrize("n_axes", [1, 2, 3, 7])
def test_mix_rows_is_the_matrix_product_row_by_row(n_axes, rng):
    a = np.eye(n_axes) + rng.uniform(-0.1, 0.1, (n_axes, n_axes))
    x = rng.uniform(-50.0, 50.0, (300, n_axes))
    out = np.empty_like(x)
    mix_rows(a, x, out)
    naive = np.array(
        [[sum(a[i, j] * row[j] for j in range(n_axes)) for i in range(n_axes)] for row in x]
    )
    assert np.allclose(out, naive, rtol=0, atol=1e-12)
    one = np.empty((1, n_axes))
    mix_rows(a, x[7:8], one)
    assert np.array_equal(one[0], out[7])  # a row alone gives the batch's bits
