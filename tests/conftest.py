"""Shared fixtures and strategies: seeded data and random invertible models."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import strategies as st

import hystcomp
from hystcomp import operators


@pytest.fixture
def rng():
    return np.random.default_rng(20261122)


def random_walk(rng, n, lo, hi, step):
    """A bounded random walk: an input with many nested reversals."""
    steps = rng.normal(scale=step, size=n)
    return np.clip(np.cumsum(steps) + 0.5 * (lo + hi), lo, hi)


def invertible_weights(rng, n, scale=1.0):
    """Weights whose partial sums stay positive, some of them negative (like the paper's)."""
    partial = scale * rng.uniform(0.2, 1.0, size=n)
    return np.diff(np.concatenate([[0.0], partial]))


@st.composite
def pi_models(draw, max_ops=8):
    seed = draw(st.integers(0, 2**32 - 1))
    n = draw(st.integers(1, max_ops))
    rng = np.random.default_rng(seed)
    span = draw(st.floats(1.0, 300.0))
    v0 = draw(st.floats(-150.0, 50.0))
    r = np.sort(rng.uniform(0, span, n))
    r[0] = 0.0
    r = np.maximum.accumulate(r + np.arange(n) * 1e-3)
    # initial states are those left by some input history (eq. 26 needs reachable states)
    initial_state = np.zeros(n)
    if draw(st.booleans()):
        history = random_walk(rng, 50, 0.0, span, span / 4)
        out = np.empty((history.size, n))
        operators.play_outputs(history, r, initial_state, out)
        initial_state = out[-1]
    model = hystcomp.PrandtlIshlinskii.from_parameters(
        thresholds=r,
        weights=invertible_weights(rng, n, scale=draw(st.floats(0.05, 5.0))),
        initial_state=initial_state,
        voltage_range=(v0, v0 + span),
        input_offset=v0,
        output_offset=draw(st.floats(-200.0, 200.0)),
    )
    return model, rng


@st.composite
def mpi_models(draw, max_ops=8):
    pi, rng = draw(pi_models(max_ops))
    m = draw(st.integers(1, max_ops))
    span = float(pi.voltage_range_[1] - pi.voltage_range_[0]) * float(pi.weights_.sum())
    rs = np.concatenate([[0.0], np.sort(rng.uniform(0.01, 1.0, m - 1)) * span])
    rs = np.maximum.accumulate(rs + np.arange(m) * 1e-6)
    model = hystcomp.ModifiedPrandtlIshlinskii.from_parameters(
        thresholds=pi.thresholds_,
        weights=pi.weights_,
        initial_state=pi.initial_state_,
        deadzone_thresholds=rs,
        deadzone_weights=invertible_weights(rng, m),
        voltage_range=pi.voltage_range_,
        input_offset=pi.input_offset_,
        output_offset=pi.output_offset_,
    )
    return model, rng
