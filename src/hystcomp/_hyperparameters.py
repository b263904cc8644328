"""Hyperparameter constraints, declared once as data and checked in one place.

As scikit-learn's ``_parameter_constraints`` (without importing it): every estimator of
:mod:`hystcomp.models` declares, in its class attribute ``_parameter_constraints``, one
:class:`Constraint` per hyperparameter, and :func:`validate_parameters` checks them all (in
``fit`` and when a model file is read). The fitting functions of :mod:`hystcomp.identify`
that take the same options declare theirs beside them, as a dictionary of the same
constraints, and check their arguments with one call of :func:`validate_parameters`. A message names the argument, its owner,
what it must be and what was given, so that no check is written by hand twice and no caller
threads its own name through the checks.

This module sits below both :mod:`hystcomp.models` and :mod:`hystcomp.identify`, so that the
models need :mod:`hystcomp.identify` only to fit.
"""

from __future__ import annotations

import numbers
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from hystcomp._validation import check_range, check_real
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


class Constraint(ABC):
    """What one hyperparameter's value must be."""

    @abstractmethod
    def check(self, value: Any, name: str, owner: str, fitting: bool) -> Any:
        """Return ``value`` (converted where the constraint says so), or raise a message
        that names ``name``, ``owner``, what the value must be and what it was.

        ``fitting`` is True when the value is about to be used by a fit, which may bound
        it more tightly than a model built from its parameters (see :class:`Integer`).
        """


@dataclass(frozen=True)
class Integer(Constraint):
    """An int (not a bool) in ``minimum .. maximum``, optionally not 0.

    ``fit_maximum`` bounds it for a fit only, with ``fit_reason`` saying why: a model read
    from a file or built from its parameters may hold more operators than a fit takes.
    ``wording`` replaces the description of the allowed values in the messages.
    """

    minimum: int | None = 1
    maximum: int | None = None
    nonzero: bool = False
    fit_maximum: int | None = None
    fit_reason: str = ""
    hint: str = ""
    wording: str | None = None

    def _what(self, number: int | None = None) -> str:
        """The allowed values, worded for ``number`` (the bound it breaks, if any)."""
        if self.wording is not None:
            return self.wording
        above = number is not None and self.maximum is not None and number > self.maximum
        if self.minimum is not None and self.maximum is not None and above:
            return f"an int in {self.minimum}..{self.maximum}"
        if self.minimum is not None:
            return f"an int >= {self.minimum}"
        if self.maximum is not None:
            return f"an int <= {self.maximum}"
        return "a non-zero int" if self.nonzero else "an int"

    def check(self, value, name, owner, fitting):
        if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Integral):
            raise InvalidTypeError(
                f"The {name!r} parameter of {owner} must be {self._what()}. Got {value!r} of "
                f"type {type(value).__name__} instead."
            )
        number = int(value)
        if (
            (self.minimum is not None and number < self.minimum)
            or (self.maximum is not None and number > self.maximum)
            or (self.nonzero and number == 0)
        ):
            raise InvalidParameterError(
                f"The {name!r} parameter of {owner} must be {self._what(number)}. Got "
                f"{value!r} instead{self.hint}."
            )
        if fitting and self.fit_maximum is not None and number > self.fit_maximum:
            raise InvalidParameterError(
                f"The {name!r} parameter of {owner} must be at most {self.fit_maximum}"
                f"{self.fit_reason}. Got {number}."
            )
        return number


@dataclass(frozen=True)
class Real(Constraint):
    """A finite real number (not a bool): ``> 0`` if ``positive``, ``>= minimum``, ``< below``;
    ``hint`` follows the bound in the messages (the usual values, what 0 means)."""

    positive: bool = False
    minimum: float | None = None
    below: float | None = None
    hint: str = ""

    def check(self, value, name, owner, fitting):
        number = check_real(value, name, owner, positive=self.positive)
        if self.minimum is not None and number < self.minimum:
            raise InvalidParameterError(
                f"The {name!r} parameter of {owner} must be >= {self.minimum:g}{self.hint}. "
                f"Got {value!r} instead."
            )
        if self.below is not None and number >= self.below:
            raise InvalidParameterError(
                f"The {name!r} parameter of {owner} must be below {self.below:g}{self.hint}. "
                f"Got {value!r} instead."
            )
        return number


@dataclass(frozen=True)
class Options(Constraint):
    """One of the strings ``values``; ``wording`` (default: "one of 'a', 'b'") and
    ``meaning`` (what each means) word the message."""

    values: tuple[str, ...]
    wording: str | None = None
    meaning: str = ""

    def _what(self) -> str:
        return self.wording or f"one of {', '.join(map(repr, self.values))}"

    def check(self, value, name, owner, fitting):
        if not (isinstance(value, str) and value in self.values):
            raise InvalidParameterError(
                f"The {name!r} parameter of {owner} must be {self._what()}{self.meaning}. "
                f"Got {value!r} instead."
            )
        return value


@dataclass(frozen=True)
class Boolean(Constraint):
    """True or False (a NumPy bool too); ``meaning`` says what each does."""

    meaning: str = ""

    def check(self, value, name, owner, fitting):
        if not isinstance(value, bool | np.bool_):
            raise InvalidTypeError(
                f"The {name!r} parameter of {owner} must be True or False{self.meaning}. "
                f"Got {value!r} of type {type(value).__name__} instead."
            )
        return bool(value)


@dataclass(frozen=True)
class Interval(Constraint):
    """A pair ``(low, high)`` of finite numbers with ``low < high`` (a range, in V)."""

    def check(self, value, name, owner, fitting):
        return check_range(value, name, owner)


@dataclass(frozen=True)
class InstanceOf(Constraint):
    """An instance of ``cls``; ``wording`` says what is expected."""

    cls: type
    wording: str

    def check(self, value, name, owner, fitting):
        if not isinstance(value, self.cls):
            raise InvalidParameterError(
                f"The {name!r} parameter of {owner} must be {self.wording}. Got "
                f"{type(value).__name__}."
            )
        return value


@dataclass(frozen=True)
class Nullable(Constraint):
    """None, or a value that ``inner`` accepts."""

    inner: Constraint

    def check(self, value, name, owner, fitting):
        return None if value is None else self.inner.check(value, name, owner, fitting)


@dataclass(frozen=True)
class TextOr(Constraint):
    """A string of ``text`` (say ``Options(("auto",))``), or any other value that ``other``
    accepts: a string goes to ``text``, anything else to ``other``."""

    text: Options
    other: Constraint

    def check(self, value, name, owner, fitting):
        if isinstance(value, str):
            return self.text.check(value, name, owner, fitting)
        return self.other.check(value, name, owner, fitting)


@dataclass(frozen=True)
class Each(Constraint):
    """A non-empty sequence whose every item ``item`` accepts (each named ``item_name``)."""

    item: Constraint
    item_name: str
    wording: str

    def check(self, value, name, owner, fitting):
        items = [self.item.check(v, self.item_name, owner, fitting) for v in value]
        if not items:
            raise InvalidParameterError(
                f"The {name!r} parameter of {owner} must hold at least one {self.wording}. "
                "Got an empty sequence instead."
            )
        return items


@dataclass(frozen=True)
class Unchecked(Constraint):
    """Checked where its meaning is known (in ``fit``, which knows the record), not here."""

    def check(self, value, name, owner, fitting):
        return value


def validate_parameters(
    constraints: Mapping[str, Constraint],
    values: Mapping[str, Any],
    owner: str,
    *,
    fitting: bool = False,
) -> dict[str, Any]:
    """Check every value against its declared constraint, in the order of ``constraints``.

    Parameters
    ----------
    constraints : mapping of str to Constraint
        One constraint per name (an estimator's ``_parameter_constraints``).
    values : mapping of str to object
        The values by name; every name of ``constraints`` must be among them.
    owner : str
        The estimator's or the function's name, for the messages.
    fitting : bool, default False
        Whether the values are about to be used by a fit (see :class:`Integer`).

    Returns
    -------
    dict
        The checked values by name (converted where a constraint converts: an int of a
        NumPy integer, a tuple of floats of a range).

    Raises
    ------
    InvalidParameterError, InvalidTypeError
        At the first value that breaks its constraint, naming it and the fix.
    """
    return {
        name: constraint.check(values[name], name, owner, fitting)
        for name, constraint in constraints.items()
    }


#: The constraints that the estimators and the fitting functions share, by option.
OPERATOR_COUNT = Integer(
    1,
    fit_maximum=MAX_OPERATORS,
    fit_reason=": the fit grows as the cube of it (256 take about 25 s), and 10 to 50 model "
    "a piezo actuator well (the paper uses 16)",
)
TRANSIENT = Nullable(Integer(0))
MARGIN = Real(positive=True, below=1.0, hint=f" (a small fraction such as {DEFAULT_MARGIN})")
FIT_CONSTRAINTS = Options(
    CONSTRAINTS,
    wording=f"one of {CONSTRAINTS}",
    meaning=" ('physical', the default: non-negative play weights beyond the first, and for a "
    "Preisach model X(v, v) = 0; 'paper': only what the paper's fits keep, the partial sums "
    "of the play weights positive)",
)
REGULARIZATION = Real(minimum=0.0, hint=" (0: eq. 19 as printed; try 1e-3 to 1e-1)")
REGULARIZATION_OPTION = TextOr(
    Options(("auto",), wording="'auto' or a number >= 0 (0: eq. 19 as printed)"),
    REGULARIZATION,
)
DEGREE = Integer(1, MAX_DEGREE, hint="; eq. (5) is degree 3")
EVERETT = Options(EVERETT_KINDS, wording="'polynomial' (eq. 5) or 'table'")
GRID_SIZE = Integer(2, 400)
ZERO_DIAGONAL = Boolean()
VOLTAGE_RANGE = Nullable(Interval())


def check_constraints(constraints, owner: str) -> str:
    """The ``constraints`` option: ``"physical"`` or ``"paper"`` (:data:`FIT_CONSTRAINTS`)."""
    return FIT_CONSTRAINTS.check(constraints, "constraints", owner, False)
