"""The classical Preisach model (paper eqs. 1-5) and its compensators (eqs. 7-10).

The model is evaluated by :mod:`hystcomp._kernels.preisach`: eqs. (3)-(4) over a bounded
memory of alternating dominant extrema with the wipe-out property, at a cost per sample that
does not grow with the depth of the memory.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from hystcomp._hyperparameters import (
    DEGREE,
    EVERETT,
    GRID_SIZE,
    MAX_DEGREE,
    ZERO_DIAGONAL,
    Constraint,
    Integer,
    Options,
)
from hystcomp._kernels import preisach as pk
from hystcomp._validation import (
    MAX_MAGNITUDE,
    _first_out_of_bounds,
    as_vector,
    check_range,
    check_real,
    real_array,
)
from hystcomp.errors import InvalidParameterError
from hystcomp.identify.compensation import compensation_error
from hystcomp.identify.preisach import FIT_METHODS, identify_preisach
from hystcomp.identify.scoring import error_report, transient_end
from hystcomp.models.base import (
    DEFAULT_VOLTAGE_RANGE,
    HysteresisModel,
    compensator_rate,
    input_range_report,
)
from hystcomp.models.compensator import Compensator
from hystcomp.models.dynamic_compensator import DynamicCompensator
from hystcomp.models.dynamics import with_dynamics
from hystcomp.models.estimator import fit_signals
from hystcomp.models.inversion import check_rising_everett
from hystcomp.models.system import Stepper

INVERSE_METHODS = ("multiplicative", "exact")
#: Nodes per axis on which a polynomial Everett function's branches are checked to rise
#: (:meth:`Preisach._check_invertible`): 0.94 V apart on 0..120 V.
CHECK_NODES = 129
#: The default ``rho`` is at least the major loop's steepest slope over this, so that eq. (10)
#: never amplifies an error on any branch: see :meth:`Preisach.default_rho`.
RHO_STEEPEST = 2.0
#: The memory bound's constraint: 3 extrema at least, and a stepper's memory allocated whole.
MAX_EXTREMA = Integer(3, pk.MAX_DEPTH)


class PreisachStepper(Stepper):
    """Streaming evaluation of a Preisach system, bit for bit equal to its batch run.

    A :class:`~hystcomp.models.system.Stepper` on the Preisach kernels: the same fast
    bound :meth:`step`, :meth:`step_block`, :meth:`reset` and :meth:`copy`. A non-finite
    input sample holds the last output (before the first sample: ``x_0`` for a model,
    ``v_min`` clamped to the output range for a compensator) and is counted in
    :attr:`nonfinite_count`.

    Parameters
    ----------
    packed : numpy.ndarray
        The packed Preisach system (parameters and initial state).
    """

    kernels = pk.PREISACH_KERNELS

    @classmethod
    def _checked(cls, packed) -> np.ndarray:
        # made only by Preisach models and their compensators, from arrays they packed
        return packed

    @property
    def memory_depth(self) -> int:
        """How many extrema the memory holds now (``beta_0`` included)."""
        return int(self._p[self._start + pk.ST_TOP]) + 1


class Preisach(HysteresisModel):
    """Classical Preisach model, eqs. (1)-(5): ``x = x_0 + H(v)``.

    ``H`` follows eqs. (3)-(4) from the Everett-type function ``X(alpha, beta)`` of eq. (2)
    and a memory of alternating dominant extrema with the wipe-out property, starting with
    every relay off at ``v_min`` (``beta_0 = v_min``). Inputs outside the Preisach plane
    ``voltage_range_`` saturate (all relays off below it, all on above it).

    ``X`` is the polynomial of eq. (5) in ``a = alpha - v_min`` and ``b = beta - v_min``
    (for ``v_min = 0``, eq. 5 itself), of any degree, or a table on a grid interpolated
    bilinearly. Eqs. (3)-(4) are used as written, so where a fitted ``X(v, v)`` is not 0 (it is
    by eq. 2, but a least-squares polynomial only approximately) the output steps by
    ``X(v, v)`` at each reversal; ``fit_report_["diagonal_max_um"]`` says how much.

    Defaults (a deviation from the paper): ``fit`` fits X by least squares over the whole
    record with a non-negative density, as a 25 x 25 table. The paper's fit, eq. (5) fitted
    to the first-order descending curves of its sinusoids (Section III-A), is
    ``Preisach(fit_method="reversal-curves", everett="polynomial", zero_diagonal=False)``.
    ``hystcomp compare`` runs it for Table I with ``zero_diagonal=True``, ``X(v, v) = 0`` as
    eq. (2) implies: fitted free on the twin, the cubic's ``X(v, v)`` reaches 0.55 µm, a step
    of the output at each reversal (its report gives both fits' tracking). The defaults were
    chosen by the measured tracking of a 1 Hz triangle on the panel of
    ``benchmarks/bench_accuracy.py`` (Benchmarks, "The Preisach fit"): least squares with a
    table tracks at least as well as the cubic (a cubic cannot follow a density that is not
    polynomial), and 25 nodes per axis has the best median. A model whose branch turns back
    has no compensator (:meth:`inverse` refuses it, whatever the method).

    Parameters
    ----------
    degree : int, default 3
        Degree of the Everett polynomial (3 is eq. 5), for ``everett="polynomial"``.
    everett : {"table", "polynomial"}, default "table"
        Representation of X that ``fit`` identifies: a table interpolated bilinearly, or
        the polynomial of eq. (5) (``degree``).
    grid_size : int, default 25
        Nodes per axis of a table (25: one every 5 V on 0..120 V).
    voltage_range : (float, float) or None, default None
        The Preisach plane and the compensators' output range, in V; None takes the
        identification record's range (``v_min`` is its minimum).
    zero_diagonal : bool, default True
        Fit the polynomial with ``X(v, v) = 0``, as eq. (2) implies (a table always has it).
        False is the paper's unconstrained least squares of eq. (5), for
        ``fit_method="reversal-curves"`` only (the least-squares fit's non-negative density
        implies the constraint).
    max_extrema : int, default 1024
        Bound of the memory (stored extrema, ``beta_0`` included). When a reversal would
        exceed it the innermost stored minor loop is wiped out first; the default is far
        beyond what measured signals reach. At most 1,000,000 (the memory of a stepper is
        allocated whole: 16 bytes per extremum).
    fit_method : {"least-squares", "reversal-curves", "auto"}, default "least-squares"
        How ``fit`` identifies X: ``"least-squares"`` fits the model's output over the
        whole record, any record that sweeps the range (``hystcomp excite rich``, the
        paper's triangles or sinusoids, a measured record), with a non-negative Preisach
        density (so every branch rises and the exact inverse exists);
        ``"reversal-curves"`` fits X to the first-order descending curves of the record
        (Section III-A, the response to ``hystcomp excite preisach``), with
        ``everett="polynomial"`` the paper's fit; ``"auto"`` takes the reversal curves when
        the record has them from 8 or more maxima, else least squares.
        See :func:`~hystcomp.identify.preisach.identify_preisach`.

    Attributes
    ----------
    theta_ : ndarray or None
        Coefficients of X in µm/V^k, eq. (5)'s order (None for a table).
    table_ : ndarray or None
        ``table_[i, j] = X(alpha_i, beta_j)`` in µm on a uniform grid over ``voltage_range_``,
        meaningful for ``j <= i``; the upper triangle is the antisymmetric extension.
    voltage_range_ : (float, float)
        ``(v_min, v_max)`` in V.
    output_offset_ : float
        ``x_0`` in µm (the sensor offset of the identification record).

    Examples
    --------
    >>> model = Preisach.from_parameters(theta=[-0.1, 0.1, 0.001, -0.002, 0.001])
    >>> model.simulate([0.0, 100.0, 50.0, 100.0]).round(6).tolist()
    [0.0, 20.0, 12.5, 20.0]
    >>> comp = model.inverse(method="exact")
    >>> comp.simulate([0.0, 20.0, 12.5]).round(9).tolist()
    [0.0, 100.0, 50.0]
    """

    kind = "preisach"
    _learned = ("voltage_range", "output_offset", "theta", "table")
    stepper_class = PreisachStepper
    _parameter_constraints: ClassVar[dict[str, Constraint]] = {
        **HysteresisModel._parameter_constraints,
        "degree": DEGREE,
        "everett": EVERETT,
        "grid_size": GRID_SIZE,
        "zero_diagonal": ZERO_DIAGONAL,
        "max_extrema": MAX_EXTREMA,
        "fit_method": Options(FIT_METHODS),
    }
    theta_: np.ndarray | None
    table_: np.ndarray | None
    output_offset_: float

    def __init__(
        self,
        *,
        degree=3,
        everett="table",
        grid_size=25,
        voltage_range=None,
        zero_diagonal=True,
        max_extrema=pk.DEFAULT_DEPTH,
        fit_method="least-squares",
    ):
        self.degree = degree
        self.everett = everett
        self.grid_size = grid_size
        self.voltage_range = voltage_range
        self.zero_diagonal = zero_diagonal
        self.max_extrema = max_extrema
        self.fit_method = fit_method

    @classmethod
    def from_parameters(
        cls,
        *,
        theta=None,
        table=None,
        voltage_range=DEFAULT_VOLTAGE_RANGE,
        output_offset=0.0,
        max_extrema=pk.DEFAULT_DEPTH,
    ) -> Preisach:
        """A model with X given by ``theta`` (eq. 5 order, µm/V^k) or ``table`` (µm).

        ``theta`` has ``d (d + 3) / 2`` entries for degree ``d`` (9 for eq. 5). ``table`` is
        a square array of ``X(alpha_i, beta_j)`` on ``n`` equally spaced voltages over
        ``voltage_range``; only its lower triangle (diagonal included) is read.

        Parameters
        ----------
        theta : array_like, optional
            The coefficients of the polynomial Everett function, eq. (5) order, µm/V^k.
        table : array_like, optional
            The Everett function on an equally spaced grid, µm (square; its lower triangle is
            read).
        voltage_range : tuple of (float, float), optional
            The amplifier's range, V.
        output_offset : float, optional
            The displacement at the start state, µm.
        max_extrema : int, optional
            The bound on the memory of dominant extrema.

        Returns
        -------
        Preisach
            The model, as if fitted.
        """
        owner = cls.__name__
        if (theta is None) == (table is None):
            raise InvalidParameterError(
                f"{owner}.from_parameters needs exactly one of 'theta' (the coefficients of "
                "eq. 5) and 'table' (X on a grid). Got "
                f"{'both' if theta is not None else 'neither'}."
            )
        MAX_EXTREMA.check(max_extrema, "max_extrema", owner, False)
        model = cls(max_extrema=max_extrema)
        plane = check_range(voltage_range, "voltage_range", owner)
        offset = check_real(output_offset, "output_offset", owner)
        if theta is not None:
            theta = as_vector(theta, "theta", owner)
            sizes = {pk.n_monomials(d): d for d in range(1, MAX_DEGREE + 1)}
            if theta.size not in sizes:
                raise InvalidParameterError(
                    f"The 'theta' parameter of {owner} must have d(d+3)/2 entries for a "
                    f"degree d in 1..{MAX_DEGREE} ({', '.join(map(str, sizes))}; 9 is eq. 5). "
                    f"Got {theta.size} instead."
                )
            model.degree = sizes[theta.size]
            model.everett = "polynomial"
        else:
            table = _check_table(table, owner)
            model.everett = "table"
            model.grid_size = table.shape[0]
        model._set_learned(voltage_range=plane, output_offset=offset, theta=theta, table=table)
        model.voltage_range = None
        return model

    @fit_signals
    def fit(self, v, x) -> Preisach:
        """Identify the model from a record (Section III-A); see
        :func:`~hystcomp.identify.preisach.identify_preisach`.

        Parameters
        ----------
        v, x : array_like
            Input voltage (V) and displacement (µm): the response to
            ``hystcomp excite preisach`` for the paper's fit, or any record that sweeps the
            range for least squares (``fit_method``).

        Returns
        -------
        Preisach
            ``self``, fitted; ``fit_report_`` holds the fit's figures, among them the
            errors of :func:`~hystcomp.identify.scoring.error_report` (``rms_error_um`` ...),
            ``tracking_rms_um``  (the estimated tracking error of ``inverse()``, µm rms,
            :func:`hystcomp.identify.compensation.compensation_error`, from the first sample
            at an end of the range on) and ``baseline_tracking_rms_um`` (the same for a
            straight line ``v = x / k_lin``), as for PI and MPI.
        """
        params = self._check_hyperparameters(fitting=True)
        result = identify_preisach(
            v,
            x,
            degree=params["degree"],
            everett=params["everett"],
            grid_size=params["grid_size"],
            voltage_range=params["voltage_range"],
            zero_diagonal=params["zero_diagonal"],
            fit_method=params["fit_method"],
        )
        self._set_learned(
            voltage_range=result.voltage_range,
            output_offset=result.output_offset,
            theta=None if result.theta is None else _frozen(result.theta),
            table=None if result.table is None else _frozen(result.table),
        )
        start = transient_end(v)
        # the same error figures as the PI and MPI reports, beside the fit's own
        report = {
            **error_report(x, self.simulate(v), start),
            **input_range_report(v),
            **result.report,
        }
        est = compensation_error(self, v, x, start=start)
        report["tracking_rms_um"] = est["tracking_rms_um"]
        report["baseline_tracking_rms_um"] = est["baseline_rms_um"]
        self.fit_report_ = report
        return self

    def _derived_hyperparameters(self) -> dict:
        if self.table_ is None:  # X is the polynomial theta_
            return {"everett": "polynomial", "degree": self.degree}
        return {"everett": "table", "grid_size": int(self.table_.shape[0])}

    def parameters(self) -> dict:
        """The learned parameters as plain Python values (``theta`` or ``table``).

        Returns
        -------
        dict
            ``theta`` or ``table`` (the one the model has), ``voltage_range`` and
            ``output_offset``, as :meth:`from_parameters` takes them.
        """
        out = super().parameters()
        return {name: value for name, value in out.items() if value is not None}

    def _packed(self, mode=pk.FORWARD, rho=1.0, max_step=np.inf, clamp=None) -> np.ndarray:
        """The packed Preisach system of :mod:`hystcomp._kernels.preisach` (not a play chain)."""
        self._check_fitted()
        depth = self._checked("max_extrema")  # set_params may have changed it since
        lo, hi = self.voltage_range_
        if self.theta_ is not None:
            kind, coef = pk.POLYNOMIAL, pk.coefficient_matrix(self.theta_, self.degree)
        elif self.table_ is not None:  # one of the two is set (from_parameters, fit)
            kind, coef = pk.TABLE, self.table_
        return pk.pack_preisach(
            kind=kind,
            coef=coef,
            v_min=lo,
            v_max=hi,
            offset=self.output_offset_,
            depth=depth,
            mode=mode,
            rho=rho,
            max_step=max_step,
            clamp=clamp,
        )

    def _check_invertible(self) -> None:
        """Raise :class:`~hystcomp.errors.NotInvertibleError` unless every branch rises
        (:func:`~hystcomp.models.inversion.check_rising_everett`): on the table's own nodes,
        or for a polynomial on :data:`CHECK_NODES` nodes per axis."""
        lo, hi = self.voltage_range_
        what = f"This {type(self).__name__} model"
        if self.table_ is not None:
            nodes = np.linspace(lo, hi, self.table_.shape[0])
            check_rising_everett(self.table_, nodes, what, cells="table")
            return
        nodes = np.linspace(lo, hi, CHECK_NODES)
        grid = self.everett_function(nodes[:, None], nodes[None, :])
        check_rising_everett(grid, nodes, what, cells="voltages")

    def everett_function(self, alpha, beta) -> np.ndarray:
        """``X(alpha, beta)`` in µm (eq. 2) at voltages clamped to the plane (broadcast).

        Parameters
        ----------
        alpha, beta : array_like
            Upper and lower switching voltages, V (clamped to the plane).

        Returns
        -------
        numpy.ndarray
            ``X(alpha, beta)``, µm, broadcast over the two.
        """
        lo, hi = self.voltage_range_
        a, b = np.broadcast_arrays(np.asarray(alpha, float), np.asarray(beta, float))
        a_flat = np.ascontiguousarray(np.clip(a, lo, hi)).ravel()
        b_flat = np.ascontiguousarray(np.clip(b, lo, hi)).ravel()
        out = np.empty(a_flat.size)
        pk.everett_many(self._packed(), a_flat, b_flat, out)
        return out.reshape(a.shape)

    def default_rho(self) -> float:
        """The gain ``rho`` of eqs. (7)-(10), µm/V: the chord of the major loop, or more where
        the loop is steep.

        The chord ``X(v_max, v_min) / (v_max - v_min)`` is the average slope of H over the
        range, which both branches of the major loop rise by. Recursion (10) multiplies the
        error of each sample by ``1 - s / rho`` where H's local slope is ``s``, so it
        contracts for ``0 < s < 2 rho``, and its per-sample error
        ``(rho / s - 1) * (x_ref[k] - x_ref[k-1])`` changes sign along a branch instead of
        piling up at one end. Where the steepest slope of the major loop's branches
        (which bound every branch's slope when the density is non-negative) exceeds
        :data:`RHO_STEEPEST` (2) times the chord, ``rho`` is that slope over
        :data:`RHO_STEEPEST`, so that the factor stays within -1 and the recursion never
        amplifies an error; the price is more lag where H is flat (Benchmarks, "The gain
        rho").

        It is a property of the model, so any model file (or preset) has it; on the paper's
        model, whose branches are nowhere twice as steep as the chord, it is the chord.

        Returns
        -------
        float
            The gain ``rho``, µm/V.
        """
        self._check_fitted()
        lo, hi = self.voltage_range_
        chord = float(self.everett_function(hi, lo)) / (hi - lo)
        if not chord > 0:
            return chord
        v = np.linspace(lo, hi, 1025)
        rising = self.everett_function(v, lo)  # the ascending branch from v_min
        falling = -self.everett_function(hi, v)  # the descending branch from v_max, shifted
        dv = v[1] - v[0]
        steepest = max(np.diff(rising).max(), np.diff(falling).max()) / dv
        return max(chord, float(steepest) / RHO_STEEPEST)

    def inverse(
        self,
        *,
        method=None,
        rho=None,
        slew_rate=None,
        sample_rate=None,
        voltage_range=None,
        dynamics=None,
    ) -> PreisachCompensator | DynamicCompensator:
        """A compensator (reference µm -> voltage V) clamped to ``voltage_range_``.

        Parameters
        ----------
        method : {"multiplicative", "exact"}, optional
            By default ``"multiplicative"``, the paper's compensator, alone; ``"exact"``
            with ``dynamics`` (unless ``rho`` is given). In series with the inverse of the
            dynamics, eq. (10)'s one-sample lag overshoots the voltage on the fast rises that
            inverse asks for, and the hysteresis memory keeps the overshoot, which the exact
            inverse does not (Benchmarks, "Dynamics").
            ``"multiplicative"``: the paper's approximate inverse multiplicative structure,
            eq. (10): ``v[k] = (x_ref[k] - Gamma(v[k-1])) / rho`` with
            ``Gamma(v) = H(v) - rho v`` and H's memory advanced by each applied ``v[k]``.
            ``"exact"``: per sample, the input on the current branch of H (through the
            stored extrema, where wipe-outs change it) with ``x_0 + H(v) = x_ref``, by a
            safeguarded regula falsi; exact for monotone branches. References out of reach
            give the range ends; a reference inside the step that a non-zero ``X(v, v)``
            opens at a reversal holds the voltage.
        rho : float, optional
            Gain in µm/V for ``"multiplicative"``; default :meth:`default_rho`.
        slew_rate, sample_rate, voltage_range, dynamics
            The output's limits and the dynamics in series, as in
            :meth:`HysteresisModel.inverse <hystcomp.models.base.HysteresisModel.inverse>`.

        Returns
        -------
        PreisachCompensator or DynamicCompensator
            The compensator; with ``dynamics``, in series with their inverse.
        """
        if method is None:
            method = "exact" if dynamics is not None and rho is None else "multiplicative"
        if dynamics is not None:
            compensator = self.inverse(
                method=method,
                rho=rho,
                slew_rate=slew_rate,
                sample_rate=compensator_rate(sample_rate, dynamics, "Preisach.inverse"),
                voltage_range=voltage_range,
            )
            return with_dynamics(self, compensator, dynamics)
        self._check_fitted()
        self._check_invertible()  # every method, and so C export, needs rising branches
        owner = type(self).__name__
        max_step, clamp = self._output_limits(slew_rate, sample_rate, voltage_range, None)
        if method not in INVERSE_METHODS:
            raise InvalidParameterError(
                f"The 'method' parameter of {owner}.inverse must be 'multiplicative' (eq. 10) "
                f"or 'exact'. Got {method!r} instead."
            )
        if method == "exact":
            if rho is not None:
                raise InvalidParameterError(
                    f"The 'rho' parameter of {owner}.inverse belongs to method="
                    "'multiplicative'; the exact inverse has no gain. Drop it."
                )
            return PreisachCompensator(
                self, method=method, rho=None, max_step=max_step, clamp=clamp
            )
        if rho is None:
            rho = self.default_rho()  # > 0: the major loop rises (checked above)
        else:
            rho = check_real(rho, "rho", f"{owner}.inverse", positive=True)
        return PreisachCompensator(self, method=method, rho=rho, max_step=max_step, clamp=clamp)


class PreisachCompensator(Compensator):
    """Preisach-based feedforward: reference displacement (µm) in, voltage (V) out.

    Built by :meth:`Preisach.inverse`; the output is always inside ``voltage_range``, and
    before the first sample it is ``v_min`` (the model's start state) clamped to it. Batch
    ``simulate`` and the stepper run the same kernel, bit for bit.

    Parameters
    ----------
    model : Preisach
        The forward model it inverts.
    method : str
        ``"multiplicative"`` (eq. 10) or ``"exact"``.
    rho : float or None
        The gain of eq. (10), µm/V (None for the exact inverse).
    max_step : float
        Largest output change per sample, V.
    clamp : tuple of (float, float)
        The output clamp, V.

    Attributes
    ----------
    kind : str
        ``"preisach"``.
    method : str
        ``"multiplicative"`` (eq. 10) or ``"exact"``.
    model : Preisach
        The forward model it inverts (its parameters, for export).
    rho : float or None
        The gain of eq. (10) in µm/V (None for the exact inverse).
    voltage_range : (float, float)
        The clamp on the output, in V.
    max_step : float
        Largest output change per sample, in V (``inf`` without a slew-rate limit).
    """

    stepper_class = PreisachStepper

    def __init__(self, model: Preisach, *, method: str, rho: float | None, max_step: float, clamp):
        mode = pk.EXACT if method == "exact" else pk.MULTIPLICATIVE
        rho_value = 1.0 if rho is None else rho
        packed = model._packed(mode=mode, rho=rho_value, max_step=max_step, clamp=clamp)
        packed.setflags(write=False)
        self._chain = packed
        self.model = model
        self.kind = model.kind
        self.method = method
        self.rho = rho
        self.voltage_range = clamp
        self.max_step = float(max_step)

    def __repr__(self) -> str:
        lo, hi = self.voltage_range
        return f"PreisachCompensator(method={self.method!r}, voltage_range=({lo:g}, {hi:g}) V)"


def _frozen(arr: np.ndarray) -> np.ndarray:
    arr = np.array(arr, dtype=np.float64)
    arr.setflags(write=False)
    return arr


def _check_table(table, owner) -> np.ndarray:
    arr = real_array(table, "table", owner, "a square 2-D array of numbers")
    if arr.ndim != 2 or arr.shape[0] != arr.shape[1] or arr.shape[0] < 2:
        raise InvalidParameterError(
            f"The 'table' parameter of {owner} must be a square 2-D array of at least 2 x 2 "
            f"values X(alpha_i, beta_j). Got shape {arr.shape} instead."
        )
    lower = np.tril(arr)
    bad = _first_out_of_bounds(lower)  # beyond MAX_MAGNITUDE, sums of X overflow to inf/NaN
    if bad is not None:
        i, j = np.unravel_index(bad, arr.shape)
        raise InvalidParameterError(
            f"The 'table' parameter of {owner} must be finite and at most {MAX_MAGNITUDE:g} "
            f"in size on and below the diagonal. Entry [{i}, {j}] is {float(arr[i, j])!r}; "
            "check the units."
        )
    return _frozen(pk.antisymmetric_table(lower))
