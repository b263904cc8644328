"""A model from a measured record, of any kind, alone or paired: what ``hystcomp identify`` runs.

:func:`identify_model` picks the workflow the options ask for: one family
(:func:`~hystcomp.workflows.identify.identify_record`), the best predicted of every family
(:func:`~hystcomp.workflows.auto.identify_best`), either one paired with the linear dynamics
of a second record (:func:`~hystcomp.workflows.pair.identify_pair_record`), or the dynamics
alone (:func:`~hystcomp.workflows.pair.identify_dynamics_record`). Its :class:`ModelResult`
holds the model to save and every step's result, whose report lines and warnings it joins
in order.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from hystcomp.errors import InvalidParameterError
from hystcomp.workflows.auto import identify_best
from hystcomp.workflows.identify import IdentificationResult, identify_record
from hystcomp.workflows.pair import identify_dynamics_record, identify_pair_record

__all__ = ["ModelResult", "identify_model"]


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
    """
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
