"""The compensators of the play-chain models, and what a compensator run reports.

A :class:`Compensator` is a :class:`~hystcomp.models.system.PackedSystem`: reference (µm)
in, voltage (V) out, through the chain kernel, clamped to its voltage range. ``Stepper`` is
importable from here too (it lives in :mod:`hystcomp.models.system`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from hystcomp._kernels import chain
from hystcomp._validation import as_signal
from hystcomp.errors import InvalidParameterError
from hystcomp.models.system import PackedSystem, Stepper, check_packed_chain

__all__ = ["Compensator", "CompensatorRun", "Stepper"]

#: The kinds of model whose inverse is a packed chain.
KINDS = ("pi", "mpi")


class CompensatorRun(NamedTuple):
    """The result of :meth:`Compensator.run`: the voltage and what the clamp did to it.

    Attributes
    ----------
    v : ndarray
        The voltage in V, one sample per reference sample (as ``simulate`` gives).
    clamped : int
        Samples whose voltage the range clamped: the reference was out of reach there.
    nonfinite : int
        Non-finite reference samples (each held the last output).
    """

    v: np.ndarray
    clamped: int
    nonfinite: int

    @property
    def clamped_share(self) -> float:
        """``clamped`` as a fraction of the samples (0 for an empty run)."""
        return self.clamped / self.v.size if self.v.size else 0.0


class Compensator(PackedSystem):
    """Inverse-based feedforward: reference displacement (µm) in, voltage (V) out.

    Built by ``model.inverse()``; the output is always inside ``voltage_range``.

    Parameters
    ----------
    packed : numpy.ndarray
        The packed inverse chain (parameters and initial state) that the kernels run.
    kind : str
        The kind of the model it inverts (``"pi"`` or ``"mpi"``).
    voltage_range : tuple of (float, float)
        The clamp on the output, V.

    Attributes
    ----------
    kind : str
        The kind of the model it inverts (``"pi"`` or ``"mpi"``).
    voltage_range : tuple of float
        The clamp on the output, in V.
    max_step : float
        Largest output change per sample, in V (``inf`` without a slew-rate limit).
    """

    _input_name = "x_ref"

    def __init__(self, packed: np.ndarray, *, kind: str, voltage_range: tuple[float, float]):
        packed = check_packed_chain(packed, "Compensator").copy()  # its own, read-only
        if kind not in KINDS:
            raise InvalidParameterError(
                f"The 'kind' parameter of Compensator must be one of {KINDS}. Got {kind!r}."
            )
        rails = (float(packed[chain.LOW]), float(packed[chain.HIGH]))
        try:
            declared = tuple(float(b) for b in voltage_range)
        except (TypeError, ValueError):
            declared = ()
        if declared != rails:
            # the kernels clamp to the rails in the array; C export and users read this
            raise InvalidParameterError(
                f"The 'voltage_range' parameter of Compensator must be the clamp held in "
                f"'packed', {rails}. Got {voltage_range!r}; build compensators with "
                "model.inverse(voltage_range=...) to narrow the range."
            )
        packed.setflags(write=False)
        self._chain = packed
        self.kind = kind
        self.voltage_range = rails
        self.max_step = float(packed[chain.MAX_STEP])

    def _packed(self) -> np.ndarray:
        return self._chain

    def run(self, x_ref) -> CompensatorRun:
        """Like :meth:`simulate`, and also count the samples the voltage range clamped.

        A clamped sample is one whose reference the actuator cannot reach inside the range
        (``model.reachable_range()`` tells the reachable displacements): the voltage then
        stays at the end of the range, and the tracking error there is the model's gap.

        Parameters
        ----------
        x_ref : array_like
            1-D finite reference in µm.

        Returns
        -------
        CompensatorRun
            ``(v, clamped, nonfinite)``; ``v`` equals ``simulate(x_ref)`` bit for bit.
        """
        u = as_signal(x_ref, self._input_name)
        s = self.stepper()
        v = s.step_block(u)
        return CompensatorRun(v, s.clamped_count, s.nonfinite_count)

    @property
    def packed(self) -> np.ndarray:
        """The read-only packed chain (parameters and initial state), e.g. for C export."""
        return self._chain

    def __repr__(self) -> str:
        lo, hi = self.voltage_range
        return f"Compensator(kind={self.kind!r}, voltage_range=({lo:g}, {hi:g}) V)"
