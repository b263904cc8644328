"""A run's tracking: a reference and what the stage did, matched by time (``hystcomp evaluate``).

A user who ran ``hystcomp compensate`` and played its voltage on the stage has the reference
``(t, x_ref)`` and a measured run ``(t, x)`` (and usually the voltage ``v``). :func:`evaluate`
matches them by time, the reference interpolated linearly at the measured instants (the
measured samples outside the reference's time span are left out and counted), leaves out
the first ``skip`` seconds, and measures what DESIGN's metrics and the paper's Table I
measure (:mod:`hystcomp.experiment.metrics`):

* the tracking error ``e = x - x_ref``: its rms and largest magnitude in µm, and its mean
  (an offset of the sensor or of the reference shows there);
* the hysteresis of ``x`` against ``x_ref`` in % of the displacement range, over the whole
  loop and over its top quarter (the paper's saturation zone), when the reference rises
  and falls;
* the error over time: rms and maximum in equal spans of the run, where a drift (creep, a
  warming stage) or a start-up transient shows.

The result is an :class:`Evaluation` (a dataclass); the command line words it, as text or
as one JSON object.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping
from typing import Any

import numpy as np

from hystcomp._validation import as_signal, check_int, check_real
from hystcomp.errors import InvalidParameterError, InvalidSignalError, InvalidTypeError
from hystcomp.experiment.metrics import hysteresis_percent, tracking_errors

__all__ = ["ErrorSpan", "Evaluation", "evaluate"]

#: Spans of the error-over-time table by default.
DEFAULT_SPANS = 10
#: A share of measured samples outside the reference's time span above which the command
#: line warns (the two files may not belong together).
OUTSIDE_WARNING = 0.1


@dataclasses.dataclass(frozen=True)
class ErrorSpan:
    """The tracking error over one span of time.

    Attributes
    ----------
    t_start, t_end : float
        The span's first and last matched instant, s.
    rms_um, max_um : float
        Rms and largest ``|x - x_ref|`` over the span, µm.
    """

    t_start: float
    t_end: float
    rms_um: float
    max_um: float


@dataclasses.dataclass(frozen=True, eq=False)
class Evaluation:
    """How a measured run tracked its reference (see :func:`evaluate`).

    Attributes
    ----------
    t : ndarray
        The matched instants (s): the measured ones inside the reference's time span,
        after ``skip``.
    x_ref, x, e : ndarray
        The reference at those instants, the measured displacement and the error
        ``x - x_ref`` (µm).
    v : ndarray or None
        The measured voltage (V) at those instants, if the run holds one.
    rms_um, max_um, mean_um : float
        Rms, largest magnitude and mean of ``e`` (µm).
    range_um : float
        ``max(x_ref) - min(x_ref)`` over the matched instants (µm).
    hysteresis_pct, saturation_zone_pct : float or None
        Hysteresis of ``x`` against ``x_ref`` in % of the displacement range, whole loop
        and top quarter (None when the reference does not rise and fall).
    spans : tuple of ErrorSpan
        The error over time, in equal spans of the matched run.
    skip_s : float
        The seconds left out at the start.
    outside : int
        Measured samples outside the reference's time span (left out).
    interpolated : bool
        Whether the reference was interpolated (False: both share the instants).
    reference, measured : str
        Where the two came from (file names), for messages.
    """

    t: np.ndarray
    x_ref: np.ndarray
    x: np.ndarray
    e: np.ndarray
    v: np.ndarray | None
    rms_um: float
    max_um: float
    mean_um: float
    range_um: float
    hysteresis_pct: float | None
    saturation_zone_pct: float | None
    spans: tuple[ErrorSpan, ...]
    skip_s: float
    outside: int
    interpolated: bool
    reference: str = "reference"
    measured: str = "measured"

    @property
    def samples(self) -> int:
        """The number of matched samples."""
        return int(self.t.size)

    @property
    def outside_share(self) -> float:
        """``outside`` as a share of the measured samples after ``skip``."""
        total = self.outside + self.samples
        return self.outside / total if total else 0.0

    @property
    def warnings(self) -> list[str]:
        """A warning when more than :data:`OUTSIDE_WARNING` of the measured samples lie
        outside the reference's time span (the two may not belong together)."""
        if not self.outside_share > OUTSIDE_WARNING:
            return []
        return [
            (
                f"{self.outside} samples ({100 * self.outside_share:.3g} %) of {self.measured} lie "
                f"outside the time span of {self.reference} and are left out; check that the two "
                "belong together and that their time columns start alike."
            )
        ]

    @property
    def lines(self) -> list[str]:
        """The figures as a report, one line each: the match, the error, the hysteresis and
        the error over time."""
        span = self.range_um
        share = f" ({100 * self.rms_um / span:.3g} % of the {span:.4g} µm range)" if span else ""
        matched = (
            "interpolated at the measured instants" if self.interpolated else "the same instants"
        )
        lines = [
            f"tracking of {self.measured} against {self.reference}",
            f"  matched:    {self.samples} samples, t {self.t[0]:.6g} .. {self.t[-1]:.6g} s "
            f"(reference {matched}"
            + (f"; the first {self.skip_s:g} s left out" if self.skip_s else "")
            + (f"; {self.outside} outside the reference's time span" if self.outside else "")
            + ")",
            (
                f"  error:      rms {self.rms_um:.4g} µm{share}, max {self.max_um:.4g} µm, "
                f"mean {self.mean_um:.4g} µm"
            ),
        ]
        if self.hysteresis_pct is None:
            lines.append("  hysteresis: - (the reference does not rise and fall)")
        else:
            lines.append(
                f"  hysteresis: {self.hysteresis_pct:.3g} % of the range (top quarter, the "
                f"saturation zone: {self.saturation_zone_pct:.3g} %)"
            )
        lines.append("  error over time:")
        lines.append(f"    {'t (s)':>21}  {'rms (µm)':>9}  {'max (µm)':>9}")
        for part in self.spans:
            when = f"{part.t_start:.4g} .. {part.t_end:.4g}"
            lines.append(f"    {when:>21}  {part.rms_um:9.4g}  {part.max_um:9.4g}")
        return lines

    def to_dict(self) -> dict[str, Any]:
        """The figures (not the signals) as plain values, ready for JSON.

        Returns
        -------
        dict
            The file names, the errors (µm: rms, max, mean), the range (µm), the hysteresis
            and saturation-zone figures (%), the sample count and the time span (s).
        """
        return {
            "reference": self.reference,
            "measured": self.measured,
            "rms_um": self.rms_um,
            "max_um": self.max_um,
            "mean_um": self.mean_um,
            "range_um": self.range_um,
            "hysteresis_pct": self.hysteresis_pct,
            "saturation_zone_pct": self.saturation_zone_pct,
            "samples": self.samples,
            "t_start_s": float(self.t[0]),
            "t_end_s": float(self.t[-1]),
            "skip_s": self.skip_s,
            "outside": self.outside,
            "interpolated": self.interpolated,
            "spans": [dataclasses.asdict(span) for span in self.spans],
        }


def _signals(obj, what: str, keys, **read) -> dict[str, np.ndarray]:
    """``t``, ``x`` (and ``v`` if there) of a file, a Record, or a mapping of columns
    (a dict or a pandas DataFrame)."""
    if isinstance(obj, str | os.PathLike):
        from hystcomp.io.records import read_table

        optional = ("v",) if "v" in keys else ()
        return read_table(obj, ("x",), optional=optional, **read)
    if hasattr(obj, "t") and hasattr(obj, "x") and not isinstance(obj, Mapping):
        table = {"t": obj.t, "x": obj.x}  # a Record
        if "v" in keys and getattr(obj, "v", None) is not None:
            table["v"] = obj.v
    elif hasattr(obj, "__getitem__") and hasattr(obj, "keys"):
        names = set(obj.keys())
        if not {"t", "x"} <= names:
            raise InvalidParameterError(
                f"The {what!r} parameter of evaluate must hold columns 't' (s) and 'x' (µm). "
                f"Got columns {sorted(map(str, names))}; rename them, or pass a file."
            )
        table = {key: obj[key] for key in ("t", *keys) if key in names}
    else:
        raise InvalidTypeError(
            f"The {what!r} parameter of evaluate must be a data file, a Record or columns "
            f"'t' and 'x' (a dict or a DataFrame). Got {type(obj).__name__}."
        )
    out = {key: as_signal(values, f"{what}.{key}", min_samples=2) for key, values in table.items()}
    if len({a.size for a in out.values()}) > 1:
        raise InvalidSignalError(
            f"The columns of {what!r} have different lengths "
            f"({', '.join(f'{k}: {a.size}' for k, a in out.items())}); give one value each "
            "per instant."
        )
    if not np.all(np.diff(out["t"]) > 0):
        raise InvalidSignalError(
            f"The time 't' of {what!r} must be strictly increasing; sort it and remove "
            "repeated instants."
        )
    return out


def _source(obj, default: str) -> str:
    if isinstance(obj, str | os.PathLike):
        return os.fspath(obj)
    return str(getattr(obj, "source", default))


def _spans(t: np.ndarray, e: np.ndarray, count: int) -> tuple[ErrorSpan, ...]:
    count = min(count, t.size)
    edges = np.linspace(t[0], t[-1], count + 1)
    cuts = np.searchsorted(t, edges[1:-1], side="left")
    out = []
    for part_t, part_e in zip(np.split(t, cuts), np.split(e, cuts), strict=True):
        if part_t.size:
            rms, peak = tracking_errors(np.zeros(part_e.size), part_e)
            out.append(ErrorSpan(float(part_t[0]), float(part_t[-1]), rms, peak))
    return tuple(out)


def evaluate(
    reference,
    measured,
    *,
    skip: float = 0.0,
    spans: int = DEFAULT_SPANS,
    columns=None,
    sample_rate=None,
    x_unit=None,
    progress=None,
) -> Evaluation:
    """How well a measured run tracked its reference: rms, max, hysteresis, error over time.

    Parameters
    ----------
    reference : str, path-like, Record or mapping
        The reference: a data file with columns ``t`` (s) and ``x`` (µm), as
        ``hystcomp compensate`` reads it, or those columns (a dict, a DataFrame, a
        :class:`~hystcomp.io.records.Record`).
    measured : str, path-like, Record or mapping
        The measured run: ``t`` (s) and ``x`` (µm), and ``v`` (V) if it holds one.
    skip : float, default 0
        Seconds left out at the start of the matched run (a start-up transient, the first
        period, as the paper's Table I leaves it out).
    spans : int, default 10
        Equal spans of time of the error-over-time figures.
    columns, sample_rate, x_unit :
        How to read a measured *file* (:func:`~hystcomp.io.records.read_table`): its
        columns (``{"x": 3}`` or ``"t=1,x=3"``), its sample rate if it has no time column,
        its displacement unit.
    progress : callable, optional
        Called with the fraction read of the measured file.

    Returns
    -------
    Evaluation
        The errors (µm), the hysteresis and saturation-zone figures (%) and the error
        over time (s, µm).

    Raises
    ------
    InvalidParameterError
        If the two share no instant after ``skip``, or ``skip`` or ``spans`` is out of range.
    DataFileError
        If a file cannot be read (naming the file, the column and the fix).

    Examples
    --------
    >>> import numpy as np, hystcomp
    >>> t = np.arange(2000) / 1000.0
    >>> x_ref = 10.0 * (1.0 - np.cos(2 * np.pi * t))
    >>> run = hystcomp.evaluate({"t": t, "x": x_ref}, {"t": t, "x": x_ref + 0.1})
    >>> round(run.rms_um, 6), round(run.max_um, 6), run.interpolated
    (0.1, 0.1, False)
    """
    skip = check_real(skip, "skip", "evaluate")
    if skip < 0:
        raise InvalidParameterError(
            f"The 'skip' parameter of evaluate must be >= 0 (seconds left out at the start). "
            f"Got {skip!r}."
        )
    spans = check_int(spans, "spans", "evaluate", minimum=1)
    if isinstance(columns, str):
        from hystcomp.io.records import parse_columns

        columns = parse_columns(columns)
    ref = _signals(reference, "reference", ("x",))
    read = {"columns": columns, "sample_rate": sample_rate, "x_unit": x_unit}
    if progress is not None:
        read["progress"] = progress
    run = _signals(measured, "measured", ("x", "v"), **read)
    t = run["t"]
    start = t[0] + skip
    kept = t >= start
    inside = kept & (t >= ref["t"][0]) & (t <= ref["t"][-1])
    outside = int(np.count_nonzero(kept & ~inside))
    if np.count_nonzero(inside) < 2:
        raise InvalidParameterError(
            f"The measured run ({_source(measured, 'measured')}, t {t[0]:.6g} .. {t[-1]:.6g} s"
            + (f", {skip:g} s skipped" if skip else "")
            + f") shares fewer than two instants with the reference's time span "
            f"({ref['t'][0]:.6g} .. {ref['t'][-1]:.6g} s). Check that the two files belong "
            "together and that their time columns start alike"
            + (", or skip less." if skip else ".")
        )
    t = t[inside]
    same = ref["t"].size == run["t"].size and np.array_equal(ref["t"], run["t"])
    x_ref = ref["x"][inside] if same else np.interp(t, ref["t"], ref["x"])
    x = run["x"][inside]
    e = x - x_ref
    rms, peak = tracking_errors(x_ref, x)
    whole: float | None
    zone: float | None
    try:
        whole, zone = hysteresis_percent(x_ref, x)
    except InvalidSignalError:  # a reference that does not rise and fall: no loop
        whole = zone = None
    return Evaluation(
        t=t,
        x_ref=x_ref,
        x=x,
        e=e,
        v=run["v"][inside] if "v" in run else None,
        rms_um=rms,
        max_um=peak,
        mean_um=float(np.mean(e)),
        range_um=float(np.ptp(x_ref)),
        hysteresis_pct=whole,
        saturation_zone_pct=zone,
        spans=_spans(t, e, spans),
        skip_s=float(skip),
        outside=outside,
        interpolated=not same,
        reference=_source(reference, "reference"),
        measured=_source(measured, "measured"),
    )
