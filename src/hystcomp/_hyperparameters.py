"""Checks of the identification hyperparameters, shared by the estimators and the fits.

The estimators of :mod:`hystcomp.models` check their hyperparameters (in ``fit`` and when a
model file is read) and the fitting functions of :mod:`hystcomp.identify` check the same
options at their own boundary; both import the checks from here, a module below both, so
that the models need :mod:`hystcomp.identify` only to fit.
"""

from __future__ import annotations

import numpy as np

from hystcomp._validation import check_int, check_real
from hystcomp.errors import InvalidParameterError, InvalidTypeError

#: Default relative invertibility margin of the PI/MPI fits.
DEFAULT_MARGIN = 1e-3

#: The constraint sets of the fits: the default, and the paper's (eqs. 12/19 with the
#: partial sums of the play weights positive; eq. 5 fitted free).
CONSTRAINTS = ("physical", "paper")

#: Highest degree of the Everett polynomial (eq. 5 is degree 3).
MAX_DEGREE = 8

#: The representations of the Everett function X.
EVERETT_KINDS = ("polynomial", "table")

#: Most plays (or dead-zones) a PI/MPI fit takes. The fit's quadratic programme grows as the
#: cube of the count: 256 plays and 256 dead-zones take about 25 s, 1000 of each hours; a
#: piezo's hysteresis is modelled with 10 to 50 (the paper: 16).
MAX_OPERATORS = 256


def check_operator_count(value, name: str, owner: str) -> int:
    """A number of plays or dead-zones to fit: an int in 1 .. :data:`MAX_OPERATORS`."""
    count = check_int(value, name, owner)
    if count > MAX_OPERATORS:
        raise InvalidParameterError(
            f"The {name!r} parameter of {owner} must be at most {MAX_OPERATORS}: the fit "
            f"grows as the cube of it (256 take about 25 s), and 10 to 50 model a piezo "
            f"actuator well (the paper uses 16). Got {count}."
        )
    return count


def check_margin(margin, owner: str) -> float:
    """The relative invertibility margin, a number in (0, 1)."""
    margin = check_real(margin, "margin", owner, positive=True)
    if margin >= 1.0:
        raise InvalidParameterError(
            f"The 'margin' parameter of {owner} must be below 1 (a small fraction such as "
            f"{DEFAULT_MARGIN}). Got {margin!r} instead."
        )
    return margin


def check_constraints(constraints, owner: str) -> str:
    """The ``constraints`` option: ``"physical"`` or ``"paper"``."""
    if constraints not in CONSTRAINTS:
        raise InvalidParameterError(
            f"The 'constraints' parameter of {owner} must be one of {CONSTRAINTS} "
            f"('physical', the default: non-negative play weights beyond the first, and for a "
            f"Preisach model X(v, v) = 0; 'paper': only what the paper's fits keep, the "
            f"partial sums of the play weights positive). Got {constraints!r} instead."
        )
    return constraints


def check_regularization(regularization, owner: str) -> float:
    """The MPI regularisation weight, a number >= 0."""
    regularization = check_real(regularization, "regularization", owner)
    if regularization < 0:
        raise InvalidParameterError(
            f"The 'regularization' parameter of {owner} must be >= 0 (0: eq. 19 as printed; "
            f"try 1e-3 to 1e-1). Got {regularization!r} instead."
        )
    return regularization


def check_regularization_option(regularization, owner: str) -> str | float:
    """The MPI estimator's ``regularization``: ``"auto"`` or a number >= 0."""
    if isinstance(regularization, str):
        if regularization != "auto":
            raise InvalidParameterError(
                f"The 'regularization' parameter of {owner} must be 'auto' or a number "
                f">= 0 (0: eq. 19 as printed). Got {regularization!r} instead."
            )
        return regularization
    return check_regularization(regularization, owner)


def check_options(degree, everett, grid_size, zero_diagonal, owner):
    """Validate the fit options of a Preisach identification; returns ``(degree, grid_size)``."""
    degree = check_int(degree, "degree", owner)
    if not isinstance(zero_diagonal, bool | np.bool_):
        raise InvalidTypeError(
            f"The 'zero_diagonal' parameter of {owner} must be True or False. "
            f"Got {zero_diagonal!r} of type {type(zero_diagonal).__name__} instead."
        )
    if degree > MAX_DEGREE:
        raise InvalidParameterError(
            f"The 'degree' parameter of {owner} must be an int in 1..{MAX_DEGREE}. "
            f"Got {degree} instead; eq. (5) is degree 3."
        )
    if everett not in EVERETT_KINDS:
        raise InvalidParameterError(
            f"The 'everett' parameter of {owner} must be 'polynomial' (eq. 5) or 'table'. "
            f"Got {everett!r} instead."
        )
    grid_size = check_int(grid_size, "grid_size", owner, minimum=2)
    if grid_size > 400:
        raise InvalidParameterError(
            f"The 'grid_size' parameter of {owner} must be an int in 2..400. "
            f"Got {grid_size} instead."
        )
    return degree, grid_size
