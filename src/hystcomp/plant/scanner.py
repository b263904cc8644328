"""A simulated raster scanner: two or three piezo axes of different hysteresis, coupled.

``v_i (V) -> hysteresis H_i -> mode D_i (own resonance) -> coupling M -> sensors (noise)``

Each axis has a hysteresis of none of the compensators' families (PI, MPI, polynomial
Preisach), so that no compensator wins by construction, and of a different kind per axis:

``bouc-wen``
    The twin's asymmetric Bouc-Wen model (:mod:`hystcomp._kernels.twin`) with other shape
    parameters: 0..120 V, about 30 µm, 12 % hysteresis.
``preisach``
    Relays on a 40 x 40 grid with a skewed, non-polynomial density (a log-normal ridge in
    the loop width times a skewed bump in the loop centre), then a saturating output map
    (``tanh``, which breaks the Preisach model's congruent minor loops): 0..120 V, about
    25 µm. (A Coleman-Hodgdon model was tried and left out: its minor loops do not close,
    so a small oscillation of the input drifts the displacement by several percent of the
    stroke in 20 cycles, which no stage of the accuracy panel and no real stack does.)
``kp``
    Krasnosel'skii-Pokrovskii ramps of finite width on a 24 x 24 grid beside a reversible
    part, then a saturating output map: 0..120 V, about 12 µm (a Z axis).

Then each axis's own lightly damped mode (a second-order system, zero-order hold), the
coupling ``x = M y`` of the axes' displacements ``y`` into the sensors' readings (``M``
unit diagonal: driving X moves the Y sensor by ``M_yx`` of X's displacement, as a flexure
scanner's cross-talk does), and white sensor noise. The scanner starts at rest at 0 V.

>>> import numpy as np
>>> scanner = raster_scanner(2, noise_um=0.0)
>>> x = scanner.run(np.zeros((3, 2)))
>>> x.tolist()
[[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]]
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hystcomp import paper
from hystcomp._kernels import scanner as k
from hystcomp._lti import zoh_matrices
from hystcomp._validation import check_range, check_real
from hystcomp.errors import InvalidParameterError
from hystcomp.models.multiaxis import as_axes
from hystcomp.plant.parameters import TwinParameters
from hystcomp.plant.twin import SampleClock, Twin

__all__ = ["KINDS", "Scanner", "ScannerAxis", "raster_scanner"]

#: The hysteresis kinds of an axis.
KINDS = ("bouc-wen", "preisach", "kp")
#: Bouc-Wen shape of the scanner's ``bouc-wen`` axes (the twin's model, other parameters).
_BOUC_WEN: dict[str, Any] = {
    "anhysteretic": (20.0, 28.0, -16.0),
    "hysteresis_amplitude": 2.6,
    "hysteresis_onset": 0.15,
    "bouc_wen_rate": 5.0,
    "bouc_wen_shape": 0.8,
}
#: Relay grid of the ``preisach`` axes.
_RELAY_GRID = 40
#: KP grid size and ramp width (fraction of the range).
_KP_GRID, _KP_WIDTH = 24, 0.06


@dataclass(frozen=True)
class ScannerAxis:
    """One axis of a :class:`Scanner`.

    Attributes
    ----------
    hysteresis : {'bouc-wen', 'preisach', 'kp'}
        The kind of its hysteresis (module notes).
    stroke_um : float
        Its displacement at the top of the range on the rising branch from rest, µm.
    resonance_hz, damping_ratio : float
        Its mode.
    voltage_range : (float, float)
        The amplifier's range, V (the input is clamped to it).
    """

    hysteresis: str
    stroke_um: float = 30.0
    resonance_hz: float = 600.0
    damping_ratio: float = 0.08
    voltage_range: tuple[float, float] = paper.VOLTAGE_RANGE

    def __post_init__(self):
        owner = "ScannerAxis"
        if self.hysteresis not in KINDS:
            raise InvalidParameterError(
                f"The 'hysteresis' parameter of {owner} must be one of {', '.join(KINDS)}. Got "
                f"{self.hysteresis!r} instead."
            )
        check_real(self.stroke_um, "stroke_um", owner, positive=True)
        check_real(self.resonance_hz, "resonance_hz", owner, positive=True)
        check_real(self.damping_ratio, "damping_ratio", owner, positive=True)
        object.__setattr__(
            self, "voltage_range", check_range(self.voltage_range, "voltage_range", owner)
        )


def _raw_hysteresis(kind: str, u: np.ndarray) -> np.ndarray:
    """The quasi-static displacement of a hysteresis kind for the normalised input ``u``,
    in its own units (scaled to the stroke by :meth:`Scanner.hysteresis`)."""
    out = np.empty_like(u)
    if kind == "bouc-wen":
        twin = Twin(TwinParameters(sensor_noise=0.0, **_BOUC_WEN))
        return twin.hysteresis(u * paper.VOLTAGE_RANGE[1])
    relays = kind == "preisach"
    edges = np.linspace(0.0, 1.0, (_RELAY_GRID if relays else _KP_GRID) + 1)
    mid = 0.5 * (edges[:-1] + edges[1:])
    a, b = np.meshgrid(mid, mid, indexing="ij")
    keep = a > b
    a, b = a[keep].copy(), b[keep].copy()
    width, centre = a - b, 0.5 * (a + b)
    if relays:  # a log-normal ridge in the width, a skewed bump in the centre
        ridge = np.exp(-(np.log(width / 0.15) ** 2) / 0.9) / width
        bump = (1.0 + 2.5 * centre**1.5) * np.exp(-(((centre - 0.375) / 0.46) ** 2))
        weight = ridge * bump
    else:
        weight = np.exp(-width / 0.1) * (0.5 + np.sin(np.pi * centre) ** 2)
    weight /= weight.sum()
    state = -np.ones(a.size)
    k.kp_run(u, a, b, weight, 1e-12 if relays else _KP_WIDTH, state, out)
    s = 0.5 * (out + 1.0)
    if relays:  # a reversible part beside the relays
        return np.tanh(1.1 * (0.4 * u + 0.6 * s))
    s = 0.55 * u + 0.45 * s  # a reversible part beside the hysterons
    return np.tanh(1.6 * s) / np.tanh(1.6)


@dataclass(frozen=True)
class Scanner(SampleClock):
    """A multi-axis piezo scanner: voltages (V, (n, N)) in, sensor readings (µm) out.

    Parameters
    ----------
    axes : tuple of ScannerAxis
        The axes.
    coupling : array_like, shape (N, N)
        ``M``, unit diagonal (module notes).
    sample_rate : float, default 20000
        Hz.
    noise_um : float, default 0.003
        Sensor noise, µm rms, per axis.
    seed : int, default 0
        Seed of the noise.
    """

    axes: tuple[ScannerAxis, ...]
    coupling: np.ndarray
    sample_rate: float = paper.SAMPLE_RATE
    noise_um: float = 0.003
    seed: int = 0
    _scale: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        axes = tuple(self.axes)
        object.__setattr__(self, "axes", axes)
        m = as_axes(self.coupling, "coupling", "Scanner").copy()
        if m.shape != (len(axes), len(axes)) or not np.allclose(np.diag(m), 1.0):
            raise InvalidParameterError(
                f"The 'coupling' parameter of Scanner must be a {len(axes)} x {len(axes)} "
                f"matrix with a unit diagonal. Got {m.tolist()}."
            )
        m.setflags(write=False)
        object.__setattr__(self, "coupling", m)
        check_real(self.sample_rate, "sample_rate", "Scanner", positive=True)
        if check_real(self.noise_um, "noise_um", "Scanner") < 0:
            raise InvalidParameterError(
                f"The 'noise_um' parameter of Scanner must be >= 0. Got {self.noise_um!r}."
            )
        scale = []
        for axis in axes:
            rise = _raw_hysteresis(axis.hysteresis, np.linspace(0.0, 1.0, 401))
            scale.append(axis.stroke_um / (rise[-1] - rise[0]))
        object.__setattr__(self, "_scale", np.array(scale))

    @property
    def n_axes(self) -> int:
        """N."""
        return len(self.axes)

    def _normalised(self, V) -> np.ndarray:
        V = as_axes(V, "V", "Scanner", n_axes=self.n_axes)
        lo = np.array([a.voltage_range[0] for a in self.axes])
        hi = np.array([a.voltage_range[1] for a in self.axes])
        return np.ascontiguousarray((np.clip(V, lo, hi) - lo) / (hi - lo))

    def hysteresis(self, V) -> np.ndarray:
        """Each axis's quasi-static displacement ``H_i[v_i]`` (µm, (n, N)): no mode, no
        coupling, no noise.

        Parameters
        ----------
        V : array_like
            The voltages, V, shape ``(n, N)``; each axis's is clipped to its range.

        Returns
        -------
        numpy.ndarray
            The displacements, µm, shape ``(n, N)``, 0 at rest.
        """
        U = self._normalised(V)
        H = np.empty_like(U)
        for i, axis in enumerate(self.axes):
            raw = _raw_hysteresis(axis.hysteresis, np.ascontiguousarray(U[:, i]))
            rest = _raw_hysteresis(axis.hysteresis, np.zeros(1))[0]
            H[:, i] = self._scale[i] * (raw - rest)
        return H

    def run_noiseless(self, V) -> np.ndarray:
        """The axes' true positions as the sensors see them, without noise (µm, (n, N)).

        Parameters
        ----------
        V : array_like
            One voltage column per axis, V, from rest; each is clipped to its axis's range.

        Returns
        -------
        numpy.ndarray
            The positions, µm, shape ``(n, N)``: each axis's hysteresis through its mode,
            then the coupling.
        """
        H = self.hysteresis(V)
        Y = np.empty_like(H)
        for i, axis in enumerate(self.axes):
            ad, bd = zoh_matrices(axis.resonance_hz, axis.damping_ratio, self.sample_rate)
            k.mode_run(np.ascontiguousarray(H[:, i]), ad, bd, Y[:, i])
        return Y @ self.coupling.T

    def run(self, V, *, seed: int | None = None) -> np.ndarray:
        """The sensors' readings (µm, (n, N)) for the voltages ``V`` (V, (n, N)), from rest.

        The noise is drawn from ``seed`` (default: the scanner's), so a run is reproducible.

        Parameters
        ----------
        V : array_like
            The voltages, V, shape ``(n, N)``.
        seed : int, optional
            The seed of the sensor noise (the scanner's if None).

        Returns
        -------
        numpy.ndarray
            The readings, µm, shape ``(n, N)``.
        """
        X = self.run_noiseless(V)
        rng = np.random.default_rng(self.seed if seed is None else seed)
        return X + self.noise_um * rng.standard_normal(X.shape)


#: The couplings of :func:`raster_scanner` (``M - I``), percent: X into Y 4 %, Y into X
#: -2.5 %, and for a Z axis, X and Y into Z 6 % and 3 %, Z into X and Y 2 %.
COUPLING_PERCENT = {
    2: [[0.0, -3.0], [6.0, 0.0]],
    3: [[0.0, -3.0, 2.0], [6.0, 0.0, -2.0], [5.0, 8.0, 0.0]],
}


def raster_scanner(n_axes: int = 2, *, scale: float = 1.0, noise_um: float = 0.003, seed=0):
    """The built-in raster scanner: X Bouc-Wen (30 µm, 600 Hz), Y Preisach (25 µm, 450 Hz) and,
    with ``n_axes=3``, Z Krasnosel'skii-Pokrovskii (12 µm, 1.2 kHz).

    Parameters
    ----------
    n_axes : {2, 3}
        XY or XYZ.
    scale : float, default 1
        Multiplies the couplings of :data:`COUPLING_PERCENT` (2.5 to 6 %).
    noise_um : float, default 0.003
        Sensor noise, µm rms.
    seed : int, default 0
        Seed of the noise.

    Returns
    -------
    Scanner
    """
    if n_axes not in COUPLING_PERCENT:
        raise InvalidParameterError(
            f"The 'n_axes' parameter of raster_scanner must be 2 or 3. Got {n_axes!r}."
        )
    axes = [
        ScannerAxis("bouc-wen", 30.0, 600.0, 0.08),
        ScannerAxis("preisach", 25.0, 450.0, 0.1),
        ScannerAxis("kp", 12.0, 1200.0, 0.06),
    ][:n_axes]
    m = np.eye(n_axes) + scale * np.asarray(COUPLING_PERCENT[n_axes]) / 100.0
    return Scanner(tuple(axes), m, noise_um=noise_um, seed=seed)
