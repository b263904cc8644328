"""The forward model on a voltage, with a validation against a measured displacement.

:func:`simulate_voltage` is what ``hystcomp simulate`` runs, for one axis or N coupled axes:
the model's displacement for the voltage, warnings where the voltage leaves the model's
range, and, when the input also holds a measured displacement, the model's error against it
beside a straight line's fitted to the same record (:func:`validation`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hystcomp.errors import InvalidSignalError, ModelFileError
from hystcomp.identify.scoring import error_report, straight_line, transient_end
from hystcomp.models.dynamics import LinearDynamics
from hystcomp.models.hammerstein import HammersteinModel
from hystcomp.models.multiaxis import MultiAxisModel
from hystcomp.workflows.compensate import check_dynamics_rate

__all__ = ["SimulationResult", "simulate_voltage", "validation"]


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """What :func:`simulate_voltage` computed.

    Attributes
    ----------
    x : ndarray
        The model's displacement in µm (one column per axis for an N-axis model).
    warnings : list of str
        The voltage leaving the model's range (per axis for an N-axis model).
    lines : list of str
        The validation against the measured displacement, if one was given.
    """

    x: np.ndarray = field(repr=False)
    warnings: list[str]
    lines: list[str]


def simulate_voltage(
    model, t, v, *, measured=None, source: str = "the model", data: str = "the input", progress=None
) -> SimulationResult:
    """The displacement of ``model`` for the voltage ``v``, with its warnings.

    Parameters
    ----------
    model : HysteresisModel, HammersteinModel or MultiAxisModel
        A fitted forward model (not linear dynamics alone, which act on a displacement).
    t : ndarray
        Time in s of the samples.
    v : ndarray
        Voltage in V (one column per axis for an N-axis model).
    measured : ndarray, optional
        A measured displacement in µm of one axis, to validate the model against.
    source, data : str, optional
        Where the model and the input came from, for the messages.
    progress : context manager, optional
        Entered around the simulation.

    Returns
    -------
    SimulationResult
        The displacement (µm) for each sample of ``v``, the warnings (the voltage leaving
        the model's range) and the validation lines against a measured displacement (µm).
    """
    import contextlib

    if isinstance(model, LinearDynamics):
        raise ModelFileError(
            f"{source!r} holds linear dynamics, not a hysteresis model; simulate runs a PI, "
            "MPI or Preisach model file on a voltage (the dynamics act on a displacement: "
            "LinearDynamics.simulate in Python)."
        )
    multi = isinstance(model, MultiAxisModel)
    if multi and v.shape[1] != model.n_axes:
        n = model.n_axes
        raise InvalidSignalError(
            f"{data!r} holds voltages for {v.shape[1]} axes, but {source} is a model of {n} "
            f"axes: give one column per axis, v1..v{n}."
        )
    if isinstance(model, HammersteinModel):  # discrete-time dynamics: at their rate only
        check_dynamics_rate(model.dynamics, t)
    told = []
    ranges = (
        model.voltage_range_ if multi else [getattr(model, "voltage_range_", (-np.inf, np.inf))]
    )
    for i, (lo, hi) in enumerate(ranges):
        vi = v[:, i] if multi else v
        if vi.min() < lo or vi.max() > hi:
            whose = f"axis {i + 1}'s input" if multi else "the input"
            model_range = "its model's" if multi else "the model's"
            told.append(
                f"{whose} ({vi.min():.4g} .. {vi.max():.4g} V) leaves {model_range} voltage "
                f"range ({lo:.4g} .. {hi:.4g} V); the model extrapolates there."
            )
    with contextlib.nullcontext() if progress is None else progress:
        x = model.simulate(v)
    lines = [] if measured is None else [validation(v, measured, x, data)]
    return SimulationResult(x, told, lines)


def validation(v, measured, x, source) -> str:
    """The model's error against a measured displacement, beside a straight line's.

    The error is taken after the start-up transient (where the model's memory and the
    stage's may differ), unless too little is left after it.

    Parameters
    ----------
    v : ndarray
        The voltage in V.
    measured : ndarray
        The measured displacement in µm.
    x : ndarray
        The model's displacement in µm.
    source : str
        Where the record came from, for the line.

    Returns
    -------
    str
        One line: the model's rms and largest error, and the rms error of a straight line
        fitted to the record.
    """
    start = transient_end(v)
    if v.size - start < max(10, v.size // 10):  # too little left after it: score it all
        start = 0
    model = error_report(measured, x, start)
    a, b = straight_line(v[start:], measured[start:])
    line = float(np.sqrt(np.mean((a * v[start:] + b - measured[start:]) ** 2)))
    after = f" from sample {start + 1} (after the start-up transient)" if start else ""
    return (
        f"  against the measured x of {source}{after}: model rms {model['rms_error_um']:.4g} "
        f"µm, max {model['max_error_um']:.4g} µm; a straight line fitted to it: rms "
        f"{line:.4g} µm"
    )
