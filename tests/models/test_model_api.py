"""The model API made explicit: what the base declares, and the one path by which the
learned attributes are set."""

import numpy as np
import pytest

from hystcomp import (
    LinearDynamics,
    ModifiedPrandtlIshlinskii,
    MultiAxisModel,
    PrandtlIshlinskii,
    Preisach,
    presets,
)
from hystcomp.identify.excitation import triangle_sequence
from hystcomp.models.base import HysteresisModel
from hystcomp.models.estimator import set_learned


def test_the_base_declares_what_every_forward_model_gives():
    assert {"fit", "inverse", "_packed"} <= HysteresisModel.__abstractmethods__
    for name in ("simulate", "stepper", "reachable_range", "score", "to_dict", "from_dict"):
        assert callable(getattr(HysteresisModel, name))
    for cls in (PrandtlIshlinskii, ModifiedPrandtlIshlinskii, Preisach):
        assert not cls.__abstractmethods__  # each gives them all


def test_a_model_without_an_inverse_cannot_be_made():
    class NoInverse(HysteresisModel):
        kind = "none"
        _learned = ("weights",)

        def __init__(self, *, voltage_range=None):
            self.voltage_range = voltage_range

        def fit(self, v, x):
            return self

        def _packed(self):
            return np.zeros(1)

    with pytest.raises(TypeError, match="abstract"):
        NoInverse()


def _arrays(model, names):
    return [getattr(model, name + "_") for name in names]


@pytest.mark.parametrize(
    "make",
    [
        lambda w: PrandtlIshlinskii.from_parameters(thresholds=[0.0, 10.0], weights=w),
        lambda w: ModifiedPrandtlIshlinskii.from_parameters(
            thresholds=[0.0, 10.0],
            weights=w,
            deadzone_thresholds=[0.0, 4.0],
            deadzone_weights=[1.0, -0.5],
        ),
        lambda w: Preisach.from_parameters(theta=[-0.1, w[0], 0.001, -0.002, w[1]]),
    ],
)
def test_learned_arrays_are_the_models_own_and_read_only(make):
    given = np.array([0.2, 0.001])
    model = make(given)
    before = model.simulate([0.0, 50.0, 20.0])
    given[:] = 7.0  # the caller's array changes; the model does not
    np.testing.assert_array_equal(model.simulate([0.0, 50.0, 20.0]), before)
    arrays = [a for a in _arrays(model, model._learned) if isinstance(a, np.ndarray)]
    assert arrays
    assert not any(a.flags.writeable for a in arrays)


def test_a_fit_sets_the_learned_attributes_through_the_same_path():
    _, v = triangle_sequence([60.0, 120.0], sample_rate=500)
    model = PrandtlIshlinskii(n_operators=4).fit(v, presets.paper_pi().simulate(v))
    for name in model._learned:
        value = getattr(model, name + "_")
        if isinstance(value, np.ndarray):
            assert not value.flags.writeable
    multi = MultiAxisModel.from_parameters(axes=[model, model])
    assert not multi.decoupling_.flags.writeable  # derived, set with the others


def test_set_learned_takes_exactly_the_learned_names():
    dyn = LinearDynamics()
    with pytest.raises(TypeError, match="learned attributes of LinearDynamics"):
        set_learned(dyn, dyn._learned, sample_rate=20_000.0)
