"""One BLAS thread for the identification's small matrix products.

The PI/MPI fits accumulate their Gram matrix from blocks of 2048 x 34 regressors
(:func:`hystcomp.identify.lsq.normal_equations`). A multi-threaded BLAS splits each product
over its threads and wakes them for every block: on a machine whose other cores are busy,
each block waits for a thread that the scheduler has given to someone else, and a fit
takes many times as long as on one thread (Benchmarks, "Speed"). These
products are too small to gain from threads, so they run on one
(:func:`one_blas_thread`, with threadpoolctl), whatever the process's BLAS is set to; the
process's setting is back when the block ends.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Run the block with every loaded BLAS library limited to one thread (threadpoolctl).

    Costs about 0.1 ms (it looks up the loaded libraries); the previous limits are restored
    on exit, also on an error.
    """
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        yield
