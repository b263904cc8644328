"""Input checks shared by the public functions (the boundary layer).

Kernels trust their input; everything a user passes goes through one of these first.
Messages follow one pattern: what the argument must be, what was found, and the fix.
"""

from __future__ import annotations

import numbers
import os
import warnings
from pathlib import Path

import numpy as np

from hystcomp.errors import InvalidParameterError, InvalidSignalError, InvalidTypeError

#: Largest magnitude accepted for a signal sample or a model parameter (V, µm, µm/V, ...).
#: Far beyond any actuator, and small enough that no sum or product of such numbers in the
#: models overflows to inf (which could turn into a NaN output).
MAX_MAGNITUDE = 1e12
#: Longest signal that the excitations and the comparison make (1.6 GB of t and v); a
#: request beyond is a mistake.
MAX_SIGNAL_SAMPLES = 10**8


def check_int(value, name: str, owner: str, *, minimum: int = 1, maximum: int | None = None) -> int:
    """Return ``value`` as an int ``>= minimum`` (and ``<= maximum``) or raise a message."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise InvalidTypeError(
            f"The {name!r} parameter of {owner} must be an int >= {minimum}. "
            f"Got {value!r} of type {type(value).__name__} instead."
        )
    number = int(value)
    if number < minimum:
        raise InvalidParameterError(
            f"The {name!r} parameter of {owner} must be an int >= {minimum}. Got {value!r} instead."
        )
    if maximum is not None and number > maximum:
        raise InvalidParameterError(
            f"The {name!r} parameter of {owner} must be an int <= {maximum}. Got {value!r} instead."
        )
    return number


def check_real(
    value, name: str, owner: str, *, positive: bool = False, bound: float = MAX_MAGNITUDE
) -> float:
    """Return ``value`` as a finite float of size at most ``bound`` (``> 0`` if ``positive``)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InvalidTypeError(
            f"The {name!r} parameter of {owner} must be a real number. "
            f"Got {value!r} of type {type(value).__name__} instead."
        )
    try:
        value = float(value)
    except OverflowError:
        value = float("inf")
    if not (np.isfinite(value) and abs(value) <= bound) or (positive and value <= 0):
        need = "a finite number > 0" if positive else "a finite number"
        size = f" of magnitude at most {bound:g}" if np.isfinite(bound) else ""
        raise InvalidParameterError(
            f"The {name!r} parameter of {owner} must be {need}{size}. Got {value!r} instead."
        )
    return value


def check_range(value, name: str, owner: str) -> tuple[float, float]:
    """Return ``(low, high)`` with finite ``low < high`` or raise (booleans and text are not
    numbers here: ``(False, True)`` is not 0 .. 1 V)."""
    try:
        low, high = value
        if not all(isinstance(v, numbers.Real) and not isinstance(v, bool) for v in (low, high)):
            raise TypeError
        low, high = float(low), float(high)
    except (TypeError, ValueError, OverflowError):
        raise InvalidParameterError(
            f"The {name!r} parameter of {owner} must be a pair (low, high) of numbers. "
            f"Got {value!r} instead."
        ) from None
    if not (abs(low) <= MAX_MAGNITUDE and abs(high) <= MAX_MAGNITUDE and low < high):
        raise InvalidParameterError(
            f"The {name!r} parameter of {owner} must be a pair (low, high) of finite numbers "
            f"with low < high (magnitude at most {MAX_MAGNITUDE:g}). "
            f"Got ({low!r}, {high!r}) instead."
        )
    return low, high


def real_array(value, name: str, owner: str, what: str) -> np.ndarray:
    """Return a float64 copy of ``value``, or raise a message that says it must be ``what``
    (text, booleans and complex numbers are not numbers here).

    Parameters
    ----------
    value : array_like
        The parameter's value.
    name, owner : str
        The parameter and what it belongs to, for the message.
    what : str
        What it must be, for the message (``"a 1-D array of real numbers"``).

    Returns
    -------
    ndarray
        A float64 copy, of any shape.

    Raises
    ------
    InvalidTypeError
        If ``value`` does not convert to real numbers.
    """
    try:
        return _real_array(value, copy=True)
    except (TypeError, ValueError, OverflowError):
        raise InvalidTypeError(
            f"The {name!r} parameter of {owner} must be {what}. "
            f"Got a {type(value).__name__} that does not convert to numbers."
        ) from None


def as_vector(value, name: str, owner: str, *, length: int | None = None) -> np.ndarray:
    """Return a read-only 1-D finite float64 copy of ``value`` or raise."""
    arr = real_array(value, name, owner, "a 1-D array of real numbers")
    if arr.ndim != 1 or arr.size == 0:
        raise InvalidParameterError(
            f"The {name!r} parameter of {owner} must be a non-empty 1-D array. "
            f"Got an array of shape {arr.shape} instead."
        )
    if length is not None and arr.size != length:
        raise InvalidParameterError(
            f"The {name!r} parameter of {owner} must have {length} entries, one per operator. "
            f"Got {arr.size} instead."
        )
    if (bad := _first_out_of_bounds(arr)) is not None:
        value = float(arr[bad])
        need = f"be at most {MAX_MAGNITUDE:g} in size" if np.isfinite(value) else "be finite"
        raise InvalidParameterError(
            f"The {name!r} parameter of {owner} must {need}. Entry {bad} is {value!r}"
            + ("; check the units." if np.isfinite(value) else ".")
        )
    arr.setflags(write=False)
    return arr


def check_thresholds(value, name: str, owner: str) -> np.ndarray:
    """Thresholds ``0 = r_0 < r_1 < ... < r_n`` (paper, after eqs. 12 and 15)."""
    r = as_vector(value, name, owner)
    if r[0] != 0.0:
        raise InvalidParameterError(
            f"The {name!r} parameter of {owner} must start at 0 (r_0 = 0, as in eqs. 16 and 17). "
            f"Got r_0 = {float(r[0])!r}; shift the thresholds so that the first is 0."
        )
    if r.size > 1 and not np.all(np.diff(r) > 0):
        bad = int(np.flatnonzero(np.diff(r) <= 0)[0]) + 1
        raise InvalidParameterError(
            f"The {name!r} parameter of {owner} must be strictly increasing. "
            f"Entry {bad} ({float(r[bad])!r}) is not above entry {bad - 1} ({float(r[bad - 1])!r})."
        )
    return r


def check_reachable_state(state: np.ndarray, thresholds: np.ndarray, owner: str) -> None:
    """Play states that some input history leaves: neighbouring plays differ by no more than
    their thresholds do, ``|y_(i+1) - y_i| <= r_(i+1) - r_i``. Eq. (26) inverts only such a
    state; another one makes the inverse wrong until the input has swept it away."""
    gap = np.abs(np.diff(state)) - np.diff(thresholds)
    slack = 1e-9 * max(1.0, float(np.abs(state).max()), float(thresholds[-1]))
    if gap.size and gap.max() > slack:
        i = int(np.argmax(gap))
        raise InvalidParameterError(
            f"The 'initial_state' parameter of {owner} is not a state the plays can reach: "
            f"entries {i} and {i + 1} differ by {abs(float(state[i + 1] - state[i])):.6g} V, "
            f"more than their thresholds ({float(thresholds[i + 1] - thresholds[i]):.6g} V). "
            "Neighbouring plays may differ by at most the difference of their thresholds; "
            "leave the state out for eq. 18's zero start."
        )


def as_path(value, name: str, owner: str) -> Path:
    """Return ``value`` (a str or path-like) as a Path, or raise a message that names it."""
    try:
        path = Path(os.fspath(value))
    except TypeError:
        raise InvalidTypeError(
            f"The {name!r} parameter of {owner} must be a file name (str or path-like). "
            f"Got {type(value).__name__}."
        ) from None
    if not str(value):
        raise InvalidParameterError(f"The {name!r} parameter of {owner} is an empty file name.")
    return path


def as_signal(value, name: str, *, min_samples: int = 1) -> np.ndarray:
    """Return a 1-D finite float64 array of samples, C-contiguous and writable.

    A copy is made if conversion is needed, and of a read-only array (a
    :class:`~hystcomp.io.records.Record`'s): every kernel then sees one array type and is
    compiled once, not once more for read-only input. The kernels do not write into it.
    """
    try:
        if value is None:
            raise TypeError
        arr = _real_array(value, copy=False)
    except (TypeError, ValueError, OverflowError):
        raise InvalidTypeError(
            f"{name!r} must be a 1-D array of real numbers (samples). "
            f"Got a {type(value).__name__} that does not convert to numbers."
        ) from None
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1:
        raise InvalidSignalError(
            f"{name!r} must be a 1-D array of samples. Got an array of shape {arr.shape}; "
            "pass one channel at a time (for example x[:, 0])."
        )
    if arr.size < min_samples:
        raise InvalidSignalError(
            f"{name!r} must have at least {min_samples} sample{'' if min_samples == 1 else 's'}. "
            f"Got {arr.size}."
        )
    if (bad := _first_out_of_bounds(arr)) is not None:
        value = float(arr[bad])
        if np.isfinite(value):
            raise InvalidSignalError(
                f"{name!r} must hold samples of magnitude at most {MAX_MAGNITUDE:g}. Sample "
                f"{bad} is {value:.6g}; check the units."
            )
        raise InvalidSignalError(
            f"{name!r} must be finite. Sample {bad} is {value!r}; "
            "remove or interpolate non-finite samples first."
        )
    if not (arr.flags.c_contiguous and arr.flags.writeable):
        arr = np.array(arr, order="C")
    return arr


def as_signal_pair(a, b, names: tuple[str, str], owner: str, *, min_samples: int = 1, kinds=None):
    """Two signals (see :func:`as_signal`) with one sample each per instant.

    ``kinds`` (for example ``("voltage", "displacement")``) names what the two counts in the
    message are of.
    """
    a = as_signal(a, names[0], min_samples=min_samples)
    b = as_signal(b, names[1], min_samples=min_samples)
    if a.size != b.size:
        if kinds is None:
            got = f"{a.size} and {b.size}"
        else:
            got = f"{a.size} {kinds[0]} samples and {b.size} {kinds[1]}"
        raise InvalidSignalError(
            f"{owner}: {names[0]!r} and {names[1]!r} must have one sample each per instant. "
            f"Got {got} samples."
        )
    return a, b


def _real_array(value, *, copy: bool) -> np.ndarray:
    """``value`` as a float64 array; anything but real numbers raises TypeError.

    Text, booleans, dates and complex numbers are refused rather than converted (``"1.5"``
    or ``True`` are not samples), and so is any conversion that warns. A float64 array,
    the common case, needs no conversion and no warning filter.
    """
    if type(value) is np.ndarray and value.dtype == np.float64:  # not a subclass
        return value.copy() if copy else value
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # e.g. a ComplexWarning from an object array
        try:
            probe = np.asarray(value)
            if probe.dtype.kind not in "iufO":
                raise TypeError(f"values of dtype {probe.dtype}")
            # an object array (e.g. a pandas text column) converts "1.5" silently: refuse text
            if probe.dtype.kind == "O" and any(
                isinstance(item, str | bytes | bool | np.bool_) for item in probe.flat
            ):
                raise TypeError("text or booleans among the values")
            if copy:
                return np.array(probe, dtype=np.float64)
            return np.asarray(probe, dtype=np.float64)
        except Warning as exc:
            raise TypeError(str(exc)) from None


def _first_out_of_bounds(arr: np.ndarray) -> int | None:
    """Index of the first entry that is not finite or exceeds :data:`MAX_MAGNITUDE`."""
    # two reductions and no temporary array (a third of the time): NaN propagates through
    # min and max, and fails both comparisons
    if arr.size == 0 or (-MAX_MAGNITUDE <= arr.min() and arr.max() <= MAX_MAGNITUDE):
        return None
    ok = np.abs(arr) <= MAX_MAGNITUDE  # False for NaN
    return int(np.flatnonzero(~ok.reshape(-1))[0])
