"""The kernels against the slow references of tests/naive.py."""

import numpy as np
import pytest

from hystcomp._kernels import chain
from hystcomp._kernels._jit import step_function
from tests import naive
from tests.conftest import random_walk


def test_play_outputs_match_naive_play(rng):
    v = random_walk(rng, 3000, -50, 150, 7.0)
    r = np.array([0.0, 3.0, 11.5, 40.0, 90.0])
    y0 = np.array([0.0, 5.0, -2.0, 20.0, 0.0])
    out = np.empty((v.size, r.size))
    chain.play_outputs(v, r, y0, out)
    for i in range(r.size):
        np.testing.assert_allclose(out[:, i], naive.play(v, r[i], y0[i]), rtol=0, atol=1e-12)
    assert y0.tolist() == [0.0, 5.0, -2.0, 20.0, 0.0]  # initial state not consumed


def test_play_is_backlash_with_the_expected_width():
    # a 0 -> 10 -> 0 ramp through a play of r = 2: lags by 2 on the way up and down
    v = np.concatenate([np.linspace(0, 10, 11), np.linspace(9, 0, 10)])
    y = naive.play(v, 2.0)
    out = np.empty((v.size, 1))
    chain.play_outputs(v, np.array([2.0]), np.zeros(1), out)
    np.testing.assert_array_equal(out[:, 0], y)
    assert (out[10, 0], out[12, 0], out[-1, 0]) == (8.0, 8.0, 2.0)


def test_one_sample_deadzone_block_matches_naive(rng):
    # the folded one-sample path of deadzone_block (a streaming step), on both sides of
    # every threshold and exactly on them
    r = np.array([0.0, 0.5, 2.0, 7.0])
    w = np.array([1.5, -0.4, 0.3, -0.2])
    out = np.empty(1)
    for z in [*rng.uniform(-5, 12, 200), *r, -0.0]:
        chain.deadzone_block(np.array([z]), 0.0, r, w, out)
        expected = naive.saturation(np.array([z]), r, w)[0]
        assert out[0] == pytest.approx(expected, abs=1e-12)


def test_chain_clamps_and_limits_slew():
    p = chain.pack_chain(
        plays=(np.zeros(1), np.ones(1), np.zeros(1)), low=0.0, high=10.0, max_step=2.0
    )
    out = np.empty(6)
    chain.chain_run(p, np.array([5.0, 50.0, 50.0, 50.0, 50.0, -3.0]), out)
    assert out.tolist() == [2.0, 4.0, 6.0, 8.0, 10.0, 8.0]


def test_chain_holds_last_output_on_non_finite_input():
    p = chain.pack_chain(plays=(np.zeros(1), np.ones(1), np.zeros(1)))
    u = np.array([1.0, np.nan, np.inf, -np.inf, 3.0])
    out = np.empty(5)
    chain.chain_run(p, u, out)
    assert out.tolist() == [1.0, 1.0, 1.0, 1.0, 3.0]
    assert p[chain.chain_state_start(p) + chain.STATE_NONFINITE] == 3.0


def test_deadzone_block_gives_the_same_bits_for_any_block_length(rng):
    x = rng.uniform(-5, 12, 1000)
    r = np.array([0.0, 0.5, 2.0, 7.0, 9.5])
    w = np.array([1.5, -0.4, 0.3, -0.2, 0.1])
    whole = np.empty_like(x)
    chain.deadzone_block(x, 1.25, r, w, whole)
    one_by_one = np.empty_like(x)
    for k in range(x.size):
        chain.deadzone_block(x[k : k + 1], 1.25, r, w, one_by_one[k : k + 1])
    np.testing.assert_allclose(whole, naive.saturation(x - 1.25, r, w), rtol=0, atol=1e-12)
    assert np.array_equal(whole, one_by_one)


def test_padding_plays_change_nothing_and_unpack_drops_them(rng):
    r = np.array([0.0, 1.0, 2.5, 4.0, 6.0])
    w = np.array([1.0, 0.3, -0.2, 0.25, 0.1])
    y0 = np.array([0.5, 0.2, 0.0, -1.0, 0.0])
    p = chain.pack_chain(plays=(r, w, y0), in_offset=2.0, out_offset=-1.0)
    assert p[chain.N_PLAY] == chain.PLAY_MULTIPLE  # 5 plays padded to 8
    u = random_walk(rng, 3 * chain.BLOCK + 17, -10, 10, 1.0)  # several blocks
    out = np.empty_like(u)
    chain.chain_run(p, u, out)
    expected = naive.pi_model(u, r, w, y0, v0=2.0, x0=-1.0)
    np.testing.assert_allclose(out, expected, rtol=0, atol=1e-12)
    parts = chain.unpack_chain(p)
    assert parts.play_r.tolist() == r.tolist()
    assert parts.play_w.tolist() == w.tolist()
    assert parts.plays.size == 5  # the states after the run, without padding
    assert (parts.in_offset, parts.out_offset) == (2.0, -1.0)
    assert not parts.play_w.flags.writeable


def test_step_is_a_one_sample_run(rng):
    pre = (np.array([0.0, 1.0, 3.0]), np.array([1.0, 0.5, -0.3]))
    plays = (np.array([0.0, 0.7, 2.0]), np.array([0.8, 0.3, 0.2]), np.zeros(3))
    post = (np.array([0.0, 2.0]), np.array([1.0, -0.4]))
    packed = chain.pack_chain(pre=pre, plays=plays, post=post, low=-3.0, high=3.0)
    u = random_walk(rng, 600, -6, 6, 0.8)
    u[[10, 300]] = np.nan
    batch = np.empty_like(u)
    chain.chain_run(packed.copy(), u, batch)
    p = packed.copy()
    steps = [chain.chain_step(p, uk) for uk in u]
    step = step_function(chain.chain_step)  # the entry point a Stepper binds
    q = packed.copy()
    bound = [step(q, uk) for uk in u]
    assert np.array_equal(steps, batch)
    assert np.array_equal(bound, batch)
    assert p[chain.chain_state_start(p) + chain.STATE_NONFINITE] == 2.0
