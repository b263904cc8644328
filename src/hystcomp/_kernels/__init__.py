"""Every numba loop of the package (the bottom layer), with one decorator set.

* :mod:`._jit`: the decorators (batch, inlined and step kernels) and their fast-math flags;
* :mod:`.chain`: the play / dead-zone chain of the PI-type models and inverses;
* :mod:`.preisach`: the Preisach model, its inverses and its identification regressors;
* :mod:`.dynamics`: the inverse of the linear dynamics;
* :mod:`.twin`: the simulated axis;
* :mod:`.reversals`: turning points of a record, for identification.

Packed systems (parameters and state in one float64 array) name their slots with
constants of their module; a :data:`~._jit.StepKernels` bundle tells the one streaming
stepper (:class:`hystcomp.models.system.Stepper`) how to run each kind. Kernels trust their
input: validation happens in the public classes above.
"""
