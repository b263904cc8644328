"""Choose the model family by what its compensator will do.

Which family tracks best changes from stage to stage, and the fit error cannot tell (every
family fits its record about equally well; Benchmarks, "Choosing the model family").
:func:`identify_best` fits every family the record determines
(:func:`~hystcomp.workflows.identify.identify_record` for each) and keeps the one whose
compensator is predicted to track a reference over the range best
(:func:`~hystcomp.identify.compensation.tracking_estimate`). The ranking, each family's
estimate and its error on held-out reversal branches (references that turn inside the range)
go with the result.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from hystcomp._notice import Notice
from hystcomp.errors import IdentificationError
from hystcomp.workflows.identify import (
    LABELS,
    SIZE_OPTIONS,
    IdentificationResult,
    identify_record,
)

__all__ = ["FAMILIES", "AutoResult", "identify_best"]

#: The families :func:`identify_best` tries, in the order that breaks a tie.
FAMILIES = ("preisach", "mpi", "pi")


@dataclass(frozen=True, eq=False)
class AutoResult:
    """What :func:`identify_best` found.

    Attributes
    ----------
    best : IdentificationResult
        The chosen family's identification (its model, report lines and warnings).
    ranking : list of (str, dict)
        ``(kind, tracking estimate)`` of every family fitted, the best first (see
        :func:`~hystcomp.identify.compensation.tracking_estimate`).
    skipped : dict
        ``{kind: reason}`` for the families the record could not determine.
    results : dict
        ``{kind: IdentificationResult}`` of every family fitted.
    lines : list of str
        The ranking, one line a family, to be printed before the chosen model's own report.
    """

    best: IdentificationResult
    ranking: list[tuple[str, dict]]
    skipped: dict[str, str] = field(default_factory=dict)
    results: dict[str, IdentificationResult] = field(default_factory=dict, repr=False)
    lines: list[str] = field(default_factory=list)

    @property
    def model(self):
        """The chosen model (fitted)."""
        return self.best.model

    @property
    def margin(self) -> float:
        """How many times the runner-up's estimate is the winner's (inf if alone)."""
        if len(self.ranking) < 2:
            return float("inf")
        first, second = (e["tracking_rms_um"] for _, e in self.ranking[:2])
        return second / first if first > 0 else float("inf")


def identify_best(record, *, families=FAMILIES, progress=None, **options) -> AutoResult:
    """Fit every family in ``families`` to ``record`` and keep the best predicted tracker.

    Parameters
    ----------
    record : hystcomp.io.records.Record
        The measured record.
    families : sequence of {'pi', 'mpi', 'preisach'}, optional
        The families tried [all three].
    progress : callable, optional
        ``progress(kind)`` returns the context manager entered around that family's fit
        (``hystcomp identify`` shows one status line per family).
    **options
        Those of :func:`~hystcomp.workflows.identify.identify_record` (``voltage_range``,
        ``transient``, ``holdout``, ...); a family option (``operators``, ``grid``, ...)
        goes to the families that take it.

    Returns
    -------
    AutoResult
        The chosen family's identification, the ranking by tracking estimate (µm rms),
        the families skipped and why, and the ranking's report lines.

    Raises
    ------
    IdentificationError
        If no family could be fitted (the message gives each one's reason).
    """
    family_options = {name for names in SIZE_OPTIONS.values() for name in names}
    results: dict[str, IdentificationResult] = {}
    skipped: dict[str, str] = {}
    for kind in families:
        mine = {
            k: v for k, v in options.items() if k not in family_options or k in SIZE_OPTIONS[kind]
        }
        if progress is not None:
            mine["progress"] = progress(kind)
        try:
            results[kind] = identify_record(record, kind, **mine)
        except IdentificationError as exc:
            skipped[kind] = str(exc)
    if not results:
        raise IdentificationError(
            "No model family could be identified from the record: "
            + "; ".join(f"{LABELS[k]}: {why}" for k, why in skipped.items())
        )
    order = sorted(
        results, key=lambda k: (results[k].tracking["tracking_rms_um"], families.index(k))
    )
    ranking = [(k, results[k].tracking) for k in order]
    best = results[order[0]]
    lines = [
        "auto: the family whose compensator is predicted to track best over the range, of "
        + ", ".join(LABELS[k] for k in families)
    ]
    top = ranking[0][1]["tracking_rms_um"]
    for i, (kind, est) in enumerate(ranking):
        times = est["tracking_rms_um"] / top if top > 0 else float("inf")
        note = "chosen" if i == 0 else f"{times:.3g}x the {LABELS[order[0]]}'s"
        held = est["held_out_rms_um"]
        held_text = f", cross-validated {held:.3g} µm" if math.isfinite(held) else ""
        lines.append(
            f"  {LABELS[kind]:<9} {est['tracking_rms_um']:.4g} µm ({est['ratio']:.2g}x the "
            f"straight line{held_text}): {note}"
        )
    for kind, why in skipped.items():
        lines.append(f"  {LABELS[kind]:<9} not identified: {why}")
    inside = _held_out_best(ranking)
    if inside is not None:
        kind, held, winner_held = inside
        lines.append(
            Notice(
                f"  for references that turn inside the range the {LABELS[kind]} model is "
                f"predicted better (cross-validated {held:.3g} µm against {winner_held:.3g} "
                "µm): {model}",
                kind="line",
                others=kind,
            )
        )
    return AutoResult(best, ranking, skipped, results, lines)


#: Another family is named for references that turn inside the range when its held-out
#: error is below the winner's by this factor.
INSIDE_MARGIN = 1.5


def _held_out_best(ranking):
    """``(kind, held out, winner's held out)`` of a family other than the winner whose error
    on held-out reversal branches is :data:`INSIDE_MARGIN` times lower, or None."""
    winner = ranking[0][1]["held_out_rms_um"]
    others = [
        (e["held_out_rms_um"], k) for k, e in ranking[1:] if math.isfinite(e["held_out_rms_um"])
    ]
    if not others or not math.isfinite(winner):
        return None
    held, kind = min(others)
    return (kind, held, winner) if INSIDE_MARGIN * held < winner else None
