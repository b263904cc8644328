"""A model from a measured record, of any kind, alone or paired: what ``hystcomp identify`` runs.

:func:`identify_model` picks the workflow the options ask for: one family
(:func:`~hystcomp.workflows.identify.identify_record`), the best predicted of every family
(:func:`~hystcomp.workflows.auto.identify_best`), either one paired with the linear dynamics
of a second record (:func:`~hystcomp.workflows.pair.identify_pair_record`), or the dynamics
alone (:func:`~hystcomp.workflows.pair.identify_dynamics_record`). Its :class:`ModelResult`
holds the model to save and every step's result, whose report lines and warnings it joins
in order. :func:`check_identification` refuses, before any record is read, the arguments that
a kind or an N-axis record does not take, each named as a notice's argument
(:class:`hystcomp._notice.Notice`), which the command line says as its option.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from hystcomp._notice import Notice
from hystcomp.errors import InvalidParameterError
from hystcomp.workflows.auto import identify_best
from hystcomp.workflows.identify import (
    SIZE_OPTIONS,
    IdentificationResult,
    check_options,
    identify_record,
)
from hystcomp.workflows.pair import identify_dynamics_record, identify_pair_record

__all__ = ["ModelResult", "check_identification", "identify_model"]


@dataclass(frozen=True, eq=False)
class ModelResult:
    """What :func:`identify_model` found.

    Its ``lines`` and ``warnings`` gather those of every step, in order.

    Attributes
    ----------
    model : object
        The model to save: a hysteresis model, a pair or the linear dynamics.
    hysteresis : IdentificationResult or None
        The hysteresis model's identification (None for the dynamics alone).
    steps : list
        The result of each workflow run, in order (the ranking of ``'auto'``, the hysteresis
        model's identification, the pair's), each with its report lines and warnings.
    """

    model: Any
    hysteresis: IdentificationResult | None
    steps: list

    @property
    def lines(self) -> list[str]:
        """Every step's report lines, in order."""
        return [line for step in self.steps for line in getattr(step, "lines", ())]

    @property
    def warnings(self) -> list[str]:
        """Every step's warnings, in order."""
        return [warning for step in self.steps for warning in getattr(step, "warnings", ())]


def identify_model(
    record,
    kind="auto",
    *,
    dynamics_record=None,
    holdout: float | None = None,
    progress=None,
    **options,
) -> ModelResult:
    """Identify a model of ``kind`` from ``record``, paired with the dynamics if given.

    Parameters
    ----------
    record : hystcomp.io.records.Record
        The measured record (for ``'dynamics'``: the answer to the dynamics excitation).
    kind : {'auto', 'pi', 'mpi', 'preisach', 'dynamics'} or estimator, default 'auto'
        The model family (``'auto'``: the one predicted to track best), or an estimator.
    dynamics_record : hystcomp.io.records.Record, optional
        The answer to the dynamics excitation: the model is identified with the linear
        dynamics as one pair.
    holdout : float, optional
        The fraction of ``record`` held out at its end (not with ``dynamics_record``).
    progress : callable, optional
        ``progress(kind)`` returns the context manager entered around that family's fit.
    **options
        Those of :func:`~hystcomp.workflows.identify.identify_record` (``voltage_range``,
        ``transient``, family options, ...).

    Returns
    -------
    ModelResult
        The fitted model (hysteresis, pair or dynamics), the hysteresis model's
        identification and each step's result with its report lines and warnings.

    Raises
    ------
    InvalidParameterError
        An argument that ``kind`` does not take (:func:`check_identification`), or
        ``holdout`` with ``dynamics_record``.
    """
    if isinstance(kind, str):  # an argument that the kind does not take is refused
        check_identification(kind, holdout=holdout, dynamics_record=dynamics_record, **options)
    if dynamics_record is not None and holdout is not None:
        raise InvalidParameterError(
            "The 'holdout' argument of identify_model does not apply with a dynamics record: "
            "the pair's tracking is estimated on the dynamics record's triangles. Hold out "
            "without it."
        )
    if isinstance(kind, str) and kind == "dynamics":
        found = identify_dynamics_record(record)
        return ModelResult(found.model, None, [found])
    steps: list = []
    if isinstance(kind, str) and kind == "auto":
        chosen = identify_best(record, holdout=holdout, progress=progress, **options)
        steps, result = [chosen], chosen.best
    elif dynamics_record is None:
        if progress is not None:
            options["progress"] = progress(getattr(kind, "kind", kind))
        result = identify_record(record, kind, holdout=holdout, **options)
    if dynamics_record is None:
        return ModelResult(result.model, result, [*steps, result])
    if steps:  # the model auto fitted, not fitted again
        paired = identify_pair_record(record, dynamics_record, result.model, hysteresis=result)
    else:
        if progress is not None:
            options["progress"] = progress(getattr(kind, "kind", kind))
        paired = identify_pair_record(record, dynamics_record, kind, **options)
    return ModelResult(paired.model, paired.hysteresis, [*steps, paired.hysteresis, paired])


#: The options that size or shape the hysteresis model, of every family, in order.
FAMILY = tuple(dict.fromkeys(name for names in SIZE_OPTIONS.values() for name in names))
#: What the linear dynamics and an N-axis record leave out: (arguments, what they are).
_NOT_TAKEN = {
    "dynamics": (
        (*FAMILY, "transient", "voltage_range", "holdout", "dynamics_record"),
        "{set_kind}",
    ),
    "axes": (("holdout", "dynamics_record", "plot"), "an N-axis record"),
}


def check_identification(kind="auto", *, axes: bool = False, **given) -> dict:
    """Refuse, before any record is read, the arguments that an identification of ``kind``
    does not take (:func:`identify_model`, or N axes'
    :func:`~hystcomp.workflows.multiaxis.identify_axes`).

    Parameters
    ----------
    kind : {'auto', 'pi', 'mpi', 'preisach', 'dynamics'}, default 'auto'
        The model family.
    axes : bool, default False
        The record has N axes (columns v1..vN, x1..xN).
    **given
        The arguments (None or False: not given): the family options of
        :func:`~hystcomp.workflows.identify.check_options`, ``transient``,
        ``voltage_range``, ``holdout``, ``dynamics_record``, ``n_jobs`` (N axes only) and
        ``plot`` (the figure of the fit, of one axis).

    Returns
    -------
    dict
        The family options given, checked (:func:`~hystcomp.workflows.identify.check_options`).

    Raises
    ------
    InvalidParameterError
        An argument that ``kind`` or the record does not take, or a family option refused.

    Examples
    --------
    >>> check_identification("pi", operators=8, holdout=0.2)
    {'operators': 8}
    """
    if axes and kind == "dynamics":
        raise InvalidParameterError(
            Notice("{set_kind} does not apply to an N-axis record.", value=kind)
        )
    names, why = _NOT_TAKEN["axes"] if axes else _NOT_TAKEN.get(kind, ((), ""))
    for name in names:
        if given.get(name) not in (None, False):
            raise InvalidParameterError(
                Notice(f"{{arg_{name}}} does not apply to {why}.", value=kind)
            )
    if not axes and given.get("n_jobs") is not None:
        raise InvalidParameterError(
            Notice("{arg_n_jobs} applies to N-axis records (columns v1..vN, x1..xN).")
        )
    checked = check_options(kind, **{k: given.get(k) for k in FAMILY})
    return {k: v for k, v in checked.items() if v is not None}
