"""Threads of the linear-algebra libraries during a time loop.

numpy's and scipy's BLAS (OpenBLAS) keeps a thread pool whose workers busy-wait after each
call. In an explicit loop the dense products are tiny (the few active contact rows), and those
spinning workers take the cores that the compiled kernels' threads (numba) need: on the 2-core
test machine the plastic ball impact ran 45–54 s with the pool, 34–41 s with one BLAS thread.
:func:`blas_threads` limits the pool for the duration of a run (threadpoolctl, the library
scikit-learn uses for the same purpose) and restores it afterwards.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

__all__ = ["blas_threads"]


@contextlib.contextmanager
def blas_threads(n: int | None) -> Iterator[None]:
    """Run the block with at most ``n`` BLAS threads (None: as they are)."""
    if n is None:
        yield
        return
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=int(n), user_api="blas"):
        yield
