"""Beyond the paper: the compensators with an inverse of the linear dynamics, on the twin.

``hystcomp compare`` runs this after Table I, on the same twin and with the same models:

1. the twin's answer to ``hystcomp excite dynamics`` (9.2 s of signal), and the MPI and
   Preisach models each identified with the linear dynamics as one pair
   (:func:`hystcomp.models.hammerstein.fit_pair`: the dynamics behind the model, the model
   in front of the dynamics, from the model's own identification record);
2. triangles at 1, 10 and 50 Hz with "MPI + dynamics" and "Preisach + dynamics", and at
   100 and 200 Hz with every method, with and without the inverse of the dynamics;
3. a step to half the reference's peak, held 3 s (creep), with and without it.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np

from hystcomp.experiment.references import triangle_reference
from hystcomp.experiment.tracking import TrackingResult, error_rows, run_tracking
from hystcomp.identify.dynamics import dynamics_excitation
from hystcomp.io.records import Record
from hystcomp.models.hammerstein import fit_pair
from hystcomp.plant import Twin

#: Frequencies of the rows with the dynamics (Hz): Table I's, and two faster.
FAST_FREQUENCIES = (100.0, 200.0)
#: Methods that get a "+ dynamics" row at every frequency, and at the fast ones only.
WITH_DYNAMICS = ("preisach", "mpi")
STEP_HOLD = 3.0  # s
STEP_FROM = 0.02  # s after the step: the window of the step's mean |error| starts here
#: Second entropy word of the seed of the dynamics record's sensor noise (the first is the
#: comparison's seed): a stream of its own, see :func:`identify_twin_pairs`.
DYNAMICS_STREAM = 1


@dataclasses.dataclass(frozen=True, eq=False)
class DynamicsComparison:
    """What the dynamics part of ``compare`` produced.

    Attributes
    ----------
    record : Record
        The twin's answer to the dynamics excitation.
    pairs : dict
        ``pairs[method]``: the :class:`HammersteinModel` of that method's model and the
        twin's dynamics, identified together.
    results : dict
        ``results[frequency][label]``: :class:`TrackingResult`; labels are the methods
        (fast frequencies only) and ``"<method> + dynamics"``.
    step : dict
        ``step[label] = (t, x_ref, x)`` for the step and hold, ``label`` as above.
    step_error : dict
        ``step_error[label]``: mean |error| in µm from :data:`STEP_FROM` s to the end.
    step_drift : dict
        ``step_drift[label]``: how far the error moves from :data:`STEP_FROM` s to the end,
        µm (means over 10 ms at each end): the creep left uncompensated.
    """

    record: Record
    pairs: dict
    results: dict
    step: dict
    step_error: dict
    step_drift: dict


def twin_dynamics_record(twin_params, seed: int) -> Record:
    """The twin's answer to the dynamics excitation, from a twin of its own at rest whose
    sensor noise is drawn from a stream of its own (``seed``, :data:`DYNAMICS_STREAM`): it
    does not depend on how many runs came before (``--periods``, ``--quick``).

    Parameters
    ----------
    twin_params : TwinParameters
        The twin's parameters.
    seed : int
        The comparison's seed.

    Returns
    -------
    Record
        The record of the dynamics excitation.
    """
    stream = int(np.random.SeedSequence([seed, DYNAMICS_STREAM]).generate_state(1)[0])
    twin = Twin(twin_params, seed=stream)
    t, v = dynamics_excitation(sample_rate=twin.sample_rate, voltage_range=twin.voltage_range)
    return Record(t=t, v=v, x=twin.run(v), source="the twin")


def identify_twin_pairs(config, records, models) -> tuple[Record, dict]:
    """Step 1 of the module: the dynamics record, and the pair of each method's model.

    ``records`` (``(record_pi, record_preisach)``) and ``models`` are the comparison's
    (:func:`hystcomp.experiment.compare.twin_pairs` measures and identifies them again,
    as the comparison does, for ``hystcomp compare``'s second process). The inverses'
    designs go with the pairs (pickled).

    Parameters
    ----------
    config : CompareConfig
        The comparison's settings.
    records : tuple of Record
        ``(record_pi, record_preisach)``.
    models : dict
        The comparison's models, by method.

    Returns
    -------
    record : Record
        The dynamics record.
    pairs : dict
        Each method's pair, by method.
    """
    record_pi, record_preisach = records
    record = twin_dynamics_record(config.twin, config.seed)
    fs = record.sample_rate
    own = {"mpi": record_pi, "preisach": record_preisach}
    pairs = {}
    for method in WITH_DYNAMICS:
        h = own[method]
        pair = fit_pair(
            models[method], h.v, h.x, record.v, record.x, sample_rate=fs, alone=models[method]
        )
        pair.inverse()  # the inverse's design, kept with the dynamics
        del pair.hysteresis_alone_  # the comparison's own model; not sent back
        pairs[method] = pair
    return record, pairs


def run_dynamics(twin, compensators, amplitude, *, periods, frequencies, identified):
    """The dynamics part of the comparison (see the module); ``compensators`` by method;
    ``identified`` is what :func:`identify_twin_pairs` returns.

    Parameters
    ----------
    twin : Twin
        The twin (with creep).
    compensators : dict
        The hysteresis compensators, by method.
    amplitude : float
        The references' height, µm.
    periods : int
        Periods per run.
    frequencies : sequence of float
        The triangles' frequencies, Hz.
    identified : tuple
        What :func:`identify_twin_pairs` returns.

    Returns
    -------
    DynamicsComparison
        The record, the pairs, the tracking results and the step.
    """
    fs = twin.sample_rate
    record, pairs = identified
    with_dyn = {m: pairs[m].inverse() for m in WITH_DYNAMICS}
    results: dict[float, dict[str, TrackingResult]] = {}
    for f in (*frequencies, *FAST_FREQUENCIES):
        fast = f in FAST_FREQUENCIES
        # a fast period is short: more of them, as many samples as Table I's 10 Hz run
        n_periods = max(periods, round(periods * f / 10.0)) if fast else periods
        _, x_ref = triangle_reference(amplitude, f, periods=n_periods, sample_rate=fs)
        row = {}
        for method in compensators if fast else ():
            row[method] = run_tracking(compensators[method], twin, x_ref, frequency=f)
        for method, comp in with_dyn.items():
            label = f"{method} + dynamics"
            row[label] = run_tracking(comp, twin, x_ref, frequency=f, method=label)
        results[f] = row
    n0 = round(0.1 * fs)
    x_ref = np.r_[np.zeros(n0), np.full(round(STEP_HOLD * fs), 0.5 * amplitude)]
    t_step = twin.time(x_ref.size)
    step, step_error, step_drift = {}, {}, {}
    ten_ms = round(0.01 * fs)
    window = slice(n0 + round(STEP_FROM * fs), None)
    for method in WITH_DYNAMICS:
        for label, comp in (
            (method, compensators[method]),
            (f"{method} + dynamics", with_dyn[method]),
        ):
            x = twin.run(comp.simulate(x_ref))
            step[label] = (t_step, x_ref, x)
            e = (x - x_ref)[window]
            step_error[label] = float(np.mean(np.abs(e)))
            step_drift[label] = float(np.mean(e[-ten_ms:]) - np.mean(e[:ten_ms]))
    return DynamicsComparison(record, pairs, results, step, step_error, step_drift)


def dynamics_rows(dc: DynamicsComparison) -> list[dict]:
    """Deprecated: :func:`hystcomp.experiment.tracking.error_rows` writes this CSV too.

    Parameters
    ----------
    dc : DynamicsComparison
        The dynamics part's results.

    Returns
    -------
    list of dict
        A row per frequency and method: rms and max error, µm.
    """
    warnings.warn(
        "dynamics_rows is deprecated; use hystcomp.experiment.tracking.error_rows.",
        DeprecationWarning,
        stacklevel=2,
    )
    return error_rows(dc)


def dynamics_markdown(dc: DynamicsComparison, table1: dict) -> list[str]:
    """The report's section on the dynamics: the pairs, the table, the step.

    Parameters
    ----------
    dc : DynamicsComparison
        The dynamics part's results.
    table1 : dict
        Table I's rows, for the errors without dynamics.

    Returns
    -------
    list of str
        Markdown lines.
    """
    found = []
    for method, pair in dc.pairs.items():
        d = pair.dynamics
        rep = d.fit_report_
        second = (
            ""
            if d.second_mode_gain_ is None
            else f", a second mode at {d.second_resonance_hz_:.4g} Hz (damping "
            f"{d.second_damping_ratio_:.3g}, {100 * d.second_mode_gain_:.2g} % of the gain)"
        )
        found.append(
            f"behind the {method.upper() if method == 'mpi' else method.title()} model, "
            f"{d.resonance_hz_:.4g} Hz (damping {d.damping_ratio_:.3g}){second} and "
            f"{100 * d.creep_fraction(0.0):.2g} % of creep within the 3 s hold (frequency-"
            f"response fit {rep['fit_percent']:.3g} % up to {rep['fit_band_hz'][1]:.0f} Hz)"
        )
    lines = [
        "## Beyond the paper: inverse of the linear dynamics",
        "",
        (
            "The twin here has creep (3 % over 1 ms .. 100 s, `plant.creep_twin`). Each model "
            "was identified with the twin's linear dynamics as one pair, `x = D[H[v]]`: `D` "
            "fitted behind the model on the twin's answer to `hystcomp excite dynamics`, the "
            "model fitted again in front of `D` on its own record with `D`'s creep and lag "
            "taken out, alternated until they agree. The dynamics came out "
            + "; ".join(found)
            + ". `+ dynamics` rows use `v = H^-1[D^-1[x_ref]]` with the stable, look-ahead "
            "inverse of `hystcomp.models.dynamics`."
        ),
        "",
        "| f (Hz) | method | rms (µm) | max (µm) | rms / rms at 1 Hz |",
        "|---:|---|---:|---:|---:|",
    ]
    low = min(dc.results)
    for f, row in dc.results.items():
        for label, r in row.items():
            base = dc.results[low].get(label) or table1[low].get(label)
            ratio = f"{r.rms / base.rms:.2f}" if base is not None else "-"
            lines.append(f"| {f:g} | {label} | {r.rms:.3f} | {r.max:.3f} | {ratio} |")
    lines += [
        "",
        (
            "What the inverse of the dynamics leaves at 100 and 200 Hz is the bandwidth of "
            "its stable inverse and each model's own hysteresis error, which reaches the "
            "stage's resonance there and is amplified by it: no linear inverse in front of the "
            "hysteresis compensator takes that out (docs/dynamics.md; `python "
            "benchmarks/bench_dynamics.py --coupling` and `--ideal` measure both)."
        ),
        "",
        (
            f"Step to half the peak, held {STEP_HOLD:g} s: mean |error| from "
            f"{1000 * STEP_FROM:g} ms to the end, and how far the error drifts over that time "
            "(the creep left), in µm. With the dynamics the drift is gone; what is left is the "
            "hysteresis model's static error at that point, and the minor loops that the "
            "compensator's own path opens (see docs/dynamics.md):"
        ),
        "",
        "| method | mean abs error | drift |",
        "|---|---:|---:|",
    ]
    for label, e in dc.step_error.items():
        lines.append(f"| {label} | {e:.3f} | {dc.step_drift[label]:+.3f} |")
    lines.append("")
    return lines
