"""The Preisach model identified from any record: least squares, non-negative density."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hystcomp import presets
from hystcomp.errors import InvalidParameterError
from hystcomp.identify.excitation import (
    random_turning_points,
    sinusoid_sequence,
    triangle_sequence,
)
from hystcomp.identify.preisach import identify_preisach
from hystcomp.identify.preisach_lsq import EverettBasis
from hystcomp.models.preisach import Preisach
from hystcomp.plant import Twin
from tests import naive
from tests.conftest import examples, monotone_theta, random_walk


@pytest.fixture(scope="module")
def random_record():
    """A random record at 2 kHz: nested minor loops of every size over 0..120 V."""
    return random_turning_points(60, seed=3, sample_rate=2_000.0)[1]


def _model(basis, coef, offset=0.0):
    theta, table = basis.to_model(coef)
    lo, hi = basis.lo, basis.hi
    return Preisach.from_parameters(
        theta=theta, table=table, voltage_range=(lo, hi), output_offset=offset
    )


@pytest.mark.parametrize(("everett", "size"), [("polynomial", 6), ("table", 10)])
def test_regressors_match_the_slow_reference(rng, everett, size):
    lo, hi = -2.0, 8.0
    v = random_walk(rng, 90, lo - 1.0, hi + 1.0, 1.5)  # also beyond the plane (clamped)
    basis = EverettBasis(everett, degree=3, grid_size=5, voltage_range=(lo, hi))
    assert basis.size == size
    if everett == "polynomial":
        funcs = naive.everett_basis_polynomial(basis.exps.tolist(), lo, hi)
    else:
        funcs = naive.everett_basis_cells(4, lo, hi)
    expected = naive.preisach_regressors(v, funcs, lo, hi)
    np.testing.assert_allclose(basis.design(v), expected, atol=1e-12)


@given(
    seed=st.integers(0, 2**32 - 1),
    everett=st.sampled_from(["polynomial", "table"]),
    degree=st.integers(1, 5),
    grid=st.integers(2, 9),
    start=st.integers(0, 50),
    stride=st.integers(1, 7),
)
def test_output_is_the_regressors_times_the_parameters(seed, everett, degree, grid, start, stride):
    rng = np.random.default_rng(seed)
    lo = rng.uniform(-150, 50)
    hi = lo + rng.uniform(1, 300)
    v = random_walk(rng, 400, lo, hi, 0.1 * (hi - lo))
    basis = EverettBasis(everett, degree=degree, grid_size=grid, voltage_range=(lo, hi))
    coef = rng.normal(size=basis.size)  # any sign: the identity is linear algebra
    offset = rng.normal()
    x = _model(basis, coef, offset).simulate(v)
    design = basis.design(v, start=start, stride=stride)
    np.testing.assert_allclose(
        design @ coef + offset, x[start::stride], atol=1e-9 * (1 + np.abs(x).max())
    )
    # the normal equations accumulated in blocks are those of the rows
    rows = np.column_stack([design, np.ones(len(design)), x[start::stride]])
    gram = basis.normal_equations(v, x, start=start, stride=stride)
    np.testing.assert_allclose(gram, rows.T @ rows, rtol=1e-10, atol=1e-9)


def test_recovers_a_known_polynomial_model_from_a_random_record(random_record, rng):
    truth = Preisach.from_parameters(theta=monotone_theta(rng, 3, 120.0, 36.0), output_offset=-50.0)
    x = truth.simulate(random_record) + 0.005 * rng.standard_normal(random_record.size)
    model = Preisach(fit_method="least-squares", everett="polynomial").fit(random_record, x)
    assert model.fit_report_["fit"] == "least-squares"
    assert model.fit_report_["record_rms_um"] == pytest.approx(0.005, rel=0.05)
    assert model.output_offset_ == pytest.approx(-50.0, abs=0.005)
    check = np.interp(np.linspace(0, 1, 3000), [0, 0.3, 0.45, 0.7, 1.0], [0, 110, 30, 90, 5])
    assert np.abs(model.simulate(check) - truth.simulate(check)).max() < 0.005  # of 36 µm


@pytest.mark.parametrize(
    ("voltage_range", "sample_rate", "offset"),
    [((0.0, 3.6), 200.0, -123.0), ((-150.0, 150.0), 5_000.0, 40.0)],
)
def test_other_ranges_rates_and_offsets(voltage_range, sample_rate, offset, rng):
    lo, hi = voltage_range
    truth = Preisach.from_parameters(
        theta=monotone_theta(rng, 3, hi - lo, 40.0), voltage_range=voltage_range
    )
    _, v = random_turning_points(
        30, seed=7, rate=0.5 * (hi - lo), sample_rate=sample_rate, voltage_range=voltage_range
    )
    x = truth.simulate(v) + offset + 0.005 * rng.standard_normal(v.size)
    for everett, bound in (("polynomial", 0.0055), ("table", 0.02)):
        model = Preisach(fit_method="least-squares", everett=everett).fit(v, x)
        assert model.voltage_range_ == pytest.approx(voltage_range)
        assert model.output_offset_ == pytest.approx(offset, abs=0.02)
        assert model.fit_report_["record_rms_um"] < bound  # noise 0.005 µm, stroke 40 µm


def test_eq_6_from_a_random_record_to_near_the_noise(random_record, rng):
    # eq. (6) with X(v, v) = 0 has a density slightly below 0 in one corner (-6e-5 µm/V^2
    # at alpha = 120, beta = 0): the constrained fit comes as close as a monotone model can
    truth = presets.paper_preisach(zero_diagonal=True)
    x = truth.simulate(random_record) + 0.005 * rng.standard_normal(random_record.size)
    model = Preisach(fit_method="least-squares", everett="polynomial").fit(random_record, x)
    assert model.fit_report_["record_rms_um"] < 0.012
    assert model.fit_report_["density_min"] >= -1e-12


def test_a_table_recovers_a_smooth_non_polynomial_system(random_record):
    # truth: a fine table of a non-polynomial density concentrated near the diagonal
    fine = EverettBasis("table", degree=3, grid_size=61, voltage_range=(0.0, 120.0))
    centre = 2.0 * (np.arange(60) + 0.5)
    sa, sb = np.tril_indices(60, -1)
    density = 0.004 * np.exp(-(((centre[sa] - centre[sb]) / 30.0) ** 2)) * (1 + centre[sa] / 120)
    truth = _model(fine, np.concatenate([np.full(60, 0.3), 4.0 * density]))
    x = truth.simulate(random_record)
    cubic = Preisach(fit_method="least-squares", everett="polynomial").fit(random_record, x)
    table = Preisach(fit_method="least-squares", everett="table").fit(random_record, x)
    assert table.fit_report_["record_rms_um"] < 0.01  # of a 34 µm stroke
    assert table.fit_report_["record_rms_um"] < 0.05 * cubic.fit_report_["record_rms_um"]


@pytest.fixture(scope="module")
def twin_record():
    """The twin's answer to a short random record (its hysteresis is of no model family)."""
    v = random_turning_points(16, seed=5)[1]
    return v, Twin(seed=2).run(v)


@pytest.mark.parametrize("everett", ["polynomial", "table"])
def test_fitted_density_is_non_negative_so_branches_rise_and_invert(twin_record, everett, rng):
    v, x = twin_record
    model = Preisach(fit_method="least-squares", everett=everett).fit(v, x)
    assert model.fit_report_["density_min"] >= -1e-9
    # every branch rises with the input, after any history
    history = random_walk(rng, 300, 0.0, 120.0, 15.0)
    for turn in (120.0, 0.0, 70.0, 20.0):
        probe = np.concatenate([history, np.linspace(history[-1], turn, 400)])
        branch = model.simulate(probe)[history.size :]
        slope = np.diff(branch) * np.sign(turn - history[-1])
        assert slope.min() >= -1e-9
    # the exact inverse then reaches every reference in range: model(inverse(x_ref)) = x_ref
    lo, hi = model.simulate([0.0])[0], model.simulate([0.0, 120.0])[-1]
    x_ref = random_walk(rng, 2000, lo + 0.01, hi - 0.01, 0.5)
    v_comp = model.inverse(method="exact").simulate(x_ref)
    np.testing.assert_allclose(model.simulate(v_comp), x_ref, atol=1e-7)


def test_start_up_transient_from_an_unknown_state_is_left_out(random_record, rng):
    truth = Preisach.from_parameters(theta=monotone_theta(rng, 3, 120.0, 36.0))
    # the actuator had a history the record does not show: it starts mid-range
    history = np.concatenate([np.linspace(0, 100, 200), np.linspace(100, 35, 200)])
    full = np.concatenate([history, np.linspace(35, 60, 100), random_record])
    x = truth.simulate(full)[history.size :]
    v = full[history.size :]
    model = Preisach(fit_method="least-squares", everett="polynomial").fit(v, x)
    start = model.fit_report_["first_used_sample"]
    assert 100 <= start < 200  # where the input first reaches an end of its range
    np.testing.assert_allclose(model.simulate(v)[start:], x[start:], atol=1e-6)


def test_auto_keeps_the_paper_fit_for_its_excitation_and_fits_every_other_record():
    truth = presets.paper_preisach(zero_diagonal=True)
    records = {
        "reversal-curves": sinusoid_sequence(sample_rate=2_000.0)[1],
        "least-squares": triangle_sequence(sample_rate=2_000.0)[1],  # 4 maxima only
    }
    for expected, v in records.items():
        model = Preisach(fit_method="auto", everett="polynomial").fit(v, truth.simulate(v))
        assert model.fit_report_["fit"] == expected
        assert model.fit_report_["record_rms_um"] < 0.1


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"fit_method": "paper"}, InvalidParameterError, r"'fit_method'.*'least-squares'.*paper"),
        (
            {"fit_method": "least-squares", "zero_diagonal": False},
            InvalidParameterError,
            r"zero_diagonal=False.*reversal curves.*fit_method='reversal-curves'",
        ),
    ],
)
def test_bad_options_get_clear_messages(kwargs, error, message):
    v = np.linspace(0.0, 120.0, 50)
    with pytest.raises(error, match=message):
        identify_preisach(v, 0.3 * v, **kwargs)


# each example fits a model to 1500 samples by constrained least squares (~0.1 s)
@settings(max_examples=examples(0.25))
@given(
    seed=st.integers(0, 2**32 - 1),
    everett=st.sampled_from(["polynomial", "table"]),
    noise=st.sampled_from([0.0, 0.05]),
)
def test_any_fit_has_rising_branches_and_an_exact_inverse(seed, everett, noise):
    # data from no Preisach model at all: a hysteretic map with a non-Preisach memory
    rng = np.random.default_rng(seed)
    v = random_walk(rng, 1500, 0.0, 10.0, 0.6)
    lag = np.empty_like(v)
    state = 0.0
    for k, u in enumerate(v):  # a play whose width shrinks with the input, then a saturation
        r = 1.0 + 0.1 * u
        state = min(max(state, u - r), u + r)
        lag[k] = state
    x = 3.0 * np.tanh(0.3 * v) + lag + noise * rng.standard_normal(v.size)
    model = Preisach(fit_method="least-squares", everett=everett, grid_size=9).fit(v, x)
    assert model.fit_report_["density_min"] >= -1e-9
    ramp = np.concatenate([np.linspace(0, 10, 200), np.linspace(10, 0, 200)])
    probe = model.simulate(np.concatenate([v, ramp]))[v.size :]
    assert np.diff(probe[:200]).min() >= -1e-9
    assert np.diff(probe[200:]).max() <= 1e-9
    low, high = probe[0], probe[199]
    if high - low > 1e-6:
        x_ref = np.linspace(low, high, 50)
        v_comp = model.inverse(method="exact").simulate(x_ref)
        np.testing.assert_allclose(model.simulate(v_comp), x_ref, atol=1e-7)
