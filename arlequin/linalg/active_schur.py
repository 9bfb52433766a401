"""Compiled dense factor of the impulse matrix of a few active unilateral rows.

The explicit step's impulse solve (:class:`~arlequin.linalg.impulses.ImpulseSolver`) adds the
active contact rows G_A to the factorised equality rows by a Schur complement. On a deforming
contact the rows are new at every step, so the complement is built and factorised at every
step:

    S = G_A M⁻¹ G_Aᵀ − S_AE D_e⁻¹ S_AEᵀ,    S_AE = G_A M⁻¹ Bᵀ[:, e]

with e the equality rows that share a dof with the active rows when those are decoupled from
the other equality rows (a symmetry axis under the contact: D_e their diagonal), and S = U ᵀU by
Cholesky. numpy and LAPACK did it in some ten calls (a scatter, a dense product, ``np.add.at``,
the factorisation and its tests), 100–150 µs a step of the ball impact, more than the
arithmetic of a dozen rows; here it is one compiled call, and the solve another.

The floats differ from LAPACK's by round-off only (the order of the sums). The tests of
positive definiteness (:func:`cholesky_checked`, also the factorisation of
:class:`~arlequin.linalg.impulses.ImpulseSolver`'s other dense paths): a non-finite entry, a
non-positive pivot, or a pivot U_jj² below 1e-14 |S_jj| (a row dependent on the others to
round-off; :class:`~arlequin.linalg.factor.ScaledLU` applies 1e-14 to its pivots after a
diagonal scaling) is refused.

numba compiles on first call (cached on disk, ``cache=True``).
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ..contract import ConstraintError

__all__ = ["FACTOR_DEPENDENT", "FACTOR_NOT_FINITE", "FACTOR_OK", "ActiveSchur", "cholesky_checked"]

#: Status codes of the compiled factorisation (:class:`ActiveSchur` raises on the last two).
FACTOR_OK, FACTOR_NOT_FINITE, FACTOR_DEPENDENT = 0, 1, 2

#: A pivot below this share of its row's diagonal entry marks a dependent row (ScaledLU's 1e-14).
PIVOT_SHARE = 1e-14


@nb.njit(cache=True)
def _cholesky_upper(a, u):
    """U with UᵀU = a (m, m) in ``u`` (its strict lower part zero); the status code."""
    m = a.shape[0]
    for i in range(m):
        for j in range(m):
            if not np.isfinite(a[i, j]):
                return FACTOR_NOT_FINITE
            u[i, j] = 0.0
    for j in range(m):
        s = a[j, j]
        for k in range(j):
            s -= u[k, j] * u[k, j]
        # also false for a NaN s
        if not (s > 0.0 and s >= PIVOT_SHARE * abs(a[j, j])):
            return FACTOR_DEPENDENT
        d = np.sqrt(s)
        u[j, j] = d
        for i in range(j + 1, m):
            t = a[j, i]
            for k in range(j):
                t -= u[k, j] * u[k, i]
            u[j, i] = t / d
    return FACTOR_OK


@nb.njit(cache=True)
def _factor_active(indptr, indices, data, pos, n_cols, minv, shared, n_shared, bt, d_e, u, s_ae):
    """The Schur complement of the module docstring, factorised into ``u`` (m, m), and S_AE
    into ``s_ae`` (m, n_e); the status code.

    ``pos`` (nnz,): each entry's column among the rows' n_cols columns; ``shared`` (nnz,):
    its column among the n_shared dofs shared with the equality rows, or −1; ``bt``
    (n_shared, n_e): Bᵀ on those dofs and rows; ``d_e`` (n_e,).
    """
    m = indptr.size - 1
    n_e = d_e.size
    a = np.zeros((m, m))
    row_i = np.zeros(n_cols)  # row i of G_A M⁻¹, scattered on the columns
    for i in range(m):
        for p in range(indptr[i], indptr[i + 1]):  # += : duplicate entries are summed
            row_i[pos[p]] += data[p] * minv[indices[p]]
        for j in range(i + 1):
            s = 0.0
            for p in range(indptr[j], indptr[j + 1]):
                s += row_i[pos[p]] * data[p]
            a[i, j] = s
            a[j, i] = s
        for p in range(indptr[i], indptr[i + 1]):
            row_i[pos[p]] = 0.0
    if n_e:
        g = np.zeros((m, n_shared))  # G_A M⁻¹ on the shared dofs, the entries in order
        for i in range(m):
            for p in range(indptr[i], indptr[i + 1]):
                c = shared[p]
                if c >= 0:
                    g[i, c] += data[p] * minv[indices[p]]
        for i in range(m):
            for e in range(n_e):
                s = 0.0
                for c in range(n_shared):
                    s += g[i, c] * bt[c, e]
                s_ae[i, e] = s
        for i in range(m):
            for j in range(i + 1):
                s = 0.0
                for e in range(n_e):
                    s += s_ae[i, e] / d_e[e] * s_ae[j, e]
                a[i, j] -= s
                if j != i:
                    a[j, i] -= s
    return _cholesky_upper(a, u)


@nb.njit(cache=True)
def _solve_active(u, s_ae, d_e, e_rows, r_a, y, lam):
    """λ_A of U ᵀU λ_A = r_a − S_AE y[e] into ``lam``, then y[e] −= S_AEᵀ λ_A / D_e in
    place (y: the equality rows' impulses without the active rows)."""
    m = r_a.size
    n_e = e_rows.size
    for i in range(m):  # Uᵀ z = r_a − S_AE y[e]
        s = r_a[i]
        for e in range(n_e):
            s -= s_ae[i, e] * y[e_rows[e]]
        for k in range(i):
            s -= u[k, i] * lam[k]
        lam[i] = s / u[i, i]
    for i in range(m - 1, -1, -1):  # U λ = z
        s = lam[i]
        for k in range(i + 1, m):
            s -= u[i, k] * lam[k]
        lam[i] = s / u[i, i]
    for e in range(n_e):
        s = 0.0
        for i in range(m):
            s += s_ae[i, e] * lam[i]
        y[e_rows[e]] -= s / d_e[e]


def _raise_for(code: int, m: int) -> None:
    """The :class:`ConstraintError` of a factorisation's status code (nothing for
    :data:`FACTOR_OK`), for the impulse matrix of ``m`` active rows."""
    if code == FACTOR_NOT_FINITE:
        raise ConstraintError(f"the impulse matrix of the {m} active rows is not finite")
    if code == FACTOR_DEPENDENT:
        raise ConstraintError(
            "active unilateral rows are dependent on each other or on the equality rows "
            f"({m} active rows)"
        )


def cholesky_checked(a: np.ndarray) -> np.ndarray:
    """Upper Cholesky factor U (m, m) of a dense symmetric matrix a (UᵀU = a, strict lower
    part zero), compiled, with the tests of the module docstring.

    Raises
    ------
    ConstraintError
        If ``a`` is not finite or not positive definite, or a row depends on the others.
    """
    a = np.ascontiguousarray(a, dtype=float)
    u = np.empty(a.shape)
    _raise_for(_cholesky_upper(a, u), a.shape[0])
    return u


class ActiveSchur:
    """The factorised impulse matrix of the active rows (module docstring), with a ``solve``.

    Parameters
    ----------
    g_a : sparse CSR, shape (m, n)
        The active rows (float64 entries, int32/int64 indices).
    inv_mass : ndarray, shape (n,)
        M⁻¹ (1/kg).
    pos : ndarray of int, shape (nnz,)
        Each entry's column among the columns the rows touch (``np.unique(indices,
        return_inverse=True)[1]``), ``n_cols`` of them.
    shared : ndarray of int, shape (nnz,), optional
        Each entry's column among the dofs shared with the equality rows ``e_rows``, −1 for
        the others; with ``bt`` (n_shared, n_e) Bᵀ on those dofs and rows and ``d_e`` (n_e,)
        the rows' diagonal entries of B M⁻¹ Bᵀ (rows decoupled from the other equality rows).
        None: no equality row shares a dof with the active rows.

    Raises
    ------
    ConstraintError
        If the matrix is not finite, not positive definite, or a row depends on the others.
    """

    __slots__ = ("d_e", "e_rows", "s_ae", "u")

    def __init__(self, g_a, inv_mass: np.ndarray, pos: np.ndarray, n_cols: int,
                 shared: np.ndarray | None = None, e_rows: np.ndarray | None = None,
                 bt: np.ndarray | None = None, d_e: np.ndarray | None = None) -> None:  # fmt: skip
        m = g_a.shape[0]
        if shared is None:
            shared = np.full(g_a.indices.size, -1, dtype=np.int64)
            e_rows, bt, d_e = np.zeros(0, np.int64), np.zeros((0, 0)), np.zeros(0)
        self.e_rows = np.ascontiguousarray(e_rows, dtype=np.int64)
        self.d_e = np.ascontiguousarray(d_e, dtype=float)
        if self.d_e.shape != self.e_rows.shape or bt.shape != (bt.shape[0], self.e_rows.size):
            raise ValueError(f"ActiveSchur: d_e {self.d_e.shape} and Bᵀ {bt.shape} must match "
                             f"the {self.e_rows.size} equality rows")  # fmt: skip
        if not (self.d_e > 0.0).all():  # also refuses NaN: the complement divides by them
            raise ConstraintError(
                f"the equality rows met by the {m} active rows have a non-positive or "
                f"non-finite diagonal entry of B M⁻¹ Bᵀ: {self.d_e.min()}"
            )
        self.u = np.empty((m, m))
        self.s_ae = np.zeros((m, self.e_rows.size))
        code = _factor_active(
            g_a.indptr, g_a.indices, np.ascontiguousarray(g_a.data, dtype=float), pos,
            int(n_cols), inv_mass, shared, int(bt.shape[0]), np.ascontiguousarray(bt, dtype=float),
            self.d_e, self.u, self.s_ae,
        )  # fmt: skip
        _raise_for(code, m)

    def solve(self, r_a: np.ndarray, y: np.ndarray | None = None) -> np.ndarray:
        """λ_A (m,) for the right-hand side r_a (m,) and the equality rows' impulses y
        (m_E,) solved without the active rows, corrected in place on ``e_rows``; a
        non-finite right-hand side gives non-finite impulses (the integrator's finite-state
        check then fails the step)."""
        m = self.u.shape[0]
        r_a = np.ascontiguousarray(r_a, dtype=float)
        if r_a.shape != (m,):
            raise ValueError(f"ActiveSchur.solve: r_a must have shape ({m},), got {r_a.shape}")
        if self.e_rows.size:
            # the compiled loop reads and writes y[e_rows] unchecked
            if not (isinstance(y, np.ndarray) and y.dtype == np.float64 and y.ndim == 1
                    and y.size > self.e_rows.max()):  # fmt: skip
                raise ValueError(f"ActiveSchur.solve: y must be a float vector holding the "
                                 f"equality rows up to {self.e_rows.max()}, got "
                                 f"{np.shape(y)}")  # fmt: skip
        else:
            y = np.zeros(0)
        lam = np.empty(m)
        _solve_active(self.u, self.s_ae, self.d_e, self.e_rows, r_a, y, lam)
        return lam
