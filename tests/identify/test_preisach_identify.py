"""Identification of the Preisach model (Section III-A) on known systems."""

import numpy as np
import pytest

from hystcomp import presets
from hystcomp.errors import IdentificationError, InvalidParameterError, InvalidSignalError
from hystcomp.identify.excitation import (
    PREISACH_AMPLITUDES,
    scaled_amplitudes,
    sinusoid_sequence,
    triangle_sequence,
)
from hystcomp.identify.preisach import find_reversal_curves, identify_preisach
from hystcomp.models.preisach import Preisach
from tests.conftest import monotone_theta

#: The paper's fit: eq. (5) by least squares on the reversal curves (Section III-A).
PAPER = {"fit_method": "reversal-curves", "everett": "polynomial"}


@pytest.fixture(scope="module")
def excitation():
    return sinusoid_sequence(sample_rate=5_000.0)[1]


def _surface_error(fitted, truth, n=41):
    lo, hi = truth.voltage_range_
    g = np.linspace(lo, hi, n)
    a, b = np.meshgrid(g, g, indexing="ij")
    keep = b <= a
    return np.abs(fitted.everett_function(a, b) - truth.everett_function(a, b))[keep].max()


def test_recovers_eq_6_from_its_own_response(excitation):
    truth = presets.paper_preisach()
    x = truth.simulate(excitation)
    # eq. (6) has X(v, v) != 0: the paper's unconstrained least squares recovers it
    model = Preisach(**PAPER, zero_diagonal=False).fit(excitation, x)
    np.testing.assert_allclose(model.theta_, presets.PAPER_PREISACH_THETA, rtol=1e-4)
    assert _surface_error(model, truth) < 1e-4
    assert model.fit_report_["n_curves"] == 24
    np.testing.assert_allclose(model.fit_report_["maxima_V"], PREISACH_AMPLITUDES)
    assert model.fit_report_["diagonal_max_um"] == pytest.approx(0.696, abs=1e-3)


def test_recovers_eq_6_with_5_nm_noise_and_an_offset(excitation, rng):
    truth = presets.paper_preisach()
    x = truth.simulate(excitation) - 120.0 + 0.005 * rng.standard_normal(excitation.size)
    model = Preisach(**PAPER, zero_diagonal=False).fit(excitation, x)
    np.testing.assert_allclose(model.theta_, presets.PAPER_PREISACH_THETA, rtol=0.01)
    # each coefficient's contribution at full scale (120 V) within 30 nm
    powers = np.array([1, 1, 2, 2, 2, 3, 3, 3, 3])
    full_scale = (model.theta_ - presets.PAPER_PREISACH_THETA) * 120.0**powers
    assert np.abs(full_scale).max() < 0.03
    assert _surface_error(model, truth) < 0.003
    assert model.output_offset_ == pytest.approx(-120.0, abs=0.002)
    assert model.fit_report_["record_rms_um"] == pytest.approx(0.005, rel=0.05)


def test_zero_diagonal_fit_of_a_continuous_model_is_exact(excitation, rng):
    truth = Preisach.from_parameters(theta=monotone_theta(rng, 3, 120.0, 36.0))
    model = Preisach(**PAPER).fit(excitation, truth.simulate(excitation))
    assert _surface_error(model, truth) < 1e-4
    g = np.linspace(0, 120, 25)
    np.testing.assert_allclose(model.everett_function(g, g), 0.0, atol=1e-12)


@pytest.mark.parametrize(
    ("voltage_range", "sample_rate", "offset"),
    [((0.0, 3.6), 200.0, -123.0), ((-150.0, 150.0), 5_000.0, 40.0), ((0.0, 120.0), 997.0, 0.0)],
)
def test_other_ranges_rates_offsets_and_noise(voltage_range, sample_rate, offset, rng):
    lo, hi = voltage_range
    truth = Preisach.from_parameters(
        theta=monotone_theta(rng, 3, hi - lo, 40.0), voltage_range=voltage_range
    )
    amplitudes = scaled_amplitudes(PREISACH_AMPLITUDES, voltage_range=voltage_range)
    _, v = sinusoid_sequence(amplitudes, sample_rate=sample_rate, v_min=lo)
    x = truth.simulate(v) + offset + 0.005 * rng.standard_normal(v.size)
    model = Preisach(**PAPER).fit(v, x)
    assert model.voltage_range_ == pytest.approx(voltage_range, abs=1e-3 * (hi - lo))
    assert model.output_offset_ == pytest.approx(offset, abs=0.01)
    assert _surface_error(model, truth) < 0.03  # of a 40 µm stroke
    assert model.fit_report_["n_curves"] == 24
    table = Preisach(fit_method="reversal-curves", everett="table").fit(v, x)
    assert _surface_error(table, truth) < 0.1


def test_noise_on_the_input_does_not_make_spurious_curves(excitation, rng):
    truth = presets.paper_preisach(zero_diagonal=True)
    x = truth.simulate(excitation)
    noisy_v = excitation + 0.02 * rng.standard_normal(excitation.size)
    curves = find_reversal_curves(noisy_v, x)
    assert len(curves) == 24
    np.testing.assert_allclose([c.alpha for c in curves], PREISACH_AMPLITUDES, atol=0.1)


def test_start_up_transient_and_partial_curves_are_skipped(rng):
    truth = presets.paper_preisach(zero_diagonal=True)
    _, v = sinusoid_sequence([20.0, 40.0, 60.0, 80.0, 100.0, 120.0], sample_rate=2_000.0)
    # the record starts mid-way up a sinusoid and has a minor reversal that is not first-order
    lead = np.linspace(50.0, 70.0, 200)
    minor = np.concatenate([np.linspace(0, 90, 300), np.linspace(90, 40, 200)])
    minor = np.concatenate([minor, np.linspace(40, 100, 200), np.linspace(100, 0, 300)])
    v = np.concatenate([lead, np.linspace(70, 0, 300), minor, v])
    curves = find_reversal_curves(v, truth.simulate(v))
    alphas = [c.alpha for c in curves]
    # 70 (rise not seen from the minimum) and 100 (after the 40 V minimum) are not first-order
    np.testing.assert_allclose(alphas, [90.0, 20.0, 40.0, 60.0, 80.0, 100.0, 120.0])


def test_fitted_model_reproduces_a_continuous_non_polynomial_preisach_system(excitation, rng):
    # truth: a Preisach model whose X is a fine table of a non-polynomial (tanh) density
    nodes = np.linspace(0, 120, 61)
    a, b = np.meshgrid(nodes, nodes, indexing="ij")
    truth_table = 0.2 * (a - b) + 9.0 * np.tanh((a - b) / 60.0) ** 2 * (1 + a / 120.0)
    truth = Preisach.from_parameters(table=np.tril(truth_table))
    x = truth.simulate(excitation)
    cubic = Preisach(**PAPER).fit(excitation, x)
    quartic = Preisach(**PAPER, degree=4).fit(excitation, x)
    table = Preisach(fit_method="reversal-curves", everett="table").fit(excitation, x)
    # a higher degree or the table follow the non-polynomial X better
    assert cubic.fit_report_["record_rms_um"] < 0.4  # of a 40 µm stroke
    assert quartic.fit_report_["record_rms_um"] < 0.05
    assert table.fit_report_["record_rms_um"] < 0.01
    check = np.interp(np.linspace(0, 1, 4000), [0, 0.3, 0.45, 0.7, 1.0], [0, 110, 30, 90, 5])
    for model, bound in ((quartic, 0.15), (table, 0.05)):
        assert np.abs(model.simulate(check) - truth.simulate(check)).max() < bound


def test_reversal_curve_fit_of_a_record_without_them_names_the_fix():
    ramp = np.linspace(0.0, 120.0, 1000)
    with pytest.raises(
        IdentificationError, match=r"no first-order descending.*excitation_signal\('preisach'\)"
    ):
        Preisach(fit_method="reversal-curves").fit(ramp, 0.3 * ramp)
    # least squares (the default, and auto's choice here) is determined along X(v, 0)
    model = Preisach(fit_method="auto").fit(ramp, 0.3 * ramp)
    assert model.fit_report_["fit"] == "least-squares"
    np.testing.assert_allclose(model.simulate(ramp), 0.3 * ramp, atol=1e-6)


def test_reversal_curve_fit_of_one_amplitude_names_what_is_missing(rng):
    # like a periodic record of constant amplitude (the micromanipulator data)
    _, v = triangle_sequence([3.6] * 6, sample_rate=200.0)
    x = presets.paper_preisach(zero_diagonal=True).simulate(v * 120 / 3.6) - 120.0
    with pytest.raises(
        IdentificationError, match=r"1 distinct maximum \(3\.6 V\).*excitation_signal\('preisach'\)"
    ):
        Preisach(**PAPER).fit(v, x)
    with pytest.raises(IdentificationError, match=r"1 distinct maximum"):
        Preisach(everett="table", fit_method="reversal-curves").fit(v, x)
    with pytest.raises(IdentificationError, match=r"constant"):
        Preisach().fit(np.full(10, 2.0), np.zeros(10))
    assert Preisach(fit_method="auto").fit(v, x).fit_report_["fit"] == "least-squares"


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"degree": 0}, r"'degree'.*>= 1"),
        ({"degree": 9}, r"'degree'.*1\.\.8"),
        ({"everett": "spline"}, r"'everett'.*'polynomial'.*'table'"),
        ({"grid_size": 1}, r"'grid_size'.*>= 2"),
        ({"voltage_range": (10.0, 100.0)}, r"'voltage_range'.*spans 0\.\.120 V"),
    ],
)
def test_bad_options_get_clear_messages(kwargs, message, excitation):
    x = 0.3 * excitation
    with pytest.raises(InvalidParameterError, match=message):
        identify_preisach(excitation, x, **kwargs)


def test_zero_diagonal_must_be_a_bool(excitation):
    with pytest.raises(TypeError, match=r"'zero_diagonal'.*True or False.*'no'"):
        identify_preisach(excitation, 0.3 * excitation, zero_diagonal="no")


def test_mismatched_lengths_are_refused():
    with pytest.raises(InvalidSignalError, match=r"same length.*100 and 99"):
        Preisach().fit(np.zeros(100), np.zeros(99))
