"""The compensation workflow: a model and a reference in, the voltage and what to know of it out.

:func:`compensate_reference` is what ``hystcomp compensate`` runs, for one axis or N coupled
axes: it builds the model's compensator (with a pair's dynamics, or dynamics identified apart,
a narrower clamp, a slew-rate limit, Preisach's inverse method), runs it on the reference and
returns a :class:`CompensationResult`: the voltage, the compensator, the clamped samples and
the warnings (samples out of reach, voltages beyond the model's record, eq. 10 turning the
voltage back on its own, a pair predicted to track worse than its hysteresis model). With
``strict`` a clamp, or a compensation whose tracking cannot be predicted, is refused instead.
:func:`inverse_for` builds the compensator alone, for the C export as well.

The warnings and errors name their remedies as data (:class:`~hystcomp._notice.Notice`): the
command line words them as its options.
"""

from __future__ import annotations

import warnings as _warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hystcomp._notice import Notice
from hystcomp._validation import MAX_MAGNITUDE
from hystcomp.errors import (
    DataFileError,
    HystcompWarning,
    InvalidParameterError,
    InvalidSignalError,
    ModelFileError,
)
from hystcomp.io.records import uneven_sampling
from hystcomp.models.dynamics import APART, LinearDynamics
from hystcomp.models.hammerstein import HammersteinModel
from hystcomp.models.multiaxis import MultiAxisModel
from hystcomp.workflows.pair import predicted_worse

__all__ = [
    "CompensationResult",
    "ExportResult",
    "check_dynamics_rate",
    "compensate_reference",
    "export_compensator",
    "inverse_for",
    "load_compensation",
    "load_dynamics",
    "own_turns",
    "reach",
    "refuse_dynamics_as_model",
    "slew_sample_rate",
    "voltage_summary",
]

#: A step of the reference's time column shorter than this share of its median step is a
#: fault of the column, not jitter: at its rate the slew-rate limit would all but hold the
#: voltage still on every sample.
SHORTEST_STEP = 1e-3
#: How far (relative) a reference's sample rate may be from the dynamics' rate.
RATE_MATCH = 1e-3
#: A turn of the voltage larger than this fraction of the range, where the reference does
#: not turn, is eq. 10 overshooting: its recursion corrects with the constant gain rho, and
#: where the model is steeper (a step, or a slope beyond 2 rho) it overshoots, or chatters.
OWN_TURN = 0.01


@dataclass(frozen=True, eq=False)
class CompensationResult:
    """What :func:`compensate_reference` computed.

    Attributes
    ----------
    v : ndarray
        The voltage in V: one column per axis for an N-axis model.
    compensator : object
        The compensator that computed it.
    clamped : int or list of int
        Samples clamped to the voltage range (per axis for an N-axis model).
    warnings : list of str
        Each a sentence, a :class:`~hystcomp._notice.Notice` where it names a remedy.
    preview : int or None
        Samples of look-ahead in the reference when the dynamics are inverted, else None.
    """

    v: np.ndarray = field(repr=False)
    compensator: Any = field(repr=False)
    clamped: Any
    warnings: list[str]
    preview: int | None = None


def load_dynamics(path) -> LinearDynamics:
    """The linear dynamics of a model file, refused if it holds another model.

    Parameters
    ----------
    path : str or path-like
        A model file written for a :class:`~hystcomp.models.dynamics.LinearDynamics`.

    Returns
    -------
    LinearDynamics
        The fitted dynamics the file holds.
    """
    from hystcomp.io.models import load_model

    model = load_model(path)
    if not isinstance(model, LinearDynamics):
        raise ModelFileError(
            Notice(
                "{dynamics_option} {path} holds a {family} model, not linear dynamics; give "
                "{identify_dynamics}.",
                path=repr(str(path)),
                family=repr(model.kind),
            )
        )
    return model


def refuse_dynamics_as_model(model, path) -> None:
    """Refuse a dynamics model given where a hysteresis model belongs.

    Parameters
    ----------
    model : object
        What the model file held.
    path : str or path-like
        The file, for the message.

    Returns
    -------
    None
    """
    if isinstance(model, LinearDynamics):
        raise ModelFileError(
            Notice(
                "{path} holds linear dynamics, not a hysteresis model; give a PI, MPI or "
                "Preisach model file and pass this one as {dynamics_option}.",
                path=repr(str(path)),
            )
        )


def check_dynamics_rate(dynamics: LinearDynamics, t) -> None:
    """Refuse a reference (time ``t`` in s) not sampled evenly at the dynamics' rate.

    Parameters
    ----------
    dynamics : LinearDynamics
        Discrete-time dynamics, identified at ``dynamics.sample_rate_``.
    t : ndarray
        The reference's time column in s.

    Returns
    -------
    None
    """
    steps = np.diff(t)
    fs = 1.0 / float(np.median(steps)) if steps.size else dynamics.sample_rate_
    # 0.1 %: a time column's jitter or rounding moves its median step, a wrong rate by far more
    if abs(fs - dynamics.sample_rate_) > RATE_MATCH * dynamics.sample_rate_:
        raise ModelFileError(
            f"The dynamics model was identified at {dynamics.sample_rate_:g} Hz but the "
            f"reference is sampled at {fs:.6g} Hz; resample the reference or identify the "
            "dynamics at the reference's rate."
        )
    uneven = uneven_sampling(t, "the reference")
    if uneven:
        raise DataFileError(uneven)


def slew_sample_rate(t, path) -> float:
    """The rate (Hz) of the shortest step of ``t``, at which a slew-rate limit holds on
    every step; refused, naming the row, if that step is a fault of the time column.

    Parameters
    ----------
    t : ndarray
        The reference's time column in s, increasing.
    path : str
        Where it was read, for the message.

    Returns
    -------
    float
        The rate (Hz).
    """
    steps = np.diff(t)
    k = int(np.argmin(steps))
    shortest, median = float(steps[k]), float(np.median(steps))
    if not shortest >= SHORTEST_STEP * median or not 1.0 / shortest <= MAX_MAGNITUDE:
        raise InvalidSignalError(
            Notice(
                "{slew} limits the voltage's change per sample at the reference's shortest "
                "time step, but the time column 't' of {path} steps by only "
                f"{shortest:.3g} s from t = {float(t[k])!r} to {float(t[k + 1])!r} s (data row "
                f"{k + 2}), against a median step of {median:.3g} s: the limit would hold the "
                "voltage nearly still. Correct the time column there, or drop it and {give_fs}.",
                path=repr(str(path)),
            )
        )
    return 1.0 / shortest


def inverse_for(
    model,
    *,
    source: str = "the model",
    voltage_range=None,
    method=None,
    slew_rate=None,
    sample_rate=None,
    dynamics=None,
):
    """The compensator of ``model`` for the options of ``compensate`` and ``export-c``.

    The options go to ``model.inverse``, but ``sample_rate`` for a pair (it runs at its own).

    Parameters
    ----------
    model : HysteresisModel, HammersteinModel or MultiAxisModel
        A fitted model (a pair inverts its own dynamics).
    source : str, optional
        Where the model came from, for the messages.
    voltage_range : (float, float), optional
        A clamp in V inside the model's range (every axis's).
    method : str, optional
        The Preisach inverse's method; refused for a model without a Preisach part.
    slew_rate, sample_rate : float, optional
        The slew-rate limit in V/s and the rate in Hz at which it holds.
    dynamics : LinearDynamics, optional
        Dynamics identified apart from ``model``, inverted in series with it.

    Returns
    -------
    compensator
        ``model.inverse(...)``, its warnings left to the caller (see :data:`APART`).
    """
    pair = isinstance(model, HammersteinModel)
    _no_dynamics(model, dynamics, source)
    options: dict[str, Any] = {"slew_rate": slew_rate, "voltage_range": voltage_range}
    if not pair:  # the pair runs at its own rate
        options["sample_rate"] = sample_rate
    if dynamics is not None:
        options["dynamics"] = dynamics
    if method is not None:
        parts = model.axes_ if isinstance(model, MultiAxisModel) else [model]
        if not any(getattr(p, "hysteresis", p).kind == "preisach" for p in parts):
            raise InvalidParameterError(
                Notice(
                    "The 'method' argument of inverse_for applies to Preisach models only; "
                    "the model in {source} is {family}, whose inverse is analytic "
                    "(eqs. 23-26). {drop_method}.",
                    source=source,
                    family=getattr(model, "kind", "?").upper(),
                )
            )
        options["method"] = method
    with _warnings.catch_warnings():
        _warnings.simplefilter("ignore", HystcompWarning)  # the caller says them as it words
        return model.inverse(**options)


def _no_dynamics(model, dynamics, source: str) -> None:
    """Refuse dynamics given apart for a pair (which has its own) or an N-axis model."""
    pair = isinstance(model, HammersteinModel)
    if dynamics is not None and (pair or isinstance(model, MultiAxisModel)):
        what = (
            "a hysteresis model and its dynamics, identified as one pair; its inverse inverts both"
            if pair
            else "a multi-axis model, whose inverse takes no dynamics"
        )
        raise ModelFileError(
            Notice("{path} holds {what}. {drop_dynamics}.", path=repr(source), what=what)
        )


def compensate_reference(
    model,
    t,
    x_ref,
    *,
    source: str = "the model",
    reference: str = "the reference",
    voltage_range=None,
    method=None,
    slew_rate=None,
    dynamics=None,
    strict: bool = False,
    progress=None,
) -> CompensationResult:
    """The voltage that makes the actuator of ``model`` follow ``x_ref``, with its warnings.

    Parameters
    ----------
    model : HysteresisModel, HammersteinModel or MultiAxisModel
        A fitted model.
    t : ndarray
        Time in s of the reference's samples.
    x_ref : ndarray
        The reference in µm: one column per axis for an N-axis model.
    source, reference : str, optional
        Where the model and the reference came from, for the messages.
    voltage_range : (float, float), optional
        A clamp in V inside the model's range.
    method : str, optional
        The Preisach inverse's method.
    slew_rate : float, optional
        The largest slew rate of the voltage in V/s, at the reference's shortest step.
    dynamics : LinearDynamics, optional
        Dynamics identified apart from ``model``, inverted in series (a warning says so).
    strict : bool, default False
        Refuse (``InvalidSignalError`` or ``ModelFileError``) what is otherwise a warning:
        a clamped sample, a pair predicted to track worse than its hysteresis model alone,
        dynamics identified apart.
    progress : context manager, optional
        Entered around the compensator's run.

    Returns
    -------
    CompensationResult
        The voltage (V) for each sample of ``x_ref``, the compensator, the samples clamped
        and the warnings (clamps, extrapolation, eq. 10's own turns) as data.
    """
    import contextlib

    multi = isinstance(model, MultiAxisModel)
    pair = isinstance(model, HammersteinModel)
    if multi and np.shape(x_ref)[1] != model.n_axes:
        k, n = np.shape(x_ref)[1], model.n_axes
        raise InvalidSignalError(
            f"{reference!r} holds references for {k} axes (x1..x{k}), but {source} is a "
            f"model of {n} axes: give one column per axis, x1..x{n}."
        )
    _no_dynamics(model, dynamics, source)
    told: list[str] = []
    rate = None if slew_rate is None else slew_sample_rate(t, reference)
    if pair:
        check_dynamics_rate(model.dynamics, t)
        worse = predicted_worse(model, x_ref, model.sample_rate)
        if worse is not None:
            what = (
                f"the pair in {source} is predicted to track this reference (about "
                f"{worse[0]:.3g} Hz) at {worse[2]:.3g} µm rms, worse than its hysteresis model "
                f"alone ({worse[1]:.3g} µm; estimated when it was identified)"
            )
            told.append(_refused(what, strict, "compensate with {pair_alone}"))
    elif dynamics is not None:
        check_dynamics_rate(dynamics, t)
        if strict:
            raise ModelFileError(
                Notice(
                    "{source} and the dynamics were identified apart, so whether their "
                    "inverse tracks better than the hysteresis model's alone cannot be "
                    "predicted. {strict}; identify them as one pair ({identify_pair}), or "
                    "{drop_strict}.",
                    source=source,
                )
            )
        told.append(APART)
    compensator = inverse_for(
        model,
        source=source,
        voltage_range=voltage_range,
        method=method,
        slew_rate=slew_rate,
        sample_rate=rate,
        dynamics=dynamics,
    )
    with contextlib.nullcontext() if progress is None else progress:
        run = compensator.run(x_ref)
    if multi:
        told += _clamped_axes(model, compensator, run, x_ref, strict)
        return CompensationResult(run.v, compensator, list(run.clamped), told)
    v, (lo, hi) = run.v, compensator.voltage_range
    hysteresis = model.hysteresis if pair else model
    if run.clamped:
        words, (d_lo, d_hi) = reach(hysteresis, lo, hi)
        what = (
            f"{run.clamped} of {v.size} samples ({100 * run.clamped_share:.3g} %) are out of "
            f"reach and clamped to {lo:.4g} .. {hi:.4g} V: the reference spans "
            f"{x_ref.min():.4g} .. {x_ref.max():.4g} µm, {words}"
        )
        remedy = f"shift or scale the reference into {d_lo:.4g} .. {d_hi:.4g} µm"
        told.append(_refused(what, strict, remedy, "to accept the clamp"))
    beyond = beyond_record(hysteresis, v)
    if beyond is not None:
        told.append(beyond)
    inner = getattr(compensator, "hysteresis", compensator)
    if getattr(inner, "method", None) == "multiplicative":
        spikes = own_turns(v, x_ref, hi - lo)
        if spikes is not None:
            n, size, k = spikes
            told.append(
                Notice(
                    "the paper's multiplicative structure (eq. 10) turns the voltage back "
                    f"where the reference does not, {n} time{'s' if n > 1 else ''} (the "
                    f"largest by {size:.3g} V, at t = {t[k]:.6g} s"
                    + (", where the reference steps from the model's rest" if k <= 2 else "")
                    + "): it overshoots where the model is steeper than its gain rho, on a "
                    "fast step or sample after sample, and each turn leaves the stage in a "
                    "minor loop that the model did not follow. {method_exact} inverts the "
                    "model without it.",
                    kind="own-turns",
                )
            )
    preview = compensator.preview if (pair or dynamics is not None) else None
    return CompensationResult(v, compensator, run.clamped, told, preview)


def _refused(what: str, strict: bool, remedy: str, accept: str = "") -> Notice:
    """The warning ``what.``, or with ``strict`` the error that refuses it, saying ``remedy``
    (a template: it may name remedies as keys)."""
    if strict:
        end = f" {accept}." if accept else "."
        raise InvalidSignalError(
            Notice("{what}. {strict}; " + remedy + ", or {drop_strict}" + end, what=what)
        )
    return Notice("{what}.", what=what)


def _clamped_axes(model, compensator, run, X, strict: bool) -> list[str]:
    """A warning per axis of an N-axis run that clamped samples (the first refused if strict)."""
    H = X @ np.asarray(compensator.decoupling).T
    told: list[str] = []
    for i, clamped in enumerate(run.clamped):
        if not clamped:
            continue
        lo, hi = compensator.voltage_range[i]
        r_lo, r_hi = model.axes_[i].reachable_range(voltage_range=(lo, hi))
        what = (
            f"axis {i + 1}: {clamped} of {X.shape[0]} samples ({100 * clamped / X.shape[0]:.3g} "
            f"%) are out of reach and clamped to {lo:.4g} .. {hi:.4g} V: its own displacement "
            f"asked for (the reference with the other axes' coupling taken out) spans "
            f"{H[:, i].min():.4g} .. {H[:, i].max():.4g} µm, the axis reaches {r_lo:.4g} .. "
            f"{r_hi:.4g} µm"
        )
        told.append(
            _refused(what, strict, "shift or scale that axis's reference", "to accept the clamp")
        )
    return told


def own_turns(v, x, span: float) -> tuple[int, float, int] | None:
    """Where the voltage turns back by itself: eq. 10 overshooting.

    Parameters
    ----------
    v : ndarray
        The compensator's voltage in V.
    x : ndarray
        The reference in µm.
    span : float
        The voltage range's width in V.

    Returns
    -------
    (int, float, int) or None
        ``(count, largest in V, index)`` of the samples where ``v`` turns back by more than
        :data:`OWN_TURN` of ``span`` (both its steps, in and out) and ``x`` does not turn
        within a sample, or None.
    """
    dv, dx = np.diff(v), np.diff(x)
    size = np.minimum(np.abs(dv[:-1]), np.abs(dv[1:]))
    turns = dx[:-1] * dx[1:] < 0
    near = turns | np.r_[False, turns[:-1]] | np.r_[turns[1:], False]  # eq. 10 a sample late
    own = (dv[:-1] * dv[1:] < 0) & ~near & (size > OWN_TURN * span)
    if not own.any():
        return None
    largest = int(np.argmax(np.where(own, size, 0.0)))
    return int(np.count_nonzero(own)), float(size[largest]), largest + 1


def beyond_record(model, v) -> Notice | None:
    """A warning for the samples of ``v`` beyond the input range the model's record covered.

    Parameters
    ----------
    model : HysteresisModel
        The model (:meth:`~hystcomp.models.base.HysteresisModel.covered_range`).
    v : ndarray
        The voltage in V.

    Returns
    -------
    Notice or None
        None when the record covered every sample (or its range is unknown).
    """
    covered = model.covered_range()
    if covered is None:
        return None
    lo, hi = covered
    slack = 1e-9 * (hi - lo)
    beyond = int(np.count_nonzero((v < lo - slack) | (v > hi + slack)))
    if not beyond:
        return None
    return Notice(
        f"{beyond} of {v.size} samples command voltages beyond {lo:.4g} .. {hi:.4g} V, the "
        f"range that the model's record covered (v from {v.min():.4g} to {v.max():.4g} V; "
        f"the model's range {model.voltage_range_[0]:.4g} .. {model.voltage_range_[1]:.4g} V "
        "was given wider): the model extrapolates there. Check the tracking there, {narrow}, "
        "or identify from a record that covers the range.",
        kind="beyond-record",
        lo=f"{lo:.6g}",
        hi=f"{hi:.6g}",
    )


def reach(model, lo: float, hi: float) -> tuple[str, tuple[float, float]]:
    """What the model reaches with ``lo .. hi`` V, in words, and where it ends a swing.

    Parameters
    ----------
    model : HysteresisModel
        A fitted model.
    lo, hi : float
        The voltage range in V.

    Returns
    -------
    (str, (float, float))
        The words, and the displacements in µm at the ends once the model has swung over
        the whole range (a model whose loops do not close at the ends no longer reaches
        its initial extremes).
    """
    x_lo, x_hi = model.reachable_range(voltage_range=(lo, hi))
    swung = model.simulate(np.array([lo, hi, lo, hi]))
    d_lo, d_hi = float(swung[2]), float(swung[3])
    text = f"the model reaches {x_lo:.4g} .. {x_hi:.4g} µm"
    if f"{d_lo:.4g} {d_hi:.4g}" != f"{x_lo:.4g} {x_hi:.4g}":
        text += (
            f", but after a swing over the whole range only {d_lo:.4g} .. {d_hi:.4g} µm "
            "(it starts from a state off its major loop, which a swing leaves for good)"
        )
    return text, (d_lo, d_hi)


@dataclass(frozen=True, eq=False)
class ExportResult:
    """What :func:`export_compensator` wrote.

    Attributes
    ----------
    paths : list of Path
        The files written: the header and the source (and each axis's of an N-axis model).
    warnings : list of str
        Dynamics identified apart from the model (:data:`~hystcomp.models.dynamics.APART`).
    """

    paths: list
    warnings: list[str]


def export_compensator(
    model,
    directory,
    *,
    prefix: str,
    source: str = "the model",
    sample_rate: float,
    inputs=(),
    **inverse,
) -> ExportResult:
    """Write the compensator of ``model`` as C99 code (:mod:`hystcomp.codegen`).

    Parameters
    ----------
    model : HysteresisModel, HammersteinModel or MultiAxisModel
        A fitted model.
    directory : str or path-like
        The folder for the files (made if its parent exists).
    prefix : str
        The C identifier that names the files, the state type and the functions.
    source : str, optional
        Where the model came from, written into the header.
    sample_rate : float
        The rate in Hz at which the step function is called; a pair's dynamics, or
        ``dynamics``, must have been identified at it.
    inputs : sequence of path-like, optional
        Files the outputs must not overwrite.
    **inverse
        ``slew_rate``, ``voltage_range``, ``method``, ``dynamics``: as :func:`inverse_for`.

    Returns
    -------
    ExportResult
        The files written (header and source) and the warnings.
    """
    from hystcomp.codegen import export_c
    from hystcomp.codegen.multiaxis import export_multiaxis_c

    own = model.dynamics if isinstance(model, HammersteinModel) else None
    dynamics = inverse.get("dynamics")
    for dyn in (d for d in (own, dynamics) if d is not None):
        if abs(dyn.sample_rate_ - sample_rate) > 1e-6 * sample_rate:
            raise InvalidParameterError(
                f"The 'sample_rate' argument of export_compensator is {sample_rate:g} Hz but "
                f"the dynamics were identified at {dyn.sample_rate_:g} Hz; the code must run "
                "at the dynamics' rate."
            )
    compensator = inverse_for(model, source=source, sample_rate=sample_rate, **inverse)
    write = export_multiaxis_c if isinstance(model, MultiAxisModel) else export_c
    options = {"prefix": prefix, "source": source, "sample_rate": sample_rate, "inputs": inputs}
    paths = list(write(compensator, directory, **options))
    return ExportResult(paths, [APART] if dynamics is not None else [])


def load_compensation(path, dynamics=None) -> tuple[Any, LinearDynamics | None]:
    """The model of a model file to invert, and the linear dynamics of a second one if given.

    Parameters
    ----------
    path : str or path-like
        A model file: a hysteresis model, a pair or an N-axis model, not linear dynamics
        alone (:func:`refuse_dynamics_as_model`).
    dynamics : str or path-like, optional
        A model file of linear dynamics (:func:`load_dynamics`), inverted in series.

    Returns
    -------
    model : object
        The model of ``path``.
    dynamics : LinearDynamics or None
        The linear dynamics of ``dynamics``, if given.
    """
    from hystcomp.io.models import load_model

    model = load_model(path)
    refuse_dynamics_as_model(model, path)
    return model, None if dynamics is None else load_dynamics(dynamics)


def voltage_summary(result: CompensationResult) -> str:
    """The voltage :func:`compensate_reference` computed, in one line: its samples, its
    range and how many were clamped (each axis's range for an N-axis model).

    Parameters
    ----------
    result : CompensationResult
        The compensation.

    Returns
    -------
    str
        E.g. ``"4000 samples, v from 2.1 to 118 V (range 0 .. 120 V, 0 clamped)"``.
    """
    v = result.v
    if v.ndim == 2:  # one column per axis
        ranges = ", ".join(f"v{i + 1} {c.min():.4g} .. {c.max():.4g} V" for i, c in enumerate(v.T))
        return f"{len(v)} samples of {v.shape[1]} axes ({ranges}; {sum(result.clamped)} clamped)"
    lo, hi = result.compensator.voltage_range
    return (
        f"{v.size} samples, v from {v.min():.4g} to {v.max():.4g} V (range {lo:.4g} .. "
        f"{hi:.4g} V, {result.clamped} clamped)"
    )
