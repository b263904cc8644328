"""Shared fixtures and strategies: seeded data and random invertible models.

Also the suite's one Hypothesis profile, loaded here for every test file: ``ci`` by default
(the same examples on every run and machine, so a failure in CI reproduces locally), or
``thorough`` (random examples, many more of them) with ``HYPOTHESIS_PROFILE=thorough``.
"""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

import hystcomp
from hystcomp._kernels import chain

settings.register_profile(
    "ci",
    max_examples=40,
    derandomize=True,  # examples seeded from each test's name: every run tests the same ones
    deadline=None,  # a first call compiles numba kernels, and the machines are shared
    suppress_health_check=[HealthCheck.too_slow],  # some strategies build and run models
    print_blob=True,  # a failure prints the @reproduce_failure line
)
settings.register_profile(
    "thorough", settings.get_profile("ci"), max_examples=1000, derandomize=False
)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


def examples(factor: float) -> int:
    """``max_examples`` for a test that needs ``factor`` times the profile's count (>= 1).

    Scales with the profile, so ``HYPOTHESIS_PROFILE=thorough`` runs these tests longer too.
    """
    return max(1, round(factor * settings.default.max_examples))


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
        chain.play_outputs(history, r, initial_state, out)
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


def everett_from_density(nu, mu, degree):
    """theta (eq. 5's order, shifted coordinates) of a Preisach model with X(v, v) = 0.

    ``X(a, b) = int_b^a nu(s) ds + int int_{b <= b' <= a' <= a} mu(a', b')``: a reversible
    part with line density ``nu(s) = sum_k nu[k] s^k`` on the diagonal and a Preisach density
    ``mu(a, b) = sum mu[(p, q)] b^p a^q``; non-negative coefficients make every branch
    monotone (and strictly so when ``nu[0] > 0``).
    """
    from hystcomp._kernels.preisach import monomial_exponents

    coef = {}

    def add(i, j, c):
        coef[(i, j)] = coef.get((i, j), 0.0) + c

    for k, c in enumerate(nu):
        add(0, k + 1, c / (k + 1))
        add(k + 1, 0, -c / (k + 1))
    for (p, q), c in mu.items():
        n = p + q + 2
        add(0, n, c / ((p + 1) * n))
        add(n, 0, c * (1 / ((p + 1) * (q + 1)) - 1 / ((p + 1) * n)))
        add(p + 1, q + 1, -c / ((p + 1) * (q + 1)))
    return np.array([coef.get(e, 0.0) for e in monomial_exponents(degree)])


def monotone_theta(rng, degree, span, stroke):
    """A random degree-``degree`` Everett polynomial with X(v, v) = 0, strictly monotone
    branches and ``X(v_max, v_min) = stroke`` on a plane ``span`` V wide."""
    nu = rng.uniform(0.0, 1.0, degree) / span ** np.arange(degree)
    nu[0] = max(nu[0], 0.2)
    mu = {
        (p, k - p): rng.uniform(0.0, 1.0) / span ** (k + 1)
        for k in range(degree - 1)
        for p in range(k + 1)
    }
    theta = everett_from_density(nu, mu, degree)
    full = sum(
        c * span ** (i + j) for c, (i, j) in zip(theta, _exps(degree), strict=True) if i == 0
    )
    return theta * stroke / full


def _exps(degree):
    from hystcomp._kernels.preisach import monomial_exponents

    return monomial_exponents(degree)


@st.composite
def preisach_models(draw, monotone=True, representation=("polynomial", "table")):
    """A Preisach model on a random plane, with an output offset.

    ``monotone``: X(v, v) = 0 and strictly monotone branches (built from a density);
    otherwise an arbitrary polynomial or table. The table samples such a polynomial on a grid.
    """
    from hystcomp._kernels.preisach import n_monomials
    from hystcomp.models.preisach import Preisach

    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    v_min = draw(st.floats(-150.0, 50.0))
    span = draw(st.floats(1.0, 300.0))
    degree = draw(st.integers(1, 4))
    stroke = draw(st.floats(1.0, 100.0))
    if monotone:
        theta = monotone_theta(rng, degree, span, stroke)
    else:
        theta = rng.normal(size=n_monomials(degree)) * stroke
        theta /= span ** np.array([i + j for i, j in _exps(degree)])
    kw = {"voltage_range": (v_min, v_min + span), "output_offset": draw(st.floats(-200, 200))}
    model = Preisach.from_parameters(theta=theta, **kw)
    if draw(st.sampled_from(representation)) == "table":
        nodes = np.linspace(v_min, v_min + span, draw(st.integers(2, 30)))
        table = model.everett_function(nodes[:, None], nodes[None, :])
        model = Preisach.from_parameters(table=table, **kw)
    return model, rng
