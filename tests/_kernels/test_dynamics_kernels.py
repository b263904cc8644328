"""The inverse filter of the linear dynamics against the slow reference of tests/naive.py."""

import itertools

import numpy as np
import pytest

from hystcomp._kernels import dynamics as dk
from hystcomp._kernels._jit import step_function
from hystcomp._kernels.chain import CLAMP_TOLERANCE
from hystcomp.models.dynamic_compensator import DynamicsInverse
from tests import naive
from tests.conftest import random_walk


def _filter(rng, n_taps, n_creep):
    """A filter with random non-negative taps and creep modes, clamped to 0 .. 30 µm."""
    taps = rng.uniform(0.0, 1.0, n_taps)
    lags = np.exp(-1.0 / rng.uniform(5.0, 5000.0, n_creep))
    weights = rng.uniform(0.0, 0.05, n_creep)
    return DynamicsInverse(
        taps / taps.sum(), lags, weights, preview=0, rest=3.0, output_range=(0.0, 30.0), bias=0.2
    )


def _reference(rng, n=4000):
    """A random walk beyond both ends of the range, with non-finite and huge samples."""
    x = random_walk(rng, n, -10.0, 40.0, 2.0)
    x[rng.choice(n, 12, replace=False)] = np.nan
    x[[50, 51, 700]] = [np.inf, -np.inf, 1e308]
    return x


def _naive(inverse, x):
    p = inverse.packed
    n, m = int(p[dk.N_FIR]), int(p[dk.N_CREEP])
    low, high = inverse.output_range
    return naive.dynamics_inverse(
        x,
        p[dk.HEADER : dk.HEADER + n],
        p[dk.HEADER + n : dk.HEADER + n + m],
        p[dk.HEADER + n + m : dk.HEADER + n + 2 * m],
        rest=inverse.rest,
        bias=float(p[dk.BIAS]),
        low=low,
        high=high,
        tolerance=CLAMP_TOLERANCE * (high - low),
    )


@pytest.mark.parametrize(("n_taps", "n_creep"), [(1, 0), (5, 1), (17, 4), (67, 2)])
def test_inverse_filter_matches_naive_over_many_turns_of_its_delay_line(rng, n_taps, n_creep):
    inverse = _filter(rng, n_taps, n_creep)
    x = _reference(rng)
    expected, clamped = _naive(inverse, x)
    p = inverse.packed.copy()
    out = np.empty_like(x)
    # blocks of uneven lengths: each starts wherever the head was left
    edges = [0, *sorted(rng.choice(np.arange(1, x.size), 9, replace=False)), x.size]
    for a, b in itertools.pairwise(edges):
        dk.inverse_run(p, x[a:b], out[a:b])
    np.testing.assert_allclose(out, expected, rtol=0, atol=1e-9)
    assert np.array_equal(np.isnan(out), np.isnan(expected))  # held where the naive holds
    assert int(p[dk.clamped_slot(p)]) == clamped > 100


def test_the_delay_line_is_circular_and_held_twice_over(rng):
    """Each finite sample moves the head back one place and is written at the head and
    ``N_FIR`` further: the last ``N_FIR`` samples, newest first, from ``line[head]`` on."""
    inverse = _filter(rng, 7, 2)
    x = rng.uniform(5.0, 25.0, 45)
    x[[10, 30]] = np.nan  # skipped: the line does not move
    p = inverse.packed.copy()
    dk.inverse_run(p, x, np.empty_like(x))
    s = dk.state_start(p)
    line = p[s + dk.ST_LINE : s + dk.ST_LINE + 14]
    head = int(p[s + dk.ST_HEAD])
    assert head == (-43) % 7  # 43 finite samples from head 0
    np.testing.assert_array_equal(line[:7], line[7:])
    np.testing.assert_array_equal(line[head : head + 7], x[np.isfinite(x)][::-1][:7])
    assert dk.clamped_slot(p) == p.size - 1


@pytest.mark.parametrize(("n_taps", "n_creep"), [(1, 0), (17, 4), (67, 2)])
def test_step_equals_the_batch_run_bit_for_bit(rng, n_taps, n_creep):
    inverse = _filter(rng, n_taps, n_creep)
    x = _reference(rng, 2000)
    batch = inverse.packed.copy()
    out = np.empty_like(x)
    cuts = np.empty_like(x)
    dk.inverse_run_cuts(batch, x, out, cuts)
    stepped = inverse.packed.copy()
    step = step_function(dk.inverse_step)
    counts = []
    for xk in x:
        assert np.array_equal(step(stepped, xk), out[len(counts)], equal_nan=True)
        counts.append(stepped[dk.clamped_slot(stepped)])
    # the scratch slots aside, the same state; the clamp counted where cuts says
    s = dk.state_start(batch)
    assert np.array_equal(
        np.delete(stepped, s + np.arange(dk.ST_HEAD + 1, dk.ST_LINE)),
        np.delete(batch, s + np.arange(dk.ST_HEAD + 1, dk.ST_LINE)),
    )
    assert np.array_equal(np.diff(np.r_[0.0, counts]), cuts)
    assert cuts.sum() > 50


def test_an_inverse_without_taps_is_refused():
    from hystcomp.errors import InvalidParameterError

    with pytest.raises(InvalidParameterError, match="'taps'"):
        DynamicsInverse([], [], [], preview=0)
