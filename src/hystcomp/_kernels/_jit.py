"""The one decorator set of the package's numba kernels.

Every kernel is cached on disk (``cache=True``) and compiled lazily, on its first call:
importing hystcomp compiles nothing. All kernels share the fast-math flags of
:data:`FASTMATH`, so that a streaming step and the batch run it mirrors (and the kernels that
inline each other) are compiled under the same rules and agree bit for bit.
"""

from __future__ import annotations

import functools
from collections import namedtuple

import numba

#: Fast-math without 'nnan'/'ninf': reassociation lets the reductions vectorise, while the
#: finiteness tests on the input must survive compilation.
FASTMATH = {"reassoc", "contract", "nsz", "arcp"}


def kernel(func):
    """Compile ``func`` as a batch kernel: cached, :data:`FASTMATH`, the GIL released."""
    return numba.njit(cache=True, fastmath=FASTMATH, nogil=True)(func)


def inline_kernel(func):
    """Compile ``func`` as a kernel inlined into its callers at numba-IR level.

    The stages of a chain then sit in one function that LLVM optimises as a whole (a call
    per stage and sample would cost more than the stage). Only small functions with few call
    sites: each inlined copy is typed and compiled again, and the first run's compile time
    grows with every copy. A small :func:`inner_kernel` is often the better choice.
    """
    return numba.njit(cache=True, fastmath=FASTMATH, nogil=True, inline="always")(func)


def inner_kernel(func):
    """Compile ``func`` as a kernel that other kernels call (not Python): :data:`FASTMATH`,
    cached, without reference counting.

    Compiled once, whatever the number of its call sites; LLVM still inlines it into a
    caller where it is small (it links the callee's code into each caller's module before
    optimising it). Without reference counting, a call does not increment and decrement the
    count of every array it is passed (two atomic operations per call: at a call per sample
    or per root-finding step, they cost as much as the arithmetic). It must not allocate.
    Python cannot call it: it has no wrapper for Python (nor for C), whose compilation is
    a third of that of a small kernel.
    """
    return numba.njit(
        cache=True, fastmath=FASTMATH, _nrt=False, no_cpython_wrapper=True, no_cfunc_wrapper=True
    )(func)


def flat_kernel(func):
    """Compile ``func`` as a batch kernel without reference counting: cached, :data:`FASTMATH`,
    the GIL released.

    A slice of an array inside its loops is then a plain view, not an object whose count is
    changed atomically (two atomic operations per slice: in a loop over operators they
    cost more than the arithmetic), so a kernel can hand 1-D rows of its 2-D arrays to an
    inlined helper whose loop vectorises. It must not allocate: work buffers are passed in.
    """
    return numba.njit(cache=True, fastmath=FASTMATH, nogil=True, _nrt=False)(func)


def step_kernel(func):
    """Compile ``func(p, u) -> float``, one sample through packed system ``p``, as a step kernel.

    One sample per call, so the fixed cost of a call is what counts: the kernel keeps the GIL
    (releasing and taking it back costs more than the sample) and is compiled without
    reference counting (the packed array and each view of it would otherwise cost an atomic
    increment and decrement, a third of the chain's call); it must not allocate. Its
    fastmath flags are those of every batch kernel of the package (:data:`FASTMATH`), so
    that a step and the batch run it mirrors agree bit for bit. :func:`step_function` gives
    its fast entry point.
    """
    return numba.njit(cache=True, fastmath=FASTMATH, _nrt=False)(func)


@functools.cache
def step_function(kernel):
    """Step kernel ``kernel`` compiled for a float64 array and a float, as a plain ``f(p, u)``.

    It skips numba's dispatch on argument types (a third of the cost of a call) and so
    trusts its arguments more still: ``p`` must be a writable, C-contiguous float64 array.
    The first call compiles the kernel or loads it from the on-disk cache.
    """
    return kernel.compile((numba.types.float64[::1], numba.types.float64))


StepKernels = namedtuple("StepKernels", "step run state_start last nonfinite clamped")
StepKernels.__doc__ = """What a streaming stepper needs to know of a kind of packed system.

``step`` is its :func:`step_kernel`, ``run(p, u, out)`` the batch kernel that the step equals
bit for bit, ``state_start(p)`` a plain Python function giving the index of the first state
slot, and ``last``, ``nonfinite`` and ``clamped`` the offsets from there of the last output,
of the count of non-finite inputs and of the count of clamped outputs (named state slots of
the kernel's module). :data:`~hystcomp._kernels.chain.CHAIN_KERNELS` is that of a packed
chain, :data:`~hystcomp._kernels.preisach.PREISACH_KERNELS` that of a Preisach system and
:data:`~hystcomp._kernels.twin.TWIN_KERNELS` that of the simulated axis.
"""
