"""A stage as one pair: a hysteresis model followed by linear dynamics, ``x = D[H[v]]``.

Beyond the paper. The paper's rig (its Fig. 2) is an amplifier, the hysteresis, then the
piezo's dynamics; its compensators invert the hysteresis alone. With the dynamics inverted
too, ``v = H^-1[D^-1[x_ref]]`` (Croft, Shed and Devasia 2001), the two parts must be one
consistent pair, a Hammerstein model:

* ``D`` is identified *behind* ``H``: its input is the hysteresis model's output ``H[v]``
  on a record at the amplitudes tracking uses (``hystcomp excite dynamics``), not the
  voltage;
* ``H`` is identified *in front of* ``D``: on the hysteresis record with ``D``'s creep and
  lag taken out, ``D^-1[x]`` (:meth:`LinearDynamics.remove`). A hysteresis model fitted
  on the raw 1 Hz record already holds the creep and lag of that record, and ``D^-1``
  would correct them a second time;
* the two fits alternate until ``H`` no longer changes (:func:`fit_pair`, at most
  :data:`MAX_ROUNDS` rounds).

The inverse of a pair inverts ``D`` with its unit steady-state gain; a hysteresis model and
dynamics identified apart (``model.inverse(dynamics=dyn)``) are matched at 1 Hz instead
(:func:`~hystcomp.models.dynamics.with_dynamics`), and warned about.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from hystcomp._validation import as_signal, as_signal_pair, check_int, check_real
from hystcomp.errors import IdentificationError, InvalidTypeError
from hystcomp.identify.scoring import transient_end
from hystcomp.models.base import HysteresisModel
from hystcomp.models.dynamic_compensator import DynamicCompensator
from hystcomp.models.dynamics import LinearDynamics, check_dynamics, with_dynamics
from hystcomp.models.estimator import ModelFile
from hystcomp.models.mpi import ModifiedPrandtlIshlinskii
from hystcomp.models.pi import PrandtlIshlinskii
from hystcomp.models.preisach import Preisach

__all__ = ["HammersteinModel", "fit_pair"]

#: Most rounds of the alternation of :func:`fit_pair`.
MAX_ROUNDS = 4
#: The alternation stops when a round moves ``H``'s output on the dynamics record by less
#: than this share of its span.
TOLERANCE = 1e-3


class HammersteinModel(ModelFile):
    """A hysteresis model in series with linear dynamics, identified as one pair.

    Building one from parts that were identified apart is the caller's statement that they
    belong together; :func:`fit_pair` (reported by
    :func:`hystcomp.workflows.pair.identify_pair_record`) identifies them as a pair.

    Parameters
    ----------
    hysteresis : PrandtlIshlinskii, ModifiedPrandtlIshlinskii or Preisach
        The fitted hysteresis model ``H`` (voltage V -> µm, before the dynamics).
    dynamics : LinearDynamics
        The linear dynamics ``D`` (unit steady-state gain), identified behind ``H``.

    Attributes
    ----------
    kind : str
        ``"hammerstein"``, the model file's kind.
    fit_report_ : dict
        Present after :func:`fit_pair`: the rounds of the alternation, ``H``'s and
        ``D``'s fit reports (and, from ``hystcomp identify``, the tracking estimates).
    """

    kind: ClassVar[str] = "hammerstein"
    fit_report_: dict[str, Any]
    hysteresis_alone_: HysteresisModel

    def __init__(self, hysteresis, dynamics):
        if not isinstance(hysteresis, HysteresisModel):
            raise InvalidTypeError(
                "The 'hysteresis' argument of HammersteinModel must be a fitted PI, MPI or "
                f"Preisach model. Got {type(hysteresis).__name__}."
            )
        check_dynamics(dynamics, "The 'dynamics' argument of HammersteinModel")
        hysteresis._check_fitted()
        dynamics._check_fitted()
        self.hysteresis = hysteresis
        self.dynamics = dynamics

    @property
    def sample_rate(self) -> float:
        """Hz: that of the dynamics, the only rate the pair runs at."""
        return self.dynamics.sample_rate_

    @property
    def voltage_range_(self) -> tuple[float, float]:
        """The hysteresis model's voltage range (V), the compensator's clamp."""
        return self.hysteresis.voltage_range_

    def simulate(self, v) -> np.ndarray:
        """``D[H[v]]`` (µm) for a voltage ``v`` (V) at :attr:`sample_rate`, from rest.

        At rest means where the compensator starts: ``H`` in its initial state and ``D``
        settled at the hysteresis model's output for the low end of its voltage range (a
        first sample elsewhere is a step from there).

        Parameters
        ----------
        v : array_like
            The voltage, V, at :attr:`sample_rate`.

        Returns
        -------
        numpy.ndarray
            The displacement, µm, one sample per voltage sample.
        """
        v = as_signal(v, "v")
        lo = self.hysteresis.voltage_range_[0]
        rest = float(self.hysteresis.simulate(np.array([lo]))[0])
        u = np.asarray(self.hysteresis.simulate(v), dtype=np.float64)
        return self.dynamics.simulate(u, initial=rest)

    def reachable_range(self, voltage_range=None) -> tuple[float, float]:
        """The displacements (µm) the pair reaches at rest (those of the hysteresis model).

        Parameters
        ----------
        voltage_range : tuple of (float, float), optional
            A narrower voltage range, V (the model's own if None).

        Returns
        -------
        tuple of (float, float)
            The lowest and highest displacement reachable, µm.
        """
        return self.hysteresis.reachable_range(voltage_range)

    def inverse(
        self, *, slew_rate=None, voltage_range=None, bandwidth_hz=None, **method
    ) -> DynamicCompensator:
        """The compensator ``v = H^-1[D^-1[x_ref]]``, clamped to the voltage range.

        ``D^-1`` is the stable, look-ahead inverse of
        :meth:`LinearDynamics.inverse` with its unit steady-state gain: ``H`` was fitted in
        front of ``D``, so nothing is matched or scaled (unlike dynamics paired after the
        fact, :func:`~hystcomp.models.dynamics.with_dynamics`).

        Parameters
        ----------
        slew_rate, voltage_range
            As in the hysteresis model's ``inverse``; the compensator runs at
            :attr:`sample_rate`.
        bandwidth_hz : float, optional
            Band of the inverse of the dynamics (see :meth:`LinearDynamics.inverse`).
        **method
            ``method`` and ``rho`` of :meth:`Preisach.inverse
            <hystcomp.models.preisach.Preisach.inverse>` (the exact inverse by default).

        Returns
        -------
        DynamicCompensator
        """
        compensator = self.hysteresis.inverse(
            slew_rate=slew_rate,
            sample_rate=self.sample_rate,
            voltage_range=voltage_range,
            **_method(self.hysteresis, method),
        )
        return with_dynamics(
            self.hysteresis, compensator, self.dynamics, bandwidth_hz=bandwidth_hz, paired=True
        )

    # -- files -----------------------------------------------------------------------------

    _document_entry = None  # model_from_dict checks the two parts first

    def _document_parts(self) -> dict[str, Any]:
        return {"hysteresis": self.hysteresis.to_dict(), "dynamics": self.dynamics.to_dict()}

    @classmethod
    def _from_document(cls, data: dict[str, Any]) -> HammersteinModel:
        parts = {c.kind: c for c in (PrandtlIshlinskii, ModifiedPrandtlIshlinskii, Preisach)}
        hysteresis = parts[data["hysteresis"]["kind"]].from_dict(data["hysteresis"])
        return cls(hysteresis, LinearDynamics.from_dict(data["dynamics"]))

    def __repr__(self) -> str:
        return f"HammersteinModel({self.hysteresis!r}, {self.dynamics!r})"


def _method(hysteresis, method: dict) -> dict:
    """The Preisach inverse's ``method`` and ``rho``: the exact inverse unless said."""
    if getattr(hysteresis, "kind", None) != "preisach":
        if method:
            raise InvalidTypeError(
                f"HammersteinModel.inverse takes {', '.join(sorted(method))} for a Preisach "
                f"model only; its hysteresis is {hysteresis.kind!r}. Leave it out."
            )
        return {}
    unknown = sorted(set(method) - {"method", "rho"})
    if unknown:
        raise InvalidTypeError(
            f"HammersteinModel.inverse got an unknown option {unknown[0]!r}; a Preisach "
            "pair takes method and rho."
        )
    if method.get("method") is None and method.get("rho") is None:
        return {"method": "exact"}
    return method


def fit_pair(
    estimator,
    v,
    x,
    v_dynamics,
    x_dynamics,
    *,
    sample_rate: float,
    hysteresis_rate: float | None = None,
    rounds: int = MAX_ROUNDS,
    alone=None,
    fit_on: slice | None = None,
) -> HammersteinModel:
    """Identify a hysteresis model and the linear dynamics as one pair, ``x = D[H[v]]``.

    Parameters
    ----------
    estimator : PrandtlIshlinskii, ModifiedPrandtlIshlinskii or Preisach
        The unfitted hysteresis model (its hyperparameters are kept; it is not changed).
    v, x : array_like
        The hysteresis record (``hystcomp excite mpi``, ``rich``, ...): V and µm.
    v_dynamics, x_dynamics : array_like
        The answer to ``hystcomp excite dynamics``: V and µm at ``sample_rate``.
    sample_rate : float
        Hz of the dynamics record, the rate the pair runs at.
    hysteresis_rate : float, optional
        Hz of the hysteresis record (``sample_rate`` by default).
    rounds : int, default 4
        Most rounds of the alternation.
    alone : fitted model, optional
        ``estimator`` already fitted on ``(v, x)`` (round 0), if the caller has it.
    fit_on : slice, optional
        The samples of the hysteresis record that ``H`` is fitted on (all by default);
        ``D^-1`` is applied to the whole record first, so that its creep's state is right
        where the slice starts.

    Returns
    -------
    HammersteinModel
        With ``fit_report_``: ``rounds`` (done), ``changes`` (how far each round moved
        ``H``'s output on the dynamics record, as a share of its span), ``hysteresis`` and
        ``dynamics`` (the parts' fit reports). The hysteresis model fitted on the raw
        record (the first round's) is kept as ``hysteresis_alone_``, not in the file.

    Notes
    -----
    Round 0 fits ``H`` on ``(v, x)``. Each round fits ``D`` behind it (the input of the
    fit is ``H[v_dynamics]``), then ``H`` again on ``(v, D^-1[x])``; the alternation stops
    when ``H`` moves by less than :data:`TOLERANCE`, and ``D`` is fitted once more behind
    the last ``H``. A start-up transient of the hysteresis record is left out of the fits
    of a model without its own ``transient`` option (as ``hystcomp identify`` does).
    """
    owner = "fit_pair"
    if not isinstance(estimator, HysteresisModel):
        raise InvalidTypeError(
            f"The 'estimator' argument of {owner} must be an unfitted PI, MPI or Preisach "
            f"model. Got {type(estimator).__name__}."
        )
    v, x = as_signal_pair(v, x, ("v", "x"), owner)
    v_d, x_d = as_signal_pair(v_dynamics, x_dynamics, ("v_dynamics", "x_dynamics"), owner)
    fs = check_real(sample_rate, "sample_rate", owner, positive=True)
    fs_h = (
        fs
        if hysteresis_rate is None
        else check_real(hysteresis_rate, "hysteresis_rate", owner, positive=True)
    )
    rounds = check_int(rounds, "rounds", owner, minimum=1)
    part = slice(None) if fit_on is None else fit_on
    v_h = v[part]
    start = 0 if "transient" in estimator.get_params() else transient_end(v_h)

    def fit_h(displacement):
        model = type(estimator)(**estimator.get_params())
        return model.fit(v_h[start:], displacement[part][start:])

    h = fit_h(x) if alone is None else alone
    alone = h
    u = np.asarray(h.simulate(v_d), dtype=np.float64)
    span = float(np.ptp(u)) or 1.0
    changes = []
    for _ in range(rounds):
        d = LinearDynamics().fit(v_d, x_d, fs, u=u)
        h = fit_h(d.remove(x, fs_h))
        new = np.asarray(h.simulate(v_d), dtype=np.float64)
        changes.append(float(np.sqrt(np.mean((new - u) ** 2))) / span)
        u = new
        if changes[-1] < TOLERANCE:
            break
    d = LinearDynamics().fit(v_d, x_d, fs, u=u)
    if not np.all(np.isfinite(u)):
        raise IdentificationError(f"{owner}: the hysteresis model's output is not finite.")
    pair = HammersteinModel(h, d)
    pair.fit_report_ = {
        "rounds": len(changes),
        "changes": changes,
        "hysteresis": dict(getattr(h, "fit_report_", {})),
        "dynamics": dict(d.fit_report_),
    }
    pair.hysteresis_alone_ = alone
    return pair
