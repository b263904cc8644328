"""The kernels against the slow references of tests/naive.py."""

import numpy as np
import pytest

from hystcomp import operators
from tests import naive
from tests.conftest import random_walk


def test_play_outputs_match_naive_play(rng):
    v = random_walk(rng, 3000, -50, 150, 7.0)
    r = np.array([0.0, 3.0, 11.5, 40.0, 90.0])
    y0 = np.array([0.0, 5.0, -2.0, 20.0, 0.0])
    out = np.empty((v.size, r.size))
    operators.play_outputs(v, r, y0, out)
    for i in range(r.size):
        np.testing.assert_allclose(out[:, i], naive.play(v, r[i], y0[i]), rtol=0, atol=1e-12)
    assert y0.tolist() == [0.0, 5.0, -2.0, 20.0, 0.0]  # initial state not consumed


def test_play_is_backlash_with_the_expected_width():
    # a 0 -> 10 -> 0 ramp through a play of r = 2: lags by 2 on the way up and down
    v = np.concatenate([np.linspace(0, 10, 11), np.linspace(9, 0, 10)])
    y = naive.play(v, 2.0)
    out = np.empty((v.size, 1))
    operators.play_outputs(v, np.array([2.0]), np.zeros(1), out)
    np.testing.assert_array_equal(out[:, 0], y)
    assert (out[10, 0], out[12, 0], out[-1, 0]) == (8.0, 8.0, 2.0)


def test_deadzone_sum_matches_naive(rng):
    r = np.array([0.0, 0.5, 2.0, 7.0])
    w = np.array([1.5, -0.4, 0.3, -0.2])
    for z in rng.uniform(-5, 12, 200):
        expected = naive.saturation(np.array([z]), r, w)[0]
        assert operators.deadzone_sum(z, r, w) == pytest.approx(expected, abs=1e-12)


def test_chain_clamps_and_limits_slew():
    p = operators.pack_chain(
        plays=(np.zeros(1), np.ones(1), np.zeros(1)), low=0.0, high=10.0, max_step=2.0
    )
    out = np.empty(6)
    operators.chain_run(p, np.array([5.0, 50.0, 50.0, 50.0, 50.0, -3.0]), out)
    assert out.tolist() == [2.0, 4.0, 6.0, 8.0, 10.0, 8.0]


def test_chain_holds_last_output_on_non_finite_input():
    p = operators.pack_chain(plays=(np.zeros(1), np.ones(1), np.zeros(1)))
    u = np.array([1.0, np.nan, np.inf, -np.inf, 3.0])
    out = np.empty(5)
    operators.chain_run(p, u, out)
    assert out.tolist() == [1.0, 1.0, 1.0, 1.0, 3.0]
    assert p[operators.chain_state_start(p) + operators.STATE_NONFINITE] == 3.0
