"""PI (eq. 12) and MPI (eq. 15) models, their analytic inverses (eqs. 23-26), steppers."""

import itertools

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import hystcomp
from hystcomp.errors import InvalidParameterError, NotFittedError, NotInvertibleError
from hystcomp.models.inversion import invert_superposition
from tests import naive
from tests.conftest import mpi_models, pi_models, random_walk


def _inputs(model, rng, n=400):
    lo, hi = model.voltage_range_
    return random_walk(rng, n, lo, hi, (hi - lo) / 8)


@given(pi_models())
def test_pi_matches_naive_sum_of_plays(case):
    model, rng = case
    v = _inputs(model, rng)
    expected = naive.pi_model(
        v,
        model.thresholds_,
        model.weights_,
        model.initial_state_,
        model.input_offset_,
        model.output_offset_,
    )
    np.testing.assert_allclose(model.simulate(v), expected, rtol=1e-12, atol=1e-9)


@given(mpi_models())
def test_mpi_matches_naive_cascade(case):
    model, rng = case
    v = _inputs(model, rng)
    expected = naive.mpi_model(
        v,
        model.thresholds_,
        model.weights_,
        model.deadzone_thresholds_,
        model.deadzone_weights_,
        model.initial_state_,
        model.input_offset_,
        model.output_offset_,
    )
    np.testing.assert_allclose(model.simulate(v), expected, rtol=1e-12, atol=1e-9)


@given(st.one_of(pi_models(), mpi_models()))
def test_inverse_after_model_returns_the_voltage(case):
    model, rng = case
    v = _inputs(model, rng)
    v_back = model.inverse().simulate(model.simulate(v))
    np.testing.assert_allclose(v_back, v, rtol=0, atol=1e-9 * max(1.0, np.abs(v).max()))


@given(st.one_of(pi_models(), mpi_models()))
def test_model_after_inverse_returns_the_reference(case):
    model, rng = case
    # references the actuator can reach: outputs of the model for in-range voltages
    x = model.simulate(_inputs(model, rng))
    x_back = model.simulate(model.inverse().simulate(x))
    np.testing.assert_allclose(x_back, x, rtol=0, atol=1e-9 * max(1.0, np.abs(x).max()))


@given(st.one_of(pi_models(), mpi_models()), st.floats(-1e4, 1e4), st.floats(0.0, 1e4))
def test_compensator_output_never_leaves_the_voltage_range(case, center, scale):
    model, rng = case
    x = center + scale * rng.standard_normal(300)
    v = model.inverse().simulate(x)
    lo, hi = model.voltage_range_
    assert v.min() >= lo
    assert v.max() <= hi


def test_stepper_equals_batch_bit_for_bit(rng):
    for model in (hystcomp.presets.paper_pi(), hystcomp.presets.paper_mpi()):
        x = random_walk(rng, 2000, 0.0, 35.0, 3.0)
        comp = model.inverse()
        batch = comp.simulate(x)
        stepper = comp.stepper()
        streamed = np.array([stepper.step(xk) for xk in x])
        assert np.array_equal(streamed, batch)
        stepper.reset()
        assert np.array_equal(stepper.step_block(x), batch)
        # a copy continues independently from the same state
        stepper.reset()
        stepper.step_block(x[:1000])
        twin = stepper.copy()
        assert np.array_equal(twin.step_block(x[1000:]), batch[1000:])
        assert np.array_equal(stepper.step_block(x[1000:]), batch[1000:])


def test_forward_stepper_equals_batch(rng):
    model = hystcomp.presets.paper_mpi()
    v = random_walk(rng, 1000, 0.0, 120.0, 10.0)
    stepper = model.stepper()
    assert np.array_equal([stepper.step(vk) for vk in v], model.simulate(v))


def test_simulate_does_not_mutate_the_model(rng):
    model = hystcomp.presets.paper_pi()
    v = random_walk(rng, 500, 0, 120, 10.0)
    first = model.simulate(v)
    assert np.array_equal(model.simulate(v), first)
    assert not model.weights_.flags.writeable


def test_stepper_holds_and_counts_non_finite_references():
    comp = hystcomp.presets.paper_pi().inverse()
    s = comp.stepper()
    assert s.last_output == 0.0
    v1 = s.step(10.0)
    assert s.step(float("nan")) == v1
    assert s.step(float("inf")) == v1
    assert s.nonfinite_count == 2
    s.reset()
    assert s.nonfinite_count == 0


def test_batch_raises_on_non_finite_reference():
    comp = hystcomp.presets.paper_pi().inverse()
    with pytest.raises(ValueError, match=r"'x_ref' must be finite\. Sample 1 is nan"):
        comp.simulate([1.0, np.nan])


def test_slew_rate_limit_bounds_every_step():
    comp = hystcomp.presets.paper_mpi().inverse(slew_rate=1e5, sample_rate=20_000)
    v = comp.simulate(np.r_[0.0, np.full(100, 30.0), np.zeros(100)])
    assert np.abs(np.diff(np.r_[0.0, v])).max() <= 5.0 + 1e-12
    assert v[60] == pytest.approx(comp.simulate(np.full(200, 30.0))[-1])


def test_rate_independence_same_turning_points_any_sampling(rng):
    # the static models see only the sequence of values, not the time between them:
    # linear interpolation between turning points at any density gives the same output there
    turning = np.array([0.0, 80.0, 20.0, 110.0, 5.0, 60.0, 40.0, 120.0, 0.0])
    for model in (hystcomp.presets.paper_pi(), hystcomp.presets.paper_mpi()):
        results = []
        for per_segment in (2, 17, 400):
            segs = [
                np.linspace(a, b, per_segment, endpoint=False)
                for a, b in itertools.pairwise(turning)
            ]
            v = np.concatenate([*segs, turning[-1:]])
            idx = np.r_[np.arange(len(turning) - 1) * per_segment, v.size - 1]
            results.append(model.simulate(v)[idx])
        np.testing.assert_allclose(results[1], results[0], atol=1e-12)
        np.testing.assert_allclose(results[2], results[0], atol=1e-12)


def test_not_invertible_names_the_index():
    model = hystcomp.PrandtlIshlinskii.from_parameters(
        thresholds=[0, 1, 2, 3], weights=[1.0, -0.5, -0.6, 0.4]
    )
    with pytest.raises(NotInvertibleError, match=r"w_0 \+ \.\.\. \+ w_2 = -0\.1.*index 2") as e:
        model.inverse()
    assert e.value.index == 2
    mpi = hystcomp.ModifiedPrandtlIshlinskii.from_parameters(
        thresholds=[0, 1],
        weights=[1.0, 0.1],
        deadzone_thresholds=[0, 1],
        deadzone_weights=[1.0, -1.0],
    )
    with pytest.raises(NotInvertibleError, match=r"saturation operator S.*index 1"):
        mpi.inverse()


def test_inverse_superposition_is_an_involution(rng):
    r = np.r_[0.0, np.cumsum(rng.uniform(0.1, 2.0, 9))]
    w = np.diff(np.r_[0.0, rng.uniform(0.2, 1.0, 10)])
    r2, w2 = invert_superposition(*invert_superposition(r, w))
    np.testing.assert_allclose(r2, r, atol=1e-12)
    np.testing.assert_allclose(w2, w, rtol=1e-10)


def test_dead_zone_inverse_matches_bisection(rng):
    r = np.array([0.0, 2.0, 5.0, 9.0])
    w = np.array([1.0, -0.3, 0.6, -0.8])
    r_inv, w_inv = invert_superposition(r, w)
    for y in rng.uniform(-3, 20, 50):
        expected = naive.invert_monotone(
            lambda z: naive.saturation(np.array([z]), r, w)[0], y, -100, 100
        )
        got = naive.saturation(np.array([y]), r_inv, w_inv)[0]
        assert got == pytest.approx(expected, abs=1e-9)


def test_unfitted_model_says_how_to_fit():
    with pytest.raises(NotFittedError, match=r"Call fit\(v, x\)"):
        hystcomp.PrandtlIshlinskii(n_operators=4).simulate([0.0])


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"thresholds": [1, 2], "weights": [1, 1]}, r"must start at 0"),
        ({"thresholds": [0, 2, 2], "weights": [1, 1, 1]}, r"strictly increasing\. Entry 2"),
        ({"thresholds": [0, 2], "weights": [1]}, r"'weights'.*must have 2 entries"),
        ({"thresholds": [0, 2], "weights": [1, np.nan]}, r"'weights'.*must be finite"),
        ({"thresholds": [0, 2], "weights": [1, 1], "voltage_range": (5, 5)}, r"low < high"),
    ],
)
def test_bad_parameters_get_clear_messages(kwargs, message):
    with pytest.raises(InvalidParameterError, match=message):
        hystcomp.PrandtlIshlinskii.from_parameters(**kwargs)


def test_stepper_method_and_bound_step_agree(rng):
    comp = hystcomp.presets.paper_mpi().inverse(slew_rate=2e5)
    x = random_walk(rng, 300, 0.0, 35.0, 4.0)
    a, b = comp.stepper(), comp.stepper()
    assert [a.step(xk) for xk in x] == [hystcomp.Stepper.step(b, xk) for xk in x]
    assert a.last_output == b.last_output
    twin = a.copy()  # a copy binds its own state
    assert twin.step(1.0) == a.step(1.0)
    assert twin.step(30.0) == a.step(30.0)


@pytest.mark.parametrize(
    ("cls", "extra"),
    [
        (hystcomp.PrandtlIshlinskii, {}),
        (
            hystcomp.ModifiedPrandtlIshlinskii,
            {"deadzone_thresholds": [0.0, 20.0], "deadzone_weights": [1.0, -0.3]},
        ),
    ],
)
def test_a_play_state_no_input_can_leave_is_refused(cls, extra):
    """Eq. 26 inverts only reachable states: neighbours differ by at most their thresholds."""
    r = np.array([0.0, 10.0, 20.0])
    plays = {"thresholds": r, "weights": [1.0, 0.5, 0.5], **extra}
    model = cls.from_parameters(**plays, initial_state=5.0 + r)  # descended to 5 V: on the bound
    v = np.r_[np.linspace(5.0, 60.0, 50), np.linspace(60.0, 30.0, 30)]
    np.testing.assert_allclose(model.inverse().simulate(model.simulate(v)), v, atol=1e-9)
    with pytest.raises(InvalidParameterError, match=r"'initial_state'.*entries 1 and 2"):
        cls.from_parameters(**plays, initial_state=[0.0, 0.0, 10.5])
