"""The simulated stages of the benchmarks (benchmarks/panel.py, benchmarks/dynamics_panel.py).

Properties that a wrong stage would break: the hysteresis each docstring gives, the rate
(in)dependence of the quasi-static parts, the linear parts' steady-state gain, resonance
and latency, ``true_dynamics()`` against ``linear()``, the amplifier's rails.
"""

from __future__ import annotations

import numpy as np
import pytest
from benchmarks import dynamics_panel as dp
from benchmarks import panel

from hystcomp.experiment.metrics import hysteresis_percent

#: Hysteresis (%) on the full-range loop, as the module docstrings give it.
HYSTERESIS = {
    "twin": 11.0,
    "boucwen": 13.0,
    "duhem": 17.0,
    "preisach": 17.0,
    "kp": 13.0,
    "maxwell": 14.0,
    "narrow": 14.0,
    "ratedep": 14.0,
    "jiles": 12.0,
}
#: Of each kind of the dynamics panel ("9 to 14 %", KP 9 %).
DYNAMICS_HYSTERESIS = {"narrow": (13.0, 14.0), "boucwen": (12.5, 13.5), "maxwell": (13.0, 14.0)}
DYNAMICS_HYSTERESIS["kp"] = (8.5, 9.5)
#: First mode (Hz, damping ratio, weight), creep (%), latency and exactness, as documented.
MODES = {
    "narrow400": (400.0, 0.2, 1.0, 5.0, 0, True),
    "boucwen630": (630.0, 0.12, 1.0, 3.0, 0, False),
    "maxwell900": (900.0, 0.07, 1.0, 2.0, 2, True),
    "narrow1200": (1200.0, 0.05, 0.92, 3.0, 0, True),
    "boucwen2000": (2000.0, 0.02, 1.0, 1.0, 1, True),
    "maxwell1500": (1500.0, 0.035, 1.0, 4.0, 0, True),
    "kp800": (800.0, 0.1, 1.0, 2.5, 1, False),
}
DYNAMICS = dp.DYNAMICS_STAGES + dp.DYNAMICS_HELD_OUT


def _triangles(lo, hi, frequency, sample_rate, periods=2):
    n = round(sample_rate / frequency)
    shape = 1.0 - np.abs(1.0 - 2.0 * np.arange(n) / n)
    return lo + (hi - lo) * np.r_[np.tile(shape, periods), 0.0], n


def _loop_percent(hysteresis, voltage_range, frequency, sample_rate):
    """Hysteresis % of the second period of full-range triangles at ``frequency``."""
    v, n = _triangles(*voltage_range, frequency, sample_rate)
    return hysteresis_percent(v[n:], hysteresis(v)[n:])[0]


def test_the_tuning_and_held_out_stages_are_apart():
    assert set(panel.ACTUATORS).isdisjoint(panel.HELD_OUT)
    assert set(panel.STAGES) == set(panel.SPECS)
    assert set(dp.DYNAMICS_STAGES).isdisjoint(dp.DYNAMICS_HELD_OUT)
    assert set(DYNAMICS) == set(dp.SPECS)
    assert len(dp.DYNAMICS_STAGES) >= 6


@pytest.mark.parametrize("name", panel.STAGES)
def test_hysteresis_of_each_stage_is_as_documented(name):
    """About 10 % (within a factor of two), within a point of the docstring's figure, and
    tens of µm of stroke, at the stage's own range and rate."""
    act = panel.actuator(name)
    percent = _loop_percent(act.hysteresis, act.voltage_range, 1.0, act.sample_rate)
    assert 5.0 <= percent <= 20.0
    assert percent == pytest.approx(HYSTERESIS[name], abs=1.0)
    x = act.hysteresis(np.array(act.voltage_range))
    assert 25.0 < x[1] - x[0] < 45.0


@pytest.mark.parametrize("kind", ["narrow", "boucwen", "maxwell", "kp"])
def test_hysteresis_of_each_dynamics_kind_is_as_documented(kind):
    name = next(n for n in DYNAMICS if dp.SPECS[n][0] == kind)
    st = dp.stage(name)
    percent = _loop_percent(st.hysteresis, st.voltage_range, 1.0, st.sample_rate)
    low, high = DYNAMICS_HYSTERESIS[kind]
    assert low <= percent <= high
    assert st.hysteresis(np.array([0.0]))[0] == 0.0  # at rest at 0 µm
    assert 30.0 < st.stroke < 40.0


@pytest.mark.parametrize("name", panel.STAGES)
def test_only_ratedep_widens_its_loop_with_rate(name):
    """50 Hz against 1 Hz triangles through the quasi-static part: ratedep's loop is 10 to
    20 % wider; every other stage's is the same within the sampling of its turning points."""
    act = panel.actuator(name)
    slow, fast = (
        _loop_percent(act.hysteresis, act.voltage_range, f, act.sample_rate) for f in (1.0, 50.0)
    )
    if name == "ratedep":
        assert 1.10 <= fast / slow <= 1.20
    else:
        assert fast / slow == pytest.approx(1.0, abs=0.03)


@pytest.mark.parametrize("kind", ["narrow", "boucwen", "maxwell", "kp"])
def test_the_dynamics_kinds_are_rate_independent(kind):
    st = dp.stage(next(n for n in DYNAMICS if dp.SPECS[n][0] == kind))
    slow, fast = (
        _loop_percent(st.hysteresis, st.voltage_range, f, st.sample_rate) for f in (1.0, 50.0)
    )
    assert fast / slow == pytest.approx(1.0, abs=0.03)


@pytest.mark.parametrize("name", panel.STAGES)
def test_accuracy_stages_clip_to_their_rails(name):
    act, again = panel.actuator(name, seed=3), panel.actuator(name, seed=3)
    lo, hi = act.voltage_range
    span = hi - lo
    v = np.r_[lo, np.linspace(lo - 0.3 * span, hi + 0.3 * span, 400), lo]
    clipped = np.clip(v, lo, hi)
    np.testing.assert_array_equal(act.hysteresis(v), act.hysteresis(clipped))
    np.testing.assert_array_equal(act.run(v), again.run(clipped))


@pytest.mark.parametrize("name", DYNAMICS)
def test_dynamics_stages_clip_to_their_rails(name):
    st, again = dp.stage(name, seed=3), dp.stage(name, seed=3)
    v = np.r_[0.0, np.linspace(-50.0, 170.0, 400), 0.0]
    np.testing.assert_array_equal(st.run(v), again.run(np.clip(v, 0.0, 120.0)))


@pytest.mark.parametrize("name", DYNAMICS)
def test_linear_part_has_unit_gain_and_its_documented_mode(name):
    """Unit gain at 0 Hz; the peak of the response at the first mode's ``fn sqrt(1 - 2
    zeta^2)``, of height ``weight (1 - creep) / (2 zeta sqrt(1 - zeta^2))``; and the
    response is that of ``linear()`` (a sinusoid through it, at the peak and at 200 Hz)."""
    hz, zeta, weight, creep, _, _ = MODES[name]
    part = dp.stage(name).linear_part
    assert abs(part.frequency_response([0.0])[0]) == pytest.approx(1.0, abs=1e-12)
    f = np.linspace(0.5 * hz, 1.5 * hz, 2001)
    gain = np.abs(part.frequency_response(f))
    assert f[np.argmax(gain)] == pytest.approx(hz * np.sqrt(1.0 - 2.0 * zeta**2), rel=0.01)
    peak = weight * (1.0 - creep / 100.0) / (2.0 * zeta * np.sqrt(1.0 - zeta**2))
    assert gain.max() == pytest.approx(peak, rel=0.03)
    fs = part.sample_rate
    t = np.arange(round(0.3 * fs)) / fs
    last = slice(round(0.2 * fs), None)  # 0.1 s, whole periods of both
    for frequency in (f[np.argmax(gain)], 200.0):
        u = np.sin(2.0 * np.pi * frequency * t)
        x = part.apply(u, rest=0.0)
        expected = part.frequency_response([frequency])[0] * np.exp(2j * np.pi * frequency * t)
        np.testing.assert_allclose(x[last], expected.imag[last], atol=0.01 * abs(expected[0]))


@pytest.mark.parametrize("name", DYNAMICS)
def test_linear_part_latency_and_creep(name):
    """The answer to a step starts ``1 + latency`` samples after it (the hold's sample, then
    the latency); 3 s later it has not yet crept all the way, and is within its creep of
    the end (or has, with time constants of 100 ms at most)."""
    _, _, _, creep, latency, _ = MODES[name]
    st = dp.stage(name)
    fs = st.sample_rate
    u = np.r_[np.zeros(10), np.ones(round(3.0 * fs))]
    x = st.linear(u)
    assert np.all(np.abs(x[: 11 + latency]) < 1e-12)  # a convolution's rounding at most
    assert x[11 + latency] > 1e-6
    end = np.mean(x[-200:])
    assert 1.0 - creep / 100.0 < end < 1.0 + 1e-12


@pytest.mark.parametrize("name", DYNAMICS)
def test_true_dynamics_is_linear_where_exact(name):
    """``true_dynamics()`` is the linear part exactly on stages with creep by lags (one mode
    or two in parallel); elsewhere an approximation (lags fitted to a continuum) with the
    stage's modes and latency. ``true_dynamics(1)``, the dominant mode alone, leaves a
    second mode out."""
    hz, zeta, weight, _, latency, exact = MODES[name]
    st = dp.stage(name)
    assert st.dynamics_exact == exact
    dyn = st.true_dynamics()
    assert (dyn.resonance_hz_, dyn.damping_ratio_, dyn.delay_samples_) == (hz, zeta, latency)
    assert dyn.modes[0][2] == pytest.approx(weight, abs=1e-15)
    u = 20.0 + np.cumsum(np.random.default_rng(0).normal(0.0, 0.5, 20_000))
    x = st.linear(u)
    error = np.max(np.abs(dyn.simulate(u) - x)) / np.ptp(u)
    if exact:
        assert error < 1e-12
    else:
        assert error < 1e-3  # lags fitted to the continuum: close, not exact
    dominant = np.max(np.abs(st.true_dynamics(1).simulate(u) - x)) / np.ptp(u)
    if weight < 1.0:
        assert dominant > 1e-3  # the second mode is left out
    else:
        assert dominant == error


def test_log_creep_is_a_continuum_of_lags():
    """:class:`LogCreep`'s step response is ``1 - R((k + 1) Ts)`` in the time domain, and its
    response at 0 Hz is 1; ``R`` falls as ``log t`` in the middle of its span."""
    creep = dp.LogCreep(0.03)
    fs = 1000.0
    step = creep.apply(np.ones(5000), fs)
    np.testing.assert_allclose(step, 1.0 - creep.remaining(np.arange(1, 5001) / fs), atol=1e-12)
    assert abs(creep.response(np.ones(1), fs)[0]) == pytest.approx(1.0, abs=1e-12)
    centre = np.sqrt(creep.tau_min * creep.tau_max)
    half_decades = creep.remaining(centre * np.array([10**-0.5, 1.0])) - creep.remaining(
        centre * np.array([1.0, 10**0.5])
    )
    assert half_decades[0] == pytest.approx(half_decades[1], rel=0.05)


def _maxwell_naive(f, stiffness, limits):
    """``x + sum k_i d_i = f`` in increments from rest, by bisection on each sample."""
    d, x, f_prev, out = -limits.copy(), 0.0, 0.0, []
    for fk in f:

        def excess(xn, d=d, x=x, df=fk - f_prev):
            return xn - x + np.sum(stiffness * (np.clip(d + xn - x, -limits, limits) - d)) - df

        lo, hi = x - 100.0, x + 100.0
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if excess(mid) > 0.0 else (mid, hi)
        xn = 0.5 * (lo + hi)
        d, x, f_prev = np.clip(d + xn - x, -limits, limits), xn, fk
        out.append(x)
    return np.array(out)


def test_maxwell_slip_kernel_matches_a_naive_solution(rng):
    limits = rng.uniform(0.1, 3.0, 12)
    stiffness = rng.uniform(0.05, 0.5, 12)
    f = np.r_[np.linspace(0.0, 10.0, 50), np.linspace(10.0, 3.0, 7), rng.uniform(0.0, 10.0, 40)]
    out = np.empty_like(f)
    panel._maxwell_run(f, stiffness, limits, out)
    np.testing.assert_allclose(out, _maxwell_naive(f, stiffness, limits), atol=1e-9)


@pytest.mark.parametrize("kind", panel.EXCITATIONS)
def test_records_are_scaled_to_the_stage(kind):
    """Every record starts at the low rail and spans the range: on the bipolar stage too."""
    act = panel.actuator("narrow")
    v = panel.excitation(kind, act.sample_rate, act.voltage_range)
    assert (v[0], v.min(), v.max()) == (-150.0, -150.0, 150.0)


def test_dynamics_references():
    """Triangles over 5..90 % of the stroke, the first period left out; a step from 10 % to
    60 %, scored from 20 ms after it."""
    st = dp.stage("maxwell900")
    refs = dp.references(st)
    assert tuple(refs) == dp.REFERENCES
    for name, periods in zip(dp.REFERENCES, dp.PERIODS.values(), strict=False):
        ref = refs[name]
        n = round(st.sample_rate / float(name.split()[0]))
        assert (ref.x_ref.min(), ref.x_ref.max()) == pytest.approx((1.55, 27.9))
        assert (ref.window.start, ref.window.stop, ref.x_ref.size) == (
            n,
            n * periods,
            1 + n * periods,
        )
    step = refs["step"]
    assert step.x_ref[0] == pytest.approx(3.1)
    assert step.x_ref[-1] == pytest.approx(18.6)
    assert step.window.start == round(0.52 * st.sample_rate)
    assert step.score(step.x_ref + 0.1) == pytest.approx(0.1)
