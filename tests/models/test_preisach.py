"""The classical Preisach model (eqs. 1-5): kernel against references, memory properties."""

import itertools
import json

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import hystcomp
from hystcomp import presets
from hystcomp._kernels import preisach as pk
from hystcomp.errors import InvalidParameterError, ModelFileError, NotFittedError
from hystcomp.models.preisach import Preisach
from tests import naive
from tests.conftest import preisach_models, random_walk


def _walk(model, rng, n=250, overshoot=0.1):
    lo, hi = model.voltage_range_
    pad = overshoot * (hi - lo)
    return random_walk(rng, n, lo - pad, hi + pad, (hi - lo) / 6)


def _reference_everett(model):
    lo, hi = model.voltage_range_
    if model.theta_ is not None:
        return naive.everett_polynomial(model.theta_, lo)
    return naive.everett_table(model.table_, lo, hi)


@given(preisach_models(monotone=False))
def test_kernel_matches_extrema_recomputed_from_scratch(case):
    # any X, even one with X(v, v) != 0 as eq. (6): eqs. (3)-(4) as written
    model, rng = case
    v = _walk(model, rng)
    lo, hi = model.voltage_range_
    expected = naive.preisach_extrema(v, _reference_everett(model), lo, hi)
    expected += model.output_offset_
    scale = max(1.0, np.abs(expected).max())
    np.testing.assert_allclose(model.simulate(v), expected, rtol=0, atol=1e-11 * scale)


@given(preisach_models(monotone=True), st.integers(3, 25))
def test_kernel_matches_relay_grid_of_eq_1(case, n_nodes):
    # eq. (1) literally: relays weighted by the density integrated over their cells
    model, rng = case
    lo, hi = model.voltage_range_
    nodes = np.linspace(lo, hi, n_nodes)
    index = np.clip(np.round(random_walk(rng, 150, 0, n_nodes - 1, 2.0)), 0, n_nodes - 1)
    index = index.astype(int)
    expected = naive.preisach_relays(index, _reference_everett(model), nodes)
    expected += model.output_offset_
    scale = max(1.0, np.abs(expected).max())
    np.testing.assert_allclose(model.simulate(nodes[index]), expected, atol=1e-10 * scale)


def test_degree_3_is_eq_5_term_by_term():
    theta = np.array([-0.137, 0.15, 0.0014, -0.0045, 0.00298, 2.5e-6, -7e-6, 1.9e-5, -1.4e-5])
    model = Preisach.from_parameters(theta=theta)
    t = theta
    for a, b in [(120.0, 0.0), (80.0, 35.0), (17.0, 3.0), (50.0, 50.0)]:
        eq5 = (
            t[0] * b
            + t[1] * a
            + t[2] * b**2
            + t[3] * b * a
            + t[4] * a**2
            + t[5] * b**3
            + t[6] * b**2 * a
            + t[7] * b * a**2
            + t[8] * a**3
        )
        assert model.everett_function(a, b) == pytest.approx(eq5, rel=1e-13, abs=1e-13)
    assert model.degree == 3
    linear, quadratic = [(1, 0), (0, 1)], [(2, 0), (1, 1), (0, 2)]
    cubic = [(3, 0), (2, 1), (1, 2), (0, 3)]
    assert pk.monomial_exponents(3) == [*linear, *quadratic, *cubic]


def test_paper_preset_is_eq_6_in_micrometres():
    model = presets.paper_preisach()
    assert model.everett_function(120.0, 0.0) == pytest.approx(36.72, abs=1e-9)
    # rising from v_min = 0 traces X(v, 0); falling from 120 V to 60 V subtracts X(120, 60)
    x = model.simulate([0.0, 60.0, 120.0, 60.0, 0.0])
    assert x[1] == pytest.approx(0.15 * 60 + 0.00298 * 60**2 - 0.000014 * 60**3)
    assert x[3] == pytest.approx(36.72 - model.everett_function(120.0, 60.0))
    assert x[4] == pytest.approx(0.0, abs=1e-12)
    # the printed coefficients leave X(v, v) != 0; the variant removes it
    assert model.everett_function(120.0, 120.0) == pytest.approx(0.696)
    fixed = presets.paper_preisach(zero_diagonal=True)
    v = np.linspace(0, 120, 13)
    np.testing.assert_allclose(fixed.everett_function(v, v), 0.0, atol=1e-12)
    np.testing.assert_allclose(fixed.everett_function(v, 0.0), model.everett_function(v, 0.0))


def _ramp(a, b, n=7):
    return np.linspace(a, b, n)[1:]


@given(preisach_models(monotone=False), st.data())
def test_wipe_out_erases_a_minor_loop_once_its_maximum_is_passed(case, data):
    model, rng = case
    lo, hi = model.voltage_range_
    prefix = random_walk(rng, 60, lo, hi, (hi - lo) / 5)
    c = prefix[-1]
    peak = data.draw(st.floats(0.05, 0.9)) * (hi - c) + c
    beyond = data.draw(st.floats(0.01, 1.0)) * (hi - peak) + peak
    # an excursion inside [c, peak]: up to its maximum, then nested reversals of shrinking size
    shrink = np.sort(rng.uniform(0.0, 1.0, data.draw(st.integers(1, 10))))[::-1]
    inner = c + (peak - c) * (0.5 + 0.5 * shrink * (-1.0) ** np.arange(shrink.size))
    excursion = np.concatenate([_ramp(c, peak), *[[u] for u in inner]])
    tail = random_walk(rng, 80, lo, hi, (hi - lo) / 5)
    # one step to 'beyond' wipes every stored extremum of the excursion at once
    with_loop = np.concatenate([prefix, excursion, [beyond], tail])
    without = np.concatenate([prefix, [beyond], tail])
    x_with = model.simulate(with_loop)
    x_without = model.simulate(without)
    n_after = tail.size + 1  # from the sample at 'beyond' on
    scale = max(1.0, np.abs(x_without).max())
    np.testing.assert_allclose(x_with[-n_after:], x_without[-n_after:], atol=1e-12 * scale)


@given(preisach_models(monotone=False), st.data())
def test_minor_loops_between_the_same_extrema_are_congruent(case, data):
    model, rng = case
    lo, hi = model.voltage_range_
    low = lo + data.draw(st.floats(0.1, 0.5)) * (hi - lo)
    high = low + data.draw(st.floats(0.1, 0.9)) * (hi - low)
    loop = np.concatenate([_ramp(low, high, 20), _ramp(high, low, 20)])
    loops = []
    for _ in range(2):
        # different histories, both ending at 'low' coming from above 'high'
        history = random_walk(rng, 50, lo, hi, (hi - lo) / 4)
        history = np.concatenate([history, _ramp(history[-1], hi), _ramp(hi, low)])
        x = model.simulate(np.concatenate([history, loop, loop]))
        loops.append(x[-loop.size :] - x[-loop.size - 1])
    scale = max(1.0, np.abs(loops[0]).max())
    np.testing.assert_allclose(loops[0], loops[1], atol=1e-10 * scale)


def test_memory_bound_wipes_out_the_innermost_loop(rng):
    extrema = 60 + 60 * (-1.0) ** np.arange(41) * 0.9 ** np.arange(41)
    v = np.concatenate([_ramp(a, b, 30) for a, b in itertools.pairwise(extrema)])
    model = presets.paper_preisach()
    deep = model.simulate(v)
    stepper = Preisach.from_parameters(theta=model.theta_, max_extrema=9).stepper()
    shallow = []
    for vk in v:
        shallow.append(stepper.step(vk))
        assert stepper.memory_depth <= 9
    shallow = np.array(shallow)
    # identical until the memory first fills (8 reversals), then off by at most the wiped loops
    first_full = 8 * 29
    np.testing.assert_array_equal(shallow[:first_full], deep[:first_full])
    assert np.abs(shallow - deep).max() < 0.05 * 36.7
    assert np.abs(shallow - deep).max() > 0  # the bound did act
    # far from full, a bound changes nothing
    roomy = Preisach.from_parameters(theta=model.theta_, max_extrema=100).simulate(v)
    np.testing.assert_array_equal(roomy, deep)


def test_inputs_outside_the_plane_saturate():
    model = presets.paper_preisach()
    x = model.simulate([-50.0, 200.0, 120.0, -10.0, 0.0])
    np.testing.assert_allclose(x, [0.0, 36.72, 36.72, 0.0, 0.0], atol=1e-12)


def test_rate_independence():
    model = presets.paper_preisach(zero_diagonal=True)
    turning = np.array([0.0, 80.0, 20.0, 110.0, 5.0, 60.0, 40.0, 120.0, 0.0])
    results = []
    for per_segment in (2, 17, 400):
        segs = [
            np.linspace(a, b, per_segment, endpoint=False) for a, b in itertools.pairwise(turning)
        ]
        v = np.concatenate([*segs, turning[-1:]])
        idx = np.r_[np.arange(len(turning) - 1) * per_segment, v.size - 1]
        results.append(model.simulate(v)[idx])
    np.testing.assert_allclose(results[1], results[0], atol=1e-12)
    np.testing.assert_allclose(results[2], results[0], atol=1e-12)


def test_stepper_equals_batch_bit_for_bit_and_holds_non_finite(rng):
    model = Preisach.from_parameters(theta=presets.PAPER_PREISACH_THETA, output_offset=-3.0)
    v = random_walk(rng, 3000, -5.0, 125.0, 6.0)
    batch = model.simulate(v)
    stepper = model.stepper()
    assert stepper.last_output == -3.0
    assert np.array_equal([stepper.step(vk) for vk in v], batch)
    stepper.reset()
    assert np.array_equal(stepper.step_block(v), batch)
    stepper.reset()
    stepper.step_block(v[:1500])
    twin = stepper.copy()
    assert np.array_equal(twin.step_block(v[1500:]), batch[1500:])
    assert np.array_equal(stepper.step_block(v[1500:]), batch[1500:])
    held = stepper.step(float("nan"))
    assert held == batch[-1]
    assert stepper.step(float("-inf")) == batch[-1]
    assert stepper.nonfinite_count == 2
    assert isinstance(stepper, hystcomp.Stepper)
    stepper.reset()
    assert stepper.nonfinite_count == 0


def test_simulate_does_not_mutate_the_model(rng):
    model = presets.paper_preisach()
    v = random_walk(rng, 500, 0, 120, 10.0)
    first = model.simulate(v)
    assert np.array_equal(model.simulate(v), first)
    assert not model.theta_.flags.writeable
    with pytest.raises(ValueError, match=r"'v' must be finite"):
        model.simulate([1.0, np.nan])


@pytest.mark.parametrize("make", ["polynomial", "table"])
def test_model_file_round_trip(make, tmp_path, rng):
    model = presets.paper_preisach()
    if make == "table":
        nodes = np.linspace(0, 120, 13)
        model = Preisach.from_parameters(
            table=model.everett_function(nodes[:, None], nodes), output_offset=2.0
        )
    path = tmp_path / "preisach.json"
    hystcomp.save_model(model, path)
    doc = json.loads(path.read_text())
    assert doc["kind"] == "preisach"
    assert ("theta" in doc["parameters"]) == (make == "polynomial")
    loaded = hystcomp.load_model(path)
    assert isinstance(loaded, Preisach)
    v = random_walk(rng, 2000, 0, 120, 8.0)
    assert np.array_equal(loaded.simulate(v), model.simulate(v))
    x = model.simulate(v)
    assert np.array_equal(loaded.inverse().simulate(x), model.inverse().simulate(x))


def test_model_file_written_before_the_table_default_loads_as_a_polynomial(tmp_path):
    # a file of the earlier default (cubic of eq. 5) names no Everett representation
    path = tmp_path / "old.json"
    doc = {"format": "hystcomp-model", "version": 1, "kind": "preisach"}
    params = {"theta": list(presets.PAPER_PREISACH_THETA), "voltage_range": [0.0, 120.0]}
    hyper = {"degree": 3, "voltage_range": None, "zero_diagonal": False, "max_extrema": 1024}
    path.write_text(json.dumps({**doc, "hyperparameters": hyper, "parameters": params}))
    loaded = hystcomp.load_model(path)
    assert (loaded.everett, loaded.degree) == ("polynomial", 3)
    v = np.linspace(0.0, 120.0, 50)
    assert np.array_equal(loaded.simulate(v), presets.paper_preisach().simulate(v))


def test_model_file_with_bad_theta_is_refused(tmp_path):
    path = tmp_path / "m.json"
    doc = {"format": "hystcomp-model", "version": 1, "kind": "preisach"}
    path.write_text(json.dumps({**doc, "parameters": {"theta": [1.0, 2.0, 3.0]}}))
    with pytest.raises(ModelFileError, match=r"'theta'.*d\(d\+3\)/2 entries"):
        hystcomp.load_model(path)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({}, r"exactly one of 'theta'.*Got neither"),
        ({"theta": [1, 2], "table": np.eye(2)}, r"Got both"),
        ({"theta": [1, 2, 3, 4]}, r"'theta'.*2, 5, 9, 14.*Got 4"),
        ({"theta": [1, np.inf]}, r"'theta'.*must be finite"),
        ({"table": np.ones((2, 3))}, r"'table'.*square.*\(2, 3\)"),
        ({"table": [[0, np.nan], [np.nan, 0]]}, r"'table'.*Entry \[1, 0\]"),
        ({"theta": [1, 2], "voltage_range": (3, 3)}, r"low < high"),
        ({"theta": [1, 2], "max_extrema": 2}, r"'max_extrema'.*>= 3"),
    ],
)
def test_bad_parameters_get_clear_messages(kwargs, message):
    with pytest.raises(InvalidParameterError, match=message):
        Preisach.from_parameters(**kwargs)


def test_unfitted_model_says_how_to_fit():
    with pytest.raises(NotFittedError, match=r"Call fit\(v, x\)"):
        Preisach().simulate([0.0])
    assert hystcomp.io.MODEL_KINDS["preisach"] is Preisach


def test_the_memory_bound_has_a_ceiling_so_that_a_stepper_cannot_ask_for_terabytes():
    v = np.r_[np.linspace(0.0, 120.0, 200), np.linspace(120.0, 0.0, 200)]
    x = presets.paper_preisach().simulate(v)
    with pytest.raises(InvalidParameterError, match="max_extrema"):
        hystcomp.Preisach(max_extrema=pk.MAX_DEPTH + 1).fit(v, x)
    data = presets.paper_preisach().to_dict()
    data["hyperparameters"]["max_extrema"] = 10**12
    with pytest.raises(InvalidParameterError, match="max_extrema"):
        hystcomp.Preisach.from_dict(data)
