"""The one decorator set of the package's numba kernels.

Every kernel is cached on disk (``cache=True``) and compiled lazily, on its first call:
importing hystcomp compiles nothing. All kernels share the fast-math flags of
:data:`FASTMATH`, so that a streaming step and the batch run it mirrors (and the kernels that
inline each other) are compiled under the same rules and agree bit for bit.

Where numba finds no folder to cache in (a read-only install and an unwritable home
folder, with ``NUMBA_CACHE_DIR`` unset), numba refuses ``cache=True`` at the decoration;
the kernels are then compiled without the cache on every run (:func:`caching`), and one
note on standard error says so and names ``NUMBA_CACHE_DIR``.
"""

from __future__ import annotations

import functools
import sys
from collections import namedtuple
from typing import Any

import numba

#: The note on standard error when kernels cannot be cached (one line).
NO_CACHE_NOTE = (
    "hystcomp: note: numba finds no writable folder for its cache of compiled kernels "
    "(the install is read-only and so is the home folder's cache), so they are compiled "
    "anew in every run (seconds); set NUMBA_CACHE_DIR to a writable folder to keep them.\n"
)


def _probe() -> int:  # pragma: no cover - never called, only decorated
    return 0


@functools.cache
def caching() -> bool:
    """Whether numba can cache kernels on disk here; if not, write :data:`NO_CACHE_NOTE`
    once to standard error and compile every kernel without the cache.

    Numba looks for a folder when a function is decorated with ``cache=True`` (beside the
    source, in the user's cache folder, or ``NUMBA_CACHE_DIR``), and raises if it finds
    none: this module's own file stands for every kernel of the package.
    """
    try:
        numba.njit(cache=True)(_probe)
    except RuntimeError as exc:
        if "no locator available" not in str(exc):
            raise
        try:
            sys.stderr.write(NO_CACHE_NOTE)
            sys.stderr.flush()
        except (OSError, ValueError, AttributeError):  # no standard error to write to
            pass
        return False
    return True


#: Fast-math without 'nnan'/'ninf': reassociation lets the reductions vectorise, while the
#: finiteness tests on the input must survive compilation.
FASTMATH = {"reassoc", "contract", "nsz", "arcp"}

#: numba's options for a kernel compiled without reference counting (``_nrt``) and, for an
#: inner kernel, without the wrappers for Python and C. numba takes them, but its type hints
#: leave them out, so they are passed as a dictionary.
NO_NRT: dict[str, Any] = {"_nrt": False}
NO_WRAPPERS: dict[str, Any] = {**NO_NRT, "no_cpython_wrapper": True, "no_cfunc_wrapper": True}


def kernel(func):
    """Compile ``func`` as a batch kernel: cached, :data:`FASTMATH`, the GIL released."""
    return numba.njit(cache=caching(), fastmath=FASTMATH, nogil=True)(func)


def inline_kernel(func):
    """Compile ``func`` as a kernel inlined into its callers at numba-IR level.

    The stages of a chain then sit in one function that LLVM optimises as a whole (a call
    per stage and sample would cost more than the stage). Only small functions with few call
    sites: each inlined copy is typed and compiled again, and the first run's compile time
    grows with every copy. A small :func:`inner_kernel` is often the better choice.
    """
    return numba.njit(cache=caching(), fastmath=FASTMATH, nogil=True, inline="always")(func)


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
        cache=caching(),
        fastmath=FASTMATH,
        **NO_WRAPPERS,
    )(func)


def flat_kernel(func):
    """Compile ``func`` as a batch kernel without reference counting: cached, :data:`FASTMATH`,
    the GIL released.

    A slice of an array inside its loops is then a plain view, not an object whose count is
    changed atomically (two atomic operations per slice: in a loop over operators they
    cost more than the arithmetic), so a kernel can hand 1-D rows of its 2-D arrays to an
    inlined helper whose loop vectorises. It must not allocate: work buffers are passed in.
    """
    return numba.njit(cache=True, fastmath=FASTMATH, nogil=True, **NO_NRT)(func)


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
    return numba.njit(cache=caching(), fastmath=FASTMATH, **NO_NRT)(func)


@functools.cache
def step_function(kernel, arrays: int = 1):
    """Step kernel ``kernel`` compiled for ``arrays`` float64 arrays and a float, as a plain
    ``f(p, u)`` (or ``f(p, q, u)`` for a kernel over two packed systems).

    It skips numba's dispatch on argument types (a third of the cost of a call) and so
    trusts its arguments more still: each array must be a writable, C-contiguous float64
    array. The first call compiles the kernel or loads it from the on-disk cache.
    """
    return kernel.compile((*[numba.types.float64[::1]] * arrays, numba.types.float64))


@functools.cache
def block_function(kernel):
    """Block kernel ``kernel(p, u, out, work) -> status`` compiled for four float64 arrays,
    as a plain function (no dispatch on argument types): the trusted path of
    ``Stepper.step_block(u, out=...)``. Its caller checks the arrays' types first."""
    array = numba.types.float64[::1]
    return kernel.compile((array, array, array, array))


StepKernels = namedtuple(
    "StepKernels", "step run state_start last nonfinite clamped block", defaults=(None,)
)
StepKernels.__doc__ = """What a streaming stepper needs to know of a kind of packed system.

``step`` is its :func:`step_kernel`, ``run(p, u, out)`` the batch kernel that the step equals
bit for bit, ``state_start(p)`` a plain Python function giving the index of the first state
slot, and ``last``, ``nonfinite`` and ``clamped`` the offsets from there of the last output,
of the count of non-finite inputs and of the count of clamped outputs (named state slots of
the kernel's module). ``block``, if given, is a :func:`step_kernel` ``block(p, u, out,
work) -> status`` over a block of samples (``run``'s loop, without reference counting, for
short blocks from Python): status 0 when it ran, else nonzero and nothing done (``out``
shorter than ``u``, or overlapping it). :data:`~hystcomp._kernels.chain.CHAIN_KERNELS` is that of a packed
chain, :data:`~hystcomp._kernels.preisach.PREISACH_KERNELS` that of a Preisach system and
:data:`~hystcomp._kernels.twin.TWIN_KERNELS` that of the simulated axis.
"""
