"""Identification from measured data, and the paper's identification signals.

The array-level functions that the models' ``fit`` methods delegate to:
:func:`~hystcomp.identify.pi.fit_pi` (eq. 12) and :func:`~hystcomp.identify.mpi.fit_mpi`
(eq. 19), both constrained least squares (:mod:`hystcomp.identify.lsq`).
"""

import importlib

__all__ = ["MPIFit", "PIFit", "fit_mpi", "fit_pi"]
_MODULES = {"MPIFit": "mpi", "fit_mpi": "mpi", "PIFit": "pi", "fit_pi": "pi"}


def __getattr__(name: str):
    # Imported on first use, so that the excitation signals load no kernel.
    if name in _MODULES:
        return getattr(importlib.import_module(f"hystcomp.identify.{_MODULES[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
