"""Several coupled axes as one model: ``x = M [H_1(v_1), ..., H_N(v_N)]``.

A scanner (XY or XYZ) drives each axis with its own voltage ``v_i`` (V); each axis has its
own hysteresis ``H_i`` (any family: PI, MPI, Preisach) and the axes couple: driving X moves
the Y sensor by a few percent of X's displacement. ``M`` (unitless, unit diagonal) holds that
coupling; ``H_i`` is what axis ``i``'s sensor reads when it alone moves.

The compensator decouples, then inverts each axis: ``h_ref = M^-1 x_ref``, ``v_i =
H_i^-1[h_ref_i]``, each axis clamped to its own voltage range. What is identifiable from
which record is said in :mod:`hystcomp.identify.coupling`; in short, a record in which every
axis sweeps its range while the others move independently (``hystcomp excite multiaxis``).

Arrays of samples are (n, N): one row per instant, one column per axis. A stepper takes and
returns one row. The mixing by ``M`` or ``M^-1`` is one compiled loop
(:mod:`hystcomp._kernels.multiaxis`), shared by the batch run and the step, so the two agree
bit for bit.
"""

from __future__ import annotations

from typing import Any, ClassVar, NamedTuple, Self

import numpy as np

from hystcomp._hyperparameters import (
    Boolean,
    Constraint,
    InstanceOf,
    Integer,
    Nullable,
    Options,
    TextOr,
    Unchecked,
)
from hystcomp._kernels.multiaxis import mix_rows
from hystcomp._notice import Notice
from hystcomp._validation import MAX_MAGNITUDE, check_range
from hystcomp.errors import (
    IdentificationError,
    InvalidParameterError,
    InvalidSignalError,
    InvalidTypeError,
)
from hystcomp.identify.compensation import tracking_estimate
from hystcomp.identify.coupling import fit_coupling, refine_coupling
from hystcomp.identify.scoring import transient_end
from hystcomp.models.base import HysteresisModel
from hystcomp.models.estimator import Estimator
from hystcomp.models.mpi import ModifiedPrandtlIshlinskii
from hystcomp.models.pi import PrandtlIshlinskii
from hystcomp.models.preisach import Preisach
from hystcomp.models.system import checked_state

__all__ = [
    "AXIS_KINDS",
    "MultiAxisCompensator",
    "MultiAxisModel",
    "MultiAxisRun",
    "MultiAxisStepper",
    "as_axes",
    "fit_axis",
]

#: The model classes an axis may have, by kind.
AXIS_KINDS: dict[str, type[HysteresisModel]] = {
    "pi": PrandtlIshlinskii,
    "mpi": ModifiedPrandtlIshlinskii,
    "preisach": Preisach,
}
#: The families ``family="auto"`` tries, in the order that breaks a tie (as
#: :func:`hystcomp.workflows.auto.identify_best`).
AUTO_FAMILIES = ("preisach", "mpi", "pi")
#: Most axes of one model (a coupling matrix of N^2 entries; a mirror's independent
#: channels belong in a :class:`~hystcomp.models.channels.ChannelBank`).
MAX_AXES = 64


def as_axes(
    value, name: str, owner: str, *, n_axes: int | None = None, finite=True, max_columns=MAX_AXES
):
    """``value`` as a C-contiguous float64 array of shape (n, N), or raise.

    A 1-D array is one sample of N axes when ``n_axes`` is given and equals its length. A
    float64 C-contiguous array is returned as it is (a view): callers do not write into it.

    Parameters
    ----------
    value : array_like
        The samples of N axes.
    name : str
        The argument's name, for an error message.
    owner : str
        The class named in an error message.
    n_axes : int, optional
        The number of axes expected (any if None).
    finite : bool, optional
        Whether to refuse NaN and inf.
    max_columns : int, optional
        The largest number of axes accepted.

    Returns
    -------
    numpy.ndarray
        A C-contiguous float64 array of shape ``(n, N)``.
    """
    try:
        arr = np.ascontiguousarray(value, dtype=np.float64)  # no copy of a float64 array
    except (TypeError, ValueError, OverflowError):
        raise InvalidTypeError(
            f"{name!r} of {owner} must be an array of real numbers of shape (samples, axes). "
            f"Got a {type(value).__name__} that does not convert to numbers."
        ) from None
    if arr.ndim == 1 and n_axes is not None and arr.size == n_axes:
        arr = arr.reshape(1, -1)
    if arr.ndim != 2 or arr.shape[0] < 1 or not 1 <= arr.shape[1] <= max_columns:
        raise InvalidSignalError(
            f"{name!r} of {owner} must have shape (samples, axes), one column per axis "
            f"(1 to {max_columns}). Got shape {arr.shape}; stack the axes as columns, "
            "np.column_stack([x1, x2])."
        )
    if n_axes is not None and arr.shape[1] != n_axes:
        raise InvalidSignalError(
            f"{name!r} of {owner} has {arr.shape[1]} columns, but the model has {n_axes} axes: "
            "give one column per axis, in the model's order."
        )
    # two reductions, no temporary array: NaN propagates through min and max
    if finite and not (-MAX_MAGNITUDE <= arr.min() and arr.max() <= MAX_MAGNITUDE):
        bad = np.argwhere(~(np.abs(arr) <= MAX_MAGNITUDE))
        k, i = (int(b) for b in bad[0])
        raise InvalidSignalError(
            f"{name!r} of {owner} has the value {arr[k, i]!r} at sample {k}, axis {i + 1}: "
            f"samples must be finite and at most {MAX_MAGNITUDE:g} in size. Remove or "
            "interpolate it."
        )
    return np.ascontiguousarray(arr)


def _mix(a: np.ndarray, x: np.ndarray) -> np.ndarray:
    out = np.empty_like(x)
    mix_rows(a, x, out)
    return out


def fit_axis(family, v: np.ndarray, h: np.ndarray, voltage_range=None) -> HysteresisModel:
    """One axis's hysteresis model fitted to its input ``v`` (V) and displacement ``h`` (µm).

    Parameters
    ----------
    family : {'auto', 'pi', 'mpi', 'preisach'} or estimator
        The family, or an unfitted estimator whose hyperparameters every axis gets (a copy
        each). ``'auto'`` fits the three families and keeps the one whose compensator is
        predicted to track best (:func:`~hystcomp.identify.compensation.tracking_estimate`,
        as :func:`hystcomp.workflows.auto.identify_best` does).
    v, h : ndarray
        The axis's input and its decoupled displacement.
    voltage_range : (float, float), optional
        The amplifier's range, the compensator's clamp [the record's].

    Returns
    -------
    HysteresisModel
        Fitted; ``fit_report_["tracking_rms_um"]`` holds the estimate.
    """
    if family == "auto":
        start = transient_end(v)
        best, best_rms = None, np.inf
        reasons = []
        for kind in AUTO_FAMILIES:
            try:
                model = fit_axis(kind, v, h, voltage_range)
            except IdentificationError as exc:
                reasons.append(f"{kind}: {exc}")
                continue
            rms = tracking_estimate(model, v, h, start=start)["tracking_rms_um"]
            model.fit_report_["tracking_rms_um"] = rms
            if rms < best_rms:
                best, best_rms = model, rms
        if best is None:
            raise IdentificationError("No model family fits this axis: " + "; ".join(reasons))
        return best
    estimator: Any
    if isinstance(family, str):
        estimator = AXIS_KINDS[family](voltage_range=voltage_range)  # type: ignore[call-arg]
    else:
        params = family.get_params()
        if voltage_range is not None and params.get("voltage_range") is None:
            params["voltage_range"] = voltage_range
        estimator = type(family)(**params)
    return estimator.fit(v, h)


class MultiAxisModel(Estimator):
    """A stage of N coupled axes: ``x = M [H_1(v_1), ..., H_N(v_N)]``, voltages V, µm.

    Parameters
    ----------
    family : {'auto', 'pi', 'mpi', 'preisach'} or estimator, default 'auto'
        Each axis's model family (see :func:`fit_axis`); with ``'auto'`` each axis gets the
        family predicted to track it best, so axes of different kinds get different models.
    coupling : bool, default True
        Identify ``M``. ``False`` keeps ``M = I``: per-axis models that ignore the coupling,
        each fitted to its own sensor's raw reading.
    voltage_range : (float, float), sequence of them, or None, default None
        Each axis's amplifier range in V (one pair for all, or one per axis); ``None`` takes
        each input's range in the record.
    n_jobs : int or None, default None
        Axes fitted in parallel by joblib (``-1``: every core; ``None``: one at a time, or
        what an enclosing ``joblib.parallel_config`` says).

    Attributes
    ----------
    axes_ : tuple of HysteresisModel
        The axes' models ``H_i`` (voltage V -> µm, before the coupling).
    coupling_ : ndarray, shape (N, N)
        ``M``, unit diagonal, read-only.
    decoupling_ : ndarray, shape (N, N)
        ``M^-1``, read-only.
    fit_report_ : dict
        After :meth:`fit`: ``coupling_percent`` (the largest off-diagonal entry of ``M``,
        %), ``shared_r2`` (how much of each axis the others' inputs explain; near 1 is not
        identifiable), per-axis ``kinds``, ``rms_error_um`` and ``tracking_rms_um``.

    Examples
    --------
    >>> import numpy as np
    >>> from hystcomp import PrandtlIshlinskii
    >>> axis = PrandtlIshlinskii.from_parameters(thresholds=[0, 10], weights=[0.2, 0.1])
    >>> model = MultiAxisModel.from_parameters(axes=[axis, axis], coupling=[[1, 0.05], [0, 1]])
    >>> V = np.array([[0.0, 0.0], [20.0, 0.0], [20.0, 20.0]])
    >>> model.simulate(V).round(6).tolist()
    [[0.0, 0.0], [5.0, 0.0], [5.25, 5.0]]
    >>> comp = model.inverse()
    >>> comp.simulate(model.simulate(V)).round(9).tolist()
    [[0.0, 0.0], [20.0, 0.0], [20.0, 20.0]]
    """

    kind: ClassVar[str] = "multiaxis"
    _learned: ClassVar[tuple[str, ...]] = ("axes", "coupling")
    _learned_derived: ClassVar[tuple[str, ...]] = ("decoupling",)
    _parameter_constraints: ClassVar[dict[str, Constraint]] = {
        "family": TextOr(
            Options(
                ("auto", *AXIS_KINDS),
                wording="'auto', 'pi', 'mpi', 'preisach' or an unfitted estimator",
            ),
            InstanceOf(
                HysteresisModel,
                "'auto', 'pi', 'mpi', 'preisach' or an unfitted estimator such as "
                "PrandtlIshlinskii(n_operators=8)",
            ),
        ),
        "coupling": Boolean(),
        "voltage_range": Unchecked(),  # one pair or one per axis: fit knows the axes
        "n_jobs": Nullable(Integer(None, nonzero=True, wording="None, -1 or an int >= 1")),
    }
    axes_: tuple[HysteresisModel, ...]
    coupling_: np.ndarray
    decoupling_: np.ndarray

    def __init__(self, *, family="auto", coupling=True, voltage_range=None, n_jobs=None):
        self.family = family
        self.coupling = coupling
        self.voltage_range = voltage_range
        self.n_jobs = n_jobs

    # -- hyperparameters -------------------------------------------------------------------

    def _axis_ranges(self, n_axes: int) -> list[tuple[float, float] | None]:
        """The ``voltage_range`` hyperparameter as one pair (or None) per axis."""
        owner = type(self).__name__
        value = self.voltage_range
        if value is None:
            return [None] * n_axes
        arr = np.asarray(value, dtype=object)
        if arr.ndim == 1:
            return [check_range(value, "voltage_range", owner)] * n_axes
        if arr.ndim == 2 and len(value) == n_axes:
            return [check_range(pair, "voltage_range", owner) for pair in value]
        raise InvalidParameterError(
            f"The 'voltage_range' parameter of {owner} must be one (low, high) pair for every "
            f"axis, or one pair per axis ({n_axes}). Got {value!r} instead."
        )

    # -- fitting -----------------------------------------------------------------------------

    def fit(self, V, X) -> Self:
        """Identify every axis's hysteresis and the coupling ``M`` from one record.

        ``M`` first (:func:`~hystcomp.identify.coupling.fit_coupling`: each sensor's reading
        on its own input's plays and the other axes' readings), then each ``H_i`` on the
        decoupled displacements ``M^-1 x`` (:func:`fit_axis`), in parallel with ``n_jobs``,
        then ``M`` again with the axes' models among the regressors
        (:func:`~hystcomp.identify.coupling.refine_coupling`).

        Parameters
        ----------
        V, X : array_like, shape (n, N)
            The axes' voltages (V) and displacements (µm), one row per instant; every axis's
            input sweeps its range while the others move independently (``hystcomp excite
            multiaxis``).

        Returns
        -------
        MultiAxisModel
            ``self``, fitted.

        Raises
        ------
        IdentificationError
            If two axes move together (their coupling is not identifiable), or an axis
            cannot be fitted.
        InvalidSignalError
            If the arrays are not (n, N) alike, hold non-finite values, or an input is
            constant.
        """
        self._check_hyperparameters()
        owner = f"{type(self).__name__}.fit"
        V = as_axes(V, "V", owner)
        X = as_axes(X, "X", owner, n_axes=V.shape[1])
        if X.shape != V.shape:
            raise InvalidSignalError(
                f"'V' and 'X' of {owner} must have one row each per instant: got {V.shape[0]} "
                f"and {X.shape[0]} rows."
            )
        for i in range(V.shape[1]):
            if np.ptp(V[:, i]) <= 0:
                raise InvalidSignalError(
                    Notice(
                        f"The input of axis {i + 1} is constant ({V[0, i]!r} V): every axis "
                        "must sweep its range for its hysteresis to be identified "
                        "({excite_multiaxis})."
                    )
                )
        n_axes = V.shape[1]
        ranges = self._axis_ranges(n_axes)
        start = max(transient_end(V[:, i]) for i in range(n_axes))
        if self.coupling:
            found = fit_coupling(V, X, start=start)
            matrix, shared = found.matrix, found.shared_r2
            H = _mix(np.linalg.inv(matrix), X)
        else:
            matrix, shared, H = np.eye(n_axes), np.zeros((n_axes, n_axes)), X
        axes = fit_axes(self.family, V, H, ranges, n_jobs=self.n_jobs)
        if self.coupling:  # M again, with each axis's model among its regressors
            own = np.column_stack([axis.simulate(V[:, i]) for i, axis in enumerate(axes)])
            matrix = refine_coupling(V, X, own, matrix, start=start)
        fitted = type(self).from_parameters(axes=axes, coupling=matrix)
        off = np.abs(matrix - np.eye(n_axes))
        predicted = fitted.simulate(V)
        report = {
            "n_axes": n_axes,
            "kinds": [axis.kind for axis in axes],
            "coupling_percent": float(100.0 * off.max()),
            "shared_r2": shared.tolist(),
            "rms_error_um": np.sqrt(np.mean((predicted[start:] - X[start:]) ** 2, 0)).tolist(),
            "tracking_rms_um": [
                float(axis.fit_report_.get("tracking_rms_um", np.nan)) for axis in axes
            ],
        }
        self._adopt(fitted, report)
        return self

    @classmethod
    def from_parameters(cls, *, axes, coupling=None) -> Self:
        """A model of fitted axis models and a coupling matrix (unit diagonal; I if None).

        Parameters
        ----------
        axes : sequence of HysteresisModel
            The fitted model of each axis, in axis order.
        coupling : array_like, optional
            The coupling matrix ``M``, shape ``(N, N)``, unit diagonal (identity if None).

        Returns
        -------
        MultiAxisModel
            The model, as if fitted.
        """
        owner = cls.__name__
        axes = tuple(axes)
        if not 1 <= len(axes) <= MAX_AXES:
            raise InvalidParameterError(
                f"The 'axes' parameter of {owner} must hold 1 to {MAX_AXES} models. Got "
                f"{len(axes)}."
            )
        for i, axis in enumerate(axes):
            if not isinstance(axis, HysteresisModel):
                raise InvalidTypeError(
                    f"Axis {i + 1} of {owner} must be a fitted PI, MPI or Preisach model. Got "
                    f"{type(axis).__name__}."
                )
            axis._check_fitted()
        n_axes = len(axes)
        m = np.eye(n_axes) if coupling is None else as_axes(coupling, "coupling", owner)
        if m.shape != (n_axes, n_axes):
            raise InvalidParameterError(
                f"The 'coupling' parameter of {owner} must be a {n_axes} x {n_axes} matrix, "
                f"one row and one column per axis. Got shape {m.shape}."
            )
        if not np.allclose(np.diag(m), 1.0, rtol=0, atol=1e-9):
            raise InvalidParameterError(
                f"The 'coupling' parameter of {owner} must have a unit diagonal (each axis's "
                f"model is what its own sensor reads). Got diagonal {np.diag(m).tolist()}; "
                "divide each column by its diagonal entry and scale that axis's model by it."
            )
        if np.linalg.cond(m) > 1e6:
            raise InvalidParameterError(
                f"The 'coupling' parameter of {owner} is singular (condition number "
                f"{np.linalg.cond(m):.3g}): the axes cannot be decoupled. Identify it again "
                "from a record in which the axes move independently."
            )
        model = cls(family=axes[0].kind if len({a.kind for a in axes}) == 1 else "auto")
        m = m.copy()
        np.fill_diagonal(m, 1.0)
        model._set_learned(axes=axes, coupling=m, decoupling=np.linalg.inv(m))
        return model

    # -- the model's run ---------------------------------------------------------------------

    @property
    def n_axes(self) -> int:
        """The number of axes N."""
        self._check_fitted()
        return len(self.axes_)

    @property
    def voltage_range_(self) -> tuple[tuple[float, float], ...]:
        """Each axis's voltage range (V), its compensator's clamp."""
        return tuple(axis.voltage_range_ for axis in self.axes_)

    def simulate(self, V) -> np.ndarray:
        """Displacements (µm, shape (n, N)) for the voltages ``V`` (V, shape (n, N)), from the
        initial state; the model is not changed.

        Parameters
        ----------
        V : array_like
            The voltages, V, shape ``(n, N)``.

        Returns
        -------
        numpy.ndarray
            The displacements, µm, shape ``(n, N)``.
        """
        self._check_fitted()
        V = as_axes(V, "V", f"{type(self).__name__}.simulate", n_axes=self.n_axes)
        H = np.column_stack([axis.simulate(V[:, i]) for i, axis in enumerate(self.axes_)])
        return _mix(np.asarray(self.coupling_), np.ascontiguousarray(H))

    def predict(self, V) -> np.ndarray:
        """:meth:`simulate`, under scikit-learn's name.

        Parameters
        ----------
        V : array_like
            A voltage row per sample and a column per axis, V.

        Returns
        -------
        numpy.ndarray
            ``simulate(V)``: a displacement row per sample, µm.
        """
        return self.simulate(V)

    def score(self, V, X) -> float:
        """R² of the predicted displacements over all axes (each axis about its own mean).

        Parameters
        ----------
        V : array_like
            The voltages, V, shape ``(n, N)``.
        X : array_like
            The measured displacements, µm, shape ``(n, N)``.

        Returns
        -------
        float
            The coefficient of determination R² (1 is perfect).
        """
        owner = f"{type(self).__name__}.score"
        X = as_axes(X, "X", owner, n_axes=self.n_axes)
        residual = float(np.sum((X - self.simulate(V)) ** 2))
        total = float(np.sum((X - X.mean(axis=0)) ** 2))
        if total == 0.0:
            return 1.0 if residual == 0.0 else 0.0
        return 1.0 - residual / total

    def stepper(self) -> MultiAxisStepper:
        """A streaming model: ``step(v_row) -> x_row``, bit for bit as :meth:`simulate`.

        Returns
        -------
        MultiAxisStepper
            A stepper in the axes' initial states.
        """
        self._check_fitted()
        return MultiAxisStepper([a.stepper() for a in self.axes_], post=self.coupling_)

    def reachable_range(self) -> tuple[tuple[float, float], ...]:
        """Each axis's reachable own displacement ``h_i`` (µm) inside its voltage range.

        Returns
        -------
        tuple of (float, float)
            One ``(low, high)`` pair per axis, µm.
        """
        self._check_fitted()
        return tuple(axis.reachable_range() for axis in self.axes_)

    def inverse(self, *, slew_rate=None, sample_rate=None, voltage_range=None, **method):
        """The compensator: ``h_ref = M^-1 x_ref``, then each axis's inverse, clamped.

        Parameters
        ----------
        slew_rate, sample_rate
            As each axis model's ``inverse`` (V/s, Hz), for every axis.
        voltage_range : (float, float) or sequence of them, optional
            Narrower clamps in V: one pair for every axis, or one per axis (``None`` keeps
            that axis's range).
        **method
            ``method`` and ``rho`` for the Preisach axes (:meth:`Preisach.inverse
            <hystcomp.models.preisach.Preisach.inverse>`).

        Returns
        -------
        MultiAxisCompensator
        """
        self._check_fitted()
        n = self.n_axes
        if voltage_range is None:
            ranges: list = [None] * n
        elif np.asarray(voltage_range, dtype=object).ndim == 1:
            ranges = [voltage_range] * n
        else:
            ranges = list(voltage_range)
            if len(ranges) != n:
                raise InvalidParameterError(
                    f"The 'voltage_range' parameter of MultiAxisModel.inverse must be one pair "
                    f"for every axis or one per axis ({n}). Got {len(ranges)} pairs."
                )
        comps = []
        for axis, rng in zip(self.axes_, ranges, strict=True):
            options: dict[str, Any] = {"slew_rate": slew_rate, "sample_rate": sample_rate}
            options["voltage_range"] = rng
            if axis.kind == "preisach":
                options.update(method)
            comps.append(axis.inverse(**options))
        return MultiAxisCompensator(comps, self.decoupling_)

    # -- model files -------------------------------------------------------------------------

    def parameters(self) -> dict[str, Any]:
        self._check_fitted()
        return {
            "axes": [axis.to_dict() for axis in self.axes_],
            "coupling": np.asarray(self.coupling_).tolist(),
        }

    _document_entry = ("axes", list)

    def _document_parts(self) -> dict[str, Any]:
        params = self.get_params()
        if not isinstance(params["family"], str):
            params["family"] = params["family"].kind
        return {"hyperparameters": params, **self.parameters()}

    @classmethod
    def _from_document(cls, data: dict[str, Any]) -> Self:
        """Every axis through its own ``from_dict``, then the coupling and the
        hyperparameters."""
        axes = []
        for i, doc in enumerate(data["axes"]):
            kind = doc.get("kind") if isinstance(doc, dict) else None
            if kind not in AXIS_KINDS:
                raise InvalidParameterError(
                    f"Axis {i + 1} of the multi-axis model has kind {kind!r}; expected one of "
                    f"{sorted(AXIS_KINDS)}."
                )
            axes.append(AXIS_KINDS[kind].from_dict(doc))
        model = cls.from_parameters(axes=axes, coupling=data.get("coupling"))
        hyper = data.get("hyperparameters", {})
        for name in ("family", "coupling", "voltage_range", "n_jobs"):
            if name in hyper:
                setattr(model, name, hyper[name])
        model._check_hyperparameters()
        return model

    def __sklearn_tags__(self):  # pragma: no cover - read by scikit-learn only
        tags = super().__sklearn_tags__()
        tags.input_tags.one_d_array = False
        tags.input_tags.two_d_array = True
        tags.target_tags.one_d_labels = False
        return tags


def fit_axes(family, V, H, ranges, *, n_jobs=None) -> list[HysteresisModel]:
    """Every axis's model (:func:`fit_axis`), in parallel by joblib when ``n_jobs`` says so."""
    n_axes = V.shape[1]
    jobs = [
        (family, np.ascontiguousarray(V[:, i]), np.ascontiguousarray(H[:, i]), ranges[i])
        for i in range(n_axes)
    ]
    from joblib import Parallel, delayed

    return list(Parallel(n_jobs=n_jobs)(delayed(fit_axis)(*job) for job in jobs))


class MultiAxisRun(NamedTuple):
    """The result of :meth:`MultiAxisCompensator.run`.

    Attributes
    ----------
    v : ndarray, shape (n, N)
        The voltages in V.
    clamped : tuple of int
        Per axis, the samples its voltage range clamped (its reference out of reach).
    nonfinite : int
        Reference rows with a non-finite value (each held every axis it couples into).
    """

    v: np.ndarray
    clamped: tuple[int, ...]
    nonfinite: int


class MultiAxisStepper:
    """N axes one sample at a time: ``step(row) -> row``, bit for bit as the batch run.

    ``pre`` mixes the input row before the axes (a compensator's ``M^-1``), ``post`` their
    outputs (a model's ``M``). Each axis keeps its own stepper; a non-finite input holds the
    outputs of the axes it reaches.

    Parameters
    ----------
    steppers : sequence
        Each axis's own stepper, in axis order.
    pre : array_like, optional
        The matrix that mixes the input row before the axes (``M^-1``), shape ``(N, N)``.
    post : array_like, optional
        The matrix that mixes the axes' outputs (``M``), shape ``(N, N)``.
    """

    def __init__(self, steppers, *, pre=None, post=None):
        self._steppers = list(steppers)
        self._n = len(self._steppers)
        self._pre = None if pre is None else np.ascontiguousarray(pre, dtype=np.float64)
        self._post = None if post is None else np.ascontiguousarray(post, dtype=np.float64)
        self._row = np.empty((1, self._n))
        self._mid = np.empty((1, self._n))
        self._out = np.empty((1, self._n))
        self._steps = [s.step for s in self._steppers]

    @property
    def n_axes(self) -> int:
        """N."""
        return self._n

    def step(self, u) -> np.ndarray:
        """Advance one sample: ``u`` has one value per axis; returns one value per axis.

        Parameters
        ----------
        u : array_like
            One input sample per axis (V for a model, µm for a compensator).

        Returns
        -------
        numpy.ndarray
            One output sample per axis.
        """
        row = self._row
        try:
            row[0, :] = u
        except (TypeError, ValueError):
            raise InvalidSignalError(
                f"MultiAxisStepper.step takes one value per axis ({self._n}). Got {u!r:.60}."
            ) from None
        mid = self._mid
        if self._pre is not None:
            mix_rows(self._pre, row, mid)
        else:
            mid[:] = row
        h, own = mid[0], self._out
        for i, step in enumerate(self._steps):
            own[0, i] = step(float(h[i]))
        if self._post is None:
            return own[0].copy()
        out = np.empty_like(own)
        mix_rows(self._post, own, out)
        return out[0]

    def step_block(self, U) -> np.ndarray:
        """Advance over a block of rows (n, N); returns the outputs (n, N).

        Parameters
        ----------
        U : array_like
            Input samples, shape ``(n, N)``.

        Returns
        -------
        numpy.ndarray
            The outputs, shape ``(n, N)``.
        """
        U = as_axes(U, "U", "MultiAxisStepper.step_block", n_axes=self._n, finite=False)
        mid = U if self._pre is None else _mix(self._pre, U)
        out = np.column_stack([s.step_block(mid[:, i]) for i, s in enumerate(self._steppers)])
        return out if self._post is None else _mix(self._post, np.ascontiguousarray(out))

    def reset(self) -> None:
        """Every axis back to its initial state."""
        for s in self._steppers:
            s.reset()

    def copy(self) -> MultiAxisStepper:
        """An independent stepper in the same state.

        Returns
        -------
        MultiAxisStepper
            A new stepper in this one's state.
        """
        return type(self)([s.copy() for s in self._steppers], pre=self._pre, post=self._post)

    @property
    def state(self) -> np.ndarray:
        """The axes' states, concatenated (a copy); set it to go back to a saved state (see
        :attr:`Stepper.state <hystcomp.models.system.Stepper.state>`).

        Returns
        -------
        ndarray
            1-D float64: axis 1's state, then axis 2's, ...
        """
        return np.concatenate([s.state for s in self._steppers])

    @state.setter
    def state(self, value) -> None:
        sizes = [s.state.size for s in self._steppers]
        value = checked_state(value, sum(sizes), self)
        for s, part in zip(self._steppers, np.split(value, np.cumsum(sizes)[:-1]), strict=True):
            s.state = part

    @property
    def clamped_count(self) -> tuple[int, ...]:
        """Per axis, the outputs clamped since the last reset."""
        return tuple(s.clamped_count for s in self._steppers)

    @property
    def nonfinite_count(self) -> tuple[int, ...]:
        """Per axis, the non-finite inputs held since the last reset."""
        return tuple(s.nonfinite_count for s in self._steppers)


class MultiAxisCompensator:
    """Feedforward for N coupled axes: references (µm, (n, N)) in, voltages (V) out.

    ``h_ref = M^-1 x_ref``, then each axis's own compensator ``v_i = H_i^-1[h_ref_i]``,
    clamped to that axis's voltage range. Built by :meth:`MultiAxisModel.inverse`.

    Parameters
    ----------
    compensators : sequence
        Each axis's own compensator, in axis order.
    decoupling : array_like
        ``M^-1``, shape ``(N, N)``.

    Attributes
    ----------
    kind : str
        ``"multiaxis"``.
    compensators : tuple
        The axes' compensators.
    decoupling : ndarray
        ``M^-1`` (read-only).
    voltage_range : tuple of (float, float)
        Each axis's clamp, V.
    """

    kind = "multiaxis"

    def __init__(self, compensators, decoupling):
        self.compensators = tuple(compensators)
        d = np.array(decoupling, dtype=np.float64)
        n = len(self.compensators)
        if d.shape != (n, n):
            raise InvalidParameterError(
                f"The 'decoupling' parameter of MultiAxisCompensator must be {n} x {n}, one row "
                f"per compensator. Got shape {d.shape}."
            )
        d.setflags(write=False)
        self.decoupling = d
        self.voltage_range = tuple(c.voltage_range for c in self.compensators)

    @property
    def n_axes(self) -> int:
        """N."""
        return len(self.compensators)

    def stepper(self) -> MultiAxisStepper:
        """A streaming compensator: ``step(x_ref_row) -> v_row``.

        Returns
        -------
        MultiAxisStepper
            A stepper in the compensators' initial states.
        """
        return MultiAxisStepper([c.stepper() for c in self.compensators], pre=self.decoupling)

    def run(self, X_ref) -> MultiAxisRun:
        """The voltages for references ``X_ref`` (µm, (n, N), finite), with the clamp counts.

        Parameters
        ----------
        X_ref : array_like
            The references, µm, shape ``(n, N)``, finite.

        Returns
        -------
        MultiAxisRun
            The voltages (V, ``(n, N)``) and, per axis, the count of clamped samples.
        """
        X = as_axes(X_ref, "X_ref", "MultiAxisCompensator.run", n_axes=self.n_axes)
        s = self.stepper()
        v = s.step_block(X)
        return MultiAxisRun(v, s.clamped_count, max(s.nonfinite_count))

    def simulate(self, X_ref) -> np.ndarray:
        """The voltages (V, (n, N)) for references ``X_ref`` (µm, (n, N)), from the start.

        Parameters
        ----------
        X_ref : array_like
            The references, µm, shape ``(n, N)``.

        Returns
        -------
        numpy.ndarray
            The voltages, V, shape ``(n, N)``.
        """
        return self.run(X_ref).v

    def __repr__(self) -> str:
        kinds = ", ".join(c.kind for c in self.compensators)
        return f"MultiAxisCompensator({self.n_axes} axes: {kinds})"
