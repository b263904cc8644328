"""hystcomp: identify and compensate the hysteresis of piezoelectric actuators.

Implements the Preisach, Prandtl-Ishlinskii (PI) and Modified Prandtl-Ishlinskii (MPI)
models and their inverse-based compensators of "Experimental model inverse-based hysteresis
compensation on a piezoelectric actuator". Units: V, µm, s.

>>> import hystcomp
>>> model = hystcomp.presets.paper_mpi()
>>> comp = model.inverse()
>>> v = comp.simulate([0.0, 10.0, 20.0])
>>> bool(abs(model.simulate(v)[-1] - 20.0) < 1e-9)
True
"""

from hystcomp import errors, presets
from hystcomp.data import Record, read_record
from hystcomp.io import load_model, save_model
from hystcomp.models.compensator import Compensator, Stepper
from hystcomp.models.dynamics import LinearDynamics
from hystcomp.models.mpi import ModifiedPrandtlIshlinskii
from hystcomp.models.pi import PrandtlIshlinskii
from hystcomp.models.preisach import Preisach

__version__ = "0.1.0"

__all__ = [
    "Compensator",
    "LinearDynamics",
    "ModifiedPrandtlIshlinskii",
    "PrandtlIshlinskii",
    "Preisach",
    "Record",
    "Stepper",
    "__version__",
    "errors",
    "load_model",
    "presets",
    "read_record",
    "save_model",
]
