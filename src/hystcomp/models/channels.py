"""Many independent channels at once: a deformable mirror's actuators, a stage array.

A :class:`ChannelBank` holds C play-chain systems (PI or MPI models, or their compensators,
each with its own parameters) and runs them together: the channels of one structure
(operator counts) in one kernel call, vectorised across channels
(:mod:`hystcomp._kernels.channels`). Arrays are (samples, channels); a stepper takes one
row, the C references of one sample, and returns the C voltages.

:func:`fit_channels` identifies the channels from their records, in parallel with joblib
(``n_jobs``). The same call runs on a cluster through joblib's dask backend::

    from dask.distributed import Client
    import joblib
    client = Client("scheduler-address:8786")        # or Client(LocalCluster(...))
    with joblib.parallel_config(backend="dask"):
        models = fit_channels(V, X, family="mpi", n_jobs=-1)

Each channel is one task (its record is sent to a worker, its fitted model comes back); the
workers need hystcomp installed, and compile its kernels once each (or find them in a shared
numba cache).
"""

from __future__ import annotations

import functools
from typing import Any

import numba
import numpy as np

from hystcomp._kernels import chain
from hystcomp._kernels import channels as ck
from hystcomp.errors import InvalidParameterError, InvalidSignalError, InvalidTypeError
from hystcomp.models.base import HysteresisModel
from hystcomp.models.compensator import Compensator
from hystcomp.models.multiaxis import as_axes, fit_axis
from hystcomp.models.system import checked_state

__all__ = ["BankStepper", "ChannelBank", "fit_channels"]

#: Most channels of one bank.
MAX_CHANNELS = 65_536


class _Group:
    """The channels of one structure, packed for :func:`~hystcomp._kernels.channels.bank_run`."""

    def __init__(self, columns: list[int], parts: list[chain.ChainParts]):
        self.columns = np.array(columns)
        n_ch = len(parts)

        def stack(name: str) -> np.ndarray:
            return np.ascontiguousarray(np.array([getattr(p, name) for p in parts]).T).reshape(
                -1, n_ch
            )

        self.pre_r, self.pre_w = stack("pre_r"), stack("pre_w")
        self.play_r, self.play_w = stack("play_r"), stack("play_w")
        pad = -self.play_r.shape[0] % ck.PLAYS_PER_PASS  # the kernel takes plays 4 by 4
        zeros = np.zeros((pad, n_ch))
        self.post_r, self.post_w = stack("post_r"), stack("post_w")
        self.scalars = np.ascontiguousarray(
            np.array([[p.in_offset, p.out_offset, p.low, p.high, p.max_step] for p in parts]).T
        )
        self.plays0 = stack("plays")
        if pad:  # plays of threshold 0 and weight 0: they add nothing
            self.play_r, self.play_w, self.plays0 = (
                np.vstack([a, zeros]) for a in (self.play_r, self.play_w, self.plays0)
            )
        counters = np.zeros((3, n_ch))
        counters[ck.LAST] = [p.state[chain.STATE_LAST] for p in parts]
        self.counters0 = counters

    def params(self):
        return (self.pre_r, self.pre_w, self.play_r, self.play_w, self.post_r, self.post_w)


class ChannelBank:
    """C independent play-chain systems run as one: (samples, C) in, (samples, C) out.

    Parameters
    ----------
    systems : sequence
        Fitted PI or MPI models (voltage V -> µm), or their compensators (``model.inverse()``,
        µm -> V, each clamped to its own range), one per channel; all models or all
        compensators. Channels of the same operator counts run in one kernel call.

    Examples
    --------
    >>> from hystcomp import PrandtlIshlinskii
    >>> a = PrandtlIshlinskii.from_parameters(thresholds=[0, 10], weights=[0.2, 0.1])
    >>> b = PrandtlIshlinskii.from_parameters(thresholds=[0, 5], weights=[0.3, 0.1])
    >>> bank = ChannelBank([a.inverse(), b.inverse()])
    >>> X = np.array([[1.0, 1.0], [4.0, 2.0]])
    >>> bool(np.allclose(bank.simulate(X)[:, 1], b.inverse().simulate(X[:, 1])))
    True
    >>> bank.stepper().step([1.0, 1.0]).round(6).tolist()
    [5.0, 3.333333]
    """

    def __init__(self, systems):
        systems = list(systems)
        if not 1 <= len(systems) <= MAX_CHANNELS:
            raise InvalidParameterError(
                f"The 'systems' parameter of ChannelBank must hold 1 to {MAX_CHANNELS} "
                f"channels. Got {len(systems)}."
            )
        kinds = set()
        parts = []
        for i, system in enumerate(systems):
            packed = self._packed_chain(system, i)
            kinds.add(isinstance(system, Compensator))
            parts.append(chain.unpack_chain(packed))
        if len(kinds) > 1:
            raise InvalidTypeError(
                "The 'systems' parameter of ChannelBank mixes models and compensators: give "
                "all models (voltage -> displacement) or all compensators (model.inverse())."
            )
        self.is_compensator = kinds.pop()
        self.n_channels = len(systems)
        by_shape: dict[tuple[int, int, int], list[int]] = {}
        for i, p in enumerate(parts):
            by_shape.setdefault((p.pre_r.size, p.play_r.size, p.post_r.size), []).append(i)
        self._groups = [
            _Group(columns, [parts[i] for i in columns]) for columns in by_shape.values()
        ]

    @staticmethod
    def _packed_chain(system, i: int) -> np.ndarray:
        if isinstance(system, Compensator) and system.stepper_class.kernels is chain.CHAIN_KERNELS:
            return system.packed
        if isinstance(system, HysteresisModel) and system.kind in ("pi", "mpi"):
            return np.asarray(system._packed())
        raise InvalidTypeError(
            f"Channel {i} of ChannelBank is a {type(system).__name__}: a bank runs PI and MPI "
            "models and their compensators (play chains). Run Preisach channels one by one "
            "(model.inverse().stepper())."
        )

    @property
    def n_groups(self) -> int:
        """How many kernel calls a sample takes: the distinct structures among the channels."""
        return len(self._groups)

    def stepper(self) -> BankStepper:
        """A streaming bank: ``step(row) -> row`` (C values each), from the initial state.

        A sample takes :attr:`n_groups` kernel calls, one per distinct structure.

        Returns
        -------
        BankStepper
            A stepper in the bank's initial state.
        """
        return BankStepper(self)

    def run(self, U) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Outputs (n, C) for inputs ``U`` (n, C), from the initial state, and per channel the
        counts of clamped outputs and of non-finite inputs held.

        Parameters
        ----------
        U : array_like
            Input samples, shape ``(n, C)``; a non-finite value holds that channel's last output.

        Returns
        -------
        outputs : numpy.ndarray
            The outputs, shape ``(n, C)``.
        clamped : numpy.ndarray
            Per channel, the number of outputs cut by its clamp (int, shape ``(C,)``).
        held : numpy.ndarray
            Per channel, the number of non-finite inputs held (int, shape ``(C,)``).
        """
        s = self.stepper()
        out = s.step_block(U)
        return out, s.clamped_count, s.nonfinite_count

    def simulate(self, U) -> np.ndarray:
        """Outputs (n, C) for finite inputs ``U`` (n, C), from the initial state; the bank
        is not changed.

        Parameters
        ----------
        U : array_like
            Finite input samples, shape ``(n, C)``.

        Returns
        -------
        numpy.ndarray
            The outputs, shape ``(n, C)``, from the initial state.
        """
        U = as_axes(
            U, "U", "ChannelBank.simulate", n_axes=self.n_channels, max_columns=MAX_CHANNELS
        )
        return self.stepper()._run(U)

    def __repr__(self) -> str:
        what = "compensators" if self.is_compensator else "models"
        return f"ChannelBank({self.n_channels} {what}, {self.n_groups} structure(s))"


class BankStepper:
    """A :class:`ChannelBank` one sample at a time; owns its state (reset, copy, state).

    Parameters
    ----------
    bank : ChannelBank
        The bank to stream; the stepper starts from its initial state.
    """

    def __init__(self, bank: ChannelBank):
        self._bank = bank
        self._plays = [g.plays0.copy() for g in bank._groups]
        self._counters = [g.counters0.copy() for g in bank._groups]
        n = bank.n_channels
        self._row = np.empty((1, n))
        self._out = np.empty((1, n))
        self._work = np.empty((2, ck.CHANNEL_BLOCK))
        self._n = n
        self._single = None
        if len(bank._groups) == 1:  # the kernel's entry point, and its arguments, once
            g = bank._groups[0]
            self._single = _entry()
            self._args = (*g.params(), g.scalars, self._plays[0], self._counters[0])
            self._args += (self._row, self._out, self._work)

    def step(self, u) -> np.ndarray:
        """Advance one sample: ``u`` has one value per channel; returns one per channel
        (a non-finite value holds that channel's last output).

        With one structure among the channels (the common case) a step is one call of the
        compiled kernel, without numba's dispatch on argument types.

        Parameters
        ----------
        u : array_like
            One input sample per channel, in the channels' input unit (V for a model, µm for a
            compensator).

        Returns
        -------
        numpy.ndarray
            One output sample per channel (float64, shape ``(C,)``).
        """
        try:
            self._row[0] = u
        except (TypeError, ValueError):
            raise InvalidSignalError(
                f"BankStepper.step takes one value per channel ({self._n}). Got {np.shape(u)}."
            ) from None
        if self._single is not None:
            self._single(*self._args)
            return self._out[0].copy()
        return self._run(self._row)[0]

    def _run(self, U: np.ndarray) -> np.ndarray:
        out = np.empty_like(U)
        for g, plays, counters in zip(self._bank._groups, self._plays, self._counters, strict=True):
            if len(self._bank._groups) == 1:
                ck.bank_run(*g.params(), g.scalars, plays, counters, U, out, self._work)
            else:
                part = np.empty((U.shape[0], g.columns.size))
                ck.bank_run(
                    *g.params(),
                    g.scalars,
                    plays,
                    counters,
                    np.ascontiguousarray(U[:, g.columns]),
                    part,
                    self._work,
                )
                out[:, g.columns] = part
        return out

    def step_block(self, U) -> np.ndarray:
        """Advance over a block of rows (n, C); returns the outputs (n, C).

        Parameters
        ----------
        U : array_like
            Input samples, shape ``(n, C)``: one row per sample, one column per channel.

        Returns
        -------
        numpy.ndarray
            The outputs, shape ``(n, C)``; the stepper's state has advanced by ``n`` samples.
        """
        U = as_axes(
            U, "U", "BankStepper.step_block", n_axes=self._n, finite=False, max_columns=MAX_CHANNELS
        )
        return self._run(U)

    def reset(self) -> None:
        """Back to the initial state."""
        for g, plays, counters in zip(self._bank._groups, self._plays, self._counters, strict=True):
            plays[:] = g.plays0
            counters[:] = g.counters0

    def copy(self) -> BankStepper:
        """An independent stepper in the same state.

        Returns
        -------
        BankStepper
            A new stepper whose state equals this one's; stepping either leaves the other as it is.
        """
        twin = BankStepper(self._bank)
        twin.state = self.state
        return twin

    @property
    def state(self) -> np.ndarray:
        """Every group's play states and counters, concatenated (a copy); set it to go back
        to a saved state (see :attr:`Stepper.state <hystcomp.models.system.Stepper.state>`).

        Returns
        -------
        ndarray
            1-D float64.
        """
        return np.concatenate(
            [a.ravel() for pair in zip(self._plays, self._counters, strict=True) for a in pair]
        )

    @state.setter
    def state(self, value) -> None:
        arrays = [a for pair in zip(self._plays, self._counters, strict=True) for a in pair]
        value = checked_state(np.ravel(value), sum(a.size for a in arrays), self)
        at = 0
        for a in arrays:
            a.ravel()[:] = value[at : at + a.size]
            at += a.size

    def _per_channel(self, row: int) -> np.ndarray:
        out = np.zeros(self._n, dtype=np.int64)
        for g, counters in zip(self._bank._groups, self._counters, strict=True):
            out[g.columns] = counters[row]
        return out

    @property
    def clamped_count(self) -> np.ndarray:
        """Per channel, the outputs clamped since the last reset."""
        return self._per_channel(ck.CLAMPED)

    @property
    def nonfinite_count(self) -> np.ndarray:
        """Per channel, the non-finite inputs held since the last reset."""
        return self._per_channel(ck.NONFINITE)


@functools.cache
def _entry():
    """:func:`~hystcomp._kernels.channels.bank_run` compiled for C-contiguous 2-D float64
    arrays, as a plain function (no dispatch on argument types)."""
    matrix = numba.types.float64[:, ::1]
    return ck.bank_run.compile((matrix,) * 12)


def _fit_channel(family, v: np.ndarray, x: np.ndarray, voltage_range) -> HysteresisModel:
    return fit_axis(family, v, x, voltage_range)


def fit_channels(V, X, *, family="mpi", voltage_range=None, n_jobs=None) -> list[Any]:
    """Identify one model per channel from its own record, in parallel with joblib.

    Parameters
    ----------
    V, X : array_like, shape (n, C)
        Every channel's voltage (V) and displacement (µm), one column each.
    family : {'auto', 'pi', 'mpi', 'preisach'} or estimator, default 'mpi'
        The family (see :func:`hystcomp.models.multiaxis.fit_axis`); a bank runs PI and MPI.
    voltage_range : (float, float), optional
        Every channel's amplifier range in V [each record's].
    n_jobs : int or None
        joblib's ``n_jobs`` (``-1``: every core, or every worker of a dask cluster under
        ``joblib.parallel_config(backend="dask")``; module notes).

    Returns
    -------
    list of HysteresisModel
        One fitted model per channel, in column order.
    """
    V = as_axes(V, "V", "fit_channels", max_columns=MAX_CHANNELS)
    X = as_axes(X, "X", "fit_channels", n_axes=V.shape[1], max_columns=MAX_CHANNELS)
    if V.shape != X.shape:
        raise InvalidSignalError(
            f"'V' and 'X' of fit_channels must have the same shape. Got {V.shape} and {X.shape}."
        )
    from joblib import Parallel, delayed

    jobs = (
        delayed(_fit_channel)(
            family, np.ascontiguousarray(V[:, c]), np.ascontiguousarray(X[:, c]), voltage_range
        )
        for c in range(V.shape[1])
    )
    return list(Parallel(n_jobs=n_jobs)(jobs))
