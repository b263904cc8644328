"""Preisach compensators: the inverse multiplicative structure (eq. 10) and the exact inverse."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import hystcomp
from hystcomp import presets
from hystcomp.errors import InvalidParameterError, NotInvertibleError
from hystcomp.identify.excitation import triangle_sequence
from hystcomp.models.preisach import Preisach, PreisachCompensator
from tests.conftest import monotone_theta, preisach_models, random_walk


def _largest_fall(model, nodes=401) -> float:
    """How far (µm) a branch of ``model`` moves against the voltage between neighbouring
    nodes of a fine grid, or how far the major loop falls short of rising (0 if neither)."""
    lo, hi = model.voltage_range_
    u = np.linspace(lo, hi, nodes)
    X = model.everett_function(u[:, None], u[None, :])
    lower = np.tril(np.ones((nodes, nodes), dtype=bool))
    along_alpha = np.where(lower[:-1], X[1:] - X[:-1], np.inf)
    along_beta = np.where(lower[:, 1:], X[:, :-1] - X[:, 1:], np.inf)
    return max(0.0, -along_alpha.min(), -along_beta.min(), -X[-1, 0] + 1e-300)


def _reachable(model, rng, n=400):
    lo, hi = model.voltage_range_
    v = random_walk(rng, n, lo, hi, (hi - lo) / 8)
    return v, model.simulate(v)


@given(preisach_models(monotone=True))
def test_model_after_exact_inverse_is_the_identity(case):
    model, rng = case
    _, x = _reachable(model, rng)
    x_back = model.simulate(model.inverse(method="exact").simulate(x))
    np.testing.assert_allclose(x_back, x, rtol=0, atol=1e-9 * max(1.0, np.abs(x).max()))


@given(preisach_models(monotone=True, representation=("polynomial",)))
def test_exact_inverse_after_model_returns_the_voltage(case):
    # strictly monotone branches: the voltage is unique
    model, rng = case
    v, x = _reachable(model, rng)
    v_back = model.inverse(method="exact").simulate(x)
    lo, hi = model.voltage_range_
    np.testing.assert_allclose(v_back, v, rtol=0, atol=1e-7 * (hi - lo))


@given(
    preisach_models(monotone=False),
    st.sampled_from(["multiplicative", "exact"]),
    st.floats(-1e4, 1e4),
    st.floats(0.0, 1e4),
)
def test_compensator_output_never_leaves_the_voltage_range(case, method, center, scale):
    model, rng = case
    try:
        compensator = model.inverse(method=method)
    except NotInvertibleError:  # refused only if a branch falls, seen on a finer grid
        assert _largest_fall(model) > 0.0
        return
    x = center + scale * rng.standard_normal(300)
    v = compensator.simulate(x)
    lo, hi = model.voltage_range_
    assert v.min() >= lo
    assert v.max() <= hi


def test_exact_inverse_on_eq_6_holds_in_the_gap_at_reversals():
    # eq. (6)'s X(v, v) != 0 steps the output at a reversal: references inside that step
    # cannot be reached, the compensator holds its voltage there and resumes after it
    model = presets.paper_preisach()
    _, x_ref = triangle_sequence([35.0, 35.0], frequency=10.0, sample_rate=20_000.0)
    v = model.inverse(method="exact").simulate(x_ref)
    error = model.simulate(v) - x_ref
    assert np.abs(error).max() <= 0.697  # at most X(120, 120)
    assert np.median(np.abs(error)) < 1e-9
    gap = np.abs(error) > 1e-9
    assert gap.mean() < 0.1


def _triangle_error(model, method, sample_rate, frequency=10.0):
    _, x_ref = triangle_sequence([30.0] * 3, frequency=frequency, sample_rate=sample_rate)
    x_ref = x_ref + 1.0
    period = round(sample_rate / frequency)
    x = model.simulate(model.inverse(method=method).simulate(x_ref))
    e = (x - x_ref)[period : 3 * period]
    return np.sqrt(np.mean(e**2)), np.abs(e).max()


def test_multiplicative_error_is_first_order_in_the_sample_time(rng):
    model = Preisach.from_parameters(theta=monotone_theta(rng, 3, 120.0, 36.0))
    rms_1, max_1 = _triangle_error(model, "multiplicative", 20_000.0)
    rms_2, max_2 = _triangle_error(model, "multiplicative", 40_000.0)
    assert rms_1 / rms_2 == pytest.approx(2.0, abs=0.15)
    assert max_1 / max_2 == pytest.approx(2.0, abs=0.15)
    assert max_1 < 0.15  # µm, for a 30 µm triangle at 10 Hz (0.03 µm per sample)
    # the exact inverse has no such lag
    assert _triangle_error(model, "exact", 20_000.0)[1] < 1e-9


def test_multiplicative_is_eq_10_written_out(rng):
    model = presets.paper_preisach()
    comp = model.inverse(rho=0.3)
    x_ref = random_walk(rng, 300, 0.0, 35.0, 1.0)
    stepper = model.stepper()
    v_prev, h_prev, expected = 0.0, model.simulate([0.0])[0], []
    for xk in x_ref:
        gamma = h_prev - 0.3 * v_prev  # eq. (9) at the previous sample
        v_prev = min(max((xk - gamma) / 0.3, 0.0), 120.0)  # eq. (10), clamped
        h_prev = stepper.step(v_prev)  # H's memory advanced by the applied voltage
        expected.append(v_prev)
    np.testing.assert_allclose(comp.simulate(x_ref), expected, rtol=1e-12, atol=1e-9)


def test_default_rho_is_the_average_slope_of_the_range():
    model = presets.paper_preisach()
    assert model.default_rho() == pytest.approx(36.72 / 120.0)
    comp = model.inverse()
    assert comp.rho == pytest.approx(0.306)
    assert (comp.kind, comp.method, comp.voltage_range) == ("preisach", "multiplicative", (0, 120))
    assert isinstance(comp, hystcomp.Compensator)
    assert comp.model is model


@pytest.mark.parametrize("method", ["multiplicative", "exact"])
def test_stepper_equals_batch_bit_for_bit(method, rng):
    model = Preisach.from_parameters(theta=presets.PAPER_PREISACH_THETA, output_offset=-5.0)
    comp = model.inverse(method=method)
    x = random_walk(rng, 3000, -6.0, 35.0, 1.5)
    batch = comp.simulate(x)
    stepper = comp.stepper()
    assert stepper.last_output == 0.0  # v_min before the first sample
    assert np.array_equal([stepper.step(xk) for xk in x], batch)
    stepper.reset()
    assert np.array_equal(stepper.step_block(x), batch)
    stepper.reset()
    stepper.step_block(x[:1000])
    twin = stepper.copy()
    assert np.array_equal(twin.step_block(x[1000:]), batch[1000:])
    assert np.array_equal(stepper.step_block(x[1000:]), batch[1000:])
    assert stepper.step(float("nan")) == batch[-1]
    assert stepper.nonfinite_count == 1
    with pytest.raises(ValueError, match=r"'x_ref' must be finite\. Sample 1 is nan"):
        comp.simulate([1.0, np.nan])


@pytest.mark.parametrize("method", ["multiplicative", "exact"])
def test_slew_rate_limit_bounds_every_step(method):
    comp = presets.paper_preisach().inverse(method=method, slew_rate=1e5, sample_rate=20_000)
    v = comp.simulate(np.r_[np.full(100, 30.0), np.zeros(100)])
    assert np.abs(np.diff(np.r_[0.0, v])).max() <= 5.0 + 1e-12
    assert comp.max_step == pytest.approx(5.0)


def test_loaded_model_file_gives_the_same_compensators(tmp_path, rng):
    model = presets.paper_preisach(zero_diagonal=True)
    hystcomp.save_model(model, tmp_path / "m.json")
    loaded = hystcomp.load_model(tmp_path / "m.json")
    x = random_walk(rng, 1000, 0.0, 35.0, 2.0)
    for method in ("multiplicative", "exact"):
        comp = loaded.inverse(method=method)
        assert isinstance(comp, PreisachCompensator)
        assert np.array_equal(comp.simulate(x), model.inverse(method=method).simulate(x))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"method": "newton"}, r"'method'.*'multiplicative'.*'exact'"),
        ({"method": "exact", "rho": 0.3}, r"'rho'.*no gain"),
        ({"rho": -1.0}, r"'rho'.*> 0"),
        ({"slew_rate": 0.0}, r"'slew_rate'.*> 0"),
    ],
)
def test_bad_inverse_options_get_clear_messages(kwargs, message):
    with pytest.raises(InvalidParameterError, match=message):
        presets.paper_preisach().inverse(**kwargs)


def _major_loop_slopes(model, n=2001):
    """Local slopes (µm/V) of the major loop's branches, from the model's own simulation."""
    lo, hi = model.voltage_range_
    up, down = np.linspace(lo, hi, n), np.linspace(hi, lo, n)
    x = model.simulate(np.r_[up, down])
    return np.r_[np.diff(x[:n]) / np.diff(up), np.diff(x[n:]) / np.diff(down)]


@given(preisach_models(monotone=True))
def test_default_rho_never_lets_eq_10_amplify_an_error(case):
    # eq. (10) multiplies a sample's error by 1 - s / rho: within [-1, 1] for 0 <= s <= 2 rho
    model, _ = case
    lo, hi = model.voltage_range_
    chord = float(model.everett_function(hi, lo)) / (hi - lo)
    rho, s = model.default_rho(), _major_loop_slopes(model)
    assert rho >= chord
    assert s.max() <= 2.0 * rho * (1 + 1e-3)
    if rho > chord:  # raised only as far as the steepest slope needs
        assert s.max() == pytest.approx(2.0 * rho, rel=1e-3)


def test_default_rho_of_a_steep_model_is_half_its_steepest_slope(rng):
    model = Preisach.from_parameters(theta=monotone_theta(rng, 3, 120.0, 36.0))
    steepest = _major_loop_slopes(model).max()
    assert steepest > 2.1 * 36.0 / 120.0  # the chord would not keep eq. (10) contracting
    assert model.default_rho() == pytest.approx(steepest / 2.0, rel=1e-3)


def test_a_model_that_falls_has_no_compensator_whatever_the_method_or_gain():
    model = Preisach.from_parameters(theta=[0.1, -0.1])  # X = -0.1 (alpha - beta)
    for options in ({}, {"rho": 0.1}, {"method": "exact"}):
        with pytest.raises(NotInvertibleError, match=r"does not rise .* = -12 µm"):
            model.inverse(**options)
