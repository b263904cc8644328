"""The mixing of a multi-axis stage's axes by a matrix: ``out[k] = A @ x[k]``, per sample.

One loop for the batch run and the streaming step of a multi-axis model or compensator
(:mod:`hystcomp.models.multiaxis`): the coupling ``x = M h`` forward, the decoupling
``h = M^-1 x`` in the compensator. Each output is summed over the axes in their order,
``A[i, 0] x[0] + A[i, 1] x[1] + ...``, the order of the generated C, so a step and the batch
run agree bit for bit. Kernels trust their input.
"""

from __future__ import annotations

from hystcomp._kernels._jit import kernel


@kernel
def mix_rows(a, x, out):
    """``out[k, i] = sum_j a[i, j] x[k, j]`` for every sample ``k`` (``x``, ``out``: (n, N))."""
    n_axes = a.shape[0]
    for k in range(x.shape[0]):
        for i in range(n_axes):
            acc = a[i, 0] * x[k, 0]
            for j in range(1, n_axes):
                acc += a[i, j] * x[k, j]
            out[k, i] = acc
