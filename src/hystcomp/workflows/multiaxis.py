"""Identify a multi-axis stage from one record: what ``hystcomp identify`` runs on an N-axis file.

The steps of :meth:`MultiAxisModel.fit <hystcomp.models.multiaxis.MultiAxisModel.fit>`,
with each axis identified as ``hystcomp identify`` identifies one axis (start-up transient,
tracking estimate, warnings; the family ``'auto'`` ranks the families per axis) on its
decoupled displacements:

1. the coupling ``M`` (:func:`~hystcomp.identify.coupling.fit_coupling`);
2. each axis's model on ``(v_i, (M^-1 x)_i)`` (:func:`~hystcomp.workflows.identify.
   identify_record`, or :func:`~hystcomp.workflows.auto.identify_best` for ``auto``), in
   parallel with joblib (``n_jobs``);
3. ``M`` again with the axes' models among the regressors
   (:func:`~hystcomp.identify.coupling.refine_coupling`).

The result carries the report lines and warnings, prefixed with their axis.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from hystcomp.errors import IdentificationError, InvalidSignalError
from hystcomp.identify.coupling import fit_coupling, refine_coupling
from hystcomp.identify.scoring import transient_end
from hystcomp.io.records import Record
from hystcomp.models.multiaxis import MultiAxisModel
from hystcomp.workflows.identify import LABELS, SIZE_OPTIONS, identify_record

__all__ = ["MultiAxisResult", "identify_axes"]


@dataclass(frozen=True, eq=False)
class MultiAxisResult:
    """What :func:`identify_axes` found.

    Attributes
    ----------
    model : MultiAxisModel
        The fitted stage.
    lines : list of str
        The report, one line each.
    warnings : list of str
        Each a sentence, its axis named.
    results : list
        Each axis's :class:`~hystcomp.workflows.identify.IdentificationResult`.
    """

    model: MultiAxisModel
    lines: list[str] = field(repr=False)
    warnings: list[str]
    results: list = field(repr=False)


def _identify_axis(record: Record, kind: str, options: dict):
    """One axis's identification (a top-level function, so that joblib can send it)."""
    if kind == "auto":
        from hystcomp.workflows.auto import identify_best

        chosen = identify_best(record, **options)
        return dataclasses.replace(chosen.best, lines=chosen.lines + chosen.best.lines)
    mine = {
        k: v for k, v in options.items() if k not in _family_options() or k in SIZE_OPTIONS[kind]
    }
    return identify_record(record, kind, **mine)


def _family_options() -> set[str]:
    return {name for names in SIZE_OPTIONS.values() for name in names}


def identify_axes(
    t, V, X, *, kind="auto", coupling=True, n_jobs=None, source="record", **options
) -> MultiAxisResult:
    """Identify every axis's hysteresis and the coupling of an N-axis record.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Time, s.
    V, X : ndarray, shape (n, N)
        Voltages (V) and displacements (µm).
    kind : {'auto', 'pi', 'mpi', 'preisach'}
        Each axis's family (``auto``: each axis its best predicted tracker).
    coupling : bool, default True
        Identify ``M`` (else ``M = I``: per-axis models of the raw readings).
    n_jobs : int or None
        Axes identified in parallel by joblib.
    source : str
        The record's name, for the report.
    **options
        Those of :func:`~hystcomp.workflows.identify.identify_record` (``voltage_range``,
        ``transient``, family options, ...); ``holdout`` is refused.

    Returns
    -------
    MultiAxisResult
        The fitted multi-axis model, and each axis's report lines and warnings,
        prefixed with the axis.

    Raises
    ------
    IdentificationError
        Axes that move together, or an axis that cannot be identified.
    """
    V = np.asarray(V, dtype=np.float64)
    X = np.asarray(X, dtype=np.float64)
    n_axes = V.shape[1]
    for i in range(n_axes):
        if np.ptp(V[:, i]) <= 0:
            raise InvalidSignalError(
                f"The voltage column 'v{i + 1}' of {source} is constant ({V[0, i]!r} V): every "
                "axis must sweep its range for its hysteresis to be identified (as the "
                "multi-axis excitation does). Check that the right column is named."
            )
    start = max(transient_end(V[:, i]) for i in range(n_axes))
    if coupling:
        found = fit_coupling(V, X, start=start)
        matrix = found.matrix
        H = X @ np.linalg.inv(matrix).T
    else:
        matrix, H = np.eye(n_axes), X
    records = [
        Record(t, V[:, i], H[:, i], source=f"{source} (axis {i + 1})") for i in range(n_axes)
    ]
    from joblib import Parallel, delayed

    try:
        results = list(
            Parallel(n_jobs=n_jobs)(delayed(_identify_axis)(r, kind, options) for r in records)
        )
    except IdentificationError as exc:
        raise IdentificationError(f"{exc} (an axis of {source})") from None
    axes = [r.model for r in results]
    if coupling:
        own = np.column_stack([axis.simulate(V[:, i]) for i, axis in enumerate(axes)])
        matrix = refine_coupling(V, X, own, matrix, start=start)
    model = MultiAxisModel.from_parameters(axes=axes, coupling=matrix)
    model.family = kind
    model.coupling = bool(coupling)
    predicted = model.simulate(V)
    rms = np.sqrt(np.mean((predicted[start:] - X[start:]) ** 2, axis=0))
    model.fit_report_ = {
        "n_axes": n_axes,
        "kinds": [a.kind for a in axes],
        "coupling_percent": float(100.0 * np.abs(matrix - np.eye(n_axes)).max()),
        "rms_error_um": rms.tolist(),
        "tracking_rms_um": [r.tracking["tracking_rms_um"] for r in results],
    }
    lines = [f"{n_axes}-axis model from {source}: x = M [H_1(v_1) .. H_{n_axes}(v_{n_axes})]"]
    if coupling:
        lines.append("  coupling M (row: sensor, column: axis driven; % off the diagonal):")
        for i in range(n_axes):
            cells = " ".join(
                f"{'1':>7}" if i == j else f"{100 * matrix[i, j]:+6.2f}%" for j in range(n_axes)
            )
            lines.append(f"    x{i + 1}: {cells}")
    else:
        lines.append("  coupling ignored (M = I): each axis fitted to its own sensor's reading")
    for i, r in enumerate(results):
        lines.append(
            f"  axis {i + 1}: {LABELS[r.kind]}, fit rms {rms[i]:.4g} µm (with the coupling), "
            f"compensation (estimated) {r.tracking['tracking_rms_um']:.4g} µm "
            f"({r.tracking['ratio']:.2g}x the straight line)"
        )
    for i, r in enumerate(results):
        lines += [f"  [axis {i + 1}] {line.strip()}" for line in r.lines]
    warnings = [f"axis {i + 1}: {w}" for i, r in enumerate(results) for w in r.warnings]
    return MultiAxisResult(model, lines, warnings, results)
