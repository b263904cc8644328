"""Identification of the classical Preisach model from a record (paper Section III-A).

The paper's procedure: (i) drive the actuator with 1 Hz sinusoids of amplitude 5, 10, ...,
120 V, each starting from ``v_min`` (:func:`hystcomp.identify.excitation.sinusoid_sequence`);
(ii) read the first-order descending reversal curves off the record and form the samples
``X(alpha, beta) = x_alpha - x_alpha,beta`` of eq. (2); (iii) fit eq. (5) by least squares.

Nothing here assumes where the curves are: turning points are found in the input itself with
a dead band against noise, a maximum starts a first-order curve when the input rose to it
straight from (within the dead band of) its minimum, which wipes the memory out. The record may
have any voltage range (``v_min`` is its minimum), sample rate, sensor offset and noise.

A record without such curves (one amplitude, the PI triangles, a random or measured record)
is fitted by least squares over the whole record instead
(:mod:`hystcomp.identify.preisach_lsq`); :func:`identify_preisach`'s ``fit_method`` chooses.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from hystcomp._hyperparameters import (
    DEGREE,
    EVERETT,
    GRID_SIZE,
    ZERO_DIAGONAL,
    Constraint,
    Options,
    validate_parameters,
)
from hystcomp._kernels import preisach as pk
from hystcomp._notice import Notice
from hystcomp._validation import as_signal, check_range, check_real
from hystcomp.errors import (
    IdentificationError,
    InvalidParameterError,
    InvalidSignalError,
)
from hystcomp.identify.compensation import CV_FOLDS
from hystcomp.identify.outliers import check_isolated
from hystcomp.identify.preisach_lsq import MAX_LSQ_GRID, fit_preisach_lsq
from hystcomp.identify.scoring import (
    check_response,
    default_tolerance,
    reversal_folds,
    transient_end,
    turning_indices,
)

N_BINS = 200  # X samples per full-range curve: each curve is averaged in bins of span / N_BINS
FIT_METHODS = ("auto", "reversal-curves", "least-squares")
#: ``fit="auto"`` uses the reversal curves when they descend from this many distinct maxima.
AUTO_MIN_MAXIMA = 8
#: The remedies of a record the reversal-curve fit cannot use (templates of a Notice).
_FIX = "Record the response to the Preisach excitation ({excite_preisach})"
_ANY = " Or fit by least squares, which takes any record that sweeps the range: {fit_lsq}."


@dataclass(frozen=True)
class ReversalCurve:
    """A first-order descending reversal curve found in a record.

    Attributes
    ----------
    alpha : float
        The turning point (V), reached by a rise straight from the record's minimum.
    x_alpha : float
        The output at ``alpha`` on that rise (µm): eq. (2)'s ``x_alpha``.
    beta, x : ndarray
        Inputs (V) and outputs (µm) of the descent that follows, down to the next minimum.
    start, peak, stop : int
        Sample indices of the minimum the rise starts from, the turning point, the descent's end.
    """

    alpha: float
    x_alpha: float
    beta: np.ndarray
    x: np.ndarray
    start: int
    peak: int
    stop: int

    @property
    def everett(self) -> np.ndarray:
        """``X(alpha, beta) = x_alpha - x_alpha,beta`` (eq. 2) along the descent, in µm."""
        return self.x_alpha - self.x


class PreisachFit(NamedTuple):
    """What :func:`identify_preisach` finds: one of ``theta``/``table``, range, offset, report."""

    theta: np.ndarray | None
    table: np.ndarray | None
    voltage_range: tuple[float, float]
    output_offset: float
    report: dict


def _x_at_turning_point(v, x, start, peak):
    """``x_alpha``: a quadratic fit of x against v on the last 1 % of the rise, taken at alpha.

    Using the rise only is eq. (2)'s definition ("once the input is increased to alpha"); the
    fit averages sensor noise without the bias a plain mean near the peak would have.
    """
    alpha = v[peak]
    width = 0.01 * (alpha - v[start])
    k = peak
    while k > start and alpha - v[k - 1] <= width:
        k -= 1
    if peak - k < 5:
        return float(x[peak])
    dv = v[k : peak + 1] - alpha
    design = np.stack([np.ones_like(dv), dv, dv * dv], axis=1)
    coef = np.linalg.lstsq(design, x[k : peak + 1], rcond=None)[0]
    return float(coef[0])


def find_reversal_curves(v, x, *, tolerance=None) -> list[ReversalCurve]:
    """The first-order descending reversal curves of a record (eq. 2's measurements).

    Parameters
    ----------
    v, x : array_like
        Input (V) and output (µm), same length.
    tolerance : float, optional
        Reversals of the input smaller than this (V) are noise; the input is at its minimum
        when within this of it. Default: ``max(1e-3 * span, 8 * estimated noise)``.

    Returns
    -------
    list of ReversalCurve
        In record order; empty when the record has none.
    """
    v = as_signal(v, "v", min_samples=3)
    x = as_signal(x, "x", min_samples=3)
    if x.size != v.size:
        raise InvalidSignalError(
            f"'v' and 'x' must have the same length (one output per input sample). "
            f"Got {v.size} and {x.size} samples."
        )
    tol = (
        default_tolerance(v)
        if tolerance is None
        else check_real(tolerance, "tolerance", "find_reversal_curves", positive=True)
    )
    idx, first_is_max = turning_indices(v, tol)
    count = idx.size
    v_min = float(v.min())
    curves = []
    # maxima sit at odd positions when the first extremum is a minimum, else at even ones
    for m in range(0 if first_is_max else 1, count, 2):
        if m == 0 or m == count - 1:
            continue  # no rise seen before it, or the record ends on the rise
        start, peak, stop = int(idx[m - 1]), int(idx[m]), int(idx[m + 1])
        if v[start] > v_min + tol:
            continue  # the rise did not start from the minimum: not a first-order curve
        curves.append(
            ReversalCurve(
                alpha=float(v[peak]),
                x_alpha=_x_at_turning_point(v, x, start, peak),
                beta=v[peak + 1 : stop + 1].copy(),
                x=x[peak + 1 : stop + 1].copy(),
                start=start,
                peak=peak,
                stop=stop,
            )
        )
    return curves


def everett_samples(curves, *, v_min: float, bin_width: float):
    """``(alpha, beta, X)`` samples of eq. (2), each curve averaged in bins of ``bin_width`` V.

    Binning in ``beta`` weights every part of a curve alike, however slowly the input passed
    it (a sinusoid lingers near its extrema), and averages the sensor noise.

    Parameters
    ----------
    curves : sequence
        First-order descending curves, each with its ``alpha`` (V) and arrays ``beta`` (V) and
        ``everett`` (µm).
    v_min : float
        The lower end of the Preisach plane, V.
    bin_width : float
        The width of the bins in ``beta``, V.

    Returns
    -------
    alpha : numpy.ndarray
        The switching-up voltage of each sample, V.
    beta : numpy.ndarray
        The switching-down voltage, V.
    value : numpy.ndarray
        ``X(alpha, beta)``, µm.
    """
    alphas, betas, values = [], [], []
    for curve in curves:
        if curve.beta.size == 0:
            continue
        key = np.floor((curve.beta - v_min) / bin_width).astype(np.int64)
        key -= key.min()
        counts = np.bincount(key)
        used = counts > 0
        betas.append(np.bincount(key, curve.beta)[used] / counts[used])
        values.append(np.bincount(key, curve.everett)[used] / counts[used])
        alphas.append(np.full(int(used.sum()), curve.alpha))
    return np.concatenate(alphas), np.concatenate(betas), np.concatenate(values)


def _distinct(values: np.ndarray, tol: float) -> list[float]:
    out: list[float] = []
    for value in np.sort(values):
        if not out or value - out[-1] > tol:
            out.append(float(value))
    return out


def fit_everett_polynomial(
    alpha, beta, value, *, degree: int, voltage_range, zero_diagonal: bool = True
) -> np.ndarray:
    """Least-squares fit of eq. (5) (or its degree-``degree`` version) to samples of X.

    ``theta`` multiplies the monomials of ``b = beta - v_min`` and ``a = alpha - v_min`` in the
    order of :func:`~hystcomp._kernels.preisach.monomial_exponents` (eq. 5 for degree 3, where
    ``v_min = 0`` makes ``a, b`` the paper's ``alpha, beta``). The columns are scaled to the
    unit square for conditioning and the result scaled back exactly.

    With ``zero_diagonal`` the fit is constrained to ``X(v, v) = 0``, which eq. (2) implies
    (``x_alpha,alpha = x_alpha``): for each degree ``k`` the coefficients sum to 0, so the
    ``beta**k`` one is eliminated, ``theta_(k,0) = -sum_(j>0) theta_(k-j,j)``, and the others
    are fitted. Without it this is the paper's plain least squares.

    Parameters
    ----------
    alpha, beta, value : array_like
        The samples of eq. (2): upper and lower switching voltages (V) and
        ``X(alpha, beta)`` (µm), e.g. from :func:`everett_samples`.
    degree : int
        The polynomial's degree (3 is eq. 5).
    voltage_range : tuple of (float, float)
        The Preisach plane, V.
    zero_diagonal : bool, optional
        Whether to constrain ``X(v, v) = 0``.

    Returns
    -------
    numpy.ndarray
        ``theta``, in the order of the monomials, µm/V^k.

    Raises
    ------
    IdentificationError
        If the samples do not determine every coefficient (too few distinct maxima).
    """
    lo, hi = voltage_range
    span = hi - lo
    a = (np.asarray(alpha) - lo) / span
    b = (np.asarray(beta) - lo) / span
    exps = pk.monomial_exponents(degree)
    if zero_diagonal:
        free = [(i, j) for i, j in exps if j > 0]
        design = np.stack([b**i * a**j - b ** (i + j) for i, j in free], axis=1)
    else:
        free = exps
        design = np.stack([b**i * a**j for i, j in free], axis=1)
    coef, _, rank, sv = np.linalg.lstsq(design, value, rcond=None)
    if rank < len(free) or sv[-1] < 1e-9 * sv[0]:
        maxima = _distinct(np.asarray(alpha), 1e-3 * span)
        raise IdentificationError(
            Notice(
                f"The reversal curves do not determine a degree-{degree} Everett polynomial: "
                f"they descend from {len(maxima)} distinct "
                f"maxim{'um' if len(maxima) == 1 else 'a'} "
                f"({', '.join(f'{m:.4g}' for m in maxima)} V) and eq. (5) needs at least "
                f"{degree} spread over the range. {_FIX}, whose sinusoids rise to 24 "
                f"different maxima, or lower the degree.{_ANY}"
            )
        )
    fitted = dict(zip(free, coef, strict=True))
    if zero_diagonal:
        for k in range(1, degree + 1):
            fitted[(k, 0)] = -sum(fitted[(k - j, j)] for j in range(1, k + 1))
    return np.array([fitted[(i, j)] / span ** (i + j) for i, j in exps])


def fit_everett_table(alpha, beta, value, *, grid_size: int, voltage_range) -> np.ndarray:
    """Least-squares fit of a bilinearly interpolated table of X to samples of X.

    The nodes are ``grid_size`` equally spaced voltages over ``voltage_range``; the unknowns
    are ``X(alpha_i, beta_j)`` for ``j < i`` (the diagonal is 0 by eq. 2, the upper triangle
    the antisymmetric extension). A light second-difference penalty inside the triangle fills
    nodes that no curve reaches. Returns the full ``(grid_size, grid_size)`` table.

    Parameters
    ----------
    alpha, beta, value : array_like
        Where the Everett function was sampled, ``alpha >= beta`` (V), and its values there
        (µm), as :func:`everett_samples` gives them.
    grid_size : int
        Nodes per axis.
    voltage_range : tuple of (float, float)
        The Preisach plane, V.

    Returns
    -------
    numpy.ndarray
        The table, µm, shape ``(grid_size, grid_size)``.
    """
    import scipy.sparse  # here: 0.2 s to import, and only the table fit needs it
    import scipy.sparse.linalg

    lo, hi = voltage_range
    n = grid_size
    h = (hi - lo) / (n - 1)
    u = np.clip((np.asarray(alpha) - lo) / h, 0.0, n - 1)
    w = np.clip((np.asarray(beta) - lo) / h, 0.0, n - 1)
    i = np.minimum(u.astype(np.int64), n - 2)
    j = np.minimum(w.astype(np.int64), n - 2)
    s, t = u - i, w - j

    def unknown(p, q):
        """Column and sign of node (p, q) in the unknowns (sign 0 on the diagonal)."""
        hi_, lo_ = np.maximum(p, q), np.minimum(p, q)
        sign = np.sign(p - q)
        return np.where(sign != 0, hi_ * (hi_ - 1) // 2 + lo_, 0), sign

    rows, cols, vals = [], [], []
    corners = [(i, j, (1 - s) * (1 - t)), (i + 1, j, s * (1 - t))]
    corners += [(i, j + 1, (1 - s) * t), (i + 1, j + 1, s * t)]
    sample = np.arange(u.size)
    for p, q, weight in corners:
        col, sign = unknown(p, q)
        rows.append(sample)
        cols.append(col)
        vals.append(weight * sign)
    n_unknown = n * (n - 1) // 2
    data = scipy.sparse.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(u.size, n_unknown),
    )
    # second differences along alpha and beta, within the closed lower triangle
    pen_rows, pen_cols, pen_vals, r = [], [], [], 0
    for p in range(n):
        for q in range(p):
            for dp, dq in ((1, 0), (0, 1)):
                if not (p - dp >= q + dq and p + dp < n and q - dq >= 0):
                    continue
                for k, c in ((-1, 1.0), (0, -2.0), (1, 1.0)):
                    pk_, qk = p + k * dp, q + k * dq
                    if pk_ > qk:  # diagonal nodes are 0, not unknowns
                        pen_rows.append(r)
                        pen_cols.append(pk_ * (pk_ - 1) // 2 + qk)
                        pen_vals.append(c)
                r += 1
    penalty = scipy.sparse.csr_matrix((pen_vals, (pen_rows, pen_cols)), shape=(r, n_unknown))
    normal = (data.T @ data).tocsc()
    scale = float(normal.diagonal().mean()) if normal.nnz else 1.0
    lhs = normal + 1e-6 * scale * (penalty.T @ penalty).tocsc()
    solution = scipy.sparse.linalg.spsolve(lhs, data.T @ np.asarray(value))
    lower = np.zeros((n, n))
    p, q = np.tril_indices(n, -1)
    lower[p, q] = solution[p * (p - 1) // 2 + q]
    return pk.antisymmetric_table(lower)


#: The options of :func:`identify_preisach` checked at its boundary.
IDENTIFY_PREISACH_OPTIONS: dict[str, Constraint] = {
    "degree": DEGREE,
    "everett": EVERETT,
    "grid_size": GRID_SIZE,
    "zero_diagonal": ZERO_DIAGONAL,
    "fit_method": Options(FIT_METHODS),
}


def identify_preisach(
    v,
    x,
    *,
    degree=3,
    everett="polynomial",
    grid_size=25,
    voltage_range=None,
    zero_diagonal=True,
    tolerance=None,
    fit_method="auto",
) -> PreisachFit:
    """Identify the classical Preisach model from a record, as in Section III-A.

    Parameters
    ----------
    v, x : array_like
        Input voltage (V) and measured displacement (µm), one sample each, e.g. the response
        to :func:`~hystcomp.identify.excitation.sinusoid_sequence`.
    degree : int, default 3
        Degree of the Everett polynomial (3 is eq. 5).
    everett : {"polynomial", "table"}
        Fit eq. (5)'s polynomial, or a bilinearly interpolated table of X.
    grid_size : int, default 25
        Nodes per axis of the table (25 puts one every 5 V on 0..120 V, the excitation's step).
    voltage_range : (float, float), optional
        The Preisach plane (V); default the record's range. It must contain the record.
    zero_diagonal : bool, default True
        Constrain the polynomial to ``X(v, v) = 0`` (eq. 2); see
        :func:`fit_everett_polynomial`. False is the paper's unconstrained fit, whose
        ``X(v, v)`` makes the output step at each reversal (tables always have it 0).
    tolerance : float, optional
        Dead band of the turning-point search (V); see :func:`find_reversal_curves`.
    fit_method : {"auto", "reversal-curves", "least-squares"}, default "auto"
        ``"reversal-curves"``: the paper's fit of X to the samples of eq. (2) read off the
        first-order descending curves. ``"least-squares"``: the model's output fitted to
        the whole record with a non-negative Preisach density
        (:mod:`hystcomp.identify.preisach_lsq`); any record that sweeps the range will do.
        ``"auto"``: the reversal curves when the record has them from at least
        :data:`AUTO_MIN_MAXIMA` distinct maxima (as the response to ``hystcomp excite
        preisach`` has: 24), else least squares.

    Returns
    -------
    PreisachFit
        ``output_offset`` is the least-squares constant between the record and the model
        (the sensor offset), over the record from the first visit to its minimum on
        (reversal curves) or to an end of its range (least squares). ``report["fit"]``
        names the fit used.

    Raises
    ------
    IdentificationError
        If the record cannot determine X: for the reversal curves, no first-order descending
        curve or too few; for least squares, an input that does not move.
    """
    owner = "identify_preisach"
    options = validate_parameters(IDENTIFY_PREISACH_OPTIONS, locals(), owner, fitting=True)
    degree, grid_size = options["degree"], options["grid_size"]
    v = as_signal(v, "v", min_samples=3)  # writable: the kernels compile for one array type
    x = as_signal(x, "x", min_samples=3)
    check_isolated(v, owner)  # one glitch would set the Preisach plane
    curves = find_reversal_curves(v, x, tolerance=tolerance)
    check_response(v, x, owner)  # rising, and more than noise
    data_range = (float(v.min()), float(v.max()))
    if voltage_range is None:
        if data_range[0] == data_range[1]:
            raise IdentificationError(
                Notice(
                    f"The input is constant ({data_range[0]:g} V): it traces no hysteresis. {_FIX}."
                )
            )
        voltage_range = data_range
    else:
        voltage_range = check_range(voltage_range, "voltage_range", owner)
        slack = 1e-9 * (voltage_range[1] - voltage_range[0])
        if data_range[0] < voltage_range[0] - slack or data_range[1] > voltage_range[1] + slack:
            raise InvalidParameterError(
                Notice(
                    "The 'voltage_range' parameter of {owner} must contain the record's input, "
                    "which spans {lo:g}..{hi:g} V: the Preisach plane covers all of it. Got "
                    "{got_lo:g}..{got_hi:g} V; widen it, or leave it out and narrow the "
                    "compensator's clamp instead ({clamp}).",
                    owner=owner,
                    lo=data_range[0],
                    hi=data_range[1],
                    got_lo=voltage_range[0],
                    got_hi=voltage_range[1],
                )
            )
    if fit_method == "auto":
        span = voltage_range[1] - voltage_range[0]
        n_maxima = len(_distinct(np.array([c.alpha for c in curves]), 1e-3 * span))
        fit_method = "reversal-curves" if n_maxima >= AUTO_MIN_MAXIMA else "least-squares"
    if fit_method == "least-squares":
        return _least_squares(
            v, x, curves, degree, everett, grid_size, voltage_range, zero_diagonal
        )
    if not curves:
        raise IdentificationError(
            Notice(
                "The record holds no first-order descending reversal curve (eq. 2): the input "
                f"never rises from its minimum ({data_range[0]:g} V) to a maximum and falls "
                f"back. {_FIX}: sinusoids of growing amplitude, each from v_min, and identify "
                f"from it.{_ANY}"
            )
        )
    lo, hi = voltage_range
    alpha, beta, value = everett_samples(curves, v_min=lo, bin_width=(hi - lo) / N_BINS)
    if everett == "polynomial":
        theta = fit_everett_polynomial(
            alpha, beta, value, degree=degree, voltage_range=(lo, hi), zero_diagonal=zero_diagonal
        )
        table = None
        kind, coef = pk.POLYNOMIAL, pk.coefficient_matrix(theta, degree)
    else:
        maxima = _distinct(alpha, 1e-3 * (hi - lo))
        if len(maxima) < 2:
            raise IdentificationError(
                Notice(
                    f"The reversal curves descend from {len(maxima)} distinct maximum "
                    f"({maxima[0]:.4g} V); a table of X needs curves from several maxima "
                    f"spread over the range. {_FIX}.{_ANY}"
                )
            )
        theta = None
        table = fit_everett_table(alpha, beta, value, grid_size=grid_size, voltage_range=(lo, hi))
        kind, coef = pk.TABLE, table
    packed = pk.pack_preisach(
        kind=kind, coef=coef, v_min=lo, v_max=hi, offset=0.0, depth=pk.DEFAULT_DEPTH
    )
    model_everett = np.empty(alpha.size)
    pk.everett_many(packed, alpha, beta, model_everett)
    h = np.empty_like(v)
    pk.preisach_run(packed, v, h)
    tol = default_tolerance(v) if tolerance is None else float(tolerance)
    settled = int(np.argmax(v <= data_range[0] + tol))  # memory known from here on
    residual = x[settled:] - h[settled:]
    offset = float(residual.mean())
    residual -= offset
    diagonal = np.linspace(lo, hi, 241)
    on_diagonal = np.empty_like(diagonal)
    pk.everett_many(packed, diagonal, diagonal, on_diagonal)
    report = {
        "fit": "reversal-curves",
        "n_curves": len(curves),
        "maxima_V": [round(c.alpha, 9) for c in curves],
        "everett_rms_um": float(np.sqrt(np.mean((model_everett - value) ** 2))),
        "record_rms_um": float(np.sqrt(np.mean(residual**2))),
        "record_max_um": float(np.abs(residual).max()),
        "diagonal_max_um": float(np.abs(on_diagonal).max()),
    }
    return PreisachFit(theta, table, (lo, hi), offset, report)


def _least_squares(v, x, curves, degree, everett, grid_size, voltage_range, zero_diagonal):
    """:func:`identify_preisach` by density-constrained least squares over the whole record."""
    if not zero_diagonal:
        raise InvalidParameterError(
            Notice(
                "zero_diagonal=False is the paper's unconstrained fit to reversal curves; the "
                "least-squares fit keeps X(v, v) = 0 (eq. 2), which a non-negative density "
                "implies. Pass {zero_diagonal}, or {fit_rc} with a record of first-order "
                "descending curves ({excite_preisach})."
            )
        )
    if everett == "table" and grid_size > MAX_LSQ_GRID:
        raise InvalidParameterError(
            f"The 'grid_size' parameter of identify_preisach must be at most {MAX_LSQ_GRID} for "
            f"the least-squares fit, whose {grid_size * (grid_size - 1) // 2} cell masses would "
            f"make a dense problem too large to solve. Got {grid_size}; use a coarser grid "
            "(25 puts a node every 5 V on 0..120 V) or the polynomial."
        )
    start = transient_end(v)
    theta, table, offset, fit_report = fit_preisach_lsq(
        v,
        x,
        everett=everett,
        degree=degree,
        grid_size=grid_size,
        voltage_range=voltage_range,
        start=start,
        folds=reversal_folds(v, start, CV_FOLDS),
    )
    lo, hi = voltage_range
    kind, coef = (
        (pk.POLYNOMIAL, pk.coefficient_matrix(theta, degree))
        if table is None
        else (
            pk.TABLE,
            table,
        )
    )
    packed = pk.pack_preisach(
        kind=kind, coef=coef, v_min=lo, v_max=hi, offset=offset, depth=pk.DEFAULT_DEPTH
    )
    model_x = np.empty_like(v)
    pk.preisach_run(packed, v, model_x)
    start = fit_report["first_used_sample"]
    residual = x[start:] - model_x[start:]
    report = {
        "fit": "least-squares",
        "n_curves": len(curves),
        "maxima_V": [round(c.alpha, 9) for c in curves],
        **fit_report,
        "record_rms_um": float(np.sqrt(np.mean(residual**2))),
        "record_max_um": float(np.abs(residual).max()),
        "diagonal_max_um": 0.0,
    }
    return PreisachFit(theta, table, (lo, hi), offset, report)
