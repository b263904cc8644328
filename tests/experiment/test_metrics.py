"""The paper's figures of merit against hand-computed values."""

import numpy as np
import pytest

from hystcomp.errors import InvalidSignalError
from hystcomp.experiment.metrics import branch_means, hysteresis_percent, tracking_errors


def test_tracking_errors_of_a_sine():
    t = np.arange(20_000) / 20_000
    reference = 30.0 * t
    output = reference + 0.7 * np.sin(2 * np.pi * 5 * t)
    rms, peak = tracking_errors(reference, output)
    assert rms == pytest.approx(0.7 / np.sqrt(2), rel=1e-9)
    assert peak == pytest.approx(0.7, rel=1e-6)


def _parallelogram(width, n=801):
    """Ascending branch x = u, descending x = u + width, u from 0 to 1: range 1 + width."""
    u = np.linspace(0.0, 1.0, n)
    return np.concatenate([u, u[::-1]]), np.concatenate([u, u[::-1] + width])


@pytest.mark.parametrize("width", [0.05, 0.1, 0.3])
def test_parallelogram_loop_has_its_width_over_its_range(width):
    reference, output = _parallelogram(width)
    whole, zone = hysteresis_percent(reference, output)
    assert whole == pytest.approx(100 * width / (1 + width), rel=1e-9)
    assert zone == pytest.approx(100 * width / (1 + width), rel=1e-9)


def test_a_clockwise_loop_counts_as_much():
    reference, output = _parallelogram(0.1)
    flipped = np.concatenate([output[: output.size // 2] + 0.1, output[output.size // 2 :] - 0.1])
    assert hysteresis_percent(reference, flipped)[0] == pytest.approx(100 * 0.1 / 1.1, rel=1e-9)


def test_ellipse_whole_loop_and_top_quarter():
    """x_ref = cos(theta), x = cos(theta - phi): vertical width 2 sin(phi) sqrt(1 - u^2)."""
    phi = 0.2
    theta = np.linspace(0.0, 4 * np.pi, 400_001)
    reference, output = np.cos(theta), np.cos(theta - phi)
    whole, zone = hysteresis_percent(reference, output, n_bins=2000)
    assert whole == pytest.approx(100 * np.sin(phi), rel=1e-3)  # width 2 sin(phi), range 2
    # top quarter: mid-line u cos(phi) >= -1 + 0.75 * 2, widest at its lower edge
    u = 0.5 / np.cos(phi)
    assert zone == pytest.approx(100 * np.sin(phi) * np.sqrt(1 - u**2), rel=5e-3)


def test_hysteresis_is_robust_to_sensor_noise(rng):
    reference, output = _parallelogram(0.1, n=20_001)
    noisy = output + rng.normal(scale=0.003, size=output.size)
    whole, zone = hysteresis_percent(reference, noisy)
    assert whole == pytest.approx(100 * 0.1 / 1.1, abs=0.1)
    assert zone == pytest.approx(100 * 0.1 / 1.1, abs=0.1)


def test_branch_means_put_both_branches_on_one_grid():
    reference, output = _parallelogram(0.2)
    centres, ascending, descending = branch_means(reference, output, n_bins=10)
    np.testing.assert_allclose(centres, np.arange(10) / 10 + 0.05)
    np.testing.assert_allclose(descending - ascending, 0.2, atol=1e-12)


def test_bad_signals_are_refused():
    with pytest.raises(InvalidSignalError, match="one sample each per instant"):
        tracking_errors([0.0, 1.0], [0.0])
    with pytest.raises(InvalidSignalError, match="must rise and fall"):
        hysteresis_percent(np.linspace(0, 1, 50), np.linspace(0, 1, 50))
    with pytest.raises(InvalidSignalError, match="finite"):
        hysteresis_percent([0.0, 1.0, np.nan, 0.0], [0.0, 1.0, 2.0, 0.0])
