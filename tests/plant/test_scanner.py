"""The simulated raster scanner: its axes' hysteresis, coupling, modes and noise."""

from __future__ import annotations

import numpy as np
import pytest

from hystcomp.errors import InvalidParameterError
from hystcomp.plant.scanner import KINDS, Scanner, ScannerAxis, raster_scanner


def _major_loop(n_axes):
    u = np.r_[
        np.linspace(0, 120, 2001), np.linspace(120, 0, 2001)[1:], np.linspace(0, 120, 2001)[1:]
    ]
    return np.column_stack([u] * n_axes)


def test_each_axis_has_its_stroke_and_a_loop_of_its_own_kind():
    scanner = raster_scanner(3, noise_um=0.0)
    H = scanner.hysteresis(_major_loop(3))
    widths = []
    for i, axis in enumerate(scanner.axes):
        up, down = H[4000:, i], H[2000:4001, i][::-1]
        assert H[:, i].min() == pytest.approx(0.0, abs=1e-9)
        assert H[4000, i] < H[-1, i]
        assert H[-1, i] == pytest.approx(axis.stroke_um, rel=0.02)
        widths.append(np.max(np.abs(up - down)) / np.ptp(H[:, i]))
    assert all(0.08 < w < 0.2 for w in widths)  # 10-18 % hysteresis, as stacks have
    assert len({round(w, 3) for w in widths}) == 3
    assert [a.hysteresis for a in scanner.axes] == list(KINDS)


def test_the_sensors_read_the_coupled_positions():
    scanner = raster_scanner(2, noise_um=0.0)
    slow = np.r_[np.linspace(0.0, 120.0, 4000), np.full(4000, 120.0)]
    V = np.column_stack([slow, np.zeros_like(slow)])  # only X moves
    X = scanner.run(V)
    # at rest after the move, the Y sensor reads M_yx of X's displacement
    assert X[-1, 1] / X[-1, 0] == pytest.approx(scanner.coupling[1, 0], rel=1e-6)
    assert 0.02 <= abs(scanner.coupling[1, 0]) <= 0.08


def test_every_axis_rings_at_its_own_resonance():
    scanner = raster_scanner(2, noise_um=0.0)
    n = 4000
    V = np.zeros((n, 2))
    V[10:, :] = 30.0  # a step on both axes
    H = scanner.hysteresis(V)
    Y = scanner.run_noiseless(V) @ np.linalg.inv(scanner.coupling).T
    for i, axis in enumerate(scanner.axes):
        ring = Y[10:, i] - H[-1, i]
        crossings = np.flatnonzero(np.diff(np.sign(ring[:800])) != 0)
        period = 2.0 * np.mean(np.diff(crossings)) / scanner.sample_rate
        assert 1.0 / period == pytest.approx(axis.resonance_hz, rel=0.05)


def test_noise_is_seeded_and_of_the_given_size():
    scanner = raster_scanner(2, noise_um=0.003, seed=4)
    V = np.zeros((20000, 2))
    a, b = scanner.run(V), scanner.run(V)
    assert np.array_equal(a, b)
    assert np.std(a, axis=0) == pytest.approx([0.003, 0.003], rel=0.05)
    assert not np.array_equal(a, scanner.run(V, seed=5))


def test_bad_axes_and_couplings_are_refused():
    with pytest.raises(InvalidParameterError, match="'hysteresis'"):
        ScannerAxis("duhem")
    with pytest.raises(InvalidParameterError, match="unit diagonal"):
        Scanner((ScannerAxis("kp"), ScannerAxis("kp")), [[1.0, 0.1], [0.1, 0.9]])
    with pytest.raises(InvalidParameterError, match="2 or 3"):
        raster_scanner(4)
