"""The packed-system base: a packed parameter/state array run by one kernel family.

A :class:`PackedSystem` (a forward model or a compensator) holds a packed array (see
:mod:`hystcomp._kernels.chain` for play chains, :mod:`hystcomp._kernels.preisach` for
Preisach systems) whose state part is the initial state. It is immutable: ``simulate`` runs a copy, so
calling it twice gives the same answer; a :class:`Stepper` owns its own copy and can be reset
or copied, and its state read and set (:attr:`Stepper.state`).

Every stepper of the package has that state API, whatever it steps (a packed system, the
inverse of the dynamics, both in series, many axes, a bank of channels, the simulated
axis): ``state`` (a copy of the state as a 1-D float64 array; set it to go back to a saved
one), ``copy()`` (an independent stepper in the same state) and ``reset()``. The :class:`Stepper` serves every packed system of the package through the
kernels its class names.
"""

from __future__ import annotations

import math
import numbers
from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import Any, ClassVar, Protocol, cast

import numpy as np

from hystcomp._kernels import chain
from hystcomp._kernels._jit import block_function, step_function
from hystcomp._validation import as_signal
from hystcomp.errors import InvalidParameterError, InvalidSignalError, InvalidTypeError


def _sample(u) -> float:
    """One input sample as a float: a real number (not a bool, text or array), else raise."""
    if isinstance(u, numbers.Real | np.floating | np.integer) and not isinstance(
        u, bool | np.bool_
    ):
        try:
            return float(u)
        except OverflowError:  # an integer beyond the floats: as an infinite sample, held
            return math.inf if str(u)[0] != "-" else -math.inf
    raise InvalidTypeError(
        f"Stepper.step takes one sample, a real number. Got {u!r:.40} of type "
        f"{type(u).__name__}; convert it with float(...), or pass a block of samples to "
        "step_block."
    )


def check_packed_chain(packed, owner: str) -> np.ndarray:
    """``packed`` as a float64 packed chain (:mod:`hystcomp._kernels.chain`) that the
    kernels can run: its counts, its length and its numbers agree with the layout.

    The kernels read the array without bounds checks, so an array of another layout would
    make them read or write outside it. Raises InvalidTypeError or InvalidParameterError.

    Parameters
    ----------
    packed : array_like
        A packed chain: counts, thresholds, weights and states, as :mod:`hystcomp._kernels.chain`
        lays them out.
    owner : str
        The class named in an error message.

    Returns
    -------
    numpy.ndarray
        ``packed`` as float64.
    """
    fix = "build it with model.inverse() (or take the .packed of one)"
    try:
        p = np.asarray(packed, dtype=np.float64)
    except (TypeError, ValueError):
        raise InvalidTypeError(
            f"The 'packed' parameter of {owner} must be a packed chain, an array of floats. "
            f"Got {type(packed).__name__}; {fix}."
        ) from None
    ok = p.ndim == 1 and p.size >= chain.HEADER
    if ok:
        counts = p[chain.N_PRE : chain.N_POST + 1]
        ok = bool(np.all((counts >= 0) & (counts <= p.size) & (counts == np.floor(counts))))
        start = chain.HEADER + 2 * int(counts.sum()) if ok else 0
        ok = ok and p.size == start + chain.STATE_PLAYS + int(counts[1])
    if not ok:
        raise InvalidParameterError(
            f"The 'packed' parameter of {owner} is not a packed chain: its length "
            f"({p.size}) and counts do not agree with the layout of hystcomp._kernels.chain; "
            f"{fix}."
        )
    parts = chain.chain_parts.py_func(p)
    low, high, max_step = float(parts.low), float(parts.high), float(parts.max_step)
    finite = np.delete(p, [chain.LOW, chain.HIGH, chain.MAX_STEP])
    thresholds = np.concatenate([parts.pre_r, parts.play_r, parts.post_r])
    rising = all(np.all(np.diff(r) >= 0.0) for r in (parts.pre_r, parts.post_r))
    if not (
        np.isfinite(finite).all()
        and (thresholds >= 0.0).all()
        and rising  # the dead-zone kernel stops at the first threshold a sample does not pass
        and low < high
        and max_step > 0.0  # NaN fails each of these
        and not np.isnan([low, high]).any()
    ):
        raise InvalidParameterError(
            f"The 'packed' parameter of {owner} holds values that no chain has: non-finite "
            f"parameters or state, a negative threshold, dead-zone thresholds that decrease, a "
            f"clamp with low >= high "
            f"({low:g}, {high:g}) or a slew limit <= 0 ({max_step:g}); {fix}."
        )
    return p


def block(u, owner: str) -> np.ndarray:
    """A block of samples for a block kernel: 1-D, contiguous, writeable float64, or raise
    (text, booleans, objects, more than one dimension).

    Parameters
    ----------
    u : array_like
        A block of input samples.
    owner : str
        The class named in an error message.

    Returns
    -------
    numpy.ndarray
        ``u`` as a 1-D, contiguous, writeable float64 array.
    """
    try:
        arr = np.asarray(u)
    except (TypeError, ValueError):  # ragged nesting
        arr = np.asarray(u, dtype=object)
    if arr.dtype.kind not in "fiu":
        raise InvalidTypeError(
            f"{owner} takes real numbers. Got an array of {arr.dtype} "
            f"({type(u).__name__}); convert it with np.asarray(u, dtype=float)."
        )
    if arr.ndim > 1:
        raise InvalidSignalError(
            f"{owner} takes a 1-D block of samples. Got shape {arr.shape}; "
            "pass one channel at a time (for example u[:, 0])."
        )
    u = np.ascontiguousarray(arr, dtype=np.float64).reshape(-1)
    if not u.flags.writeable:  # one array type for the kernel (see as_signal)
        u = u.copy()
    return u


_NDARRAY = np.ndarray
_FLOAT64 = np.dtype(np.float64)
_UNIT_STRIDE = (8,)


def output_block(out, u: np.ndarray, owner: str) -> np.ndarray:
    """``out`` if a block kernel can write the outputs of ``u`` into it, else raise: a
    writeable, C-contiguous float64 array as long as ``u`` that does not overlap it.

    Parameters
    ----------
    out : numpy.ndarray or None
        Where the caller wants the outputs written (a new array if None).
    u : numpy.ndarray
        The block of inputs.
    owner : str
        The class named in an error message.

    Returns
    -------
    numpy.ndarray
        ``out``, checked, or a new array as long as ``u``.
    """
    if not (isinstance(out, np.ndarray) and out.dtype == np.float64):
        raise InvalidTypeError(
            f"The 'out' parameter of {owner} must be a float64 NumPy array. Got "
            f"{type(out).__name__}"
            + (f" of {out.dtype}" if isinstance(out, np.ndarray) else "")
            + "; allocate it once with np.empty(len(block))."
        )
    if out.shape != u.shape or not out.flags.c_contiguous or not out.flags.writeable:
        raise InvalidParameterError(
            f"The 'out' parameter of {owner} must be a writeable, contiguous 1-D array of "
            f"the block's length ({u.size}). Got shape {out.shape}"
            + ("" if out.flags.c_contiguous else ", not contiguous")
            + ("" if out.flags.writeable else ", read-only")
            + "; allocate it once with np.empty(len(block))."
        )
    if np.may_share_memory(out, u):
        raise InvalidParameterError(
            f"The 'out' parameter of {owner} overlaps the input block; the outputs need an "
            "array of their own (np.empty(len(block)))."
        )
    return out


class _BoundStep(Protocol):
    """A stepper's fast ``step(u)``: a plain function that also names, as
    :func:`functools.partial` does, what it calls (``func``) and on what (``state``)."""

    func: Callable[..., float]
    state: Any

    def __call__(self, u: float) -> float: ...


def _named(step: Callable[[float], float], kernel, state) -> _BoundStep:
    """``step`` with the attributes of :class:`_BoundStep`."""
    bound = cast(_BoundStep, step)
    bound.func = kernel
    bound.state = state
    return bound


def checked_step(kernel, p) -> _BoundStep:
    """``step(u) = kernel(p, u)`` for a float ``u`` (the fast path: one type test), and
    for any other real number after conversion; text, bools and arrays are refused (the
    compiled kernel alone would parse a string).

    Parameters
    ----------
    kernel : callable
        A compiled step kernel, ``kernel(p, u)``.
    p : numpy.ndarray
        The packed system (its state advances).

    Returns
    -------
    callable
        ``step(u) -> float``.
    """

    def step(u):
        if u.__class__ is float:
            return kernel(p, u)
        return kernel(p, _sample(u))

    return _named(step, kernel, p)


def checked_pair_step(kernel, p, q) -> _BoundStep:
    """:func:`checked_step` for a kernel over two packed systems: ``step(u) = kernel(p, q, u)``.

    Parameters
    ----------
    kernel : callable
        A compiled step kernel over two packed systems, ``kernel(p, q, u)``.
    p : numpy.ndarray
        The first packed system (its state advances).
    q : numpy.ndarray
        The second packed system.

    Returns
    -------
    callable
        ``step(u) -> float``.
    """

    def step(u):
        if u.__class__ is float:
            return kernel(p, q, u)
        return kernel(p, q, _sample(u))

    return _named(step, kernel, (p, q))


def fast_block(kernel, p, work, checked):
    """``step_block(u, out=None)`` bound to block kernel ``kernel`` (a
    :func:`~hystcomp._kernels._jit.step_kernel`, compiled for four arrays on the first call
    that needs it, :func:`~hystcomp._kernels._jit.block_function`), state ``p`` and scratch
    ``work``.

    The trusted path: with ``u`` and ``out`` contiguous float64 arrays (``out`` writeable),
    a few type tests in Python and one compiled call, which checks the lengths and the
    overlap itself (status 0: done). Anything else goes to ``checked(u, out)``, which
    converts or refuses it with a message.

    Parameters
    ----------
    kernel : callable
        A block kernel.
    p : numpy.ndarray
        The packed system (its state advances).
    work : numpy.ndarray
        Scratch space for the kernel.
    checked : callable
        The slow path, ``checked(u, out)``, that converts or refuses other inputs.

    Returns
    -------
    callable
        ``step_block(u, out=None) -> numpy.ndarray``.
    """
    compiled = None  # a stepper that never takes this path compiles nothing for it

    def step_block(u, out=None):
        nonlocal compiled
        if (
            out is not None
            and u.__class__ is _NDARRAY
            and out.__class__ is _NDARRAY
            and u.dtype is _FLOAT64
            and out.dtype is _FLOAT64
            and u.strides == _UNIT_STRIDE
            and out.strides == _UNIT_STRIDE
            and out.flags.writeable
        ):
            if compiled is None:
                compiled = block_function(kernel)
            if compiled(p, u, out, work) == 0:
                return out
        return checked(u, out)

    return step_block


def checked_state(value, size: int, stepper: object) -> np.ndarray:
    """``value`` as the state of ``stepper``, a 1-D array of ``size`` floats, or raise (for
    the ``state`` setters of the steppers).

    Parameters
    ----------
    value : array_like
        The state to set.
    size : int
        How many values the stepper's state has.
    stepper : object
        The stepper (its class is named in the message).

    Returns
    -------
    ndarray
        ``value`` as a float64 array.

    Raises
    ------
    InvalidParameterError
        If ``value`` is not of shape ``(size,)``.
    """
    value = np.asarray(value, dtype=np.float64)
    if value.shape != (size,):
        raise InvalidParameterError(
            f"The state of this {type(stepper).__name__} has {size} values. Got shape "
            f"{value.shape}; take it from .state."
        )
    return value


class Rebound(ABC):
    """Steppers whose fast ``step`` is a closure over their state, bound by ``_bind``.

    A pickled or deep-copied stepper must step its own state, not the original's: the
    names in ``_bound`` are left out of the pickled state and bound again on unpickling.
    """

    _bound: ClassVar[tuple[str, ...]] = ("step",)

    @abstractmethod
    def _bind(self) -> None:
        """Bind the fast ``step`` (and whatever else ``_bound`` names) to the state."""

    def __getstate__(self) -> dict:
        return {k: v for k, v in self.__dict__.items() if k not in self._bound}

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._bind()


class Stepper(Rebound):
    """Streaming evaluation, one sample per call, bit for bit equal to the batch run.

    A non-finite input sample holds the last output (the amplifier keeps its voltage) and
    is counted in :attr:`nonfinite_count`; nothing is raised inside a real-time loop.

    For speed, each stepper binds :meth:`step` to the compiled step kernel and its own state
    when it is made (no method lookup, no dispatch on argument types; the cost of a call is
    in the documentation, Benchmarks, "Speed"); the exact Preisach inverse adds its root
    search per sample. One test that the sample is a float guards it (the compiled kernel alone
    would parse the text ``"1.0"``); that small Python frame is the only cost above the
    bare kernel (the ``realtime`` benchmark gives the ratio). A loop that has its samples
    in blocks can use :meth:`step_block`, faster per sample.

    The same class serves every kind of packed system: the class attribute ``kernels``
    (:class:`~hystcomp._kernels._jit.StepKernels`) names its step and batch kernels and where
    its state lies; it is the play chain's here, the Preisach system's in
    :class:`~hystcomp.models.preisach.PreisachStepper` and the simulated axis's in
    :class:`~hystcomp.plant.twin.TwinStepper`.

    Parameters
    ----------
    packed : numpy.ndarray
        The packed system (parameters and initial state); the stepper works on a copy.
    """

    kernels = chain.CHAIN_KERNELS
    # _kernel: the twin's stepper binds one too
    _bound = ("step", "step_block", "_run", "_kernel")

    def __init__(self, packed: np.ndarray):
        packed = self._checked(packed)
        self._initial = packed
        self._p = packed.copy()
        self._start = int(self.kernels.state_start(packed))
        self._work = np.empty(chain.BLOCK)  # the block kernel's scratch
        self._bind()

    @classmethod
    def _checked(cls, packed) -> np.ndarray:
        """``packed`` checked against the layout of :attr:`kernels` (a play chain here)."""
        return check_packed_chain(packed, cls.__name__)

    def _bind(self) -> None:
        """Bind the fast :meth:`step` and the block kernels to this stepper's state."""
        self._run = self.kernels.run  # looked up once: a block call is short too
        if self.kernels.block is not None:  # as step: an instance attribute over the method
            self.step_block = fast_block(  # type: ignore[method-assign]
                self.kernels.block, self._p, self._work, self._checked_block
            )
        # an instance attribute hides the method below, which documents it
        self.step = checked_step(  # type: ignore[method-assign]
            step_function(self.kernels.step), self._p
        )

    def step(self, u: float) -> float:
        """Advance one sample and return the output.

        Parameters
        ----------
        u : float
            The input sample (a reference in µm for a compensator, a voltage in V for a
            model). A non-finite value holds the last output.

        Returns
        -------
        float
            The output (V for a compensator, µm for a model).
        """
        return self.kernels.step(self._p, u)

    def step_block(self, u, out=None) -> np.ndarray:
        """Advance over a block of samples and return the outputs (non-finite samples held).

        Parameters
        ----------
        u : array_like
            A 1-D block of real samples (a single number is a block of one).
        out : ndarray, optional
            Where to write the outputs: a writeable, contiguous float64 array as long as
            ``u``, not overlapping it, allocated once and passed on every call. With ``u`` a
            contiguous float64 array too, the call takes the fast path: a few type tests and
            one compiled call, faster than a call that allocates (Benchmarks, "Speed").
            Anything else is checked and converted as without
            ``out``.

        Returns
        -------
        ndarray
            The outputs: ``out`` if given, else a new array.

        Raises
        ------
        InvalidSignalError
            If ``u`` has more than one dimension (one channel at a time).
        InvalidTypeError
            If ``u`` holds text, booleans or objects, or ``out`` is not a float64 array.
        InvalidParameterError
            If ``out`` is not as long as ``u``, is read-only or not contiguous, or overlaps
            ``u``.
        """
        return self._checked_block(u, out)

    def _checked_block(self, u, out) -> np.ndarray:
        """:meth:`step_block` with every argument checked (and converted where it can be)."""
        u = block(u, "Stepper.step_block")
        out = np.empty_like(u) if out is None else output_block(out, u, "Stepper.step_block")
        if self.kernels.block is not None:
            block_function(self.kernels.block)(self._p, u, out, self._work)
        else:
            self._run(self._p, u, out)
        return out

    def reset(self) -> None:
        """Return to the initial state."""
        self._p[:] = self._initial

    def copy(self) -> Stepper:
        """An independent stepper in the same state.

        Returns
        -------
        Stepper
            A new stepper in this one's state; stepping either leaves the other as it is.
        """
        twin = type(self)(self._initial)
        twin._p[:] = self._p
        return twin

    @property
    def state(self) -> np.ndarray:
        """The stepper's state: the state part of its packed system, as a copy.

        Get it to save where the stepper is, and set it (an array of the same size, from
        ``.state`` of this stepper or of another of the same system) to go back there: the
        next steps then give the outputs they gave after the state was taken, bit for bit.
        The counters (:attr:`nonfinite_count`, :attr:`clamped_count`) are part of it.

        Returns
        -------
        ndarray
            1-D float64, a copy (changing it changes nothing in the stepper).

        Raises
        ------
        InvalidParameterError
            On setting, if the array does not have the state's size.
        """
        return self._p[self._start :].copy()

    @state.setter
    def state(self, value) -> None:
        self._p[self._start :] = checked_state(value, self._p.size - self._start, self)

    @property
    def nonfinite_count(self) -> int:
        """How many non-finite input samples were held since the last reset."""
        return int(self._p[self._start + self.kernels.nonfinite])

    @property
    def _clamped_slot(self) -> int:
        """Index in the state of :attr:`clamped_count` (for a stage in front that counts the
        same sample first, :class:`~hystcomp.models.dynamic_compensator.DynamicStepper`)."""
        return self._start + self.kernels.clamped

    @property
    def clamped_count(self) -> int:
        """How many outputs the voltage range clamped since the last reset.

        An output counts when the compensator asked for a voltage beyond the range by more
        than :data:`~hystcomp._kernels.chain.CLAMP_TOLERANCE` of it (or, for the exact Preisach
        inverse, stopped at a range end short of the reference): the reference was out of
        the actuator's reach there. Always 0 for a forward model.
        """
        return int(self._p[self._start + self.kernels.clamped])

    @property
    def last_output(self) -> float:
        """The last output (before the first sample: the rest value of the system)."""
        return float(self._p[self._start + self.kernels.last])


class PackedSystem(ABC):
    """A static hysteretic map held as one packed array and run by the kernels of its
    :attr:`stepper_class` (a model or a compensator).

    Subclasses give :meth:`_packed` (parameters and initial state); ``simulate`` and
    ``stepper`` run it through ``stepper_class.kernels`` (the play chain's by default).
    """

    _input_name = "v"
    stepper_class: ClassVar[type[Stepper]] = Stepper

    @abstractmethod
    def _packed(self) -> np.ndarray:
        """The packed chain: parameters and initial state."""

    def simulate(self, signal) -> np.ndarray:
        """Run a whole signal from the initial state; the system is not changed.

        Parameters
        ----------
        signal : array_like
            1-D finite samples.

        Returns
        -------
        ndarray
            The output, one sample per input sample.
        """
        u = as_signal(signal, self._input_name)
        p = self._packed().copy()
        out = np.empty_like(u)
        self.stepper_class.kernels.run(p, u, out)
        return out

    def stepper(self) -> Stepper:
        """A :class:`Stepper` (of ``stepper_class``) starting from the initial state.

        Returns
        -------
        Stepper
            A stepper in the initial state.
        """
        return self.stepper_class(self._packed())
