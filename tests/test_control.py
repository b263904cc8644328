"""hystcomp.to_control: models and compensators as python-control systems."""

from __future__ import annotations

import builtins

import control
import numpy as np
import pytest

import hystcomp
from hystcomp import presets
from hystcomp.control import DiscreteSystem, register
from hystcomp.errors import InvalidParameterError, InvalidTypeError
from hystcomp.models.hammerstein import HammersteinModel

DT = 5e-5


def _signal(n=400, seed=0):
    rng = np.random.default_rng(seed)
    return np.clip(np.cumsum(rng.normal(0.0, 4.0, n)) + 60.0, -5.0, 125.0)


def _response(sys, u):
    t = DT * np.arange(u.size)
    return control.input_output_response(sys, t, u, X0=sys.x0).outputs


@pytest.mark.parametrize(
    "make",
    [presets.paper_mpi, presets.paper_pi, presets.paper_preisach],
    ids=["mpi", "pi", "preisach"],
)
def test_model_and_compensator_responses_equal_simulate(make):
    model = make()
    v = _signal()
    sys = hystcomp.to_control(model, DT)
    assert sys.isdtime(strict=True)
    assert sys.dt == DT
    assert sys.input_labels == ["v"]
    assert sys.output_labels == ["x"]
    np.testing.assert_allclose(_response(sys, v), model.simulate(v), rtol=0, atol=1e-12)

    comp = model.inverse()
    x_ref = model.simulate(v) * 0.9
    csys = hystcomp.to_control(comp, DT)
    assert (csys.input_labels, csys.output_labels) == (["x_ref"], ["v"])
    np.testing.assert_allclose(_response(csys, x_ref), comp.simulate(x_ref), rtol=0, atol=1e-12)


def test_compensator_and_model_connect_by_signal_name():
    model = presets.paper_mpi()
    comp = model.inverse()
    series = control.interconnect(
        [hystcomp.to_control(comp, DT, name="ff"), hystcomp.to_control(model, DT, name="h")],
        inplist=["x_ref"],
        outlist=["x"],
    )
    x_ref = np.abs(np.sin(np.linspace(0.0, 6.0, 300))) * 30.0
    x0 = np.concatenate([hystcomp.to_control(comp, DT).x0, hystcomp.to_control(model, DT).x0])
    out = control.input_output_response(series, DT * np.arange(x_ref.size), x_ref, X0=x0)
    expected = model.simulate(comp.simulate(x_ref))
    np.testing.assert_allclose(out.outputs, expected, rtol=0, atol=1e-12)
    assert np.abs(expected - x_ref)[:100].max() < 1e-9  # the inverse of itself, on the rise


def test_signal_names_can_be_changed_and_the_object_is_not():
    model = presets.paper_pi()
    sys = hystcomp.to_control(model, DT, inputs="u", outputs="y", name="pi")
    assert (sys.name, sys.input_labels, sys.output_labels) == ("pi", ["u"], ["y"])
    v = _signal(50)
    before = model.simulate(v)
    _response(sys, v)
    np.testing.assert_array_equal(model.simulate(v), before)


def test_bad_arguments_are_named():
    with pytest.raises(InvalidTypeError, match="'obj' parameter of to_control"):
        hystcomp.to_control(np.zeros(3), DT)
    with pytest.raises(InvalidParameterError, match="'dt' parameter of to_control"):
        hystcomp.to_control(presets.paper_pi(), 0.0)


def test_missing_python_control_names_the_extra(monkeypatch):
    real_import = builtins.__import__

    def no_control(name, *args, **kwargs):
        if name == "control":
            raise ImportError("No module named 'control'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_control)
    with pytest.raises(ImportError, match=r"hystcomp\[control\]"):
        hystcomp.to_control(presets.paper_pi(), DT)


def test_a_new_kind_plugs_in_with_one_function(monkeypatch):
    class Gain:  # a stand-in for another kind of system: y = 2 u, one state holding u
        pass

    monkeypatch.setattr("hystcomp.control._ADAPTERS", [])

    @register(Gain)
    def _gain(obj, dt):
        return DiscreteSystem(
            state=np.zeros(1),
            update=lambda s, u: np.array([float(u[0])]),
            output=lambda s, u: 2.0 * float(u[0]),
            inputs=("v",),
            outputs=("x",),
        )

    sys = hystcomp.to_control(Gain(), DT)
    np.testing.assert_array_equal(_response(sys, np.array([1.0, 2.0, 3.0])), [2.0, 4.0, 6.0])


def test_the_twin_as_a_system_equals_twin_run_noise_included():
    from hystcomp.plant import Twin

    v = _signal(3000, seed=4)
    sys = hystcomp.to_control(Twin(seed=5), DT)
    np.testing.assert_allclose(_response(sys, v), Twin(seed=5).run(v), rtol=0, atol=1e-12)
    with pytest.raises(InvalidParameterError, match="twin's sample time"):
        hystcomp.to_control(Twin(), 1e-3)


def _dynamics(**changes):
    from hystcomp.models.dynamics import LinearDynamics

    return LinearDynamics.from_parameters(
        sample_rate=20_000.0,
        resonance_hz=780.0,
        damping_ratio=0.05,
        creep_time_constants=[0.01, 0.3],
        creep_weights=[0.02, 0.01],
        **changes,
    )


@pytest.mark.parametrize(
    "changes",
    [
        {},
        {"delay_samples": 3},
        {"delay_samples": -1},
        {"second_resonance_hz": 2100.0, "second_damping_ratio": 0.03, "second_mode_gain": 0.1},
        {
            "second_resonance_hz": 2100.0,
            "second_damping_ratio": 0.03,
            "second_mode_gain": 0.1,
            "delay_samples": 2,
        },
    ],
    ids=["one mode", "latency", "early", "two modes", "two modes, latency"],
)
def test_linear_dynamics_as_a_system_equals_its_simulate(changes):
    dyn = _dynamics(**changes)
    rng = np.random.default_rng(3)
    v = np.cumsum(rng.normal(0.0, 0.5, 3000))
    response = _response(hystcomp.to_control(dyn, DT), v)
    expected = dyn.simulate(v, initial=0.0)
    np.testing.assert_allclose(response, expected, rtol=0, atol=1e-9 * np.ptp(v))
    with pytest.raises(InvalidParameterError, match="dynamics model's sample time"):
        hystcomp.to_control(dyn, 1e-3)


def test_compensator_with_dynamics_as_a_system_equals_its_stepper():
    model = presets.paper_mpi()
    comp = HammersteinModel(model, _dynamics()).inverse()
    x_ref = 10.0 + 8.0 * np.sin(np.linspace(0.0, 12.0, 2000))
    response = _response(hystcomp.to_control(comp, DT), x_ref)
    np.testing.assert_array_equal(response, comp.stepper().step_block(x_ref))
    lo, hi = comp.voltage_range
    assert lo <= response.min()
    assert response.max() <= hi


def test_systems_and_states_are_named_after_what_they_are():
    from hystcomp.plant import Twin

    model = presets.paper_mpi()
    sys = hystcomp.to_control(model, DT)
    csys = hystcomp.to_control(model.inverse(), DT)
    assert (sys.name, csys.name) == ("mpi", "inverse_mpi")
    for system in (sys, csys):
        labels = system.state_labels
        assert labels[:3] == ["last_output", "held_count", "clamped_count"]
        assert "play[0]" in labels
        assert not [s for s in labels if s.startswith("x")]  # nothing reads as the output x
    # the state named last_output holds the last output
    out = control.input_output_response(sys, DT * np.arange(3), [0.0, 60.0, 90.0], X0=sys.x0)
    assert out.states[sys.state_labels.index("last_output"), -1] == pytest.approx(
        model.simulate([0.0, 60.0])[-1]
    )
    pre = hystcomp.to_control(presets.paper_preisach(), DT)
    assert pre.name == "preisach"
    assert pre.state_labels[0] == "stack_top"
    assert pre.state_labels.count("extremum[0]") == 1
    assert sum(s.startswith("extremum[") for s in pre.state_labels) == sum(
        s.startswith("prefix_sum[") for s in pre.state_labels
    )
    twin = hystcomp.to_control(Twin(), DT)
    assert twin.name == "twin"
    assert twin.state_labels[:4] == ["input", "bouc_wen", "position", "velocity"]
    dyn = hystcomp.to_control(_dynamics(), DT)
    assert dyn.name == "dynamics"
    assert dyn.state_labels[:2] == ["creep[0]", "creep[1]"]
    dcomp = hystcomp.to_control(HammersteinModel(model, _dynamics()).inverse(), DT)
    assert dcomp.name == "inverse_dynamics_mpi"
    # a compensator and its model interconnect without a renaming (and so without a warning)
    series = control.interconnect([csys, sys], inplist=["x_ref"], outlist=["x"])
    assert "inverse_mpi_play[0]" in series.state_labels or "inverse_mpi.play[0]" in (
        series.state_labels
    )
