"""The threading settings the timing benchmarks run with, as the ``arlequin`` command does.

Imported before numba runs its first kernel: OpenMP threads sleep between parallel regions
(``OMP_WAIT_POLICY=PASSIVE``, unless set), so that a spinning worker does not slow the serial
part of each step on a small machine; the explicit loop runs BLAS on one thread
(:mod:`arlequin.linalg.threads`). :func:`settings` goes into each benchmark's JSON.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")


def settings() -> dict:
    """The threading settings of this process, for the JSON output."""
    import numba

    return {"omp_wait_policy": os.environ.get("OMP_WAIT_POLICY"),
            "numba_threads": int(numba.get_num_threads()),
            "blas_threads_in_explicit_loop": 1}  # fmt: skip
