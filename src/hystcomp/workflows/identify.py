"""The identification workflow: a measured record in, a fitted model and its figures out.

:func:`identify_record` is what ``hystcomp identify`` runs for the hysteresis models (PI,
MPI, Preisach), usable from Python: it leaves out the start-up transient, holds out the end
of the record if asked, fits a copy of the model, scores the fit
(:mod:`hystcomp.identify.scoring`), estimates the compensator's tracking error
(:mod:`hystcomp.identify.compensation`), and returns all of it in an
:class:`IdentificationResult`: the figures, the fitted model, the report lines and the
warnings, whose remedies are data (:class:`hystcomp._notice.Notice`) that the command line
words as options. It prints and writes nothing. The linear dynamics (beyond the paper) are
identified by :mod:`hystcomp.workflows.pair`.
"""

from __future__ import annotations

import contextlib
import numbers
from dataclasses import dataclass, field

import numpy as np

from hystcomp import paper
from hystcomp._hyperparameters import check_constraints
from hystcomp._notice import Notice
from hystcomp._validation import MAX_MAGNITUDE
from hystcomp.errors import IdentificationError, InvalidParameterError, InvalidTypeError
from hystcomp.identify.compensation import tracking_estimate
from hystcomp.identify.outliers import check_isolated
from hystcomp.identify.scoring import (
    check_transient,
    coverage_warning,
    error_report,
    holdout_report,
    transient_end,
)
from hystcomp.io.records import x_unit_warning
from hystcomp.models.mpi import ModifiedPrandtlIshlinskii
from hystcomp.models.pi import PrandtlIshlinskii
from hystcomp.models.preisach import Preisach

__all__ = [
    "IdentificationResult",
    "build_estimator",
    "check_options",
    "identify_record",
]

#: The number of plays (and dead-zones) when none is given: the paper's n + 1 = 16.
DEFAULT_OPERATORS = paper.N_OPERATORS

#: Model kinds and their names in the report.
LABELS = {"pi": "PI", "mpi": "MPI", "preisach": "Preisach", "dynamics": "dynamics"}

#: The options each kind takes (beside ``voltage_range``); ``dynamics`` has its own fit.
SIZE_OPTIONS = {
    "pi": ("operators", "constraints"),
    "mpi": ("operators", "deadzones", "regularization", "constraints", "initial_memory"),
    "preisach": ("degree", "fit", "everett", "grid", "constraints"),
    "dynamics": (),
}

#: The estimator class of each hysteresis model kind.
ESTIMATORS = {"pi": PrandtlIshlinskii, "mpi": ModifiedPrandtlIshlinskii, "preisach": Preisach}

_OWNER = "identify_record"
#: A compensator predicted to track within this fraction of a straight line's error is
#: warned about: the estimate is measured on the record, and another reference can lose
#: that margin (Benchmarks, "The tracking estimate").
LINE_MARGIN = 0.8
#: The fewest samples left after the transient for a model without a transient option of
#: its own (Preisach's fit needs three).
MIN_SETTLED = 3


def _estimator_class(kind: str):
    """The estimator class of a hysteresis model kind."""
    if kind in ESTIMATORS:
        return ESTIMATORS[kind]
    raise InvalidParameterError(
        f"The 'kind' argument of {_OWNER} must be 'pi', 'mpi' or 'preisach'; got {kind!r}. "
        "Linear dynamics are fitted by hystcomp.models.dynamics.LinearDynamics().fit."
    )


def build_estimator(
    kind: str,
    *,
    voltage_range=None,
    operators=None,
    deadzones=None,
    regularization=None,
    degree=None,
    fit=None,
    everett=None,
    grid=None,
    constraints=None,
    initial_memory=None,
):
    """An unfitted hysteresis model of ``kind`` from the identification options.

    Parameters
    ----------
    kind : {'pi', 'mpi', 'preisach'}
        The model family.
    voltage_range : (float, float), optional
        Amplifier range in V, the compensator's clamp [the fitted record's range].
    operators, deadzones : int, optional
        Number of plays n + 1 (pi, mpi) and of dead-zones m + 1 (mpi)
        [:data:`DEFAULT_OPERATORS`, the paper's 16].
    regularization : float or 'auto', optional
        Penalty on the inverse dead-zone weights (mpi) [the estimator's default].
    degree : int, optional
        Degree of the Everett polynomial of eq. 5 (preisach); implies
        ``everett='polynomial'``.
    fit : str, optional
        How a Preisach model is fitted (``Preisach``'s ``fit_method``).
    everett : {'table', 'polynomial'}, optional
        The Preisach model's Everett function.
    grid : int, optional
        Nodes per axis of a Preisach Everett table.
    constraints : {'physical', 'paper'}, optional
        PI and MPI: the weight constraints (eqs. 12, 19). Preisach: ``'paper'`` fits eq. 5's
        coefficients free, as Section III-A does (``zero_diagonal=False``), where
        ``'physical'`` (the default) holds ``X(v, v) = 0`` as eq. 2 implies.
    initial_memory : {'auto', 'virgin', 'descended'}, optional
        Where the plays of an MPI model start (``ModifiedPrandtlIshlinskii``'s
        ``initial_memory``) [auto].

    Returns
    -------
    estimator
        A :class:`~hystcomp.models.pi.PrandtlIshlinskii`,
        :class:`~hystcomp.models.mpi.ModifiedPrandtlIshlinskii` or
        :class:`~hystcomp.models.preisach.Preisach`, not fitted.

    Raises
    ------
    InvalidParameterError
        An unknown kind, or an option refused by :func:`check_options`.

    Examples
    --------
    >>> build_estimator("mpi", operators=8).n_deadzones
    16
    """
    cls = _estimator_class(kind)
    given = {
        "operators": operators,
        "deadzones": deadzones,
        "regularization": regularization,
        "degree": degree,
        "fit": fit,
        "everett": everett,
        "grid": grid,
        "constraints": constraints,
        "initial_memory": initial_memory,
    }
    given = check_options(kind, **given)
    if degree is not None and everett is None:
        given["everett"] = "polynomial"  # a degree names eq. 5's polynomial, not the table
    params = {"voltage_range": voltage_range}
    for name in ("operators", "deadzones"):
        if name in SIZE_OPTIONS[kind]:
            params[f"n_{name}"] = DEFAULT_OPERATORS if given[name] is None else given[name]
    params.update({_HYPERPARAMETERS.get(k, k): v for k, v in given.items() if v is not None})
    if kind == "preisach" and constraints is not None:
        check_constraints(constraints, "build_estimator")
        params["zero_diagonal"] = params.pop("constraints") == "physical"
    return cls(**params)


def check_options(kind: str = "auto", **options) -> dict:
    """Refuse, before any work, the family options that ``kind`` does not take or that
    contradict each other.

    Parameters
    ----------
    kind : {'auto', 'pi', 'mpi', 'preisach', 'dynamics'}, default 'auto'
        The model family (``'auto'``: each option goes to the families that take it).
    **options
        The options of :func:`build_estimator` (None: not given); ``regularization`` may
        also be the text of a number.

    Returns
    -------
    dict
        ``options``, with ``regularization`` as a number or ``'auto'``.

    Raises
    ------
    InvalidParameterError
        An option that ``kind`` does not take (:data:`SIZE_OPTIONS`), ``degree`` with
        ``everett='table'`` or with ``grid``, ``grid`` with ``everett='polynomial'``, or a
        ``regularization`` other than ``'auto'`` or a number from 0 to ``MAX_MAGNITUDE``.

    Examples
    --------
    >>> check_options("mpi", regularization="0.5", operators=None)
    {'regularization': 0.5, 'operators': None}
    """
    takes = SIZE_OPTIONS.get(kind, [n for names in SIZE_OPTIONS.values() for n in names])
    for name, value in options.items():
        if value is not None and name not in takes:
            which = ", which takes " + ", ".join(f"{{arg_{n}}}" for n in takes) if takes else ""
            raise InvalidParameterError(
                Notice(f"{{arg_{name}}} does not apply to {{set_kind}}{which}.", value=kind)
            )
    everett, grid, degree = (options.get(k) for k in ("everett", "grid", "degree"))
    for name, value, wants, other in (
        ("degree", degree, "polynomial", "table"),
        ("grid", grid, "table", "polynomial"),
    ):
        if value is not None and everett == other:
            has = f"; a {other} has {{arg_{'grid' if name == 'degree' else 'degree'}}}"
            raise InvalidParameterError(
                Notice(f"{{arg_{name}}} applies to {{set_everett}}{has}.", value=wants)
            )
    if grid is not None and degree is not None:
        raise InvalidParameterError(
            Notice(
                "{arg_grid} and {arg_degree} exclude each other: {arg_degree} fits the "
                "polynomial of eq. 5, {arg_grid} a table; give one of them."
            )
        )
    penalty = options.get("regularization")
    if penalty is not None and penalty != "auto":
        try:
            number = float(penalty)
        except (TypeError, ValueError):
            number = float("nan")
        if not 0 <= number <= MAX_MAGNITUDE:
            raise InvalidParameterError(
                "The 'regularization' argument of build_estimator must be 'auto' or a number "
                f"from 0 to {MAX_MAGNITUDE:g}; got {penalty!r}."
            )
        options["regularization"] = number
    return options


#: The estimator's name of an option where it is not the option's.
_HYPERPARAMETERS = {
    "operators": "n_operators",
    "deadzones": "n_deadzones",
    "fit": "fit_method",
    "grid": "grid_size",
}


def fit_samples(n: int, holdout: float | None) -> int:
    """How many samples of ``n`` are fitted on when the last ``holdout`` fraction is held out.

    Examples
    --------
    >>> fit_samples(1000, None), fit_samples(1000, 0.25)
    (1000, 750)
    """
    return n if holdout is None else n - round(holdout * n)


def extrapolation_error(voltage_range, v) -> str | None:
    """Why ``voltage_range`` (V) is refused for a model fitted on the input ``v``, or None.

    A range reaching beyond the input the model is fitted on would let the compensator
    command voltages the model never saw; a relative slack of 1e-9 of the input's span
    forgives rounding.

    Examples
    --------
    >>> import numpy as np
    >>> extrapolation_error((0.0, 100.0), np.array([0.0, 120.0])) is None
    True
    >>> extrapolation_error((0.0, 200.0), np.array([0.0, 120.0]))
    "0 200 V reaches beyond the record's input (0 .. 120 V)"
    """
    lo, hi = voltage_range
    v_lo, v_hi = float(np.min(v)), float(np.max(v))
    slack = 1e-9 * (v_hi - v_lo)
    if lo < v_lo - slack or hi > v_hi + slack:
        return f"{lo:g} {hi:g} V reaches beyond the record's input ({v_lo:.6g} .. {v_hi:.6g} V)"
    return None


@dataclass(frozen=True, eq=False)
class IdentificationResult:
    """What :func:`identify_record` found.

    Attributes
    ----------
    model : estimator
        The fitted model (PI, MPI or Preisach).
    kind : str
        ``'pi'``, ``'mpi'`` or ``'preisach'``.
    source : str
        Where the record came from (its ``source``).
    start : int
        Index of the first fitted sample; the samples before it (the start-up transient)
        are left out of the fit and of the errors.
    n_fit : int
        Samples ``0 .. n_fit - 1`` are the fitted part; the rest is held out.
    x_model : ndarray
        The model's displacement in µm over the fitted part (``n_fit`` samples).
    fit : dict
        The fit errors over ``start .. n_fit`` (:func:`~hystcomp.identify.scoring.error_report`).
    tracking : dict
        The compensator's estimated tracking error beside a straight line's, and the
        cross-validated error (:func:`~hystcomp.identify.compensation.tracking_estimate`).
    holdout : dict or None
        The hold-out figures (:func:`~hystcomp.identify.scoring.holdout_report`), or None
        without a hold-out.
    lines : list of str
        The report, one line each; a line that names a remedy is a
        :class:`~hystcomp._notice.Notice`, which the command line words as its option.
    warnings : list of str
        Each a sentence (without the ``hystcomp: warning:`` prefix of the command line),
        a :class:`~hystcomp._notice.Notice` where it names a remedy: the compensator is
        predicted to track no better than a straight line, the record does not cover what
        a reference does, or the hold-out leaves the fitted input range.
    """

    model: object
    kind: str
    source: str
    start: int
    n_fit: int
    x_model: np.ndarray = field(repr=False)
    fit: dict
    tracking: dict
    holdout: dict | None
    lines: list[str] = field(repr=False)
    warnings: list[str]

    @property
    def label(self) -> str:
        """The model family's name in the report: ``'PI'``, ``'MPI'`` or ``'Preisach'``."""
        return LABELS[self.kind]


def identify_record(
    record,
    model,
    *,
    voltage_range=None,
    allow_extrapolation: bool = False,
    transient: float | None = None,
    holdout: float | None = None,
    progress=None,
    unit_check: bool = True,
    **options,
) -> IdentificationResult:
    """Fit a hysteresis model to a measured record and score it.

    The fit starts after the start-up transient: by default at the first sample where the
    input reaches an end of its range (:func:`~hystcomp.identify.scoring.transient_end`),
    else ``transient`` seconds into the record. With ``holdout`` the last fraction of the
    record is left out of the fit and the model's prediction of it is scored against a
    straight line. The compensator's tracking error is estimated from the model's error on
    the record's swings and its inverse's on its own model
    (:func:`~hystcomp.identify.compensation.tracking_estimate`).

    Parameters
    ----------
    record : hystcomp.io.records.Record
        The measured record: time (s), voltage (V), displacement (µm).
    model : {'pi', 'mpi', 'preisach'} or estimator
        The kind to build with ``voltage_range`` and ``options`` (:func:`build_estimator`),
        or an estimator (then give neither), of which a copy with the same hyperparameters
        is fitted: the estimator given stays as it is.
    voltage_range : (float, float), optional
        Amplifier range in V, the compensator's clamp [the fitted input's range].
    allow_extrapolation : bool, optional
        Accept a ``voltage_range`` reaching beyond the fitted input; refused by default,
        since the compensator would command voltages the model never saw.
    transient : float, optional
        Seconds at the start of the record left out of the fit, >= 0.
    holdout : float, optional
        Fraction of the record, strictly between 0 and 1, held out at its end.
    progress : context manager, optional
        Entered around the fit, e.g. ``hystcomp._progress.Progress(...).ticking()``.
    unit_check : bool, default True
        Warn if the displacement's span looks like metres or nanometres read as µm
        (:func:`hystcomp.io.records.x_unit_warning`); a caller that checks before the fit
        turns it off.
    **options
        ``operators``, ``deadzones``, ``regularization``, ``degree``, ``fit``,
        ``everett``, ``grid``, ``constraints``: see :func:`build_estimator`.

    Returns
    -------
    IdentificationResult
        The fitted model, its errors, the hold-out and tracking figures, the report lines
        and the warnings.

    Raises
    ------
    InvalidParameterError
        A bad option, ``holdout`` or ``transient``, or a ``voltage_range`` beyond the fitted
        input without ``allow_extrapolation``.
    IdentificationError
        The hold-out leaves fewer than 2 samples to fit on, or the fit fails.

    Examples
    --------
    >>> import numpy as np
    >>> from hystcomp.io.records import Record
    >>> from hystcomp.plant import Twin
    >>> t = np.arange(5000) / 1000.0  # 5 s at 1 kHz, a loop with inner loops each second
    >>> v = 60.0 - 40.0 * np.cos(2 * np.pi * t) - 20.0 * np.cos(6 * np.pi * t)
    >>> record = Record(t, v, Twin().hysteresis(v), source="twin")
    >>> result = identify_record(record, "pi", operators=8, holdout=0.2)
    >>> result.model.n_operators, result.n_fit, result.holdout["n_holdout"]
    (8, 4000, 1000)
    >>> bool(result.fit["rms_error_percent"] < 2.0), bool(result.tracking["ratio"] < 1.0)
    (True, True)
    >>> result.warnings
    []
    >>> result.lines[0]
    'PI model (8 plays) from twin'
    """
    for name in ("t", "v", "x", "source", "sample_rate"):
        if not hasattr(record, name):
            raise InvalidTypeError(
                f"The 'record' argument of {_OWNER} must be a hystcomp.io.records.Record (t, v, x); "
                f"got {type(record).__name__}. Read a file with hystcomp.io.records.read_record or "
                "build a Record from arrays."
            )
    known = sorted({name for names in SIZE_OPTIONS.values() for name in names})
    unknown = sorted(set(options) - set(known))
    if unknown:
        names = {"n_operators": "operators", "n_deadzones": "deadzones", "grid_size": "grid"}
        names["fit_method"] = "fit"
        hint = "; ".join(f"{k} is called {names[k]!r} here" for k in unknown if k in names)
        raise InvalidParameterError(
            f"{_OWNER} got an unknown option {unknown[0]!r}; its options are "
            f"{', '.join(known)} (build_estimator's names)" + (f": {hint}." if hint else ".")
        )
    if progress is not None and not hasattr(progress, "__enter__"):
        raise InvalidTypeError(
            f"The 'progress' argument of {_OWNER} must be a context manager (entered while the "
            f"model is fitted) or None; got {type(progress).__name__}."
        )
    if isinstance(model, str):
        model = build_estimator(model, voltage_range=voltage_range, **options)
    elif options or voltage_range is not None:
        raise InvalidParameterError(
            f"{_OWNER} takes options ({', '.join(sorted(options) or ['voltage_range'])}) only "
            "with a model kind; got an estimator. Set them on the estimator instead."
        )
    kind = getattr(model, "kind", None)
    if kind not in ("pi", "mpi", "preisach") or not hasattr(model, "get_params"):
        raise InvalidTypeError(
            f"The 'model' argument of {_OWNER} must be 'pi', 'mpi', 'preisach' or an unfitted "
            f"PI, MPI or Preisach estimator; got {type(model).__name__}."
        )
    model = type(model)(**model.get_params())  # fitted as a copy: the caller's stays as given
    if holdout is not None and not (isinstance(holdout, numbers.Real) and 0.0 < holdout < 1.0):
        raise InvalidParameterError(
            f"The 'holdout' argument of {_OWNER} must be a fraction strictly between 0 and 1; "
            f"got {holdout!r}."
        )
    if transient is not None and not (
        isinstance(transient, numbers.Real) and 0.0 <= transient < float("inf")
    ):
        raise InvalidParameterError(
            f"The 'transient' argument of {_OWNER} must be a finite number of seconds >= 0; "
            f"got {transient!r}."
        )
    n = len(record)
    n_fit = fit_samples(n, holdout)
    if holdout is not None and not 2 <= n_fit < n:
        raise IdentificationError(
            f"The 'holdout' argument of {_OWNER}, {holdout}, leaves {n_fit} of {n} samples to "
            "fit on; choose a fraction that keeps samples on both sides."
        )
    # the whole record, rows named as the user counts them (the fit would name v[k])
    check_isolated(record.v, None, row=lambda k: _data_row(record, k), source=record.source)
    v, x = record.v[:n_fit], record.x[:n_fit]
    chosen_range = model.get_params().get("voltage_range")
    if chosen_range is not None and not allow_extrapolation:
        why = extrapolation_error(chosen_range, v)
        if why is not None:
            raise InvalidParameterError(
                Notice(
                    f"The 'voltage_range' argument of {_OWNER}, "
                    "{why}: the compensator would command voltages the model never saw. Give "
                    "a range within the record, record over the whole range, or pass "
                    "{allow_extrapolation}.",
                    why=why,
                )
            )
    if transient is None:
        start = transient_end(v)
    else:
        start = int(np.searchsorted(record.t - record.t[0], transient, side="left"))
    with contextlib.nullcontext() if progress is None else progress:
        try:
            if "transient" in model.get_params():
                if transient is not None:
                    model.set_params(transient=start)
                model.fit(v, x)
            else:  # a model without its own transient option is fitted on the settled part
                check_transient(start, v, f"{_OWNER} ({kind})", min_used=MIN_SETTLED)
                model.fit(v[start:], x[start:])
        except IdentificationError as exc:
            if holdout is None:
                raise
            cause = exc.args[0] if len(exc.args) == 1 else str(exc)
            said = isinstance(cause, Notice)  # its remedies stay data
            raise IdentificationError(
                Notice(
                    (cause.template if said else "{cause}")
                    + f" The 'holdout' argument of {_OWNER}, {holdout}, leaves the first "
                    f"{n_fit} of {n} samples to fit on: hold out a smaller fraction (0.2 "
                    f"leaves {fit_samples(n, 0.2)}).",
                    **(cause.data if said else {"cause": str(cause)}),
                )
            ) from None
    x_model = model.simulate(v)
    fit = error_report(x, x_model, start)
    tracking = tracking_estimate(model, v, x, start=start)
    held = None if holdout is None else holdout_report(model, record.v, record.x, n_fit, start)

    label = LABELS[kind]
    lines = [f"{label} model{_sizes(model)} from {record.source}"]
    lines.append(
        f"  record:    {n} samples at {record.sample_rate:.6g} Hz "
        f"({record.t[-1] - record.t[0]:.4g} s), v {record.v.min():.4g} .. "
        f"{record.v.max():.4g} V, x {record.x.min():.4g} .. {record.x.max():.4g} µm"
    )
    skipped = f" (first {start} left out: start-up transient)" if start else ""
    lines.append(f"  fitted on: samples {start + 1}..{n_fit}{skipped}")
    if model.get_params().get("regularization") == "auto":
        chosen = model.fit_report_["regularization"]
        lines.append(
            f"  regularization: {chosen:g} (auto: the best predicted tracking of 0, 1e-4 .. 1e-1)"
        )
    memory = getattr(model, "fit_report_", {}).get("initial_memory")
    if memory is not None and model.get_params().get("initial_memory", "auto") != "auto":
        lines.append(f"  initial memory: {memory} (given)")
    elif memory is not None and model.get_params().get("constraints") == "physical":
        lines.append(
            Notice(
                f"  initial memory: {memory} (the better predicted tracking of 'virgin', eq. 18, "
                "and 'descended'; {initial_memory} gives it)",
                kind="line",
            )
        )
    if kind == "preisach":
        lines.append(f"  Everett fit: {_preisach_fit_line(model)}")
    lines.append(
        f"  fit error: rms {fit['rms_error_um']:.4g} µm "
        f"({fit['rms_error_percent']:.3g} % of {fit['displacement_range_um']:.4g} µm), "
        f"max {fit['max_error_um']:.4g} µm ({fit['max_error_percent']:.3g} %)"
    )
    lines.append(
        f"  compensation (estimated): tracking rms {tracking['tracking_rms_um']:.4g} µm over "
        f"the range, straight line v = (x - b)/a {tracking['baseline_rms_um']:.4g} µm "
        f"({tracking['ratio']:.2g}x)"
    )
    if np.isfinite(tracking["held_out_rms_um"]):
        lines.append(
            f"  cross-validated: {tracking['held_out_rms_um']:.4g} µm rms on the reversal "
            "branches each fit left out (references that turn inside the range)"
        )
    warnings = []
    unit = x_unit_warning(record.x, str(record.source)) if unit_check else None
    if unit is not None:  # the compensator would then clamp a reference in µm throughout
        warnings.append(unit)
    coverage = coverage_warning(v, start)
    if not tracking["ratio"] < LINE_MARGIN:
        others = " or ".join(k for k in ESTIMATORS if k != kind)
        warnings.append(
            Notice(
                f"the {label} compensator is predicted to track "
                + (
                    "no better than a straight line"
                    if not tracking["ratio"] < 1.0
                    else f"barely better than a straight line ({tracking['ratio']:.2g}x)"
                )
                + f" ({tracking['tracking_rms_um']:.3g} vs {tracking['baseline_rms_um']:.3g} µm "
                "rms), and other references may track worse than the line; "
                + (
                    "record a signal with turning points across the range ({excite_rich}), "
                    "or try {model}."
                    if coverage is not None
                    else "try {model}."
                ),
                kind="line",
                others=others,
            )
        )
    if coverage is not None:
        warnings.append(coverage)
    elif tracking["flatters"]:
        warnings.append(
            Notice(
                f"on reversal branches it was not fitted on, the {label} model is "
                f"{tracking['held_out_rms_um'] / tracking['tracking_rms_um']:.2g}x further "
                f"from the record ({tracking['held_out_rms_um']:.3g} µm) than the estimate "
                "above: a reference that turns inside the range may track that much worse. "
                "Record more turning points ({excite_rich}), or compare the other models.",
                kind="flatters",
            )
        )
    if chosen_range is not None and allow_extrapolation:
        why = extrapolation_error(chosen_range, v)
        if why is not None:  # allowed, and still said: the estimate does not cover it
            warnings.append(
                f"the voltage range {why}, as allowed: the model extrapolates there, and the "
                "estimate above does not cover it. Check the tracking there before relying "
                "on it."
            )
    if held is not None:
        lines.append(
            f"  hold-out:  last {held['n_holdout']} samples ({100 * holdout:g} %): model rms "
            f"{held['model_rms_um']:.4g} µm, straight line rms {held['line_rms_um']:.4g} µm: "
            f"{_verdict(held['improvement'])}"
        )
        lo, hi = float(v.min()), float(v.max())
        held_v = record.v[n_fit:]
        if held_v.min() < lo or held_v.max() > hi:
            warnings.append(
                f"the hold-out drives {held_v.min():.4g} .. {held_v.max():.4g} V, beyond the "
                f"fitted range {lo:.4g} .. {hi:.4g} V; the model extrapolates there. Hold out "
                "a part that stays inside the range."
            )
    return IdentificationResult(
        model=model,
        kind=kind,
        source=str(record.source),
        start=start,
        n_fit=n_fit,
        x_model=x_model,
        fit=fit,
        tracking=tracking,
        holdout=held,
        lines=lines,
        warnings=warnings,
    )


def _data_row(record, k: int) -> str:
    """Sample ``k`` of ``record`` as the user finds it: its data row (1-based) and time."""
    return f"data row {k + 1} (t = {float(record.t[k]):.6g} s)"


def _verdict(improvement: float) -> str:
    """``line rms / model rms`` in words: "2.5x better", or "1.14x worse" below 1."""
    if improvement >= 1.0:
        return f"{improvement:.3g}x better"
    if improvement > 0.0:
        return f"{1.0 / improvement:.3g}x worse"
    return "no better (the line fits the held-out part exactly)"


def _sizes(model) -> str:
    parts = []
    if hasattr(model, "n_operators"):
        parts.append(f"{model.n_operators} plays")
    if hasattr(model, "n_deadzones"):
        parts.append(f"{model.n_deadzones} dead-zones")
    return f" ({', '.join(parts)})" if parts else ""


def _preisach_fit_line(model) -> str:
    """How a Preisach model was fitted, in a few words."""
    report = model.fit_report_
    what = (
        f"{model.grid_size} x {model.grid_size} table"
        if model.everett == "table"
        else f"degree-{model.degree} polynomial"
    )
    if report["fit"] == "reversal-curves":
        how = f"reversal curves from {report['n_curves']} maxima"
        if model.everett == "polynomial":
            how += " (paper, Section III-A)"
    else:
        how = "least squares over the record, non-negative density"
    why = ""
    if model.fit_method == "auto":
        why = (
            " (auto: first-order descending curves from 8 or more maxima)"
            if report["fit"] == "reversal-curves"
            else " (auto: the record has too few first-order descending curves)"
        )
    return f"{what}, {how}{why}"
