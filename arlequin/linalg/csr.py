"""A compiled product y = A x with a CSR matrix, the same floats as scipy's ``A @ x``.

The explicit loop multiplies the same assembled matrices (the linear blocks' stiffness) at every
step. scipy's ``A @ x`` checks its operand's type and shape in Python (a few µs a call) and runs
a C++ loop whose sums are those of :func:`csr_times`: each row's products added in stored order
from zero. The compiled loop here makes the same additions in the same order, so the results are
equal bit for bit, and with unsigned 32-bit column indices (numba adds a wraparound test to
every signed index) it ran 1.25–1.4 times faster than scipy on one core from 58k to 925k stored
entries (the ball impact's stiffness, 418k entries: 233 → 172 µs). Above
:data:`PARALLEL_MIN_NNZ` entries the rows are split over numba's threads (each row still summed
by one thread, in order: the same floats for any thread count).

numba compiles on first call (cached on disk, ``cache=True``).
"""

from __future__ import annotations

import numba as nb
import numpy as np
import scipy.sparse as sp

__all__ = [
    "PARALLEL_MIN_NNZ",
    "CsrProduct",
    "csr_times",
    "csr_times_gathered",
    "csr_times_subtract_scaled",
    "subtract_scaled_transposed",
]

#: From this many stored entries the product runs on numba's threads. Waking the sleeping worker
#: costs tens of µs: a product of 58k entries (22 µs on one core) does not repay it, one of 925k
#: (352 µs on one core, 236 µs on two) does; the ball impact's stiffness, 418k entries, took
#: 233 µs with scipy, 172 µs here on one core and 140 µs on two called back to back (the worker
#: awake), a gain that one wake-up a step would mostly take back.
PARALLEL_MIN_NNZ = 1_000_000


@nb.njit(cache=True)
def csr_times(indptr, indices, data, x, y):
    """y = A x for A in CSR form (any integer indices: :class:`CsrProduct` passes uint64 and
    uint32, the faster ones, and the active contact rows scipy's own), data float64: each row's
    products added in stored order from zero, as scipy's ``csr_matvec``.

    Parameters
    ----------
    indptr : ndarray of int, shape (n_rows + 1,)
    indices : ndarray of int, shape (nnz,)
    data : ndarray of float64, shape (nnz,)
    x : ndarray of float64, shape (n_cols,)
    y : ndarray of float64, shape (n_rows,)
        Output (overwritten).
    """
    for i in range(indptr.size - 1):
        s = 0.0
        for k in range(indptr[i], indptr[i + 1]):
            s += data[k] * x[indices[k]]
        y[i] = s


@nb.njit(cache=True, error_model="numpy")
def csr_times_gathered(indptr, indices, data, cols, x, z, divisor, w, y):
    """y = A w with ``w = x[cols] + z[cols] / divisor``, w formed in a scratch vector: the
    floats of :func:`csr_times` on that w (each w_j the same two operations), without numpy's
    gathers and temporaries.

    Parameters
    ----------
    indptr, indices, data
        A in CSR form, as :func:`csr_times`.
    cols : ndarray of uint32, shape (n_cols,)
        The entries of x and z that A's columns stand for.
    x, z : ndarray of float64
        Full-size vectors.
    divisor : float
    w : ndarray of float64, shape (n_cols,)
        Scratch (overwritten).
    y : ndarray of float64, shape (n_rows,)
        Output (overwritten).
    """
    for j in range(cols.size):
        c = cols[j]
        w[j] = x[c] + z[c] / divisor
    csr_times(indptr, indices, data, w, y)


@nb.njit(cache=True)
def subtract_scaled_transposed(indptr, indices, data, lam, scale, v, acc):
    """v −= scale ⊙ (Aᵀ λ) in place, on A's columns only, for a few CSR rows A (m, n).

    The floats of ``push = np.bincount(indices, data * λ_row, minlength=n); push *= scale;
    v -= push`` (each column's products summed from zero in stored order, then one product and
    one subtraction): the same bits, without the three passes over all n entries that a handful
    of contact rows made every step.

    Parameters
    ----------
    indptr, indices, data
        A in CSR form (any integer index type; float64 values).
    lam : ndarray of float64, shape (m,)
    scale : ndarray of float64, shape (n,)
    v : ndarray of float64, shape (n,)
        Updated in place.
    acc : ndarray of float64, shape (n,)
        Scratch of zeros; left zeros.
    """
    m = indptr.size - 1
    for i in range(m):
        for k in range(indptr[i], indptr[i + 1]):
            acc[indices[k]] += data[k] * lam[i]
    for i in range(m):
        for k in range(indptr[i], indptr[i + 1]):
            j = indices[k]
            # a column met again subtracts scale·0 = +0 (scale > 0: M⁻¹): v − (+0) = v
            v[j] -= acc[j] * scale[j]
            acc[j] = 0.0


@nb.njit(cache=True)
def csr_times_subtract_scaled(indptr, indices, data, x, cols, scale, v):
    """``v[cols] −= scale ⊙ (A x)`` in place for A in CSR form (n_rows, ·), its rows' entries
    ``cols`` (n_rows,) of v and ``scale`` (n_rows,): each row's products added in stored order
    from zero (:func:`csr_times`), then the row's product with its scale subtracted, the floats
    of ``y = A @ x; v[cols] -= scale * y`` without y. The indices are not checked (the caller's
    own, valid by construction)."""
    for i in range(indptr.size - 1):
        s = 0.0
        for k in range(indptr[i], indptr[i + 1]):
            s += data[k] * x[indices[k]]
        c = cols[i]
        v[c] = v[c] - scale[i] * s


@nb.njit(parallel=True, cache=True)
def _csr_times_parallel(indptr, indices, data, x, y, n_parts):
    """:func:`csr_times` with the rows in ``n_parts`` contiguous ranges over the threads."""
    n = indptr.size - 1
    size = (n + n_parts - 1) // n_parts
    for part in nb.prange(n_parts):
        for i in range(part * size, min(n, (part + 1) * size)):
            s = 0.0
            for k in range(indptr[i], indptr[i + 1]):
                s += data[k] * x[indices[k]]
            y[i] = s


class CsrProduct:
    """x ↦ A x for a fixed CSR matrix A, compiled (see the module docstring).

    Parameters
    ----------
    matrix : scipy.sparse matrix, shape (n_rows, n_cols)
        Converted to CSR once; its values are copied (a later change of ``matrix`` is not seen:
        build a new product).

    Raises
    ------
    ValueError
        If the matrix has more than 2³² − 1 columns (32-bit column indices).
    """

    def __init__(self, matrix) -> None:
        a = sp.csr_matrix(matrix, dtype=float)
        if a.shape[1] >= 2**32:
            raise ValueError(f"CsrProduct: at most 2**32 - 1 columns, got {a.shape[1]}")
        self.shape = a.shape
        self.nnz = int(a.nnz)
        self._indptr = np.ascontiguousarray(a.indptr, dtype=np.uint64)
        self._indices = np.ascontiguousarray(a.indices, dtype=np.uint32)
        self._data = np.array(a.data, dtype=np.float64)
        self._scratch: np.ndarray | None = None  # times_gathered's vector (n_cols,)
        self._cols_max: tuple[np.ndarray, int] | None = None  # its last cols, their largest

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """A x, a new array (n_rows,), bit for bit scipy's ``A @ x`` for a float64 vector x."""
        x = np.ascontiguousarray(x, dtype=np.float64)
        if x.shape != (self.shape[1],):
            raise ValueError(f"CsrProduct: x must have shape ({self.shape[1]},), got {x.shape}")
        y = np.empty(self.shape[0])
        # numba.get_num_threads() costs several µs (a Python-level launch check): only when
        # the size may call for the threads
        if self.nnz >= PARALLEL_MIN_NNZ and (n_threads := nb.get_num_threads()) > 1:
            _csr_times_parallel(self._indptr, self._indices, self._data, x, y, n_threads)
        else:
            csr_times(self._indptr, self._indices, self._data, x, y)
        return y

    def times_gathered(self, cols: np.ndarray, x: np.ndarray, z: np.ndarray,
                       divisor: float) -> np.ndarray:  # fmt: skip
        """``A (x[cols] + z[cols] / divisor)`` (n_rows,), the same floats as
        ``self(x[cols] + z[cols] / divisor)`` (:func:`csr_times_gathered`): e.g. the rows'
        ``B (v + u/Δt)`` of the explicit impulse on the dofs they touch.

        Parameters
        ----------
        cols : ndarray of uint32, shape (n_cols,)
            The full vectors' entries of A's columns (unsigned: no wraparound test).
        x, z : ndarray of float64
            Full-size vectors.
        divisor : float
        """
        if cols.shape != (self.shape[1],) or cols.dtype != np.uint32:
            raise ValueError(f"CsrProduct: cols must be uint32 of shape ({self.shape[1]},), got "
                             f"{cols.dtype} {cols.shape}")  # fmt: skip
        x = np.ascontiguousarray(x, dtype=np.float64)
        z = np.ascontiguousarray(z, dtype=np.float64)
        # the compiled loop reads x and z unchecked: their size against the largest column
        # (kept for the last cols array, the same one at every step)
        if self._cols_max is None or self._cols_max[0] is not cols:
            self._cols_max = (cols, int(cols.max()) if cols.size else -1)
        if x.ndim != 1 or x.shape != z.shape or x.size <= self._cols_max[1]:
            raise ValueError(f"CsrProduct: x and z must be vectors of one size above "
                             f"{self._cols_max[1]}, got {x.shape} and {z.shape}")  # fmt: skip
        y = np.empty(self.shape[0])
        if self._scratch is None:
            self._scratch = np.empty(self.shape[1])
        csr_times_gathered(self._indptr, self._indices, self._data, cols, x, z, float(divisor),
                           self._scratch, y)  # fmt: skip
        return y
