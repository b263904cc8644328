"""Identification from measured data, and the paper's identification signals.

The array-level functions that the models' ``fit`` methods delegate to:
:func:`~hystcomp.identify.pi.fit_pi` (eq. 12) and :func:`~hystcomp.identify.mpi.fit_mpi`
(eq. 19), both constrained least squares (:mod:`hystcomp.identify.lsq`).
"""

from hystcomp.identify.mpi import MPIFit, fit_mpi
from hystcomp.identify.pi import PIFit, fit_pi

__all__ = ["MPIFit", "PIFit", "fit_mpi", "fit_pi"]
