"""The compensation, simulation and any-kind identification workflows, and their warnings as data."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from hystcomp import presets
from hystcomp._notice import Notice, worded
from hystcomp.errors import InvalidParameterError, InvalidSignalError, ModelFileError
from hystcomp.io.records import Record
from hystcomp.models.dynamics import LinearDynamics
from hystcomp.workflows.compensate import (
    compensate_reference,
    inverse_for,
    own_turns,
    refuse_dynamics_as_model,
)
from hystcomp.workflows.identify import build_estimator, identify_record
from hystcomp.workflows.record import identify_model
from hystcomp.workflows.simulate import simulate_voltage

CLI = {"strict": "Nothing written (--strict)", "drop_strict": "drop --strict"}


def test_a_notice_is_its_sentence_and_keeps_its_remedies_as_data():
    note = Notice("try {model}, or {transient} {n}.", kind="line", others="mpi", n=3)
    assert note == "try the model mpi, or the 'transient' argument 3."
    assert note.worded({"model": "--model {others}", "transient": "--transient"}) == (
        "try --model mpi, or --transient 3."
    )
    assert worded("plain text", {"model": "x"}) == "plain text"
    again = pickle.loads(pickle.dumps(note))  # joblib's workers hand results back pickled
    assert (again, again.kind, again.template) == (note, "line", note.template)


def test_identify_record_fits_a_copy_of_the_estimator_given():
    t = np.arange(3000) / 1000.0
    v = 60.0 - 40.0 * np.cos(2 * np.pi * t) - 20.0 * np.cos(6 * np.pi * t)
    rec = Record(t, v, presets.paper_mpi().simulate(v), source="loops")
    estimator = build_estimator("mpi", operators=6, deadzones=6)
    before = estimator.get_params()
    result = identify_record(rec, estimator, transient=0.5)
    assert estimator.get_params() == before  # the transient was not written into it
    assert not hasattr(estimator, "weights_")  # nor was it fitted
    assert result.model is not estimator
    assert result.model.get_params()["transient"] == 500


def _far_reference():
    t = np.arange(400) / 1000.0
    return t, np.full(t.size, 1e3)  # far beyond what the model reaches


def test_a_clamped_reference_is_a_warning_or_with_strict_an_error():
    model = presets.paper_pi()
    t, x = _far_reference()
    result = compensate_reference(model, t, x, source="m.json")
    assert result.clamped == x.size
    assert result.warnings[0].startswith(f"{x.size} of {x.size} samples (100 %) are out of reach")
    with pytest.raises(InvalidSignalError, match=r"refused \(strict=True\)") as caught:
        compensate_reference(model, t, x, source="m.json", strict=True)
    said = worded(caught.value.args[0], CLI)  # the command line words its options
    assert "Nothing written (--strict); shift or scale the reference into" in said
    assert said.endswith("or drop --strict to accept the clamp.")


def test_the_inverse_refuses_what_the_model_cannot_take():
    with pytest.raises(InvalidParameterError, match="applies to Preisach models only"):
        inverse_for(presets.paper_pi(), method="exact")
    dynamics = LinearDynamics.from_parameters(
        sample_rate=1000.0,
        resonance_hz=100.0,
        damping_ratio=0.1,
        creep_time_constants=[0.1],
        creep_weights=[0.01],
    )
    with pytest.raises(ModelFileError, match="holds linear dynamics, not a hysteresis"):
        refuse_dynamics_as_model(dynamics, "dyn.json")
    assert inverse_for(presets.paper_pi()).voltage_range == (0.0, 120.0)


def test_own_turns_finds_a_voltage_that_turns_where_the_reference_does_not():
    x = np.linspace(0.0, 10.0, 50)
    v = np.linspace(0.0, 100.0, 50)
    assert own_turns(v, x, 120.0) is None
    v[20] += 10.0  # a spike: the voltage turns back twice (at 20 and 21), the reference never
    step = 100.0 / 49.0
    count, size, k = own_turns(v, x, 120.0)
    assert (count, k) == (2, 20)
    assert size == pytest.approx(10.0 - step)  # the smaller of its steps in and out


def test_simulate_warns_outside_the_models_range_and_validates_against_a_record():
    model = presets.paper_pi()
    t = np.arange(1000) / 1000.0
    v = 60.0 - 60.0 * np.cos(2 * np.pi * t)
    measured = presets.paper_mpi().simulate(v)
    result = simulate_voltage(model, t, v, measured=measured, data="rec.csv")
    np.testing.assert_array_equal(result.x, model.simulate(v))
    assert result.warnings == []
    assert result.lines[0].startswith("  against the measured x of rec.csv")
    beyond = simulate_voltage(model, t, 1.5 * v)
    assert beyond.warnings[0].startswith("the input (0 .. 180 V) leaves the model's voltage range")


def test_identify_model_refuses_a_holdout_with_a_dynamics_record():
    t = np.arange(100) / 100.0
    rec = Record(t, t, t, source="r")
    with pytest.raises(InvalidParameterError, match=r"'holdout' .* does not apply with a dynamics"):
        identify_model(rec, "pi", dynamics_record=rec, holdout=0.2)
