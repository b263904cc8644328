"""The hyperparameter constraints: declared once per estimator, checked in one place, with
messages that name the argument, its owner, what it must be and what it was."""

import numpy as np
import pytest

import hystcomp
from hystcomp._hyperparameters import (
    MAX_OPERATORS,
    OPERATOR_COUNT,
    Integer,
    Nullable,
    Options,
    validate_parameters,
)
from hystcomp.errors import InvalidParameterError, InvalidTypeError
from hystcomp.models.estimator import Estimator
from hystcomp.models.multiaxis import MultiAxisModel

ESTIMATORS = [
    hystcomp.PrandtlIshlinskii,
    hystcomp.ModifiedPrandtlIshlinskii,
    hystcomp.Preisach,
    MultiAxisModel,
]


@pytest.mark.parametrize("cls", ESTIMATORS)
def test_every_hyperparameter_has_one_constraint(cls):
    assert list(cls._parameter_constraints) != []
    assert set(cls._parameter_constraints) == set(cls._get_param_names())
    cls()._check_hyperparameters()  # the defaults keep them


def test_an_estimator_without_a_constraint_for_a_hyperparameter_is_refused_when_made():
    with pytest.raises(TypeError, match=r"missing \['size'\]"):

        class Undeclared(Estimator):
            def __init__(self, *, size=1):
                self.size = size


@pytest.mark.parametrize(
    ("cls", "params", "error", "message"),
    [
        (hystcomp.PrandtlIshlinskii, {"n_operators": 0}, InvalidParameterError, r"int >= 1"),
        (hystcomp.PrandtlIshlinskii, {"n_operators": 2.0}, InvalidTypeError, r"of type float"),
        (hystcomp.PrandtlIshlinskii, {"transient": -1}, InvalidParameterError, r"'transient'"),
        (hystcomp.PrandtlIshlinskii, {"margin": 1.5}, InvalidParameterError, r"below 1 \("),
        (hystcomp.PrandtlIshlinskii, {"voltage_range": (5, 1)}, InvalidParameterError, "low <"),
        (hystcomp.ModifiedPrandtlIshlinskii, {"n_deadzones": True}, InvalidTypeError, "bool"),
        (hystcomp.ModifiedPrandtlIshlinskii, {"regularization": -1}, InvalidParameterError, ">= 0"),
        (hystcomp.Preisach, {"grid_size": 401}, InvalidParameterError, r"in 2\.\.400"),
        (hystcomp.Preisach, {"zero_diagonal": "yes"}, InvalidTypeError, "True or False"),
        (hystcomp.Preisach, {"fit_method": "lsq"}, InvalidParameterError, "'least-squares'"),
        (MultiAxisModel, {"n_jobs": 0}, InvalidParameterError, "None, -1 or an int >= 1"),
        (MultiAxisModel, {"family": 3}, InvalidParameterError, "unfitted estimator such as"),
        (MultiAxisModel, {"family": "pl"}, InvalidParameterError, r"Got 'pl' instead"),
        (MultiAxisModel, {"coupling": 1}, InvalidTypeError, "True or False"),
    ],
)
def test_a_broken_constraint_names_the_argument_and_its_owner(cls, params, error, message):
    name = next(iter(params))
    with pytest.raises(error, match=message) as info:
        cls(**params)._check_hyperparameters()
    assert f"The {name!r} parameter of {cls.__name__} must be" in str(info.value)


def test_checked_values_are_converted_and_the_attributes_stay_as_given():
    est = hystcomp.PrandtlIshlinskii(n_operators=np.int64(8), voltage_range=[0, 100])
    params = est._check_hyperparameters()
    assert type(params["n_operators"]) is int
    assert params["voltage_range"] == (0.0, 100.0)
    assert est.voltage_range == [0, 100]  # stored unchanged, as scikit-learn does


def test_a_fit_bounds_the_operator_count_and_a_model_file_does_not():
    with pytest.raises(InvalidParameterError, match=f"at most {MAX_OPERATORS}: the fit"):
        OPERATOR_COUNT.check(MAX_OPERATORS + 1, "n_operators", "fit_pi", True)
    assert OPERATOR_COUNT.check(MAX_OPERATORS + 1, "n_operators", "from_dict", False) == 257


def test_validate_parameters_checks_in_the_declared_order():
    constraints = {"a": Integer(0), "b": Nullable(Options(("x", "y")))}
    assert validate_parameters(constraints, {"a": 1, "b": None, "c": "other"}, "f") == {
        "a": 1,
        "b": None,
    }
    with pytest.raises(InvalidParameterError, match=r"'a' parameter of f must be an int >= 0"):
        validate_parameters(constraints, {"a": -1, "b": "z"}, "f")
    with pytest.raises(InvalidParameterError, match=r"'b' parameter of f must be one of 'x'"):
        validate_parameters(constraints, {"a": 0, "b": "z"}, "f")
