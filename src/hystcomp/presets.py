"""The models identified in the paper, in hystcomp's units (V in, µm out).

Unit conversion: the paper's weights (eqs. 20-21) are in m/V (the ``10^-6`` factor in front);
multiplied by ``10^6`` they are µm/V. The dead-zone weights of eq. (22) are unitless.

Assumptions, since the paper leaves them implicit:

* Thresholds follow eq. (16) with ``max{v} = 120 V`` and ``n + 1 = 16`` plays, initial states
  zero (eq. 18), voltage range 0..120 V, no offsets.
* Eq. (22) lists the *inverse* dead-zone weights ``w'_S`` that eq. (19) identifies (the paper
  labels them ``w_xS``). Read as forward weights they would give a 170 µm stroke; read as
  inverse weights the stroke is 36 µm, in line with eq. (20)'s PI (38 µm) and eq. (6)'s
  Preisach model (37 µm), so this is the reading we take.
* Eq. (17) needs ``max{x_p}``, the largest measured displacement, which the paper does not
  give. We take the self-consistent value: the ``M`` for which the model's own largest
  displacement on the paper's identification triangle (30..120 V) equals ``M``
  (:data:`PAPER_MPI_MAX_DISPLACEMENT`, about 36 µm, found by fixed-point iteration).

For the Preisach model (eqs. 5-6), see :func:`paper_preisach`.
"""

from __future__ import annotations

import numpy as np

from hystcomp import paper
from hystcomp.identify.excitation import triangle_sequence
from hystcomp.models.mpi import ModifiedPrandtlIshlinskii
from hystcomp.models.pi import PrandtlIshlinskii, paper_thresholds
from hystcomp.models.preisach import Preisach

PAPER_V_MAX = paper.VOLTAGE_RANGE[1]  # V, eq. (16)

#: Eq. (20), PI play weights in µm/V.
PAPER_PI_WEIGHTS = np.array(paper.PI_WEIGHTS)
#: Eq. (21), MPI play weights in µm/V.
PAPER_MPI_WEIGHTS = np.array(paper.MPI_WEIGHTS)
#: Eq. (22), MPI inverse dead-zone weights (unitless).
PAPER_MPI_INVERSE_DEADZONE_WEIGHTS = np.array(paper.MPI_INVERSE_DEADZONE_WEIGHTS)


def paper_identification_triangle(sample_rate: float = 1000.0) -> np.ndarray:
    """The paper's identification input (eq. 19): triangles of 30..120 V at 1 Hz from 0 V.

    Parameters
    ----------
    sample_rate : float, optional
        Samples per second, Hz.

    Returns
    -------
    numpy.ndarray
        The voltage, V: four triangles of 30, 60, 90 and 120 V peak, 1 s each.
    """
    return triangle_sequence(sample_rate=sample_rate)[1]


def paper_pi() -> PrandtlIshlinskii:
    """The PI model of eq. (20): 16 plays on 0..120 V.

    Returns
    -------
    PrandtlIshlinskii
        The model of eq. (20).

    Examples
    --------
    >>> model = paper_pi()
    >>> round(float(model.simulate([0.0, 120.0])[-1]), 3)
    37.789
    """
    return PrandtlIshlinskii.from_parameters(
        thresholds=paper_thresholds(paper.N_OPERATORS, PAPER_V_MAX),
        weights=PAPER_PI_WEIGHTS,
        voltage_range=paper.VOLTAGE_RANGE,
    )


def paper_mpi_with(max_displacement: float) -> ModifiedPrandtlIshlinskii:
    """The MPI of eqs. (21)-(22) with eq. (17)'s thresholds for ``max{x_p} = max_displacement`` µm.

    Parameters
    ----------
    max_displacement : float
        ``max{x_p}`` of eq. (17), the largest measured displacement, µm.

    Returns
    -------
    ModifiedPrandtlIshlinskii
        The model of eqs. (21)-(22) with those dead-zone thresholds.
    """
    r_inv = paper_thresholds(paper.N_DEADZONES, max_displacement)  # eq. (17)
    rs, ws = ModifiedPrandtlIshlinskii.forward_deadzones(r_inv, PAPER_MPI_INVERSE_DEADZONE_WEIGHTS)
    return ModifiedPrandtlIshlinskii.from_parameters(
        thresholds=paper_thresholds(paper.N_OPERATORS, PAPER_V_MAX),
        weights=PAPER_MPI_WEIGHTS,
        deadzone_thresholds=rs,
        deadzone_weights=ws,
        voltage_range=paper.VOLTAGE_RANGE,
    )


#: The ``max{x_p}`` of eq. (17) behind the MPI preset, in µm: the fixed point ``M`` of
#: ``M = max(paper MPI with M on paper_identification_triangle())`` (see the module
#: docstring; ``tests/test_presets_and_files.py`` checks that it is one).
PAPER_MPI_MAX_DISPLACEMENT = 35.886667354280206


def paper_mpi() -> ModifiedPrandtlIshlinskii:
    """The MPI model of eqs. (21)-(22) (16 plays, 16 dead-zones) on 0..120 V.

    Returns
    -------
    ModifiedPrandtlIshlinskii
        The paper's fitted MPI model, eqs. (21)-(22), as printed.

    Examples
    --------
    >>> model = paper_mpi()
    >>> round(float(model.simulate([0.0, 120.0])[-1]), 2)
    35.89
    """
    return paper_mpi_with(PAPER_MPI_MAX_DISPLACEMENT)


#: Eq. (6), the coefficients of eq. (5) in µm/V, µm/V^2 and µm/V^3 (eq. 5's order).
PAPER_PREISACH_THETA = np.array(paper.PREISACH_THETA)


def paper_preisach(*, zero_diagonal: bool = False) -> Preisach:
    """The Preisach model of eqs. (5)-(6): a cubic Everett polynomial on 0..120 V.

    Assumptions, since the paper leaves them implicit:

    * ``theta`` of eq. (6) is in µm/V^k, with alpha and beta in V: then ``X(120, 0) =
      36.72 µm``, the stroke of eq. (20)'s PI model (37.8 µm) and of the MPI model (35.9 µm);
      read in m it would be a stroke of 37 m.
    * The Preisach plane is the amplifier's 0..120 V, ``beta_0 = v_min = 0`` (the sinusoids
      of the identification start there), no output offset.
    * Eq. (6) does not satisfy ``X(v, v) = 0``, which eq. (2) implies: ``X(v, v) = 0.013 v
      - 0.00012 v^2 + 5e-7 v^3`` rises to 0.70 µm at 120 V (the paper's least squares was not
      constrained, and the printed digits are few). Used in eqs. (3)-(4) as written, such an
      X makes the output step by ``X(v, v)`` at every reversal of the input, and the inverse
      multiplicative structure (eq. 10) then chatters after each reversal. By default the
      preset keeps eq. (6) as printed; ``zero_diagonal=True`` replaces the three pure-beta
      coefficients by the values that make ``X(v, v) = 0`` (``theta_0 = -theta_1``,
      ``theta_2 = -(theta_3 + theta_4)``, ``theta_5 = -(theta_6 + theta_7 + theta_8)``),
      which keeps the initial ascending curve ``X(v, 0)`` and the major loop's end points and
      changes a descending branch by ``X(beta, beta)`` (at most 0.7 µm).

    Parameters
    ----------
    zero_diagonal : bool, optional
        Subtract ``X(beta, beta)`` so that ``X(v, v) = 0``, as eq. (2) implies (eq. 6 as printed if
        False).

    Returns
    -------
    Preisach
        The model of eqs. (5)-(6).

    Examples
    --------
    >>> model = paper_preisach()
    >>> round(float(model.everett_function(120.0, 0.0)), 3)
    36.72
    >>> round(float(model.simulate([0.0, 120.0])[-1]), 3)
    36.72
    >>> abs(float(paper_preisach(zero_diagonal=True).everett_function(120.0, 120.0))) < 1e-12
    True
    """
    theta = PAPER_PREISACH_THETA.copy()
    if zero_diagonal:
        theta[0] = -theta[1]
        theta[2] = -(theta[3] + theta[4])
        theta[5] = -(theta[6] + theta[7] + theta[8])
    return Preisach.from_parameters(
        theta=theta, voltage_range=paper.VOLTAGE_RANGE, output_offset=0.0
    )
