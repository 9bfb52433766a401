"""Sparse factorisations of the integrators' constraint and saddle-point matrices.

The matrices mix rows of very different units (stiffness N/m, mass kg, constraint rows of m² for
L2 coupling): :class:`ScaledLU` scales them symmetrically before SuperLU and turns (numerical)
singularity into a :class:`~arlequin.contract.ConstraintError` that names the offending row.
:func:`factor_rows` factorises the impulse matrix B M⁻¹ Bᵀ of constraint rows, by
:class:`LowRankSplitSolver` when a few dofs shared by many rows make it dense, or
:class:`DiagonalLowRankSolver` when every row has a dof of its own (rows in their pivot basis,
:mod:`arlequin.solvers.dynamics.row_basis`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numba as nb
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.linalg.lapack import dpotrf, dpotrs
from scipy.sparse.csgraph import connected_components, reverse_cuthill_mckee

from ..contract import ConstraintError
from .csr import CsrProduct

__all__ = [
    "DiagonalLowRankSolver",
    "IsolatedRowsSolver",
    "LowRankSplitSolver",
    "ScaledLU",
    "dense_cho_factor",
    "dense_cho_solve",
    "factor_checked",
    "factor_rows",
    "low_rank_solve",
]


def dense_cho_factor(a: np.ndarray) -> tuple[np.ndarray, bool]:
    """``scipy.linalg.cho_factor(a)`` (upper factor) of a real matrix by LAPACK ``dpotrf``.

    The same routine and arguments, so the same factor bit for bit, in half the time at the
    size of the few active contact rows that are factorised every step (scipy's wrappers cost
    more than the factorisation there).

    Raises
    ------
    ValueError
        If ``a`` has a non-finite entry.
    numpy.linalg.LinAlgError
        If ``a`` is not positive definite.
    """
    a = np.asarray(a, dtype=float)
    if not np.isfinite(a).all():
        raise ValueError("array must not contain infs or NaNs")
    c, info = dpotrf(a, lower=False, overwrite_a=False, clean=False)
    if info > 0:
        raise np.linalg.LinAlgError(f"{info}-th leading minor not positive definite")
    if info < 0:
        raise ValueError(f"illegal value in argument {-info} of the LAPACK potrf call")
    return c, False


def dense_cho_solve(factor: tuple[np.ndarray, bool], rhs: np.ndarray) -> np.ndarray:
    """``scipy.linalg.cho_solve(factor, rhs)`` for real arrays by LAPACK ``dpotrs`` (the same
    result).

    Raises
    ------
    ValueError
        If ``rhs`` has a non-finite entry.
    """
    c, lower = factor
    rhs = np.asarray(rhs, dtype=float)
    if not np.isfinite(rhs).all():
        raise ValueError("array must not contain infs or NaNs")
    x, info = dpotrs(c, rhs, lower=lower, overwrite_b=False)
    if info != 0:
        raise ValueError(f"illegal value in argument {-info} of the LAPACK potrs call")
    return x


class ScaledLU:
    """Sparse LU (SuperLU) of a symmetric matrix after symmetric diagonal scaling ``D A D``.

    ``D_ii = |A_ii|^{-1/2}``; rows with a zero diagonal (multiplier rows of a saddle point) get
    the inverse norm of their scaled row, so that stiffness, mass and constraint rows of very
    different units become commensurate. A pivot below ``1e-14`` of the largest one (after
    scaling) means linearly dependent rows: :class:`ConstraintError`.

    Parameters
    ----------
    mat : sparse, shape (N, N)
    what : str
        Name of the matrix for the error message.
    names : callable, optional
        Row index -> description, for the error message.
    spd : bool
        Symmetric positive definite: symmetric ordering, diagonal pivots.
    """

    def __init__(
        self,
        mat: sp.spmatrix,
        what: str,
        names: Callable[[int], str] | None = None,
        spd: bool = False,
    ) -> None:
        mat = sp.csr_matrix(mat)
        n = mat.shape[0]
        self.shape = mat.shape
        self._inv_diag: np.ndarray | None = None
        if _is_diagonal(mat):
            # independent rows (a wall, a symmetry axis): no factorisation, one division
            dg = mat.diagonal()
            scale = np.max(np.abs(dg)) if n else 0.0
            small = np.nonzero(~(np.abs(dg) > 1e-14 * scale))[0] if n else np.zeros(0, int)
            if small.size:
                i = int(small[0])
                where = f" ({names(i)})" if names is not None else ""
                raise ConstraintError(f"{what} has an empty row {i}{where}")
            self._inv_diag = 1.0 / dg
            return
        diag = np.abs(mat.diagonal())
        d = np.zeros(n)
        nz = diag > 0.0
        d[nz] = 1.0 / np.sqrt(diag[nz])
        if not np.all(nz):
            scaled_cols = sp.csr_matrix(mat[~nz] @ sp.diags(d))
            norms = np.sqrt(np.asarray(scaled_cols.multiply(scaled_cols).sum(axis=1)).ravel())
            bad = np.nonzero(norms == 0.0)[0]
            if bad.size:
                i = int(np.nonzero(~nz)[0][bad[0]])
                where = f" ({names(i)})" if names is not None else ""
                raise ConstraintError(f"{what} has an empty row {i}{where}")
            d[~nz] = 1.0 / norms
        self.d = d
        scaled = sp.csc_matrix(sp.diags(d) @ mat @ sp.diags(d))
        try:
            if spd:
                self.lu = spla.splu(scaled, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0)
            else:
                self.lu = spla.splu(scaled)
        except RuntimeError as exc:
            raise ConstraintError(
                f"{what} is singular ({exc}): the constraint rows are linearly dependent"
            ) from exc
        piv = np.abs(self.lu.U.diagonal())
        tiny = np.nonzero(~(piv > 1e-14 * piv.max()))[0] if piv.size else np.zeros(0, int)
        if tiny.size:
            where = ""
            if names is not None:
                where = f" (near {names(int(self.lu.perm_c[tiny[0]]) if spd else int(tiny[0]))})"
            raise ConstraintError(
                f"{what} is numerically singular: {tiny.size} pivot(s) below 1e-14 of the "
                f"largest after scaling{where}; the constraint rows are linearly dependent (e.g. "
                "a Dirichlet condition on dofs that the mediator rows already tie, or duplicate "
                "rows)"
            )

    def decoupled_rows(self) -> tuple[np.ndarray, np.ndarray]:
        """(the rows coupled to no other: all of a diagonal matrix, none otherwise; their
        diagonal entries)."""
        if self._inv_diag is None:
            return np.zeros(0, dtype=np.int64), np.zeros(0)
        return np.arange(self.shape[0]), 1.0 / self._inv_diag

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve A x = rhs; rhs of shape (N,) or (N, k)."""
        if self._inv_diag is not None:
            inv = self._inv_diag if rhs.ndim == 1 else self._inv_diag[:, None]
            return inv * rhs
        d = self.d if rhs.ndim == 1 else self.d[:, None]
        return d * self.lu.solve(np.ascontiguousarray(d * rhs))


def _is_diagonal(mat: sp.csr_matrix) -> bool:
    """True if the CSR matrix has no stored entry off its diagonal (zeros pruned)."""
    mat = mat.copy()
    mat.eliminate_zeros()
    rows = np.repeat(np.arange(mat.shape[0]), np.diff(mat.indptr))
    return bool(np.all(mat.indices == rows))


def factor_checked(
    mat: sp.spmatrix, what: str, names: Callable[[int], str] | None = None, spd: bool = False
) -> ScaledLU | None:
    """:class:`ScaledLU` of a square sparse matrix (None if it is empty)."""
    if mat.shape[0] == 0:
        return None
    return ScaledLU(mat, what, names, spd)


class LowRankSplitSolver:
    """Solves (B M⁻¹ Bᵀ) x = r by splitting B's columns: S = A + U Uᵀ, through the augmented
    quasi-definite system

        [ A   U ] [x]   [r]
        [ Uᵀ −I ] [y] = [0],     (y = Uᵀ x, so (A + U Uᵀ) x = r).

    A fine-mediator L2 coupling has rows that each touch a few fine dofs and the coarse dofs
    of the coarse cell below: a coarse dof is shared by every row in its cells (about
    2·(2^levels + 1)² of them), so S = B M⁻¹ Bᵀ is nearly dense by blocks (a band of 7,600 rows
    at three levels: 480 entries a row, a SuperLU solve of 2.8 ms). With B = [B_L, B_H], the
    heavy columns H (the shared dofs, few) and the light ones L, A = B_L M_L⁻¹ B_Lᵀ stays as
    sparse as the fine mesh and U = B_H M_H^{-1/2} has a few columns, each touching the rows of
    one coarse dof. A symmetric quasi-definite matrix has an LDLᵀ factorisation in any symmetric
    order (Vanderbei 1995), so SuperLU factorises it with diagonal pivots and a minimum-degree
    order that leaves the |H| dense rows for last: one sparse solve a step. On the ball impact's
    block band (4,336 rows, |H| = 308) the augmented factor holds 361k entries and a solve
    takes 0.55 ms, against 1.24 ms for the Woodbury form it replaces (two solves with A, 294k
    entries each, and a dense Cholesky solve of size |H|) and 0.72 ms for S itself (779k).

    Parameters
    ----------
    b : sparse, shape (m, n)
        The rows (on the dofs they touch).
    inv_mass : ndarray, shape (n,)
        M⁻¹ on those dofs (1/kg).
    heavy : ndarray of bool, shape (n,)
        The columns put in U.
    what : str
        Name of the matrix, for errors.

    Raises
    ------
    ConstraintError
        If the augmented matrix is (numerically) singular, i.e. S is, or a diagonal pivot
        vanished: the caller falls back to one factorisation of S, which names the rows.
    """

    def __init__(self, b: sp.csr_matrix, inv_mass: np.ndarray, heavy: np.ndarray,
                 what: str) -> None:  # fmt: skip
        b = sp.csc_matrix(b)
        light = np.nonzero(~heavy)[0]
        heavy_cols = np.nonzero(heavy)[0]
        b_l = b[:, light]
        a = b_l @ sp.diags(inv_mass[light]) @ b_l.T
        u = b[:, heavy_cols] @ sp.diags(np.sqrt(inv_mass[heavy_cols]))
        k = heavy_cols.size
        aug = sp.bmat([[a, u], [u.T, -sp.identity(k)]], format="csc")
        self.aug = ScaledLU(aug, what, spd=True)
        self.shape = (b.shape[0], b.shape[0])
        self.n_heavy = int(k)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve S x = rhs; rhs of shape (m,) or (m, k)."""
        m = self.shape[0]
        pad = np.zeros((self.n_heavy, *rhs.shape[1:]))
        return self.aug.solve(np.concatenate([rhs, pad]))[:m]


class IsolatedRowsSolver:
    """Solves (B M⁻¹ Bᵀ) x = r when some rows share no dof with any other row.

    Those rows (a symmetry axis or a support away from a coupling band) are one division
    each; the others go to ``rest``. A right-hand side that is zero on the other rows (the
    contact rows coupled to the axis at the contact point) costs no solve at all.

    Parameters
    ----------
    isolated : ndarray of int
        The isolated rows.
    diagonal : ndarray, shape (len(isolated),)
        Their diagonal entries Σ_j B_ij² M⁻¹_j.
    rest : ndarray of int
        The other rows.
    rest_solver : object with ``solve``, or None
        Their factorisation.
    """

    def __init__(self, isolated: np.ndarray, diagonal: np.ndarray, rest: np.ndarray,
                 rest_solver) -> None:  # fmt: skip
        self.isolated, self.rest = isolated, rest
        self.inv_diag = 1.0 / diagonal
        self.rest_solver = rest_solver
        m = isolated.size + rest.size
        self.shape = (m, m)

    def decoupled_rows(self) -> tuple[np.ndarray, np.ndarray]:
        """(the isolated rows, their diagonal entries)."""
        return self.isolated, 1.0 / self.inv_diag

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve S x = rhs; rhs of shape (m,) or (m, k)."""
        x = np.zeros_like(rhs, dtype=float)
        inv = self.inv_diag if rhs.ndim == 1 else self.inv_diag[:, None]
        x[self.isolated] = inv * rhs[self.isolated]
        part = rhs[self.rest]
        if self.rest.size and np.any(part):
            x[self.rest] = self.rest_solver.solve(part)
        return x


class DiagonalLowRankSolver:
    """Solves (B M⁻¹ Bᵀ) x = r when every row has a column no other row touches.

    Those private columns give a diagonal D = Σ_private B_ij² M⁻¹_j and the k others
    U = B_O M_O^{-1/2}, so S = D + U Uᵀ and, by Woodbury,

        S⁻¹ r = D⁻¹ r − D⁻¹ U C⁻¹ Uᵀ D⁻¹ r,    C = I_k + Uᵀ D⁻¹ U   (k × k, SPD),

    one factorisation of C (by its independent groups: C couples the shared dofs that share a
    row, a coarse mesh's neighbours; dense groups up to 300 dofs, SuperLU beyond), then per
    solve two products with U and C's triangular solves. Rows in their pivot basis
    (v_F + P v_O = 0: the fine mediator of a nested patch,
    :mod:`arlequin.solvers.dynamics.row_basis`) and single-dof rows have this form: on the ball
    impact's equality rows (two bands and the axes, 4,592 rows, k = 450 in four groups) a
    solve takes 0.06 ms against 0.75 ms for the sparse LU of the rows as assembled. C's
    eigenvalues are at least 1: S is positive definite whatever B (the private columns make
    the rows independent).

    Parameters
    ----------
    b : sparse, shape (m, n)
        The rows (on the dofs they touch).
    inv_mass : ndarray, shape (n,)
        M⁻¹ on those dofs (1/kg).
    private : ndarray of bool, shape (n,)
        The columns touched by one row each (every row must have one).
    """

    def __init__(self, b: sp.csr_matrix, inv_mass: np.ndarray, private: np.ndarray) -> None:
        b = sp.csr_matrix(b)
        bp = b[:, np.nonzero(private)[0]]
        self.d = np.asarray(bp.multiply(bp) @ inv_mass[private]).ravel()
        if not np.all(self.d > 0.0):
            raise ValueError("every row needs a private column with a non-zero entry")
        others = np.nonzero(~private)[0]
        k = int(others.size)
        self.u = (b[:, others] @ sp.diags(np.sqrt(inv_mass[others]))).tocsr()
        self.u_t = self.u.T.tocsr()
        cap = (sp.identity(k) + self.u_t @ sp.diags(1.0 / self.d) @ self.u).tocsr()
        # C couples the shared dofs that share a row (a coarse mesh's neighbours), in groups
        # apart (a band, a displacement component): each group's factor, dense when small
        # (LAPACK's solve of 110 unknowns takes 7 µs, SuperLU's wrapper about as much alone)
        self._groups: list[tuple[np.ndarray, Any, bool]] = []
        if k:
            _, label = connected_components(cap, directed=False)
            for g in np.unique(label):
                idx = np.nonzero(label == g)[0]
                block = cap[idx][:, idx]
                if idx.size <= _DENSE_GROUP:
                    self._groups.append((idx, dense_cho_factor(block.toarray()), True))
                else:
                    lu = spla.splu(block.tocsc(), permc_spec="MMD_AT_PLUS_A",
                                   diag_pivot_thresh=0.0)  # fmt: skip
                    self._groups.append((idx, lu, False))
        self.shape = (b.shape[0], b.shape[0])
        self.k = k
        # U and Uᵀ as compiled products for the vector path with SuperLU groups (scipy's floats)
        self._u_times = CsrProduct(self.u)
        self._u_t_times = CsrProduct(self.u_t)
        self._compiled = self._sparse_factor(cap) if k and all(g[2] for g in self._groups) \
            else None  # fmt: skip

    def _sparse_factor(self, cap: sp.csr_matrix) -> tuple[np.ndarray, ...]:
        """C's Cholesky factor L (C = L Lᵀ) as sparse rows, for :func:`low_rank_solve`: each
        group's unknowns in reverse Cuthill–McKee order, which keeps its factor in a band of a
        few entries (C couples the neighbours of a coarse mesh: on the ball impact's 573 shared
        dofs 3,083 entries of L against 42,154 in the four dense factors), factorised dense (the
        groups are at most :data:`_DENSE_GROUP`) and its exact zeros dropped. With U's columns
        in that order, a vector solve is one compiled pass (69 → 19–23 µs a step there)."""
        order = []
        for idx, _, _ in self._groups:
            block = cap[idx][:, idx].tocsr()
            order.append(idx[reverse_cuthill_mckee(block, symmetric_mode=True)])
        perm = np.concatenate(order)
        cp = cap[perm][:, perm]
        rows, cols, vals = [], [], []
        start = 0
        for idx in order:
            n = idx.size
            sl = slice(start, start + n)
            low = np.linalg.cholesky(cp[sl, sl].toarray())
            r, c = np.nonzero(low)  # row by row, the diagonal last in each row
            rows.append(r + start)
            cols.append(c + start)
            vals.append(low[r, c])
            start += n
        low = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                            shape=(self.k, self.k))  # fmt: skip
        low.sort_indices()
        u = self.u[:, perm].tocsr()
        u.sort_indices()
        as_u32 = np.uint32 if max(self.k, self.shape[0]) < 2**32 else np.int64
        # reciprocals of D and of L's diagonal: products in the solve's dependency chains
        # (a division's latency is three to five times a product's)
        inv_diag = 1.0 / low.diagonal()
        return (
            1.0 / self.d,
            np.ascontiguousarray(u.indptr, dtype=np.int64), u.indices.astype(as_u32),
            np.ascontiguousarray(u.data, dtype=float),
            np.ascontiguousarray(low.indptr, dtype=np.int64), low.indices.astype(as_u32),
            np.ascontiguousarray(low.data, dtype=float), inv_diag, np.empty(self.k),
        )  # fmt: skip

    def decoupled_rows(self) -> tuple[np.ndarray, np.ndarray]:
        """(the rows coupled to no other in S: no shared column, their diagonal entries)."""
        free = np.nonzero(np.diff(self.u.indptr) == 0)[0]
        return free, self.d[free]

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve S x = rhs; rhs of shape (m,) or (m, c).

        Raises
        ------
        ValueError
            If ``rhs`` has a non-finite entry (the compiled vector path tests ``rhs`` itself;
            the others the vector Uᵀ D⁻¹ rhs, as LAPACK's wrapper does).
        """
        if rhs.ndim == 1 and self._compiled is not None:
            out = np.empty(self.shape[0])
            if not low_rank_solve(np.ascontiguousarray(rhs, dtype=float), *self._compiled, out):
                raise ValueError("array must not contain infs or NaNs")
            return out
        d = self.d if rhs.ndim == 1 else self.d[:, None]
        y = rhs / d
        if self.k == 0:
            return y
        vector = rhs.ndim == 1
        w = self._u_t_times(y) if vector else self.u_t @ y
        if len(self._groups) == 1:
            _, fac, dense = self._groups[0]
            z = dense_cho_solve(fac, w) if dense else fac.solve(w)
        else:
            z = np.empty_like(w)
            for idx, fac, dense in self._groups:
                z[idx] = dense_cho_solve(fac, w[idx]) if dense else fac.solve(w[idx])
        return y - (self._u_times(z) if vector else self.u @ z) / d


@nb.njit(cache=True)
def low_rank_solve(rhs, inv_d, u_indptr, u_indices, u_data, l_indptr, l_indices, l_data,
                   inv_diag, z, out):  # fmt: skip
    """The vector solve of :class:`DiagonalLowRankSolver` in one pass:
    ``x = y − D⁻¹ U C⁻¹ Uᵀ y`` with ``y = D⁻¹ rhs`` and C = L Lᵀ.

    Parameters
    ----------
    rhs, inv_d : ndarray, shape (m,)
        Right-hand side and the inverse of D's diagonal.
    u_indptr, u_indices, u_data
        U (m, k) in CSR form, its columns in L's order.
    l_indptr, l_indices, l_data
        L (k, k) lower triangular in CSR form, each row's columns sorted (its diagonal last).
    inv_diag : ndarray, shape (k,)
        The inverse of L's diagonal.
    z : ndarray, shape (k,)
        Scratch (overwritten).
    out : ndarray, shape (m,)
        x (overwritten).

    Returns
    -------
    bool
        False if ``rhs`` has a non-finite entry (``out`` is then not the solution).
    """
    m = rhs.size
    k = z.size
    finite = True
    for j in range(k):
        z[j] = 0.0
    for i in range(m):
        r = rhs[i]
        if not (abs(r) < np.inf):
            finite = False
        y = r * inv_d[i]
        out[i] = y
        for kk in range(u_indptr[i], u_indptr[i + 1]):  # w = Uᵀ y, into z
            z[u_indices[kk]] += u_data[kk] * y
    for a in range(k):  # L t = w
        s = z[a]
        last = l_indptr[a + 1] - 1
        for kk in range(l_indptr[a], last):
            s -= l_data[kk] * z[l_indices[kk]]
        z[a] = s * inv_diag[a]
    for a in range(k - 1, -1, -1):  # Lᵀ c = t, by L's rows taken as Lᵀ's columns
        last = l_indptr[a + 1] - 1
        c = z[a] * inv_diag[a]
        z[a] = c
        for kk in range(l_indptr[a], last):
            z[l_indices[kk]] -= l_data[kk] * c
    for i in range(m):  # x = y − D⁻¹ U c
        s = 0.0
        for kk in range(u_indptr[i], u_indptr[i + 1]):
            s += u_data[kk] * z[u_indices[kk]]
        out[i] -= s * inv_d[i]
    return finite


def _diagonal_low_rank(b: sp.csr_matrix, pattern: sp.csr_matrix, counts: np.ndarray,
                       inv_mass: np.ndarray) -> DiagonalLowRankSolver | None:  # fmt: skip
    """A DiagonalLowRankSolver if every row has a private column and the others are at most
    as many as the rows; None otherwise."""
    private = counts == 1
    if not np.all(pattern @ private.astype(float) > 0):
        return None
    used = counts > 0
    if int((used & ~private).sum()) > b.shape[0]:
        return None
    cols = np.nonzero(used)[0]
    return DiagonalLowRankSolver(b[:, cols], inv_mass[cols], private[cols])


#: Groups of a DiagonalLowRankSolver's capacitance matrix up to this size are factorised dense.
_DENSE_GROUP = 300

#: Columns shared by more rows than this (and than 4× the median) are candidates for U.
_HEAVY_COLUMN = 32


def factor_rows(
    b: sp.spmatrix, inv_mass: np.ndarray, what: str, names: Callable[[int], str] | None = None
) -> Any:
    """Factorisation of the impulse matrix B M⁻¹ Bᵀ of constraint rows (None if no rows).

    Rows sharing no dof with another row are split off (:class:`IsolatedRowsSolver`);
    :class:`DiagonalLowRankSolver` when every row has a dof of its own and the other dofs are
    at most as many as the rows;
    :class:`LowRankSplitSolver` when a few columns shared by many rows (at most a fifth of the
    rows, each row keeping a column of its own) make the matrix at least 4× denser than
    without them; one :class:`ScaledLU` otherwise, or if the split's A is singular (then the
    whole matrix's factorisation names the dependent rows).

    Parameters
    ----------
    b : sparse, shape (m, n)
        The rows on the dofs they touch.
    inv_mass : ndarray, shape (n,)
        M⁻¹ on those dofs (1/kg).
    what, names
        As for :class:`ScaledLU`.
    """
    b = sp.csr_matrix(b)
    b.eliminate_zeros()
    m = b.shape[0]
    if m == 0:
        return None
    pattern = b.copy()
    pattern.data = np.ones_like(pattern.data)
    counts = np.asarray(pattern.sum(axis=0)).ravel()
    # rows with a dof of their own each (rows in their pivot basis, single-dof rows):
    # diagonal plus low rank, the isolated rows with them (no split to gather and scatter)
    diag = _diagonal_low_rank(b, pattern, counts, inv_mass)
    if diag is not None:
        return diag
    # rows whose dofs no other row touches: diagonal (a non-empty row only)
    shared = pattern @ (counts > 1).astype(float)
    isolated = np.nonzero((shared == 0) & (np.diff(b.indptr) > 0))[0]
    if 0 < isolated.size < m:
        rest = np.setdiff1d(np.arange(m), isolated)
        diag = np.asarray(b[isolated].multiply(b[isolated]) @ inv_mass).ravel()
        sub_names = None if names is None else (lambda i: names(int(rest[i])))
        return IsolatedRowsSolver(isolated, diag, rest,
                                  factor_rows(b[rest], inv_mass, what, sub_names))  # fmt: skip
    used = counts[counts > 0]
    heavy = counts > max(_HEAVY_COLUMN, 4.0 * (np.median(used) if used.size else 0.0))
    if heavy.any():
        # a row with only heavy columns would leave A singular: its columns stay light
        light_per_row = pattern @ (~heavy).astype(float)
        lonely = np.nonzero(light_per_row == 0)[0]
        if lonely.size:
            heavy[pattern[lonely].indices] = False
    n_heavy = int(heavy.sum())
    if 0 < n_heavy <= m // 5:
        light = pattern[:, np.nonzero(~heavy)[0]]
        nnz_a = (light @ light.T).nnz
        nnz_s = (pattern @ pattern.T).nnz
        if nnz_s >= 4 * nnz_a:
            try:
                return LowRankSplitSolver(b, inv_mass, heavy, what)
            except (ConstraintError, np.linalg.LinAlgError):
                pass
    s = (b @ sp.diags(inv_mass) @ b.T).tocsc()
    return ScaledLU(s, what, names, spd=True)
