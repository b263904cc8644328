"""The simulated piezo axis (the "twin") of the paper's Section II.

>>> from hystcomp.plant import Twin, TwinParameters
>>> twin = Twin(TwinParameters(sensor_noise=0.0))
>>> float(twin.run([0.0, 0.0])[-1])
0.0
"""

from hystcomp.plant.parameters import TwinParameters, creep_twin
from hystcomp.plant.twin import Twin, TwinStepper

__all__ = ["Twin", "TwinParameters", "TwinStepper", "creep_twin"]
