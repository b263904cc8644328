"""The twin's parameters: one frozen dataclass, every value documented with its source.

The paper's rig (Section II, Fig. 2): ``voltage amplifier -> hysteresis H -> piezo
dynamics D(s) -> capacitive sensor``, sampled at 20 kHz.

==========================  ====================  ===========================================
parameter                   default               source
==========================  ====================  ===========================================
``sample_rate``             20 000 Hz             Section II (xPC Target acquisition)
``voltage_range``           0 .. 120 V            Section II/IV: the piezo voltage ``v_px``
``amplifier_gain``          1 V/V                 the command is already ``v_px`` (the
                                                  paper's identification signals are in
                                                  piezo volts); the amplifier's static gain
                                                  ``G_v`` is folded in, its rails clamp
``anhysteretic``            (24.68, 35.13,        fitted: the loops of the paper's
                            -20.59) µm            identified Preisach model (eqs. 5-6) for
``hysteresis_amplitude``    2.272 µm              30/60/90/120 V sinusoids (its Fig. 5),
``hysteresis_onset``        0.0914                with the stroke held at 37 µm and the
``bouc_wen_rate``           6.763                 hysteresis of the saturation zone at 10 %
``bouc_wen_shape``          0.6749                (Section V); see ``experiment/calibration``
``resonance_hz``            630 Hz                Section II: bandwidth of the T-402 piezo
``damping_ratio``           0.1                   not given; lightly damped, chosen from the
                                                  paper's 1 -> 50 Hz degradation (see note)
``creep_gain``              0 (off)               not in the paper's model (Fig. 2); 3 % in
                                                  :func:`creep_twin` (see note)
``creep_time_constants``    1 ms .. 100 s         one lag per decade, equal gains: the
                                                  step response rises as ``log t``
``sensor_gain``             0.2 V/µm              Section II: CS005, 200 V/mm
``sensor_noise``            0.6 mV rms            assumed: 3 nm rms at the sensor gain, the
                                                  order of a capacitive sensor at 8.5 kHz
``sensor_offset``           0 µm                  the sensor is zeroed at rest
==========================  ====================  ===========================================

Notes
-----
* The hysteresis is a rate-independent Bouc-Wen model (``n = 1``, normalised form) whose
  output passes through an input-dependent gain and adds to a smooth anhysteretic curve
  (see :mod:`hystcomp._kernels.twin`). It is none of the compensators' families (PI, MPI,
  polynomial-Everett Preisach): no method matches it by construction. The hysteretic gain
  ``w0 (1 - exp(-u / u_w))`` vanishes at the low end of the range, so that every loop that
  returns to 0 V closes at the rest position, as the paper's nested loops do (Fig. 5); the
  cubic anhysteretic curve is convex at low voltage and saturates at high voltage.
* Section II quotes 235 nm/V for the actuator, but every model the paper identified on the
  rig (eqs. 6, 20, 21-22) has 36-38 µm of stroke at 120 V, i.e. about 306 nm/V on average:
  the twin follows the identified models, since they are what the compensators saw.
* Damping: the paper gives the bandwidth only. From 1 to 50 Hz its compensated errors grow
  by 0.9 to 1.6 µm at their maximum (Table I). On a 50 Hz, 33 µm triangle the twin's linear
  dynamics alone (the ringing after each corner, the lag of the ramps) give 0.51 µm rms and
  1.68 µm max with ``zeta = 0.1`` (0.79 and 1.88 with 0.03, 0.53 and 1.59 with 0.2), and
  the compensated errors of the compare run grow by the paper's amounts (PI: +0.9 µm max,
  the paper's +0.9). Lighter damping makes the 50 Hz runs ring through whole periods.
* Creep: a piezo stage held after a step keeps moving by a few percent, about equally per
  decade of time (``x(t) ~ x_0 (1 + gamma log10(t / t_0))``). Equal first-order lags with
  one time constant per decade give nearly that between the shortest and the longest
  time constant: with the default 1 ms .. 100 s and ``creep_gain = 0.03``, about 0.5 % of
  the final displacement per decade; after a step to 60 V the displacement still rises by
  1.0 % of its final value after 1 s, and by 1.1 % (0.18 µm) from 20 ms to 3 s.
  The paper's model of its rig (Fig. 2) has no creep, and the twin's default has none;
  ``hystcomp compare`` runs on :func:`creep_twin` (see :mod:`hystcomp.experiment.compare`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from hystcomp import paper
from hystcomp._lti import zoh_matrices
from hystcomp._validation import check_range, check_real
from hystcomp.errors import InvalidParameterError

_OWNER = "TwinParameters"


@dataclasses.dataclass(frozen=True)
class TwinParameters:
    """Parameters of the simulated piezo axis; the defaults are the paper's rig (see module).

    Attributes
    ----------
    sample_rate : float
        Sampling frequency in Hz.
    voltage_range : (float, float)
        The amplifier's output rails in V: the piezo voltage is clamped to it.
    amplifier_gain : float
        Static gain from command to piezo voltage, V/V.
    anhysteretic : (float, float, float)
        ``(c1, c2, c3)`` in µm: the anhysteretic curve ``c1 u + c2 u^2 + c3 u^3`` of the
        normalised piezo voltage ``u`` (0 at the low rail, 1 at the high rail).
    hysteresis_amplitude : float
        ``w0`` in µm: the gain of the hysteretic state at high voltage.
    hysteresis_onset : float
        ``u_w`` (fraction of the range): the hysteretic gain reaches 63 % of ``w0`` there.
    bouc_wen_rate : float
        ``rho``, per unit of normalised voltage: how fast the hysteretic state turns.
    bouc_wen_shape : float
        ``sigma > 0``: the state turns faster just after a reversal when ``sigma > 1/2``.
    resonance_hz, damping_ratio : float
        ``D(s) = wn^2 / (s^2 + 2 zeta wn s + wn^2)``, ``wn = 2 pi resonance_hz``.
    creep_gain : float
        Extra displacement reached by creep after a long hold, as a fraction (0: no creep).
    creep_time_constants : tuple of float
        Time constants of the creep lags in s (the gain is shared equally between them).
    sensor_gain : float
        Capacitive sensor gain in V/µm; the twin divides by it, as an acquisition would.
    sensor_noise : float
        Sensor noise in V rms (white, Gaussian).
    sensor_offset : float
        Sensor reading at rest, in µm.
    """

    sample_rate: float = paper.SAMPLE_RATE
    voltage_range: tuple[float, float] = paper.VOLTAGE_RANGE
    amplifier_gain: float = 1.0
    anhysteretic: tuple[float, float, float] = (24.68, 35.13, -20.59)
    hysteresis_amplitude: float = 2.272
    hysteresis_onset: float = 0.0914
    bouc_wen_rate: float = 6.763
    bouc_wen_shape: float = 0.6749
    resonance_hz: float = paper.PIEZO_BANDWIDTH
    damping_ratio: float = 0.1
    creep_gain: float = 0.0
    creep_time_constants: tuple[float, ...] = (1e-3, 1e-2, 0.1, 1.0, 10.0, 100.0)
    sensor_gain: float = paper.SENSOR_GAIN
    sensor_noise: float = 0.6e-3
    sensor_offset: float = 0.0

    def __post_init__(self):
        for name in ("sample_rate", "amplifier_gain", "hysteresis_onset", "bouc_wen_rate"):
            check_real(getattr(self, name), name, _OWNER, positive=True)
        for name in ("bouc_wen_shape", "resonance_hz", "damping_ratio", "sensor_gain"):
            check_real(getattr(self, name), name, _OWNER, positive=True)
        for name in ("hysteresis_amplitude", "creep_gain", "sensor_noise"):
            if check_real(getattr(self, name), name, _OWNER) < 0:
                raise InvalidParameterError(
                    f"The {name!r} parameter of {_OWNER} must be >= 0. "
                    f"Got {getattr(self, name)!r} instead."
                )
        check_real(self.sensor_offset, "sensor_offset", _OWNER)
        object.__setattr__(
            self, "voltage_range", check_range(self.voltage_range, "voltage_range", _OWNER)
        )
        try:
            coefficients = tuple(self.anhysteretic)
        except TypeError:
            coefficients = ()
        if len(coefficients) != 3:
            raise InvalidParameterError(
                f"The 'anhysteretic' parameter of {_OWNER} must be three coefficients "
                f"(c1, c2, c3) in µm. Got {self.anhysteretic!r} instead."
            )
        object.__setattr__(
            self, "anhysteretic", tuple(check_real(c, "anhysteretic", _OWNER) for c in coefficients)
        )
        object.__setattr__(
            self,
            "creep_time_constants",
            tuple(
                check_real(tau, "creep_time_constants", _OWNER, positive=True)
                for tau in self.creep_time_constants
            ),
        )
        nyquist = 0.5 * float(self.sample_rate)
        if self.resonance_hz >= nyquist:
            raise InvalidParameterError(
                f"The 'resonance_hz' parameter of {_OWNER} must be below the Nyquist frequency "
                f"({nyquist:g} Hz at sample_rate={self.sample_rate:g}). Got {self.resonance_hz!r}; "
                "raise the sample rate or lower the resonance."
            )

    @property
    def sample_time(self) -> float:
        """Sampling period in s."""
        return 1.0 / float(self.sample_rate)

    def replace(self, **changes) -> TwinParameters:
        """A copy with some parameters changed (validated again).

        Parameters
        ----------
        **changes
            New values by parameter name.

        Returns
        -------
        TwinParameters
            The copy.
        """
        return dataclasses.replace(self, **changes)


def dynamics_matrices(params: TwinParameters) -> tuple[np.ndarray, np.ndarray]:
    """``(Ad, Bd)`` of the exact zero-order-hold discretisation of ``D(s)``.

    States are position (µm) and velocity (µm/s); the position is the output and the DC
    gain is 1. In closed form (:func:`hystcomp._lti.zoh_matrices`, the discretisation that
    the identification fits), which agrees with ``scipy.linalg.expm`` of the augmented
    matrix to 1e-15 and spares ``hystcomp compare`` SciPy's import (0.2 s).

    Parameters
    ----------
    params : TwinParameters
        The twin's parameters (resonance, damping, sample rate).

    Returns
    -------
    Ad : numpy.ndarray
        The state matrix, shape ``(2, 2)``.
    Bd : numpy.ndarray
        The input matrix, shape ``(2,)``.
    """
    return zoh_matrices(params.resonance_hz, params.damping_ratio, float(params.sample_rate))


#: Creep of :func:`creep_twin`: 3 % after a long hold, as on a typical stack actuator.
CREEP_GAIN = 0.03


def creep_twin(**changes) -> TwinParameters:
    """The default twin with creep switched on (:data:`CREEP_GAIN`), plus any ``changes``.

    >>> creep_twin().creep_gain
    0.03

    Parameters
    ----------
    **changes
        Further parameters to change by name.

    Returns
    -------
    TwinParameters
        The parameters of the twin with creep.
    """
    return TwinParameters(**{"creep_gain": CREEP_GAIN, **changes})
