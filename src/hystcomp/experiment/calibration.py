"""How the twin's hysteresis parameters were found, and the figures that check them.

The paper gives three quantitative facts about its rig's hysteresis: the Preisach model it
identified (eqs. 5-6, whose loops its Fig. 5 shows for 30, 60, 90 and 120 V sinusoids),
a stroke of about 37 µm at 120 V (eqs. 6, 20 and 21-22 agree), and 10 % of hysteresis in
the saturation zone of the uncompensated loop (Section V). :func:`fit_twin_hysteresis`
fits the twin's seven hysteresis parameters to the first, with the other two as targets;
its result, rounded, is the default :class:`~hystcomp.plant.TwinParameters`.

``hystcomp calibrate`` prints the calibration figures of the default twin
(:func:`calibration_report`; add ``--refit`` to run the fit again first, a few seconds).
"""

from __future__ import annotations

import numpy as np

from hystcomp import paper
from hystcomp.experiment.baseline import LinearCompensator, linear_gain
from hystcomp.experiment.metrics import hysteresis_percent
from hystcomp.experiment.references import FREQUENCIES, REFERENCE_FRACTION, triangle_reference
from hystcomp.experiment.tracking import run_tracking
from hystcomp.identify.excitation import sinusoid_sequence, triangle_sequence
from hystcomp.plant import Twin, TwinParameters
from hystcomp.plant.parameters import dynamics_matrices
from hystcomp.presets import paper_preisach

#: Calibration targets: stroke at 120 V (µm; eqs. 6, 20 and 21-22 give 36-38 µm) and
#: saturation-zone hysteresis (%, the uncompensated loop of Section V).
TARGET_STROKE = 37.0
TARGET_SATURATION_ZONE = paper.SATURATION_ZONE_PCT["uncompensated"]
FIT_AMPLITUDES = paper.FIG5_AMPLITUDES  # V, the loops of the paper's Fig. 5


def paper_everett(alpha, beta):
    """Eq. (5) with the parameters of eq. (6): ``X_p(alpha, beta)`` in µm.

    The model's own eq. (5), :meth:`hystcomp.models.preisach.Preisach.everett_function` of
    :func:`hystcomp.presets.paper_preisach` (on its plane, 0..120 V).

    Parameters
    ----------
    alpha : array_like
        Upper switching voltages, V.
    beta : array_like
        Lower switching voltages, V.

    Returns
    -------
    numpy.ndarray
        ``X_p(alpha, beta)``, µm.
    """
    return paper_preisach().everett_function(alpha, beta)


def paper_preisach_cycles(amplitudes, samples_per_period: int) -> tuple[np.ndarray, np.ndarray]:
    """The paper's Preisach model (eqs. 3-4, 6) on sinusoids ``0 -> A -> 0``, one per amplitude.

    Every cycle starts from 0 V, the bottom of the Preisach triangle, so its rising half is
    ``X_p(v, 0)`` and its falling half the first-order curve ``X_p(A, 0) - X_p(A, v)``.

    Parameters
    ----------
    amplitudes : sequence of float
        The sinusoids' amplitudes, V.
    samples_per_period : int
        Samples per cycle.

    Returns
    -------
    v : numpy.ndarray
        The voltage, V, the cycles one after the other.
    x : numpy.ndarray
        The paper's model's displacement, µm.
    """
    _, v = sinusoid_sequence(amplitudes, sample_rate=float(samples_per_period))
    x = np.empty_like(v)
    for i, a in enumerate(amplitudes):
        cycle = slice(i * samples_per_period, (i + 1) * samples_per_period)
        vc = v[cycle]
        rising = np.arange(vc.size) <= vc.size // 2
        x[cycle] = np.where(
            rising, paper_everett(vc, 0.0), paper_everett(a, 0) - paper_everett(a, vc)
        )
    x[-1] = 0.0
    return v, x


def major_loop(twin: Twin, samples: int = 2001) -> tuple[np.ndarray, np.ndarray]:
    """Quasi-static loop over the whole voltage range, the second of two cycles from rest.

    Parameters
    ----------
    twin : Twin
        The twin.
    samples : int, optional
        Samples of the rising half.

    Returns
    -------
    v : numpy.ndarray
        The voltage, V.
    x : numpy.ndarray
        The quasi-static displacement, µm.
    """
    lo, hi = twin.voltage_range
    up = np.linspace(lo, hi, samples)
    cycle = np.concatenate([up, up[-2::-1]])
    x = twin.hysteresis(np.concatenate([cycle, cycle[1:]]))
    return cycle, x[cycle.size - 1 :]


def loop_figures(twin: Twin) -> dict[str, float]:
    """Stroke (µm) and hysteresis % (whole, saturation zone) of the quasi-static major loop.

    Parameters
    ----------
    twin : Twin
        The twin.

    Returns
    -------
    dict of str to float
        ``stroke_um``, ``hysteresis_pct`` and ``saturation_zone_pct``.
    """
    v, x = major_loop(twin)
    whole, zone = hysteresis_percent(v, x)
    lo, hi = twin.voltage_range
    stroke = float(twin.hysteresis(np.linspace(lo, hi, 2001))[-1])
    return {"stroke_um": stroke, "hysteresis_pct": whole, "saturation_zone_pct": zone}


def resonance(params: TwinParameters) -> tuple[float, float]:
    """Natural frequency (Hz) and damping ratio read from the poles of the discrete ``D``.

    Parameters
    ----------
    params : TwinParameters
        The twin's parameters.

    Returns
    -------
    frequency : float
        The natural frequency, Hz.
    damping : float
        The damping ratio.
    """
    ad, _ = dynamics_matrices(params)
    s = np.log(np.linalg.eigvals(ad).astype(complex)) * params.sample_rate
    wn = float(np.abs(s[0]))
    return wn / (2 * np.pi), float(-s[0].real / wn)


def _with_hysteresis(params: TwinParameters, p) -> TwinParameters:
    c1, c2, c3, w0, uw, rho, sigma = (float(a) for a in p)
    return params.replace(
        anhysteretic=(c1, c2, c3),
        hysteresis_amplitude=w0,
        hysteresis_onset=uw,
        bouc_wen_rate=rho,
        bouc_wen_shape=sigma,
    )


def fit_twin_hysteresis(params: TwinParameters | None = None) -> TwinParameters:
    """Fit the hysteresis parameters to the paper's Preisach loops (a few seconds).

    Least squares on the difference between the twin's quasi-static output and the paper's
    Preisach model (eq. 6) on 30/60/90/120 V sinusoids (400 samples a period), plus two
    penalty terms that hold the stroke at :data:`TARGET_STROKE` (weight 1 per µm) and the
    saturation-zone hysteresis of the major loop at :data:`TARGET_SATURATION_ZONE`
    (weight 0.3 per %).

    Parameters
    ----------
    params : TwinParameters, optional
        The starting parameters (the defaults if None); only the hysteresis ones change.

    Returns
    -------
    TwinParameters
        The parameters with the fitted hysteresis.
    """
    from scipy.optimize import least_squares

    params = TwinParameters() if params is None else params
    v, x_paper = paper_preisach_cycles(FIT_AMPLITUDES, 400)
    scale = 1.0 / np.sqrt(v.size)

    def residuals(p):
        twin = Twin(_with_hysteresis(params, p))
        figures = loop_figures(twin)
        return np.concatenate(
            [
                scale * (twin.hysteresis(v) - x_paper),
                [figures["stroke_um"] - TARGET_STROKE],
                [0.3 * (figures["saturation_zone_pct"] - TARGET_SATURATION_ZONE)],
            ]
        )

    start = [20.0, 20.0, 0.0, 5.0, 0.1, 4.0, 1.0]
    lower = [0.0, -100.0, -100.0, 0.0, 0.005, 0.1, 0.05]
    upper = [100.0, 100.0, 100.0, 30.0, 2.0, 60.0, 5.0]
    fit = least_squares(residuals, start, bounds=(lower, upper), x_scale="jac")
    return _with_hysteresis(params, fit.x)


def paper_loop_difference(twin: Twin) -> float:
    """Rms difference (µm) between the twin's and the paper's Preisach loops (Fig. 5).

    Parameters
    ----------
    twin : Twin
        The twin whose quasi-static ``hysteresis`` is compared, on the paper's fit cycles.

    Returns
    -------
    float
        The rms difference, µm.
    """
    v, x_paper = paper_preisach_cycles(FIT_AMPLITUDES, 400)
    return float(np.sqrt(np.mean((twin.hysteresis(v) - x_paper) ** 2)))


def uncompensated_errors(twin: Twin, *, gain: float, amplitude: float, periods: int = 3):
    """Rms and max error (µm) of ``v = x_ref / gain`` on 0..``amplitude`` triangles, per frequency.

    Parameters
    ----------
    twin : Twin
        The twin.
    gain : float
        The linear gain ``k_lin``, µm/V.
    amplitude : float
        The triangles' height, µm.
    periods : int, optional
        Periods per run (the first is not measured).

    Returns
    -------
    dict
        For each frequency of :data:`FREQUENCIES` (Hz), ``(rms, max)`` in µm.
    """
    lo, hi = twin.voltage_range
    baseline = LinearCompensator(gain, (lo, hi))
    out = {}
    for f in FREQUENCIES:
        _, x_ref = triangle_reference(amplitude, f, periods=periods, sample_rate=twin.sample_rate)
        result = run_tracking(baseline, twin, x_ref, frequency=f)
        out[f] = (result.rms, result.max)
    return out


def calibration_report(params: TwinParameters | None = None, seed: int = 0) -> str:
    """The calibration figures of a twin, as text (see the module docstring).

    Parameters
    ----------
    params : TwinParameters, optional
        The twin's parameters (the defaults if None).
    seed : int, optional
        The seed of the sensor noise.

    Returns
    -------
    str
        The report, several lines.
    """
    twin = Twin(params, seed=seed)
    loop = loop_figures(twin)
    fn, zeta = resonance(twin.params)
    _, v = triangle_sequence(sample_rate=twin.sample_rate)
    x = twin.run(v)
    stroke = float(x.max())
    eq6_stroke = float(paper_everett(*paper.VOLTAGE_RANGE[::-1]))
    zone = loop["saturation_zone_pct"]
    freqs = ", ".join(f"{f:g}" for f in FREQUENCIES)
    paper_cells = ", ".join(
        "{:.2f}/{:.2f}".format(*paper.TABLE_I[f]["uncompensated"]) for f in FREQUENCIES
    )
    sheet = paper.DATASHEET_GAIN
    lines = [
        f"stroke: {loop['stroke_um']:.2f} µm (target {TARGET_STROKE:g}; eq. 6: {eq6_stroke:.2f})",
        f"major-loop hysteresis: {loop['hysteresis_pct']:.2f} % whole, {zone:.2f} % in the "
        + f"saturation zone (target {TARGET_SATURATION_ZONE:g})",
        f"rms difference to the eq. 6 loops: {paper_loop_difference(twin):.3f} µm",
        f"D(s) from the discrete poles: {fn:.2f} Hz, damping ratio {zeta:.4f}",
        f"uncompensated errors, rms/max µm at {freqs} Hz (paper {paper_cells}):",
    ]
    cases = [
        ("least-squares k_lin", linear_gain(v, x), REFERENCE_FRACTION * stroke),
        ("end-point k_lin", linear_gain(v, x, method="end-point"), REFERENCE_FRACTION * stroke),
        (f"datasheet {sheet:g} µm/V", sheet, REFERENCE_FRACTION * stroke),
        (f"datasheet, 0..{100.0 * sheet:g} µm", sheet, 100.0 * sheet),
    ]
    for name, gain, amplitude in cases:
        errors = uncompensated_errors(twin, gain=gain, amplitude=amplitude)
        cells = ", ".join(f"{rms:.2f}/{peak:.2f}" for rms, peak in errors.values())
        lines.append(f"  {name:<22} k = {gain:.4f}, 0..{amplitude:.1f} µm: {cells}")
    return "\n".join(lines)
