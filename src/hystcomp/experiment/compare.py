"""The paper's whole experiment (Section V) on the twin: identify, compensate, track, measure.

1. Run the paper's identification signals on the twin: the PI/MPI triangles of 30..120 V
   (Section IV-A) and the Preisach sinusoids of 5..120 V (Section III-A), both at 1 Hz.
2. Identify the three models from those records (:func:`identify_models`) and the
   uncompensated baseline's gain ``k_lin`` (:mod:`hystcomp.experiment.baseline`).
3. Track triangles at 1, 10 and 50 Hz with each of the four methods and measure the
   errors (Table I) and the hysteresis (Fig. 9).

:func:`run_comparison` returns everything as a :class:`Comparison`; the files (tables,
figures, report) are written by :func:`hystcomp.experiment.report.write_outputs`.
"""

from __future__ import annotations

import dataclasses
import time
import warnings
from collections.abc import Callable

import numpy as np

from hystcomp._validation import MAX_SIGNAL_SAMPLES, check_int, check_real
from hystcomp.errors import InvalidParameterError, InvalidTypeError
from hystcomp.experiment.baseline import LinearCompensator, linear_gain
from hystcomp.experiment.references import FREQUENCIES, REFERENCE_FRACTION, triangle_reference
from hystcomp.experiment.tracking import TrackingResult, check_compensator, run_tracking
from hystcomp.identify.excitation import (
    PREISACH_AMPLITUDES,
    sinusoid_sequence,
    triangle_sequence,
)
from hystcomp.io.records import Record
from hystcomp.models.mpi import ModifiedPrandtlIshlinskii
from hystcomp.models.pi import PrandtlIshlinskii
from hystcomp.models.preisach import Preisach
from hystcomp.paper import DATASHEET_GAIN, FIG5_AMPLITUDES, METHODS, N_DEADZONES, N_OPERATORS
from hystcomp.plant import Twin, TwinParameters, creep_twin

#: The model kinds that :func:`identify_models` returns, and the amplitudes of Fig. 5.
MODEL_KINDS = ("preisach", "pi", "mpi")


@dataclasses.dataclass(frozen=True)
class CompareConfig:
    """What to run. The defaults are the paper's experiment.

    Attributes
    ----------
    seed : int
        Seed of the twin's sensor noise.
    periods : int
        Periods of each tracking reference (the first is left out of the metrics).
    frequencies : tuple of float
        Reference frequencies in Hz.
    reference_fraction : float
        Peak of the references as a fraction of the largest displacement measured in the
        PI/MPI identification record (see :mod:`hystcomp.experiment.references`).
    preisach_amplitudes : tuple of float
        Amplitudes (V) of the Preisach identification sinusoids.
    n_operators, n_deadzones, preisach_degree : int
        Model sizes: 16 plays, 16 dead-zones and the cubic Everett function of the paper.
    twin : TwinParameters
        The simulated axis: the default twin with 3 % creep (:func:`creep_twin`), as a
        real stage has; the paper's Table I is measured on it too (creep adds about
        0.1 µm rms to the uncompensated 1 Hz run and moves the compensated ones by a few
        hundredths).
    dynamics : bool
        Also run the compensators with an inverse of the linear dynamics, at 1 .. 200 Hz
        and on a step (beyond the paper; :mod:`hystcomp.experiment.compare_dynamics`).
    """

    seed: int = 0
    periods: int = 3
    frequencies: tuple[float, ...] = FREQUENCIES
    reference_fraction: float = REFERENCE_FRACTION
    preisach_amplitudes: tuple[float, ...] = PREISACH_AMPLITUDES
    n_operators: int = N_OPERATORS
    n_deadzones: int = N_DEADZONES
    preisach_degree: int = 3
    twin: TwinParameters = dataclasses.field(default_factory=creep_twin)
    dynamics: bool = True

    def __post_init__(self):
        owner = "CompareConfig"
        check_int(self.seed, "seed", owner, minimum=0)
        check_int(self.periods, "periods", owner, minimum=2)
        for name in ("n_operators", "n_deadzones", "preisach_degree"):
            check_int(getattr(self, name), name, owner)
        fraction = check_real(self.reference_fraction, "reference_fraction", owner, positive=True)
        if fraction > 1.0:
            raise InvalidParameterError(
                f"The 'reference_fraction' parameter of {owner} must be in (0, 1]: a reference "
                f"beyond the measured stroke cannot be tracked. Got {fraction!r} instead."
            )
        for name in ("frequencies", "preisach_amplitudes"):
            values = tuple(check_real(f, name, owner, positive=True) for f in getattr(self, name))
            if not values:
                raise InvalidParameterError(f"The {name!r} parameter of {owner} is empty.")
            object.__setattr__(self, name, values)
        if not isinstance(self.twin, TwinParameters):
            raise InvalidTypeError(
                f"The 'twin' parameter of {owner} must be a TwinParameters. "
                f"Got {type(self.twin).__name__}."
            )
        # the slowest reference is the longest: refused now, not after the identification
        longest = self.periods * self.twin.sample_rate / min(self.frequencies)
        if longest > MAX_SIGNAL_SAMPLES:
            raise InvalidParameterError(
                f"The 'periods' parameter of {owner} (--periods) makes the {min(self.frequencies):g} "
                f"Hz reference {longest:.3g} samples long, more than {MAX_SIGNAL_SAMPLES:.0e}. Got "
                f"{self.periods}; use at most {int(MAX_SIGNAL_SAMPLES * min(self.frequencies) / self.twin.sample_rate)}."
            )

    @classmethod
    def quick(cls, **changes) -> CompareConfig:
        """A short run for tests and a first look: 2 periods, four Preisach sinusoids.

        Parameters
        ----------
        **changes
            Further settings to change by name.

        Returns
        -------
        CompareConfig
            The short configuration.
        """
        changes = {"periods": 2, "preisach_amplitudes": FIG5_AMPLITUDES, **changes}
        return cls(**changes)


@dataclasses.dataclass(frozen=True, eq=False)
class Comparison:
    """Everything the experiment produced.

    Attributes
    ----------
    config : CompareConfig
    record_pi, record_preisach, record_loops : Record
        The twin's answers to the PI/MPI triangles, the Preisach sinusoids, and the
        30/60/90/120 V sinusoids of Fig. 5.
    models : dict
        The identified models by kind (``"preisach"``, ``"pi"``, ``"mpi"``).
    gain : float
        ``k_lin`` of the uncompensated baseline, µm/V.
    reference_amplitude : float
        Peak of the triangle references, µm.
    results : dict
        ``results[frequency][method]`` is a :class:`TrackingResult`.
    datasheet : dict
        ``datasheet[frequency]``: the uncompensated run with the datasheet gain instead.
    preisach_exact : dict
        ``preisach_exact[frequency]``: the Preisach model's exact inverse in place of the
        inverse multiplicative structure (empty if the Preisach model has no exact inverse).
    paper_fit : dict
        ``paper_fit[kind]`` for each model kind: the lowest frequency tracked with the
        paper's own fit (:func:`identify_models` ``as_printed``), for the report (empty with
        a custom ``identify``).
    seconds : float
        Wall-clock time of the run.
    """

    config: CompareConfig
    record_pi: Record
    record_preisach: Record
    record_loops: Record
    models: dict
    gain: float
    reference_amplitude: float
    results: dict[float, dict[str, TrackingResult]]
    datasheet: dict[float, TrackingResult]
    preisach_exact: dict[float, TrackingResult]
    seconds: float
    dynamics: object = None  # compare_dynamics.DynamicsComparison (beyond the paper)
    paper_fit: dict[str, TrackingResult] = dataclasses.field(default_factory=dict)


def identify_models(
    record_pi: Record,
    record_preisach: Record,
    config: CompareConfig | None = None,
    *,
    as_printed: bool = False,
) -> dict:
    """Identify the paper's three models from the twin's records.

    PI and MPI (16 plays, 16 dead-zones, Section IV-A) from the triangle record; Preisach
    (cubic Everett function, eq. 5) from the sinusoid record. Each model's ``inverse()`` is
    its compensator. PI and MPI use the library's defaults: physical constraints
    (non-negative play weights beyond the first) and, for MPI, the regularisation whose
    compensator is predicted to track best (:mod:`hystcomp.identify.compensation`);
    The Preisach fit is the paper's with ``X(v, v) = 0`` imposed, as eq. 2 implies (fitted
    free, the cubic's ``X(v, v)`` makes the output step at every reversal).

    With ``as_printed`` the three are fitted exactly as printed, for the report: eq. 5
    fitted free to the reversal curves (``zero_diagonal=False``); eq. 12 and eq. 19 with the
    partial-sum constraints only, no regularisation (``constraints="paper"``,
    ``regularization=0``).

    Parameters
    ----------
    record_pi : Record
        The twin's answer to the triangles.
    record_preisach : Record
        The twin's answer to the sinusoids.
    config : CompareConfig, optional
        The comparison's settings (the defaults if None).
    as_printed : bool, optional
        Fit eqs. 5, 12 and 19 as printed instead of with the library's defaults.

    Returns
    -------
    dict
        ``{"preisach": ..., "pi": ..., "mpi": ...}``, the fitted models.
    """
    config = CompareConfig() if config is None else config
    paper: dict = {"constraints": "paper"} if as_printed else {}
    unregularized: dict = {"regularization": 0.0} if as_printed else {}
    pi = PrandtlIshlinskii(n_operators=config.n_operators, **paper)
    mpi = ModifiedPrandtlIshlinskii(
        n_operators=config.n_operators, n_deadzones=config.n_deadzones, **paper, **unregularized
    )
    # the paper's fit (Section III-A), not the library's default; X(v, v) = 0 (eq. 2) unless
    # as printed
    preisach = Preisach(
        degree=config.preisach_degree,
        everett="polynomial",
        fit_method="reversal-curves",
        zero_diagonal=not as_printed,
    )
    return {
        "preisach": preisach.fit(record_preisach.v, record_preisach.x),
        "pi": pi.fit(record_pi.v, record_pi.x),
        "mpi": mpi.fit(record_pi.v, record_pi.x),
    }


def paper_fits(record_pi: Record, record_preisach: Record, config: CompareConfig) -> dict:
    """Deprecated: ``identify_models(..., as_printed=True)``.

    Parameters
    ----------
    record_pi, record_preisach : Record
        The triangle and sinusoid records.
    config : CompareConfig
        The settings.

    Returns
    -------
    dict
        The models fitted as printed, by kind.
    """
    warnings.warn(
        "paper_fits is deprecated; use identify_models(..., as_printed=True).",
        DeprecationWarning,
        stacklevel=2,
    )
    return identify_models(record_pi, record_preisach, config, as_printed=True)


def run_comparison(
    config: CompareConfig | None = None,
    *,
    identify: Callable[[Record, Record, CompareConfig], dict] | None = None,
    progress: Callable[[str], None] | None = None,
    table1: Callable[[Comparison], None] | None = None,
    twin_dynamics: Callable[[], tuple | None] | None = None,
) -> Comparison:
    """Run the paper's experiment on the twin.

    Parameters
    ----------
    config : CompareConfig, optional
        What to run; the paper's experiment by default.
    identify : callable, optional
        ``identify(record_pi, record_preisach, config) -> {"preisach": m, "pi": m, "mpi": m}``
        where each model has ``inverse()``; :func:`identify_models` by default.
    progress : callable, optional
        Called with one line of text at each stage.
    table1 : callable, optional
        Called with the comparison as far as Table I (records, models, ``results``,
        ``datasheet``, ``preisach_exact``; no ``dynamics`` or ``paper_fit`` yet) as soon
        as it is measured: ``hystcomp compare`` draws the paper's figures meanwhile.
    twin_dynamics : callable, optional
        Returns what :func:`~hystcomp.experiment.compare_dynamics.identify_twin_pairs`
        returns for ``config``, computed elsewhere (``hystcomp compare``: in a second
        process, from the start), or None: then it is computed here, from this run's
        records and models.

    Returns
    -------
    Comparison
    """
    config = CompareConfig() if config is None else config
    if not isinstance(config, CompareConfig):
        raise InvalidTypeError(f"'config' must be a CompareConfig. Got {type(config).__name__}.")
    identify = identify_models if identify is None else identify
    say = progress or (lambda _line: None)
    start = time.perf_counter()
    twin = Twin(config.twin, seed=config.seed)
    fs = twin.sample_rate

    say("identification experiments on the twin (triangles 30..120 V, sinusoids 5..120 V)")
    record_pi, record_preisach = measure_identification(config, twin)
    record_loops = _measure(twin, sinusoid_sequence(FIG5_AMPLITUDES, sample_rate=fs))

    say("identifying the Preisach, PI and MPI models")
    models = identify(record_pi, record_preisach, config)
    missing = [kind for kind in MODEL_KINDS if kind not in models]
    if missing:
        raise InvalidParameterError(f"'identify' returned no model for {missing}.")
    gain = linear_gain(record_pi.v, record_pi.x)
    lo, hi = twin.voltage_range
    compensators = {"uncompensated": LinearCompensator(gain, (lo, hi))}
    for kind in MODEL_KINDS:
        compensators[kind] = check_compensator(models[kind].inverse(), f"{kind} compensator")
    datasheet_baseline = LinearCompensator(DATASHEET_GAIN, (lo, hi))
    exact = None
    if isinstance(models["preisach"], Preisach):
        exact = check_compensator(models["preisach"].inverse(method="exact"), "exact inverse")

    amplitude = config.reference_fraction * float(record_pi.x.max())
    results: dict[float, dict[str, TrackingResult]] = {}
    datasheet: dict[float, TrackingResult] = {}
    preisach_exact: dict[float, TrackingResult] = {}
    for f in config.frequencies:
        say(f"tracking a {f:g} Hz triangle of 0..{amplitude:.1f} µm with the four methods")
        _, x_ref = triangle_reference(amplitude, f, periods=config.periods, sample_rate=fs)
        results[f] = {
            m: run_tracking(compensators[m], twin, x_ref, frequency=f, method=m) for m in METHODS
        }
        datasheet[f] = run_tracking(
            datasheet_baseline, twin, x_ref, frequency=f, method="uncompensated (datasheet gain)"
        )
        if exact is not None:
            preisach_exact[f] = run_tracking(
                exact, twin, x_ref, frequency=f, method="preisach (exact inverse)"
            )
    measured = Comparison(
        config=config,
        record_pi=record_pi,
        record_preisach=record_preisach,
        record_loops=record_loops,
        models=models,
        gain=gain,
        reference_amplitude=amplitude,
        results=results,
        datasheet=datasheet,
        preisach_exact=preisach_exact,
        seconds=time.perf_counter() - start,
    )
    if table1 is not None:
        table1(measured)
    dynamics = None
    if config.dynamics:
        from hystcomp.experiment.compare_dynamics import identify_twin_pairs, run_dynamics

        say("identifying the linear dynamics; tracking with their inverse up to 200 Hz")
        identified = None if twin_dynamics is None else twin_dynamics()
        if identified is None:
            identified = identify_twin_pairs(config, (record_pi, record_preisach), models)
        dynamics = run_dynamics(
            twin,
            compensators,
            amplitude,
            periods=config.periods,
            frequencies=config.frequencies,
            identified=identified,
        )
    paper_fit: dict[str, TrackingResult] = {}
    if identify is identify_models:
        low = min(config.frequencies)
        _, x_ref = triangle_reference(amplitude, low, periods=config.periods, sample_rate=fs)
        for kind, model in identify_models(
            record_pi, record_preisach, config, as_printed=True
        ).items():
            paper_fit[kind] = run_tracking(
                model.inverse(), twin, x_ref, frequency=low, method=f"{kind} (paper's fit)"
            )
    return dataclasses.replace(
        measured, dynamics=dynamics, paper_fit=paper_fit, seconds=time.perf_counter() - start
    )


def measure_identification(config: CompareConfig, twin: Twin | None = None):
    """``(record_pi, record_preisach)``: the twin's answers to the paper's identification
    signals, the triangles then the sinusoids, from ``twin`` (by default a new one of
    ``config``'s parameters and seed, as :func:`run_comparison` starts with).

    Parameters
    ----------
    config : CompareConfig
        The comparison's settings.
    twin : Twin, optional
        The twin to measure (a new one of ``config``'s if None).

    Returns
    -------
    record_pi : Record
        The answer to the triangles.
    record_preisach : Record
        The answer to the sinusoids.
    """
    twin = Twin(config.twin, seed=config.seed) if twin is None else twin
    fs = twin.sample_rate
    record_pi = _measure(twin, triangle_sequence(sample_rate=fs))
    record_preisach = _measure(twin, sinusoid_sequence(config.preisach_amplitudes, sample_rate=fs))
    return record_pi, record_preisach


def twin_pairs(config: CompareConfig):
    """What :func:`run_comparison` identifies for its dynamics part, from scratch: the
    records and models of ``config`` (the same seeded twin gives the same ones), then
    :func:`~hystcomp.experiment.compare_dynamics.identify_twin_pairs`. ``hystcomp compare``
    runs it in a second process from its start.

    Parameters
    ----------
    config : CompareConfig
        The comparison's settings.

    Returns
    -------
    tuple of (Record, dict)
        What :func:`~hystcomp.experiment.compare_dynamics.identify_twin_pairs` returns.
    """
    from hystcomp.experiment.compare_dynamics import identify_twin_pairs

    record_pi, record_preisach = measure_identification(config)
    models = identify_models(record_pi, record_preisach, config)
    return identify_twin_pairs(config, (record_pi, record_preisach), models)


def _measure(twin: Twin, signal: tuple[np.ndarray, np.ndarray]) -> Record:
    t, v = signal
    return Record(t=t, v=v, x=twin.run(v), source="the twin")
