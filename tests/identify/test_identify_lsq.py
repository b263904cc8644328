"""The least-squares machinery of identification against slow, independent references."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from hystcomp import presets
from hystcomp._kernels import chain
from hystcomp.identify.excitation import triangle_sequence
from hystcomp.identify.lsq import constrained_lsq, normal_equations
from hystcomp.identify.pi import paper_thresholds
from hystcomp.identify.scoring import (
    RANGE_BINS,
    RANGE_WEIGHT_CAP,
    range_weights,
    reversal_folds,
)
from tests import naive
from tests.conftest import random_walk


def _design(u, r, y0, z, rs_tail):
    """The regressors of identify.lsq written out with the naive operators."""
    plays = [naive.play(u, ri, yi) for ri, yi in zip(r, y0, strict=True)]
    deadzones = [-naive.deadzone(z, rj) for rj in rs_tail]
    return np.column_stack([*plays, *deadzones, np.ones_like(u)])


def test_deadzone_values_match_naive(rng):
    r = np.array([0.0, 0.5, 2.0, 7.0])
    out = np.empty(r.size)
    for z in rng.uniform(-5, 12, 100):
        chain.deadzone_values(z, r, out)
        expected = [naive.deadzone(np.array([z]), rj)[0] for rj in r]
        np.testing.assert_allclose(out, expected, rtol=0, atol=1e-15)


def test_normal_equations_equal_the_explicit_design(rng):
    # more samples than one block of the kernel, and a transient left out
    u = random_walk(rng, 2500, 0.0, 10.0, 0.8)
    z = 3.0 * u + rng.normal(size=u.size)
    r, y0 = np.array([0.0, 1.0, 2.5, 6.0]), np.array([0.0, 0.5, 2.0, 5.0])
    rs = np.array([4.0, 15.0])
    start = 37
    gram = normal_equations(u, r, y0, z, rs, start)
    full = np.column_stack([_design(u, r, y0, z, rs), z])[start:]
    np.testing.assert_allclose(gram, full.T @ full, rtol=1e-11, atol=1e-6)


def test_gram_blocks_run_on_one_blas_thread_and_the_setting_comes_back(rng, monkeypatch):
    """On a busy machine a threaded BLAS woken for every 2048 x 34 block made a fit many
    times slower: the products run on one thread, whatever the process's setting."""
    from threadpoolctl import threadpool_info, threadpool_limits

    seen = []
    rows = chain.regressor_rows

    def watched(*args):
        seen.append([lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"])
        return rows(*args)

    monkeypatch.setattr(chain, "regressor_rows", watched)
    u = random_walk(rng, 5000, 0.0, 10.0, 0.8)
    with threadpool_limits(limits=2, user_api="blas"):
        normal_equations(u, np.array([0.0, 2.0]), np.zeros(2), 3.0 * u, np.array([4.0]), 0)
        after = [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]
    assert len(seen) >= 3  # every block was watched
    assert all(threads and set(threads) == {1} for threads in seen)
    assert set(after) == {2}  # the caller's setting is back


def test_weighted_normal_equations_equal_the_explicit_weighted_design(rng):
    u = random_walk(rng, 2500, 0.0, 10.0, 0.8)
    z = 3.0 * u + rng.normal(size=u.size)
    r, y0 = np.array([0.0, 1.0, 2.5, 6.0]), np.array([0.0, 0.5, 2.0, 5.0])
    rs = np.array([4.0, 15.0])
    c = rng.uniform(0.2, 3.0, u.size)
    gram = normal_equations(u, r, y0, z, rs, 37, weights=c)
    full = np.column_stack([_design(u, r, y0, z, rs), z])[37:]
    np.testing.assert_allclose(gram, full.T @ (c[37:, None] * full), rtol=1e-11, atol=1e-6)


@given(st.lists(st.integers(0, RANGE_BINS - 1), min_size=1, max_size=200), st.integers(0, 5))
def test_range_weights_match_a_count_per_part(parts, start):
    # after `start` samples left out: the span's two ends, 0 and 24, and samples at the
    # middle of its parts 0..23
    u = np.r_[np.zeros(start), 0.0, np.array(parts) + 0.5, float(RANGE_BINS)]
    w = range_weights(u, start)
    fitted = u[start:]
    part = np.minimum(np.floor(u), RANGE_BINS - 1).astype(int)
    counts = np.array([np.sum(part[start:] == p) for p in range(RANGE_BINS)])
    raw = np.minimum(fitted.size / RANGE_BINS / counts[part], RANGE_WEIGHT_CAP)
    np.testing.assert_allclose(w, raw / raw[start:].mean(), rtol=1e-12)
    assert w[start:].mean() == pytest.approx(1.0)


def test_range_weights_of_a_constant_input_are_one():
    np.testing.assert_array_equal(range_weights(np.full(5, 3.0)), 1.0)


def test_range_weights_favour_the_rarely_visited_top_up_to_the_cap():
    # ten passes through the lowest quarter for one through the rest, as nested triangles
    ramp = np.linspace(0.0, 120.0, 2401)
    u = np.r_[np.tile(ramp[ramp < 30.0], 9), ramp]
    w = range_weights(u)
    # a count of 10 passes below 30 V and 1 above; 3.25 on average: the top's weight
    # 3.25 / 1 is capped at 3, the bottom's is 3.25 / 10
    ratio = w[u >= 30.0].mean() / w[u < 30.0].mean()
    assert ratio == pytest.approx(RANGE_WEIGHT_CAP / 0.325, rel=0.02)


def test_constrained_lsq_matches_a_bounded_solver_when_constraints_bind(rng):
    # a "true" superposition whose partial sums go negative: the unconstrained optimum is
    # not invertible, so the constraint must bind and both routes must agree
    u = triangle_sequence([4.0, 8.0, 12.0], sample_rate=300.0)[1]
    r = paper_thresholds(5, 12.0)
    y0 = np.zeros(5)
    truth = np.array([1.0, -1.3, 0.6, 0.1, -0.2])
    x = naive.pi_model(u, r, truth) + 2.0 + 0.01 * rng.standard_normal(u.size)
    bound = 0.05
    sol = constrained_lsq(
        normal_equations(u, r, y0, x, np.empty(0), 0),
        blocks=[(0, 5, bound)],
        scales=np.full(5, 12.0),
    )
    expected = naive.partial_sum_lsq(_design(u, r, y0, x, []), x, [(0, 5, bound)])
    assert np.cumsum(sol.coef[:5]).min() >= bound - 1e-9
    assert np.cumsum(sol.coef[:5]).min() == pytest.approx(bound, abs=1e-9)  # it binds
    np.testing.assert_allclose(sol.coef, expected, rtol=1e-6, atol=1e-7)


def test_mpi_problem_matches_a_bounded_solver():
    # eq. (19) on the paper's MPI with a small margin: same optimum by both routes
    _, v = triangle_sequence(sample_rate=200.0)
    model = presets.paper_mpi()
    z = model.simulate(v)
    r = paper_thresholds(16, 120.0)
    rs = paper_thresholds(6, z.max())
    blocks = [(0, 16, 0.02), (16, 21, -0.5)]
    sol = constrained_lsq(
        normal_equations(v, r, np.zeros(16), z, rs[1:], 0),
        blocks=blocks,
        scales=np.r_[np.full(16, 120.0), np.full(5, z.max())],
    )
    design = _design(v, r, np.zeros(16), z, rs[1:])
    expected = naive.partial_sum_lsq(design, z, blocks)
    np.testing.assert_allclose(design @ sol.coef, design @ expected, atol=1e-6)
    assert sol.rss == pytest.approx(np.sum((design @ expected - z) ** 2), rel=1e-6)


def test_regressors_that_never_move_are_fixed_at_zero():
    # plays with r >= span/2 cannot move once both ends are reached: only the offset is seen
    u = 1.8 + 1.8 * np.sin(np.linspace(0, 12 * np.pi, 1200))
    r = paper_thresholds(8, 3.6)
    x = naive.pi_model(u - u.min(), r[:4], [2.0, 1.0, 0.5, 0.3]) - 100.0
    start = int(np.argmax(u))
    sol = constrained_lsq(
        normal_equations(u - u.min(), r, np.full(8, u[0]), x + 100.0, np.empty(0), start),
        blocks=[(0, 8, 1e-3)],
        scales=np.full(8, 3.6),
    )
    assert sol.varies.tolist() == [True] * 4 + [False] * 4
    np.testing.assert_array_equal(sol.coef[4:8], 0.0)
    np.testing.assert_allclose(sol.coef[:4], [2.0, 1.0, 0.5, 0.3], atol=1e-8)


def test_fold_grams_are_each_folds_samples_and_sum_to_the_whole(rng):
    u = random_walk(rng, 2500, 0.0, 10.0, 0.8)
    z = 3.0 * u + rng.normal(size=u.size)
    r, y0, rs = np.array([0.0, 1.0, 2.5]), np.zeros(3), np.array([4.0, 15.0])
    start = 37
    folds = reversal_folds(u, start, 3)
    grams = normal_equations(u, r, y0, z, rs, start, folds, 3)
    full = np.column_stack([_design(u, r, y0, z, rs), z])
    for f in range(3):
        part = full[(folds == f) & (np.arange(u.size) >= start)]
        np.testing.assert_allclose(grams[f], part.T @ part, rtol=1e-11, atol=1e-6)
    np.testing.assert_allclose(
        grams.sum(axis=0), normal_equations(u, r, y0, z, rs, start), rtol=1e-11, atol=1e-6
    )


def test_reversal_folds_deal_whole_segments_in_turn():
    v = np.array([0.0, 1.0, 3.0, 2.0, 0.0, 1.0, 5.0, 4.0, 4.5])
    np.testing.assert_array_equal(reversal_folds(v, 1, 2), [-1, 0, 0, 1, 1, 0, 0, 1, 0])
