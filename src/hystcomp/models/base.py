"""What the Prandtl-Ishlinskii-type models share: parameters, fitted check, serialisation."""

from __future__ import annotations

import inspect
from typing import Any, ClassVar

import numpy as np

from hystcomp import operators, paper
from hystcomp._validation import (
    as_signal_pair,
    as_vector,
    check_int,
    check_range,
    check_real,
    check_thresholds,
)
from hystcomp.errors import InvalidParameterError, NotFittedError
from hystcomp.identify.pi import check_constraints, check_margin
from hystcomp.models.compensator import ChainSystem, Compensator
from hystcomp.models.inversion import inverse_initial_state, invert_superposition

DEFAULT_VOLTAGE_RANGE = paper.VOLTAGE_RANGE  # V, the paper's piezo voltage v_px


class HysteresisModel(ChainSystem):
    """Base of the forward models: voltage (V) in, displacement (µm) out.

    Subclasses list their learned parameters in ``_learned`` (names without the trailing
    underscore); the learned attributes end in ``_`` as in scikit-learn. The hyperparameters
    are the keyword parameters of the subclass's ``__init__``, which stores each unchanged
    under its own name (validation waits for ``fit``): :meth:`get_params`, :meth:`set_params`,
    the model file and ``repr`` read them from the signature, so a new hyperparameter is
    written once. That is scikit-learn's estimator contract, without importing it:
    ``sklearn.base.clone``, grid searches and pipelines work on these models, and
    :meth:`score` is the coefficient of determination of the predicted displacement.
    A model without learned parameters can only be fitted.
    """

    kind: ClassVar[str]
    _learned: ClassVar[tuple[str, ...]]

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

    def _check_hyperparameters(self) -> None:
        """Validate every hyperparameter's type and value, as ``fit`` does (and raise).

        Subclasses extend it for their own; ``fit`` and ``from_dict`` both call it, so a
        new hyperparameter is checked on both paths once it is checked here.
        """
        if self.voltage_range is not None:
            check_range(self.voltage_range, "voltage_range", type(self).__name__)

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

    def set_params(self, **params) -> HysteresisModel:
        """Set hyperparameters by name (checked in :meth:`fit`, as in scikit-learn).

        Learned attributes stay as they are until the next :meth:`fit`.

        Returns
        -------
        HysteresisModel
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

    def score(self, v, x) -> float:
        """Coefficient of determination R² of the displacement predicted for ``v``.

        ``1 - sum((x - x_hat)^2) / sum((x - mean(x))^2)`` with ``x_hat = simulate(v)``, as
        scikit-learn's regressors score; 1 is a perfect prediction. Like
        ``sklearn.metrics.r2_score``, a constant ``x`` scores 1.0 if predicted exactly,
        else 0.0.

        Parameters
        ----------
        v, x : array_like
            Input voltage (V) and measured displacement (µm), one sample each per instant.

        Returns
        -------
        float
        """
        v, x = as_signal_pair(v, x, ("v", "x"), f"{type(self).__name__}.score")
        residual = float(np.sum((x - self.simulate(v)) ** 2))
        total = float(np.sum((x - x.mean()) ** 2))
        if total == 0.0:
            return 1.0 if residual == 0.0 else 0.0
        return 1.0 - residual / total

    def parameters(self) -> dict[str, Any]:
        """The learned parameters as plain Python values (lists and floats)."""
        self._check_fitted()
        out = {}
        for name in self._learned:
            value = getattr(self, name + "_")
            out[name] = value.tolist() if isinstance(value, np.ndarray) else value
        return out

    def to_dict(self) -> dict[str, Any]:
        """Kind, hyperparameters, parameters and fit report, ready for JSON."""
        out = {
            "kind": self.kind,
            "hyperparameters": self.get_params(),
            "parameters": self.parameters(),
        }
        report = getattr(self, "fit_report_", None)
        if report is not None:
            out["fit_report"] = dict(report)
        return out

    @classmethod
    def from_dict(cls, data: dict[str, Any]):
        """Inverse of :meth:`to_dict` (validates everything through ``from_parameters``).

        :func:`hystcomp.io.model_from_dict` checks a whole document (keys, JSON types) first.
        """
        if not (isinstance(data, dict) and isinstance(data.get("parameters"), dict)):
            raise InvalidParameterError(
                f"{cls.__name__}.from_dict needs a dict with a 'parameters' dict (as written "
                f"by to_dict). Got {type(data).__name__}."
            )
        model = cls.from_parameters(**data["parameters"])
        derived = model._derived_hyperparameters()
        for name, value in data.get("hyperparameters", {}).items():
            if name not in cls._get_param_names():
                continue
            if name in derived and not _same_value(value, derived[name]):
                raise InvalidParameterError(
                    f"The hyperparameter {name!r} of this {cls.__name__} is {value!r}, but its "
                    f"parameters give {derived[name]!r}: the two disagree. The file was "
                    f"edited by hand; set {name!r} to {derived[name]!r} or identify again."
                )
            setattr(model, name, value)
        model._check_hyperparameters()  # every value, as fit() would check it
        if "fit_report" in data:
            model.fit_report_ = dict(data["fit_report"])
        return model

    _estimator_type = "regressor"  # what scikit-learn < 1.6 reads

    def __sklearn_tags__(self):
        """scikit-learn's description (>= 1.6): a regressor of 1-D signals.

        Called only by scikit-learn, so importing it here adds no dependency.
        """
        from sklearn.utils import InputTags, RegressorTags, Tags, TargetTags

        return Tags(
            estimator_type="regressor",
            target_tags=TargetTags(required=True, one_d_labels=True),
            input_tags=InputTags(one_d_array=True, two_d_array=False),
            regressor_tags=RegressorTags(),
        )

    def _clamp_range(self, voltage_range, owner: str) -> tuple[float, float]:
        """The compensator's clamp: ``voltage_range_``, or a ``voltage_range`` inside it.

        A compensator may be told to stay in a narrower range than the model's (a stage
        rated below the amplifier), never a wider one: the model was identified inside its
        range and says nothing about the actuator outside it.
        """
        lo, hi = self.voltage_range_
        if voltage_range is None:
            return lo, hi
        low, high = check_range(voltage_range, "voltage_range", owner)
        if low < lo or high > hi:
            raise InvalidParameterError(
                f"The 'voltage_range' parameter of {owner} may only narrow the model's voltage "
                f"range {lo:g} .. {hi:g} V: the model was identified inside it and would "
                f"command voltages it never saw. Got {low:g} .. {high:g} V; choose limits "
                f"within {lo:g} .. {hi:g} V, or identify the model over a wider range."
            )
        return low, high

    def reachable_range(self, voltage_range=None) -> tuple[float, float]:
        """The displacements (µm) the model reaches with voltages inside a range.

        The extremes of the major loop: the model run from its initial state over
        ``lo -> hi -> lo -> hi`` (its branches are monotone, so the extremes lie at the
        ends). A compensator clamps every reference beyond this range
        (:meth:`Compensator.run <hystcomp.models.compensator.Compensator.run>` counts them).

        Parameters
        ----------
        voltage_range : (float, float), optional
            A range in V inside ``voltage_range_`` (default: ``voltage_range_``).

        Returns
        -------
        (float, float)
            Lowest and highest displacement in µm.
        """
        self._check_fitted()
        lo, hi = self._clamp_range(voltage_range, f"{type(self).__name__}.reachable_range")
        x = self.simulate(np.array([lo, hi, lo, hi]))
        return float(x.min()), float(x.max())

    def _adopt(self, fitted: HysteresisModel, fit_report: dict) -> None:
        """Take the learned parameters of ``fitted`` (built by ``from_parameters``, so validated)."""
        for name in self._learned:
            setattr(self, name + "_", getattr(fitted, name + "_"))
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


def check_play_hyperparameters(model) -> None:
    """The hyperparameters of every PI-type model: operator count, transient, margin,
    constraints (the range is checked by ``HysteresisModel._check_hyperparameters``)."""
    owner = type(model).__name__
    check_int(model.n_operators, "n_operators", owner)
    check_fit_options(model, owner)
    check_constraints(model.constraints, owner)


def set_common_parameters(model, owner, *, voltage_range, input_offset, output_offset):
    """Validate and set the parameters every PI-type model has."""
    model.voltage_range_ = check_range(voltage_range, "voltage_range", owner)
    model.input_offset_ = check_real(input_offset, "input_offset", owner)
    model.output_offset_ = check_real(output_offset, "output_offset", owner)


def initial_state_or_zero(initial_state, length, owner):
    """Eq. (18): play states start at 0 unless given."""
    if initial_state is None:
        out = np.zeros(length)
        out.setflags(write=False)
        return out
    return as_vector(initial_state, "initial_state", owner, length=length)


def slew_to_step(slew_rate, sample_rate, owner) -> float:
    """Largest voltage change per sample from a slew-rate limit in V/s (``inf`` if None)."""
    if slew_rate is None:
        return np.inf
    slew_rate = check_real(slew_rate, "slew_rate", owner, positive=True)
    sample_rate = check_real(sample_rate, "sample_rate", owner, positive=True)
    return slew_rate / sample_rate


def fit_voltage_range(voltage_range, v, owner) -> tuple[float, float]:
    """The ``voltage_range`` hyperparameter, or the data's ``(min v, max v)`` if it is None."""
    if voltage_range is None:
        v = np.asarray(v, dtype=np.float64)
        return float(v.min()), float(v.max())
    return check_range(voltage_range, "voltage_range", owner)


def thinned_record(v, x, fit) -> tuple[np.ndarray, np.ndarray, int]:
    """The samples a PI/MPI fit ran over (``fit.samples``), and the first one in its cost.

    For a record longer than :data:`hystcomp.identify.scoring.MAX_SAMPLES` these are its
    turning points and a regular subset: the fit report and the tracking estimate are
    computed there, which gives the same figures as the whole record at a fraction of the
    cost (rate independence).
    """
    keep = fit.samples
    v, x = np.asarray(v, dtype=np.float64), np.asarray(x, dtype=np.float64)
    if keep is None or keep.size == v.size:
        return v, x, fit.first_sample
    return v[keep], x[keep], int(np.searchsorted(keep, fit.first_sample))


def check_fit_options(model, owner) -> None:
    """Validate the identification hyperparameters ``transient`` and ``margin``."""
    if model.transient is not None:
        check_int(model.transient, "transient", owner, minimum=0)
    check_margin(model.margin, owner)


def set_plays(model, owner, *, thresholds, weights, initial_state) -> np.ndarray:
    """Validate and set a PI-type model's plays (``thresholds_``, ``weights_``,
    ``initial_state_``); returns the thresholds."""
    r = check_thresholds(thresholds, "thresholds", owner)
    model.thresholds_ = r
    model.weights_ = as_vector(weights, "weights", owner, length=r.size)
    model.initial_state_ = initial_state_or_zero(initial_state, r.size, owner)
    return r


def inverse_play_compensator(
    model, *, slew_rate, sample_rate, voltage_range, pre=None
) -> Compensator:
    """The compensator of a PI-type ``model`` (invertibility already checked).

    The chain ``x -> (x - x_0) -> [pre dead-zones] -> inverse plays (eqs. 24-26) -> + v_0``,
    slew-limited and clamped to ``voltage_range_`` or a narrower ``voltage_range``.
    """
    owner = type(model).__name__
    max_step = slew_to_step(slew_rate, sample_rate, owner)
    lo, hi = model._clamp_range(voltage_range, f"{owner}.inverse")
    packed = operators.pack_chain(
        pre=pre,
        plays=(
            *invert_superposition(model.thresholds_, model.weights_),
            inverse_initial_state(model.weights_, model.initial_state_),
        ),
        in_offset=model.output_offset_,
        out_offset=model.input_offset_,
        low=lo,
        high=hi,
        max_step=max_step,
    )
    return Compensator(packed, kind=model.kind, voltage_range=(lo, hi))
