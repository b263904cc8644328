"""The uncompensated baseline of the paper's Table I: a linear map ``v = x_ref / k_lin``.

``k_lin`` comes from the identification record. We take the least-squares gain through the
origin, ``k = sum(v x) / sum(v^2)``, rather than the end-point gain ``x_max / v_max``: it
uses every sample (one end-point sample carries its noise and any overshoot), and it is the
same criterion and the same record as the identification of the models it is compared with
(the least squares of eqs. 12 and 19). The end-point gain is available for comparison.
"""

from __future__ import annotations

import numpy as np

from hystcomp._validation import as_signal, as_signal_pair, check_range, check_real
from hystcomp.errors import IdentificationError, InvalidParameterError
from hystcomp.paper import VOLTAGE_RANGE

GAIN_METHODS = ("least-squares", "end-point")


def linear_gain(v, x, *, method: str = "least-squares") -> float:
    """The gain ``k_lin`` (µm/V) of a straight line through the origin fitted to ``(v, x)``.

    Parameters
    ----------
    v, x : array_like
        Voltage (V) and displacement (µm) of an identification record, starting at rest.
    method : {"least-squares", "end-point"}
        ``sum(v x) / sum(v^2)``, or ``max(x) / max(v)``.

    Returns
    -------
    float
        ``k_lin``, µm/V.

    Examples
    --------
    >>> linear_gain([0.0, 1.0, 2.0], [0.0, 0.3, 0.6])
    0.3
    """
    if method not in GAIN_METHODS:
        raise InvalidParameterError(
            f"The 'method' parameter of linear_gain must be one of {GAIN_METHODS}. "
            f"Got {method!r} instead."
        )
    v, x = as_signal_pair(v, x, ("v", "x"), "linear_gain", min_samples=2)
    if method == "least-squares":
        gain = float(v @ x) / float(v @ v) if np.any(v) else 0.0
    else:
        gain = float(x.max()) / float(v.max()) if v.max() > 0 else 0.0
    if not gain > 0:
        raise IdentificationError(
            f"The record gives no positive gain ({gain:g} µm/V): the displacement must grow "
            "with the voltage. Check the sign and the columns of the record."
        )
    return gain


class LinearCompensator:
    """``v = x_ref / gain``, clamped to ``voltage_range``: the uncompensated baseline.

    Parameters
    ----------
    gain : float
        ``k_lin`` in µm/V (> 0).
    voltage_range : (float, float), default (0, 120)
        The amplifier's range in V.

    Examples
    --------
    >>> LinearCompensator(0.3).simulate([0.0, 15.0, 60.0]).tolist()
    [0.0, 50.0, 120.0]
    """

    kind = "linear"

    def __init__(self, gain: float, voltage_range=VOLTAGE_RANGE):
        self.gain = check_real(gain, "gain", "LinearCompensator", positive=True)
        self.voltage_range = check_range(voltage_range, "voltage_range", "LinearCompensator")

    def simulate(self, x_ref) -> np.ndarray:
        """The voltage (V) for the reference ``x_ref`` (µm).

        Parameters
        ----------
        x_ref : array_like
            The reference displacement, µm; each sample is inverted on its own.

        Returns
        -------
        numpy.ndarray
            ``x_ref / k_lin`` clamped to the voltage range, V.
        """
        lo, hi = self.voltage_range
        return np.clip(as_signal(x_ref, "x_ref") / self.gain, lo, hi)

    def __repr__(self) -> str:
        return f"LinearCompensator(gain={self.gain:.6g})"
