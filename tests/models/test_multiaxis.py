"""The multi-axis model x = M [H_1(v_1) .. H_N(v_N)]: what is identifiable, and its inverse."""

from __future__ import annotations

import functools
import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import hystcomp
from hystcomp.errors import IdentificationError, InvalidParameterError, InvalidSignalError
from hystcomp.identify.coupling import fit_coupling
from hystcomp.identify.multiaxis_excitation import multiaxis_sequence
from hystcomp.io.models import model_from_dict, model_text
from hystcomp.models.multiaxis import MultiAxisModel
from hystcomp.plant import Twin
from tests.conftest import examples, mpi_models, pi_models, random_walk

M_TRUE = np.array([[1.0, 0.05, -0.02], [-0.03, 1.0, 0.04], [0.06, 0.02, 1.0]])


@functools.cache
def _fitted_pi():
    """A PI model of the twin, fitted as the package fits: its thresholds are those a fit
    over 0..120 V takes, so stages built on them are exactly PI-identifiable."""
    _, v = multiaxis_sequence(1, sample_rate=500.0)
    return hystcomp.PrandtlIshlinskii(n_operators=8).fit(v[:, 0], Twin().hysteresis(v[:, 0]))


def _pi(rng):
    """A PI axis: the twin's fitted weights, each scaled by a random factor (all positive
    beyond the first, as the physical constraints keep them)."""
    base = _fitted_pi()
    return hystcomp.PrandtlIshlinskii.from_parameters(
        thresholds=base.thresholds_,
        weights=base.weights_ * rng.uniform(0.7, 1.3, base.weights_.size),
        voltage_range=(0.0, 120.0),
    )


def _known_stage(rng, n_axes=3):
    axes = [_pi(rng) for _ in range(n_axes)]
    return MultiAxisModel.from_parameters(axes=axes, coupling=M_TRUE[:n_axes, :n_axes])


@pytest.fixture(scope="module")
def record():
    """A noiseless record of a 3-axis PI stage: multiaxis_sequence at 500 Hz."""
    rng = np.random.default_rng(3)
    stage = _known_stage(rng)
    _, V = multiaxis_sequence(3, sample_rate=500.0)
    return stage, V, stage.simulate(V)


def test_the_coupling_of_a_known_stage_is_recovered(record):
    _stage, V, X = record
    found = fit_coupling(V, X)
    assert np.allclose(found.matrix, M_TRUE, atol=2e-3)
    assert np.allclose(found.decoupling @ found.matrix, np.eye(3), atol=1e-12)
    assert np.all(found.shared_r2 < 0.5)  # the excitation moves the axes independently


def test_fit_identifies_each_axis_on_the_decoupled_displacements(record):
    stage, V, X = record
    model = MultiAxisModel(family="pi").fit(V, X)
    assert np.allclose(model.coupling_, M_TRUE, atol=2e-3)
    assert model.fit_report_["kinds"] == ["pi", "pi", "pi"]
    span = X.max(0) - X.min(0)
    assert np.all(np.array(model.fit_report_["rms_error_um"]) < 2e-3 * span)
    # its compensator inverts the stage: the stage driven by it follows the reference
    rng = np.random.default_rng(4)
    reach = np.array(model.reachable_range())
    H = np.column_stack([random_walk(rng, 3000, 0.2 * hi, 0.8 * hi, 0.01 * hi) for _, hi in reach])
    X_ref = H @ M_TRUE.T
    v = model.inverse().simulate(X_ref)
    assert np.abs(stage.simulate(v) - X_ref).max() < 0.01 * span.max()


def test_ignoring_the_coupling_keeps_m_the_identity(record):
    _, V, X = record
    model = MultiAxisModel(family="pi", coupling=False).fit(V, X)
    assert np.array_equal(model.coupling_, np.eye(3))


def test_axes_that_move_together_are_refused():
    rng = np.random.default_rng(5)
    stage = _known_stage(rng, 2)
    v = random_walk(rng, 4000, 0.0, 120.0, 3.0)
    V = np.column_stack([v, 0.5 * v + 30.0])  # one waveform on both axes
    with pytest.raises(IdentificationError, match="Axes 1 and 2 move together"):
        MultiAxisModel(family="pi").fit(V, stage.simulate(V))


def test_a_constant_axis_is_refused():
    V = np.column_stack([np.linspace(0, 120, 200), np.full(200, 10.0)])
    with pytest.raises(InvalidSignalError, match="axis 2 is constant"):
        MultiAxisModel(family="pi").fit(V, V)


def test_inverse_after_forward_is_the_identity_and_step_equals_batch():
    rng = np.random.default_rng(6)
    stage = _known_stage(rng)
    V = np.column_stack([random_walk(rng, 2000, 0.0, 120.0, 4.0) for _ in range(3)])
    X = stage.simulate(V)
    comp = stage.inverse()
    assert np.allclose(comp.simulate(X), V, atol=1e-9)
    stepper = comp.stepper()
    stepped = np.array([stepper.step(row) for row in X])
    assert np.array_equal(stepped, comp.simulate(X))  # bit for bit
    forward = stage.stepper()
    assert np.array_equal(np.array([forward.step(row) for row in V]), X)


def test_each_axis_is_clamped_to_its_own_range_and_counted():
    rng = np.random.default_rng(7)
    a, b = _pi(rng), _pi(rng)
    stage = MultiAxisModel.from_parameters(axes=[a, b], coupling=[[1, 0.03], [0.02, 1]])
    comp = stage.inverse(voltage_range=[(0.0, 120.0), (10.0, 90.0)])
    x_hi = stage.simulate([[120.0, 0.0]])[0, 0]
    X = np.column_stack([np.linspace(0, 1.5 * x_hi, 500), np.linspace(1.0, 2.0, 500)])
    run = comp.run(X)
    assert run.v[:, 0].max() == 120.0
    assert run.v[:, 1].min() >= 10.0
    assert run.v[:, 1].max() <= 90.0
    assert run.clamped[0] > 100
    assert run.clamped[1] > 0


def test_a_non_finite_reference_holds_the_axes_it_reaches():
    rng = np.random.default_rng(8)
    stage = _known_stage(rng, 2)
    s = stage.inverse().stepper()
    first = s.step([3.0, 2.0])
    held = s.step([np.nan, 2.0])
    assert np.array_equal(held, first)  # M^-1 mixes the NaN into both axes: both hold
    assert s.nonfinite_count == (1, 1)


def test_stepper_state_is_public_and_copies_are_independent():
    rng = np.random.default_rng(9)
    s = _known_stage(rng, 2).inverse().stepper()
    s.step([5.0, 5.0])
    saved = s.state
    twin = s.copy()
    a = s.step([1.0, 2.0])
    s.state = saved
    assert np.array_equal(s.step([1.0, 2.0]), a)
    assert np.array_equal(twin.step([1.0, 2.0]), a)


def test_the_model_file_holds_the_axes_and_m():
    rng = np.random.default_rng(10)
    stage = MultiAxisModel.from_parameters(
        axes=[_pi(rng), hystcomp.presets.paper_mpi(), hystcomp.presets.paper_preisach()],
        coupling=M_TRUE,
    )
    doc = json.loads(model_text(stage))
    assert doc["kind"] == "multiaxis"
    assert len(doc["axes"]) == 3
    assert [a["kind"] for a in doc["axes"]] == ["pi", "mpi", "preisach"]
    again = model_from_dict(doc)
    V = np.column_stack([np.linspace(0, 100, 50)] * 3)
    assert np.array_equal(again.simulate(V), stage.simulate(V))


@pytest.mark.parametrize(
    ("coupling", "match"),
    [([[1, 0.1], [0.1, 2]], "unit diagonal"), ([[1, 1], [1, 1]], "singular"), ([[1]], "2 x 2")],
)
def test_bad_coupling_matrices_are_refused(coupling, match):
    rng = np.random.default_rng(11)
    with pytest.raises(InvalidParameterError, match=match):
        MultiAxisModel.from_parameters(axes=[_pi(rng), _pi(rng)], coupling=coupling)


def test_to_control_has_n_inputs_and_outputs():
    control = pytest.importorskip("control")
    rng = np.random.default_rng(12)
    stage = _known_stage(rng, 2)
    V = np.column_stack([random_walk(rng, 60, 0.0, 120.0, 5.0) for _ in range(2)])
    sys = hystcomp.to_control(stage.inverse(), 5e-5)
    assert sys.ninputs == 2
    assert sys.noutputs == 2
    X = stage.simulate(V)
    res = control.input_output_response(sys, 5e-5 * np.arange(60), X.T, X0=sys.x0)
    assert np.allclose(res.outputs.T, stage.inverse().simulate(X), rtol=0, atol=1e-12)


@settings(max_examples=examples(0.5))
@given(
    first=mpi_models(),
    second=pi_models(),
    coupling=st.lists(st.floats(-0.08, 0.08), min_size=2, max_size=2),
)
def test_property_inverse_after_forward_is_the_identity(first, second, coupling):
    """Random MPI and PI axes, random couplings up to 8 %: the compensator recovers any
    voltage inside the ranges from the displacements it produced."""
    (a, rng), (b, _) = first, second
    stage = MultiAxisModel.from_parameters(
        axes=[a, b], coupling=[[1.0, coupling[0]], [coupling[1], 1.0]]
    )
    V = np.column_stack(
        [random_walk(rng, 300, *m.voltage_range_, 0.05 * np.ptp(m.voltage_range_)) for m in (a, b)]
    )
    X = stage.simulate(V)
    back = stage.inverse().simulate(X)
    span = np.array([np.ptp(m.voltage_range_) for m in (a, b)])
    assert np.all(np.abs(back - V) <= 1e-6 * span)
