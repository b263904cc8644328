"""The simulated piezo axis ("twin") of the paper's Section II, batch and streaming.

``command v (V) -> amplifier (static gain, rails) -> hysteresis H -> [creep] -> D(s)
-> capacitive sensor (gain, noise, offset) -> displacement (µm)``

The twin starts at rest at the low end of its voltage range with the sensor reading
``sensor_offset``. It is an immutable set of parameters: :meth:`Twin.run` starts from
rest every time, and only the noise generator, seeded once, advances from run to run, so
a sequence of experiments is reproducible from the seed.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from hystcomp._kernels import twin as k
from hystcomp._kernels._jit import step_function
from hystcomp._validation import as_signal, check_int, check_real
from hystcomp.errors import InvalidTypeError
from hystcomp.models.system import Stepper
from hystcomp.plant.parameters import TwinParameters, dynamics_matrices

#: The Bouc-Wen state at rest: the actuator was last driven down to the low rail.
REST_STATE = -1.0


def _pack(params: TwinParameters) -> np.ndarray:
    """Packed parameters and rest state for the kernels (see :mod:`hystcomp._kernels.twin`)."""
    ad, bd = dynamics_matrices(params)
    lo, hi = params.voltage_range
    taus = np.asarray(params.creep_time_constants, dtype=np.float64)
    if params.creep_gain == 0.0:
        taus = taus[:0]
    lags = np.exp(-params.sample_time / taus)
    gains = np.full(taus.size, params.creep_gain / max(taus.size, 1))
    head = [lo, hi, params.amplifier_gain, *params.anhysteretic, params.hysteresis_amplitude]
    head += [params.hysteresis_onset, params.bouc_wen_rate, params.bouc_wen_shape]
    head += [ad[0, 0], ad[0, 1], ad[1, 0], ad[1, 1], bd[0], bd[1], taus.size]
    state = np.zeros(k.S_CREEP + taus.size)
    state[k.S_Z] = REST_STATE
    packed = np.concatenate([np.asarray(head, dtype=np.float64), lags, gains, state])
    packed.setflags(write=False)
    return packed


class SampleClock(ABC):
    """What a plant at a fixed ``sample_rate`` (Hz) shares: the times of its samples."""

    @property
    @abstractmethod
    def sample_rate(self) -> float:
        """The sample rate, Hz (each plant says its own)."""

    def time(self, n_samples: int) -> np.ndarray:
        """Time of ``n_samples`` samples from 0, in s.

        Parameters
        ----------
        n_samples : int
            The number of samples.

        Returns
        -------
        numpy.ndarray
            ``arange(n_samples) / sample_rate``, s.
        """
        n = check_int(n_samples, "n_samples", f"{type(self).__name__}.time", minimum=0)
        return np.arange(n) / self.sample_rate


class Twin(SampleClock):
    """The simulated piezo axis: command voltage (V) in, measured displacement (µm) out.

    Parameters
    ----------
    params : TwinParameters, optional
        The axis; the default is calibrated on the paper's rig (see
        :mod:`hystcomp.plant.parameters`).
    seed : int, default 0
        Seed of the sensor-noise generator.

    Examples
    --------
    >>> twin = Twin(seed=1)
    >>> v = np.linspace(0.0, 120.0, 20_001)
    >>> x = twin.run(v)                      # µm, with sensor noise
    >>> round(float(twin.run_noiseless(v)[-1]), 1)
    37.0
    >>> t = twin.time(v.size)                # s, at 20 kHz
    >>> float(t[1])
    5e-05
    """

    def __init__(self, params: TwinParameters | None = None, *, seed: int = 0):
        if params is None:
            params = TwinParameters()
        if not isinstance(params, TwinParameters):
            raise InvalidTypeError(
                f"The 'params' parameter of Twin must be a TwinParameters. "
                f"Got {type(params).__name__}; build one with TwinParameters(...)."
            )
        self.params = params
        self.seed = check_int(seed, "seed", "Twin", minimum=0)
        self._rng = np.random.default_rng(self.seed)
        self._packed = _pack(params)
        start = k.state_start.py_func(self._packed)
        self._p = self._packed[:start]  # the parameters
        self._rest = self._packed[start:]  # the state at rest

    @property
    def sample_rate(self) -> float:
        """Sampling frequency in Hz."""
        return float(self.params.sample_rate)

    @property
    def voltage_range(self) -> tuple[float, float]:
        """The amplifier's rails in V."""
        return self.params.voltage_range

    def run_noiseless(self, v) -> np.ndarray:
        """Displacement in µm for the command ``v`` in V, from rest, without sensor noise.

        Parameters
        ----------
        v : array_like
            The command, V, at the twin's sample rate.

        Returns
        -------
        numpy.ndarray
            The displacement, µm.
        """
        u = as_signal(v, "v")
        out = np.empty_like(u)
        k.twin_run(self._packed.copy(), u, out)
        return out + self.params.sensor_offset

    def run(self, v) -> np.ndarray:
        """Measured displacement in µm for the command ``v`` in V (from rest, with noise).

        The sensor reads ``G_cap x + n`` volts and the acquisition divides by ``G_cap``.

        Parameters
        ----------
        v : array_like
            The voltage command, V, one sample per ``1 / sample_rate`` s.

        Returns
        -------
        numpy.ndarray
            The measured displacement, µm: :meth:`run_noiseless` plus white sensor noise of
            ``sensor_noise / sensor_gain`` µm rms, from the twin's random generator.
        """
        x = self.run_noiseless(v)
        return x + self._noise(x.size)

    def hysteresis(self, v) -> np.ndarray:
        """The quasi-static displacement ``H[v]`` in µm (no creep, no dynamics, no noise).

        Parameters
        ----------
        v : array_like
            The command, V.

        Returns
        -------
        numpy.ndarray
            The quasi-static displacement, µm.
        """
        u = as_signal(v, "v")
        out = np.empty_like(u)
        k.hysteresis_run(self._packed.copy(), u, out)
        return out

    def stepper(self, *, noise: bool = True) -> TwinStepper:
        """A streaming twin, one sample per call, at rest.

        Parameters
        ----------
        noise : bool, default True
            Add the sensor's noise, from a generator of its own (spawned from the twin's);
            False reads the displacement without noise (the offset is still added), and
            leaves the twin's generator as it was.

        Returns
        -------
        TwinStepper
            A stepper at rest.
        """
        return TwinStepper(self._packed, self.params, self._rng.spawn(1)[0] if noise else None)

    def _noise(self, n: int) -> np.ndarray:
        sigma = self.params.sensor_noise / self.params.sensor_gain
        return sigma * self._rng.standard_normal(n)

    def __repr__(self) -> str:
        if self.params == TwinParameters():
            return f"Twin(seed={self.seed})"
        return f"Twin({self.params!r}, seed={self.seed})"


class TwinStepper(Stepper):
    """The twin one sample at a time: the package's :class:`~hystcomp.models.system.Stepper`
    over the twin's kernel (the same as :meth:`Twin.run`'s), plus the sensor's offset and noise.

    Use it in a loop with a compensator's stepper: ``x_k = twin.step(comp.step(x_ref_k))``.
    Unlike a compensator's stepper it refuses a non-finite command (a simulation has no
    reason to send one), so :attr:`nonfinite_count` and :attr:`clamped_count` stay 0.

    Parameters
    ----------
    packed : numpy.ndarray
        The twin's packed system (parameters and state at rest).
    params : TwinParameters
        The twin's parameters (sensor offset and noise).
    rng : numpy.random.Generator
        The noise generator; the stepper owns it.
    """

    kernels = k.TWIN_KERNELS

    def __init__(self, packed, params: TwinParameters, rng: np.random.Generator | None):
        super().__init__(packed)
        self._params = params
        self._offset = params.sensor_offset
        self._sigma = params.sensor_noise / params.sensor_gain
        self._rng = rng

    @classmethod
    def _checked(cls, packed) -> np.ndarray:
        return packed  # made only by Twin.stepper, from the array the twin packed

    def _bind(self) -> None:
        super()._bind()
        self._kernel = step_function(self.kernels.step)
        # the base class binds a step and a step_block without the sensor; use the methods below
        del self.step
        self.__dict__.pop("step_block", None)

    def step(self, v: float) -> float:
        """Apply one command sample (V) and return the measured displacement (µm).

        Parameters
        ----------
        v : float
            The command, V.

        Returns
        -------
        float
            The measured displacement, µm.
        """
        v = check_real(v, "v", "TwinStepper.step")
        x = self._kernel(self._p, v) + self._offset
        return x if self._rng is None else x + self._sigma * self._rng.normal()

    def step_block(self, v, out=None) -> np.ndarray:
        """Apply a block of command samples and return the measured displacements (into
        ``out`` if given, as :meth:`Stepper.step_block <hystcomp.models.system.Stepper.step_block>`).

        Parameters
        ----------
        v : array_like
            Command samples, V.
        out : numpy.ndarray, optional
            Where to write the displacements (a new array if None).

        Returns
        -------
        numpy.ndarray
            The measured displacements, µm.
        """
        u = as_signal(v, "v")
        x = super().step_block(u, out)
        if self._rng is None:
            x += self._offset
        else:
            x += self._offset + self._sigma * self._rng.standard_normal(u.size)
        return x

    def copy(self) -> TwinStepper:
        """An independent stepper in the same state, with a noise generator spawned from this
        one's.

        Returns
        -------
        TwinStepper
            A new stepper in this one's state.
        """
        rng = None if self._rng is None else self._rng.spawn(1)[0]
        twin = type(self)(self._initial, self._params, rng)
        twin._p[:] = self._p
        return twin

    def reset(self) -> None:
        """Back to rest (the noise generator keeps going)."""
        super().reset()
