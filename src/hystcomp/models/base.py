"""What the Prandtl-Ishlinskii-type models share: parameters, fitted check, serialisation."""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from hystcomp import operators
from hystcomp._validation import as_vector, check_int, check_range, check_real, check_thresholds
from hystcomp.errors import InvalidParameterError, NotFittedError
from hystcomp.identify.pi import check_margin
from hystcomp.models.compensator import ChainSystem, Compensator
from hystcomp.models.inversion import inverse_initial_state, invert_superposition

DEFAULT_VOLTAGE_RANGE = (0.0, 120.0)


class HysteresisModel(ChainSystem):
    """Base of the forward models: voltage (V) in, displacement (µm) out.

    Subclasses list their learned parameters in ``_learned`` (names without the trailing
    underscore) and their hyperparameters in ``_hyper``; the learned attributes end in ``_``
    as in scikit-learn. A model without learned parameters can only be fitted.
    """

    kind: ClassVar[str]
    _hyper: ClassVar[tuple[str, ...]]
    _learned: ClassVar[tuple[str, ...]]

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

    def get_params(self) -> dict[str, Any]:
        """The hyperparameters given to ``__init__``."""
        return {name: getattr(self, name) for name in self._hyper}

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
            if name not in cls._hyper:
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
        args = ", ".join(f"{k}={v!r}" for k, v in self.get_params().items())
        state = "" if hasattr(self, self._learned[0] + "_") else ", unfitted"
        return f"{type(self).__name__}({args}{state})"


def _same_value(value, expected) -> bool:
    """Equal and of the same JSON type (3 is not 3.0, "3" or True)."""
    return type(value) is type(expected) and value == expected


def check_play_hyperparameters(model) -> None:
    """The hyperparameters of every PI-type model: operator count, range, transient, margin."""
    owner = type(model).__name__
    check_int(model.n_operators, "n_operators", owner)
    check_fit_options(model, owner)


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
