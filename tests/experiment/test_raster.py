"""The AFM raster on the simulated scanner: the coupled model against per-axis compensators.

Targets (for stages of two and three axes, coupled by 2-8 %, of different hysteresis
kinds): each axis tracks within 0.15x its uncompensated rms, and the axes' summed rms is at
most 0.5x that of per-axis compensators that ignore the coupling. The default suite checks
the two-axis stage at 5 kHz with Preisach axes; the slow suite the full measurement (20 kHz,
the default auto family, two and three axes).
"""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from hystcomp.cli import main
from hystcomp.experiment.raster import (
    METHODS,
    SPAN,
    plot_raster,
    raster_experiment,
    raster_image,
    raster_reference,
)
from hystcomp.plant.scanner import Scanner, raster_scanner


def _check_targets(result):
    assert set(result.rms_um) == set(METHODS)
    assert np.all(result.ratio("coupled") <= 0.15), result.table()
    assert result.summed_ratio <= 0.5, result.table()
    # the coupling is identified within a fifth of its size
    off = ~np.eye(result.coupling.shape[0], dtype=bool)
    assert np.all(np.abs(result.identified - result.coupling)[off] <= 0.2 * 0.08)


@pytest.fixture(scope="module")
def fast_result():
    base = raster_scanner(2)
    scanner = Scanner(base.axes, base.coupling, sample_rate=5000.0)
    return raster_experiment(scanner, family="preisach", lines=8, excitation_frequency=2.0)


def test_the_coupled_model_meets_the_raster_targets(fast_result):
    _check_targets(fast_result)
    # and per-axis compensation alone does not: the coupling is what is left
    assert fast_result.rms_um["per-axis"][1] > 2.0 * fast_result.rms_um["coupled"][1]


def test_the_reference_is_two_frames_and_a_retrace_over_10_to_80_percent():
    t, X, measured = raster_reference([30.0, 25.0, 12.0], lines=4, sample_rate=1000.0)
    assert t[1] == pytest.approx(1e-3)
    frame = 4 * 100
    assert X.shape == (3 * frame, 3)
    assert measured == slice(2 * frame, 3 * frame)
    for i, stroke in enumerate([30.0, 25.0, 12.0]):
        assert X[:, i].min() >= SPAN[0] * stroke - 1e-9
        assert X[:, i].max() <= SPAN[1] * stroke + 1e-9
    assert np.all(np.diff(X[measured, 1]) >= 0)  # the slow axis rises over the frame
    assert np.sum(np.diff(np.sign(np.diff(X[measured, 0]))) != 0) >= 2 * 4 - 2  # 4 lines


def test_the_figure_is_written(fast_result, tmp_path):
    image = raster_image(fast_result, "coupled")
    assert image.shape[0] >= 7  # one row per trace line
    assert np.nanmin(image) == 0.0
    assert np.nanmax(image) == 1.0
    plot_raster(fast_result, tmp_path / "raster.png")
    assert (tmp_path / "raster.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.slow
@pytest.mark.parametrize("n_axes", [2, 3])
def test_the_full_raster_measurement(n_axes):
    _check_targets(raster_experiment(n_axes=n_axes))


@pytest.mark.slow
def test_the_raster_command_prints_the_table_and_writes_the_figure(tmp_path):
    result = CliRunner().invoke(main, ["raster", "--lines", "16", "--out", str(tmp_path), "-q"])
    assert result.exit_code == 0, result.stderr
    assert "coupled / per-axis" in result.stdout
    assert (tmp_path / "raster.png").exists()
    assert (tmp_path / "raster.csv").read_text().splitlines()[0].startswith("axis,method")
