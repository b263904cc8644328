"""References, the uncompensated baseline and tracking runs on the twin."""

import numpy as np
import pytest

from hystcomp import presets
from hystcomp.errors import (
    IdentificationError,
    InvalidParameterError,
    InvalidSignalError,
    InvalidTypeError,
)
from hystcomp.experiment.baseline import LinearCompensator, linear_gain
from hystcomp.experiment.references import period_samples, triangle_reference
from hystcomp.experiment.tracking import run_tracking
from hystcomp.plant import Twin, TwinParameters

#: A twin without hysteresis or noise: x = 0.3 µm/V * v through D(s).
LINEAR = TwinParameters(anhysteretic=(36.0, 0.0, 0.0), hysteresis_amplitude=0.0, sensor_noise=0.0)


def test_triangle_reference_shape():
    t, x = triangle_reference(30.0, 10.0, periods=3)
    n = period_samples(10.0)
    assert n == 2000
    assert x.size == 3 * n + 1
    assert t[1] == pytest.approx(5e-5)
    assert x.max() == pytest.approx(30.0)
    np.testing.assert_allclose(x[: n + 1], x[n : 2 * n + 1])  # periodic
    assert x[n // 2] == pytest.approx(30.0)
    assert np.all(np.abs(np.diff(x)) == pytest.approx(2 * 30.0 * 10.0 / 20_000))


def test_triangle_reference_refuses_too_few_periods_or_samples():
    with pytest.raises(InvalidParameterError, match="'periods' parameter"):
        triangle_reference(30.0, 1.0, periods=1)
    with pytest.raises(InvalidParameterError, match="at least 4 samples per period"):
        triangle_reference(30.0, 8000.0)


def test_linear_gain_least_squares_and_end_point():
    v = np.array([0.0, 60.0, 120.0, 60.0, 0.0])
    x = np.array([0.0, 15.0, 36.0, 21.0, 0.0])
    assert linear_gain(v, x) == pytest.approx((60 * 15 + 120 * 36 + 60 * 21) / (2 * 3600 + 14400))
    assert linear_gain(v, x, method="end-point") == pytest.approx(0.3)
    with pytest.raises(InvalidParameterError, match="'method' parameter of linear_gain"):
        linear_gain(v, x, method="median")
    with pytest.raises(IdentificationError, match="no positive gain"):
        linear_gain(v, -x)
    with pytest.raises(InvalidSignalError, match="one sample each"):
        linear_gain(v, x[:3])


def test_linear_compensator_clamps_to_the_range():
    comp = LinearCompensator(0.3, (0.0, 100.0))
    np.testing.assert_allclose(comp.simulate([-3.0, 15.0, 36.0]), [0.0, 50.0, 100.0])


def test_exact_compensation_of_a_linear_axis_leaves_only_the_dynamics():
    twin = Twin(LINEAR)
    _, x_ref = triangle_reference(30.0, 1.0, periods=2)
    result = run_tracking(LinearCompensator(0.3), twin, x_ref, frequency=1.0, method="linear")
    assert result.rms < 0.01
    assert result.max < 0.05  # ramp lag and one sample of delay: 30 µm/0.5 s * 50 µs = 3 nm
    assert result.hysteresis_pct < 0.1
    assert result.window == slice(20_000, 40_000)
    np.testing.assert_allclose(result.e, result.x - result.x_ref)
    assert result.v.max() == pytest.approx(100.0)


def test_uncompensated_errors_of_the_twin_are_calibrated():
    twin = Twin(seed=2)
    _, v = triangle_reference(120.0, 1.0, periods=2)  # any record from rest gives the gain
    gain = linear_gain(v, twin.run(v))
    _, x_ref = triangle_reference(33.3, 1.0, periods=2)
    result = run_tracking(LinearCompensator(gain), twin, x_ref, frequency=1.0)
    assert 1.4 < result.rms < 2.1  # µm; the paper's 4.70 needs its datasheet gain (report)
    assert result.saturation_zone_pct == pytest.approx(10.0, abs=1.5)


def test_compensator_output_is_checked():
    class Reckless:
        voltage_range = (0.0, 120.0)

        def simulate(self, x_ref):
            return np.asarray(x_ref) * 10.0

    _, x_ref = triangle_reference(30.0, 10.0)
    with pytest.raises(InvalidParameterError, match="outside its range"):
        run_tracking(Reckless(), Twin(), x_ref, frequency=10.0)
    with pytest.raises(InvalidTypeError, match="simulate"):
        run_tracking(object(), Twin(), x_ref, frequency=10.0)
    with pytest.raises(InvalidParameterError, match="at least two periods"):
        run_tracking(presets.paper_pi().inverse(), Twin(), x_ref[:3000], frequency=10.0)
