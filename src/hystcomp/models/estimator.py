"""The estimator base: scikit-learn's contract for the models, without importing it.

:class:`Estimator` holds what every fitted model shares as an *estimator*: hyperparameters
read from the ``__init__`` signature (``get_params``, ``set_params``, ``repr``), the fitted
check, ``score``, the hyperparameter checks that ``fit`` and model files share, and the
model-file dictionary (``to_dict``, ``from_dict``). How a model computes its output lives
elsewhere (:class:`~hystcomp.models.system.PackedSystem`).
"""

from __future__ import annotations

import functools
import inspect
from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar, Self, TypeVar

import numpy as np

from hystcomp._blas import one_blas_thread
from hystcomp._hyperparameters import Constraint, validate_parameters
from hystcomp._validation import as_signal_pair
from hystcomp.errors import (
    InvalidParameterError,
    InvalidSignalError,
    InvalidTypeError,
    NotFittedError,
)

Fit = TypeVar("Fit", bound=Callable[..., Any])


def one_column(values, name: str, owner: str):
    """A signal given as scikit-learn gives ``X``: a 2-D array or DataFrame of one column
    becomes that column; anything else is returned as it is (and validated later).

    scikit-learn's pipelines, ``cross_val_score`` and ``df[["v"]]`` hand an estimator a
    matrix of shape ``(n_samples, n_features)``; these models have one feature, the voltage.
    A sparse matrix, complex numbers, NaN or inf, or a matrix of another number of columns
    are refused with scikit-learn's wording of each problem beside the fix.

    Parameters
    ----------
    values : array_like
        A signal, or ``X`` / ``y`` as scikit-learn passes it.
    name : str
        The argument's name, for an error message.
    owner : str
        The class named in an error message.

    Returns
    -------
    array_like
        The one column of a matrix, else ``values`` as given.
    """
    if hasattr(values, "tocsr") and hasattr(values, "nnz"):  # scipy.sparse, not imported
        raise InvalidTypeError(
            f"{owner}: {name!r} is a sparse matrix; sparse input is not supported, as a signal "
            "is dense. Convert it with .toarray()."
        )
    shape: tuple[int, ...] | None = getattr(values, "shape", None)
    if shape is None:
        if not isinstance(values, list | tuple) or not values:
            return values
        shape = np.shape(values)
    if len(shape) != 2:
        return values
    if hasattr(values, "iloc"):  # a DataFrame: its columns by position
        column = values.iloc[:, 0] if shape[1] else None
        probe = values.to_numpy() if shape[1] else np.empty(shape)
    else:
        probe = np.asarray(values)
        column = probe[:, 0] if shape[1] else None
    if np.iscomplexobj(probe):
        raise InvalidSignalError(
            f"{owner}: Complex data not supported: {name!r} holds complex numbers; pass the "
            "real signal."
        )
    if probe.dtype.kind in "fc" and not np.isfinite(probe).all():
        raise InvalidSignalError(
            f"{owner}: {name!r} holds NaN or inf; remove or interpolate those samples."
        )
    if shape[1] != 1:
        raise InvalidSignalError(
            f"{owner}: {name!r} given as a matrix must have one column, the signal; found "
            f"{shape[1]} feature(s) (shape={tuple(shape)}) while a minimum of 1 is required "
            "and a maximum of 1 allowed. Select its column (df[['v']] or X[:, [0]]), or pass "
            "a 1-D array."
        )
    return column


def check_target(x, owner: str):
    """``x`` (``y``) for a fit: present, and one column if a matrix.

    Parameters
    ----------
    x : array_like or None
        The measured displacement, µm, as given to ``fit`` (``y`` in scikit-learn).
    owner : str
        The class named in an error message.

    Returns
    -------
    array_like
        ``x`` as a signal (a one-column matrix becomes its column), validated later.
    """
    if x is None:
        raise InvalidSignalError(
            f"{owner} requires y to be passed, but the target y is None: give the measured "
            "displacement x (µm), one sample per voltage sample."
        )
    return one_column(x, "x", owner)


def fit_signals(fit: Fit) -> Fit:
    """Decorate an estimator's ``fit(v, x)``: a one-column ``X`` (or ``y``) becomes a
    signal (:func:`one_column`), and the fit runs on one BLAS thread
    (:func:`hystcomp._blas.one_blas_thread`: its matrix products are small, and a threaded
    BLAS on a busy machine made fits many times slower).

    Parameters
    ----------
    fit : callable
        An estimator's ``fit(self, v, x, ...)``.

    Returns
    -------
    callable
        The wrapped ``fit``, with the same signature.
    """

    @functools.wraps(fit)
    def wrapper(self, v, x):
        owner = f"{type(self).__name__}.fit"
        if v is not None:  # y first, as scikit-learn's checks word it; a None v is named below
            x = check_target(x, owner)
        v = one_column(v, "v", owner)
        with one_blas_thread():
            fitted = fit(self, v, x)
        fitted.n_features_in_ = 1  # scikit-learn's attribute: one feature, the voltage
        return fitted

    return wrapper  # type: ignore[return-value]


def set_learned(model: object, names: tuple[str, ...], **learned: Any) -> None:
    """Set a model's learned attributes, ``name_`` for each of ``names``: the one path by
    which ``fit``, ``from_parameters`` and the model files write them.

    An array that the caller may still change is copied first, so that every array of the
    model is its own and read-only. The values are taken as they are: ``from_parameters``
    validates them before, and a fit computed them under its constraints.

    Parameters
    ----------
    model : object
        The model whose attributes are set.
    names : tuple of str
        Its learned parameters, without the trailing underscore.
    **learned
        A value for each of ``names``, and nothing else.

    Raises
    ------
    TypeError
        If ``learned`` does not name exactly ``names`` (a programming error).
    """
    if set(learned) != set(names):  # a programming error in a model class, not a user's
        raise TypeError(
            f"The learned attributes of {type(model).__name__} are {', '.join(names)}; got "
            f"{', '.join(learned)}."
        )
    for name in names:
        value = learned[name]
        if isinstance(value, np.ndarray) and value.flags.writeable:
            value = value.copy()
            value.setflags(write=False)
        setattr(model, name + "_", value)


def learned_values(model: object, names: tuple[str, ...]) -> dict[str, Any]:
    """A model's learned attributes by name (without the underscore), as
    :func:`set_learned` takes them.

    Parameters
    ----------
    model : object
        A fitted model.
    names : tuple of str
        The learned parameters to read, without the trailing underscore.

    Returns
    -------
    dict
        Name to value.
    """
    return {name: getattr(model, name + "_") for name in names}


def model_document(model: Any, **parts: Any) -> dict[str, Any]:
    """A model file's dictionary: the model's ``kind``, then ``parts``, then its
    ``fit_report`` if it has one (:mod:`hystcomp.io.models` writes it as JSON).

    Parameters
    ----------
    model : object
        A model with a ``kind`` (and maybe a ``fit_report_``).
    **parts
        The document's entries after ``kind``, in their order.

    Returns
    -------
    dict
    """
    out: dict[str, Any] = {"kind": model.kind, **parts}
    report = getattr(model, "fit_report_", None)
    if report is not None:
        out["fit_report"] = dict(report)
    return out


def check_document(cls: type, data: Any, key: str, kind: type) -> None:
    """Raise unless ``data`` is a dict whose ``key`` holds a ``kind`` (a model file's
    dictionary for ``cls.from_dict``).

    Parameters
    ----------
    cls : type
        The class whose ``from_dict`` reads ``data`` (named in the message).
    data : object
        The document.
    key : str
        The entry it must hold.
    kind : type
        The type of that entry (``dict``, ``list``).

    Raises
    ------
    InvalidParameterError
        If it does not.
    """
    if not (isinstance(data, dict) and isinstance(data.get(key), kind)):
        article = "an" if kind.__name__[0] in "aeiou" else "a"
        raise InvalidParameterError(
            f"{cls.__name__}.from_dict needs a dict with {article} {key!r} {kind.__name__} (as "
            f"written by to_dict). Got {type(data).__name__}."
        )


def read_fit_report(model: Any, data: dict[str, Any]) -> None:
    """Give ``model`` the fit report of its model file's dictionary, if it holds one.

    Parameters
    ----------
    model : object
        The model read from ``data``.
    data : dict
        Its model file's dictionary.
    """
    if "fit_report" in data:
        model.fit_report_ = dict(data["fit_report"])


class ModelFile(ABC):
    """What a model file holds, written and read the same way for every kind of model.

    :meth:`to_dict` writes the model's ``kind``, its parts (:meth:`_document_parts`) and
    its fit report; :meth:`from_dict` checks the document's main entry
    (``_document_entry``), builds the model from it (:meth:`_from_document`, which
    validates everything) and gives it the fit report back. :mod:`hystcomp.io.models`
    writes the dictionary as JSON, with a format and a version.
    """

    kind: ClassVar[str]
    #: The entry that :meth:`from_dict` checks first, and its type (None: the document's
    #: shape is checked by :func:`hystcomp.io.models.model_from_dict`).
    _document_entry: ClassVar[tuple[str, type] | None] = ("parameters", dict)

    @abstractmethod
    def _document_parts(self) -> dict[str, Any]:
        """The document's entries after ``kind``, in their order."""

    @classmethod
    @abstractmethod
    def _from_document(cls, data: dict[str, Any]) -> Self:
        """The model a checked document describes, every value validated."""

    def to_dict(self) -> dict[str, Any]:
        """The model file's dictionary: kind, parts and fit report, ready for JSON.

        Returns
        -------
        dict
            ``{"kind": ..., <the model's parts>, "fit_report": ...}``: for an estimator its
            ``hyperparameters`` and ``parameters``, for a pair its ``hysteresis`` and
            ``dynamics``, for many axes each axis's own dictionary; ``fit_report`` only for
            a fitted model.
        """
        return model_document(self, **self._document_parts())

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Self:
        """Inverse of :meth:`to_dict`: the model that a dictionary describes, validated.

        :func:`hystcomp.io.models.model_from_dict` checks a whole document (keys, JSON
        types) first.

        Parameters
        ----------
        data : dict
            A dictionary as :meth:`to_dict` writes it.

        Returns
        -------
        object
            The model, of the class it is called on.

        Raises
        ------
        InvalidParameterError
            If the document does not describe a valid model of this kind.
        """
        if cls._document_entry is not None:
            check_document(cls, data, *cls._document_entry)
        model = cls._from_document(data)
        read_fit_report(model, data)
        return model


class Estimator(ModelFile):
    """Base of the fitted models: voltage (V) in, displacement (µm) out, learned from data.

    Subclasses list their learned parameters in ``_learned`` (names without the trailing
    underscore); the learned attributes end in ``_`` as in scikit-learn. The hyperparameters
    are the keyword parameters of the subclass's ``__init__``, which stores each unchanged
    under its own name (validation waits for ``fit``): :meth:`get_params`, :meth:`set_params`,
    the model file and ``repr`` read them from the signature, so a new hyperparameter is
    written once. That is scikit-learn's estimator contract, without importing it:
    ``sklearn.base.clone``, grid searches and pipelines work on these models, and
    :meth:`predict` is :meth:`simulate` and :meth:`score` the coefficient of determination
    of the predicted displacement.
    A model without learned parameters can only be fitted.

    A subclass gives ``simulate(v)`` (the prediction :meth:`score` rates) and the
    classmethod ``from_parameters(**parameters)`` (which :meth:`from_dict` calls).
    """

    kind: ClassVar[str]
    _learned: ClassVar[tuple[str, ...]]
    #: Each hyperparameter's constraint (:mod:`hystcomp._hyperparameters`), declared once
    #: per class and checked by :meth:`_check_hyperparameters`; every hyperparameter of
    #: ``__init__`` has one (checked when the class is made).
    _parameter_constraints: ClassVar[dict[str, Constraint]] = {}
    #: Learned attributes computed from those of ``_learned`` (not in the model file).
    _learned_derived: ClassVar[tuple[str, ...]] = ()
    fit_report_: dict[str, Any]

    if TYPE_CHECKING:  # what every subclass gives (declared for the type checker only)

        def simulate(self, v) -> np.ndarray: ...  # its system's run

        @classmethod
        def from_parameters(cls, *args: Any, **parameters: Any) -> Self: ...

    @classmethod
    def _get_param_names(cls) -> tuple[str, ...]:
        """The hyperparameter names: the parameters of ``__init__``, in their order."""
        names = []
        for param in inspect.signature(cls.__init__).parameters.values():
            if param.name == "self":
                continue
            if param.kind in (param.VAR_POSITIONAL, param.VAR_KEYWORD):
                raise TypeError(  # a programming error in a subclass, not a user's
                    f"{cls.__name__}.__init__ must name its hyperparameters explicitly "
                    f"(no *args or **kwargs); found {param}."
                )
            names.append(param.name)
        return tuple(names)

    @classmethod
    def _param_defaults(cls) -> dict[str, Any]:
        return {
            name: param.default
            for name, param in inspect.signature(cls.__init__).parameters.items()
            if name != "self"
        }

    def _check_fitted(self) -> None:
        if not hasattr(self, self._learned[0] + "_"):
            name = type(self).__name__
            raise NotFittedError(
                f"This {name} has no parameters yet. Call fit(v, x) on measured data, "
                f"build it with {name}.from_parameters(...), or load one with "
                "hystcomp.load_model(path)."
            )

    def _derived_hyperparameters(self) -> dict[str, Any]:
        """Hyperparameters that the learned parameters determine (e.g. the operator count
        from the thresholds), with their values; a model file must agree with them."""
        return {}

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "__init__" in cls.__dict__:  # a concrete estimator: a constraint per hyperparameter
            names, declared = set(cls._get_param_names()), set(cls._parameter_constraints)
            if names != declared:  # a programming error in the class, found at import
                raise TypeError(
                    f"{cls.__name__}._parameter_constraints must declare exactly the "
                    f"hyperparameters of __init__; missing {sorted(names - declared)}, "
                    f"unknown {sorted(declared - names)}."
                )

    def _check_hyperparameters(self, *, fitting: bool = False) -> dict[str, Any]:
        """Validate every hyperparameter against ``_parameter_constraints`` (and raise).

        ``fit`` and ``from_dict`` both call it, so a hyperparameter is checked on both
        paths once its constraint is declared.

        Parameters
        ----------
        fitting : bool, default False
            The values are about to be used by a fit, which may bound them more tightly.

        Returns
        -------
        dict
            The checked hyperparameters by name (ints of NumPy integers, ranges as pairs
            of floats); the attributes themselves stay as given, as in scikit-learn.
        """
        return validate_parameters(
            self._parameter_constraints, self.get_params(), type(self).__name__, fitting=fitting
        )

    def _checked(self, name: str) -> Any:
        """One hyperparameter, checked against its declared constraint."""
        return self._parameter_constraints[name].check(
            getattr(self, name), name, type(self).__name__, False
        )

    def get_params(self, deep: bool = True) -> dict[str, Any]:
        """The hyperparameters, as given to ``__init__`` (scikit-learn's contract).

        Parameters
        ----------
        deep : bool, default True
            Accepted for scikit-learn; these models hold no nested estimators.

        Returns
        -------
        dict
            Name to value, in the order of ``__init__``'s signature.
        """
        return {name: getattr(self, name) for name in self._get_param_names()}

    def set_params(self, **params) -> Self:
        """Set hyperparameters by name (checked in :meth:`fit`, as in scikit-learn).

        Learned attributes stay as they are until the next :meth:`fit`.

        Parameters
        ----------
        **params
            Hyperparameters by name, each with its new value.

        Returns
        -------
        estimator
            ``self``.

        Raises
        ------
        InvalidParameterError
            If a name is not a hyperparameter of this model.

        Examples
        --------
        >>> from hystcomp import PrandtlIshlinskii
        >>> PrandtlIshlinskii().set_params(n_operators=8)
        PrandtlIshlinskii(n_operators=8, unfitted)
        """
        valid = self._get_param_names()
        for name, value in params.items():
            if name not in valid:
                raise InvalidParameterError(
                    f"{name!r} is not a hyperparameter of {type(self).__name__}. Valid "
                    f"hyperparameters are: {', '.join(valid)}. Check the spelling."
                )
            setattr(self, name, value)
        return self

    def predict(self, v) -> np.ndarray:
        """The displacement (µm) predicted for the voltage ``v`` (V): :meth:`simulate`, under
        scikit-learn's name, so that its scorers, ``cross_val_predict`` and a pipeline's
        ``predict`` work on these models too. ``v`` may also be ``X`` of shape
        ``(n_samples, 1)`` or a one-column DataFrame, as scikit-learn passes it.

        Parameters
        ----------
        v : array_like
            The voltage, V: a 1-D signal, or ``X`` of shape ``(n_samples, 1)``.

        Returns
        -------
        numpy.ndarray
            The displacement, µm, one sample per voltage sample.
        """
        owner = f"{type(self).__name__}.predict"
        self._check_fitted()
        return self.simulate(one_column(v, "v", owner))

    def score(self, v, x) -> float:
        """Coefficient of determination R² of the displacement predicted for ``v``.

        ``1 - sum((x - x_hat)^2) / sum((x - mean(x))^2)`` with ``x_hat = simulate(v)``, as
        scikit-learn's regressors score; 1 is a perfect prediction. Like
        ``sklearn.metrics.r2_score``, a constant ``x`` scores 1.0 if predicted exactly,
        else 0.0.

        Parameters
        ----------
        v, x : array_like
            Input voltage (V) and measured displacement (µm), one sample each per instant;
            ``v`` may be ``X`` of shape ``(n_samples, 1)`` or a one-column DataFrame.

        Returns
        -------
        float
        """
        owner = f"{type(self).__name__}.score"
        self._check_fitted()
        v, x = one_column(v, "v", owner), check_target(x, owner)
        v, x = as_signal_pair(v, x, ("v", "x"), owner)
        residual = float(np.sum((x - self.simulate(v)) ** 2))
        total = float(np.sum((x - x.mean()) ** 2))
        if total == 0.0:
            return 1.0 if residual == 0.0 else 0.0
        return 1.0 - residual / total

    def parameters(self) -> dict[str, Any]:
        """The learned parameters as plain Python values (lists and floats).

        Returns
        -------
        dict
            The parameters by name, as :meth:`from_parameters` takes them.
        """
        self._check_fitted()
        out = {}
        for name in self._learned:
            value = getattr(self, name + "_")
            out[name] = value.tolist() if isinstance(value, np.ndarray) else value
        return out

    def _document_parts(self) -> dict[str, Any]:
        return {"hyperparameters": self.get_params(), "parameters": self.parameters()}

    @classmethod
    def _from_document(cls, data: dict[str, Any]) -> Self:
        """``from_parameters`` validates the parameters; a hyperparameter the parameters
        determine must agree with them, and every hyperparameter keeps its constraint."""
        model = cls.from_parameters(**data["parameters"])
        derived = model._derived_hyperparameters()
        for name, value in data.get("hyperparameters", {}).items():
            if name not in cls._get_param_names():
                continue
            if name in derived and not _same_value(value, derived[name]):
                quoted = isinstance(value, str) and not isinstance(derived[name], str)
                raise InvalidParameterError(
                    f"The hyperparameter {name!r} of this {cls.__name__} is "
                    + (f"the text {value!r}, not a number" if quoted else repr(value))
                    + f", but its parameters give {derived[name]!r}: the two disagree. The "
                    f"file was edited by hand; set {name!r} to {derived[name]!r}"
                    + (" (no quotes)" if quoted else "")
                    + " or identify again."
                )
            setattr(model, name, value)
        model._check_hyperparameters()  # every value, as fit() would check it
        return model

    _estimator_type = "regressor"  # what scikit-learn < 1.6 reads
    n_features_in_: int  # scikit-learn's: 1 once fitted (the voltage)

    def __sklearn_tags__(self):
        """scikit-learn's description (>= 1.6): a regressor of one feature, the voltage
        (``X`` of shape ``(n_samples, 1)``; a 1-D signal is taken too).

        Called only by scikit-learn, so importing it here adds no dependency.
        """
        from sklearn.utils import (  # type: ignore[import-untyped]  # no stubs
            InputTags,
            RegressorTags,
            Tags,
            TargetTags,
        )

        return Tags(
            estimator_type="regressor",
            target_tags=TargetTags(required=True, one_d_labels=True),
            input_tags=InputTags(one_d_array=False, two_d_array=True),
            regressor_tags=RegressorTags(),
        )

    def _set_learned(self, **learned: Any) -> None:
        """Set the learned attributes: the one place where ``fit``, ``from_parameters`` and
        the model files write them (:func:`set_learned`, with ``_learned`` and
        ``_learned_derived``)."""
        set_learned(self, (*self._learned, *self._learned_derived), **learned)

    def _learned_values(self) -> dict[str, Any]:
        """The learned attributes by name (without the underscore), as :meth:`_set_learned`
        takes them."""
        return learned_values(self, (*self._learned, *self._learned_derived))

    def _adopt(self, fitted: Self, fit_report: dict[str, Any]) -> None:
        """Take the learned parameters of ``fitted`` (built by ``from_parameters``, so validated)."""
        self._set_learned(**fitted._learned_values())
        self.fit_report_ = fit_report

    def __repr__(self) -> str:
        """Only the hyperparameters that differ from their defaults, as scikit-learn shows."""
        defaults = self._param_defaults()
        args = [f"{k}={v!r}" for k, v in self.get_params().items() if _differs(v, defaults[k])]
        if not hasattr(self, self._learned[0] + "_"):
            args.append("unfitted")
        return f"{type(self).__name__}({', '.join(args)})"


def _differs(value, default) -> bool:
    """Whether a hyperparameter differs from its default (for ``repr``)."""
    if value is default:
        return False
    if type(value) is not type(default):
        return True
    try:
        return not bool(value == default)
    except (TypeError, ValueError):  # e.g. an array's ambiguous truth value
        return True


def _same_value(value, expected) -> bool:
    """Equal and of the same JSON type (3 is not 3.0, "3" or True)."""
    return type(value) is type(expected) and value == expected


#: Why :func:`sklearn.utils.estimator_checks.check_estimator` cannot pass these checks on a
#: hysteresis model, by reason; the other checks run and pass.
_MULTI_FEATURE = (
    "feeds X of several columns of random numbers: a hysteresis model has one input, the "
    "voltage (X of one column is taken; more are refused, naming the column to select)"
)
_UNRELATED = (
    "fits a y unrelated to X (random numbers or class labels): the fits refuse a record "
    "whose displacement does not respond to its voltage, as the command line does (a wrong "
    "column, a dead sensor)"
)
_ONE_D = "expects 1-D X to be refused: a signal is 1-D, and model.fit(v, x) takes it on purpose"
_NOT_FITTED = (
    "expects scikit-learn's own NotFittedError class; hystcomp raises "
    "hystcomp.errors.NotFittedError (a ValueError) so as not to depend on scikit-learn"
)
SKLEARN_EXPECTED_FAILED_CHECKS: dict[str, str] = {
    **dict.fromkeys(
        (
            "check_dict_unchanged",
            "check_dont_overwrite_parameters",
            "check_dtype_object",
            "check_estimators_dtypes",
            "check_estimators_fit_returns_self",
            "check_estimators_nan_inf",
            "check_estimators_overwrite_params",
            "check_estimators_pickle",
            "check_f_contiguous_array_estimator",
            "check_fit2d_1sample",
            "check_fit2d_predict1d",
            "check_fit_check_is_fitted",
            "check_fit_idempotent",
            "check_fit_score_takes_y",
            "check_n_features_in",
            "check_n_features_in_after_fitting",
            "check_pipeline_consistency",
            "check_positive_only_tag_during_fit",
            "check_readonly_memmap_input",
            "check_regressor_data_not_an_array",
            "check_regressors_int",
            "check_regressors_no_decision_function",
            "check_regressors_train",
            "check_supervised_y_2d",
        ),
        _MULTI_FEATURE,
    ),
    "check_methods_sample_order_invariance": _MULTI_FEATURE
    + "; and it shuffles the samples, while a hysteretic output depends on their order",
    "check_methods_subset_invariance": _MULTI_FEATURE
    + "; and it takes subsets of the samples, while a hysteretic output depends on the "
    "samples before",
    "check_fit2d_1feature": _UNRELATED,
    "check_fit1d": _ONE_D,
    "check_estimators_unfitted": _NOT_FITTED,
}


def sklearn_expected_failed_checks(estimator=None) -> dict[str, str]:
    """The checks of scikit-learn's ``check_estimator`` that do not apply to a hysteresis
    model, each with the reason: ``check_estimator(model,
    expected_failed_checks=sklearn_expected_failed_checks(model))`` runs every other check
    (or ``parametrize_with_checks(..., expected_failed_checks=...)`` in a test suite).

    The checks feed tabular data: several columns of random numbers, an unrelated target,
    shuffled rows. A hysteresis model maps one signal, the voltage, to the displacement,
    and its output depends on the order of the samples; those checks cannot apply.

    Parameters
    ----------
    estimator : Estimator, optional
        The estimator to be checked (the list is the same for every model of the package).

    Returns
    -------
    dict of str to str
        The name of each check that does not apply, with the reason.
    """
    return dict(SKLEARN_EXPECTED_FAILED_CHECKS)
