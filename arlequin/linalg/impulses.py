"""The impulse solve of the explicit scheme: (B M⁻¹ Bᵀ) Λ = r for the equality rows plus the
active unilateral rows (contact), with the equality block factorised once and the active rows
added by a Schur complement (dense, cached by the rows' content) or one sparse factorisation
when there are many of them."""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from ..contract import ConstraintError, same_pattern
from .active_schur import ActiveSchur, cholesky_checked
from .factor import dense_cho_solve, factor_checked, factor_rows

__all__ = ["ImpulseSolver"]


class ImpulseSolver:
    """Solves (B M⁻¹ Bᵀ) Λ = r for the equality rows E plus the active unilateral rows A.

    The equality block S_EE is factorised once (:func:`~arlequin.linalg.factor.factor_rows`:
    by a low-rank split under a fine mediator); active rows enter by a Schur complement
    (dense, cached for the last active rows, keyed by their content), or by a sparse
    factorisation of the whole matrix when there are many of them.
    """

    _DENSE_SCHUR = 300

    def __init__(self, rows, inv_mass: np.ndarray) -> None:
        self.rows = rows
        self.inv_mass = inv_mass
        self.m_e = rows.m
        if self.m_e:
            self.lu = factor_rows(
                rows.matrix_cols, inv_mass[rows.cols],
                "the impulse matrix B M⁻¹ Bᵀ of the equality rows", rows.row_name,
            )  # fmt: skip
        else:
            self.lu = None
        self._s_ee: sp.csc_matrix | None = None
        # Bᵀ of the equality rows, once (the Schur complement's S_AE = G_A M⁻¹ Bᵀ every step)
        self._eq_t = rows.matrix.T.tocsr() if self.m_e else None
        # the last active rows' arrays, their factor and the rows object they came from
        self._last: tuple[tuple, Any, Any] | None = None
        self._eq_t_rows: tuple | None = None  # _shared_part's last slice of Bᵀ
        self._pattern: tuple | None = None  # the last active rows and their pattern's arrays
        self._eq_mask = np.zeros(inv_mass.size, dtype=bool)
        self._shares: tuple | None = None  # the last active rows and whether they share dofs
        if self.m_e:
            self._eq_mask[rows.cols] = True
        # the equality rows decoupled from the others in S_EE, and their diagonal entries
        self._free = np.zeros(self.m_e, dtype=bool)
        self._free_diag = np.zeros(self.m_e)
        decoupled = getattr(self.lu, "decoupled_rows", None)
        if decoupled is not None:
            idx, diag = decoupled()
            self._free[idx] = True
            self._free_diag[idx] = diag

    @property
    def s_ee(self) -> sp.csc_matrix:
        """B M⁻¹ Bᵀ of the equality rows (built on first use: it is dense by blocks under a
        fine mediator)."""
        if self._s_ee is None:
            bj = self.rows.matrix_cols
            self._s_ee = (bj @ sp.diags(self.inv_mass[self.rows.cols]) @ bj.T).tocsc()
        return self._s_ee

    def solve_equality(self, r: np.ndarray) -> np.ndarray:
        """Λ_E (N·s per row unit) of the equality rows alone for the right-hand side r (m_E,)."""
        return self.lu.solve(r) if self.m_e else np.zeros(0)

    def _cached(self, build, g_a: sp.csr_matrix):
        """The factorisation for the active rows ``g_a``: the last one if they are the same
        rows (the same object, or equal CSR arrays), else ``build()``. One entry: the rows
        change with the statuses or, on a deforming contact, at every step, so comparing the
        arrays (a few µs) replaced hashing them (50 µs a step of the ball impact)."""
        last = self._last
        if last is not None and last[2] is g_a:
            return last[1]
        key = self._key(g_a)
        if last is not None and (
            len(last[0]) == len(key)
            and all(a.shape == b.shape and np.array_equal(a, b) for a, b in zip(last[0], key))
        ):
            return last[1]
        fac = build()
        # the rows object itself too: the stacked active rows are the same object while they
        # do not change (rows.stack_active) and never modified in place, so that object is a
        # hit without comparing its arrays (20 µs a step of the Taylor bar)
        self._last = (tuple(np.array(a, copy=True) for a in key), fac, g_a)
        return fac

    def _shares_equality_dofs(self, g_a: sp.csr_matrix) -> bool:
        """Whether the active rows touch a dof of the equality rows, remembered for the last
        rows object (the same object while the statuses hold, never modified in place)."""
        last = self._shares
        if last is not None and last[0] is g_a:
            return last[1]
        shares = bool(self.m_e) and bool(self._eq_mask[g_a.indices].any())
        self._shares = (g_a, shares)
        return shares

    @staticmethod
    def _key(g_a: sp.csr_matrix) -> tuple:
        return (np.asarray(g_a.shape), g_a.indptr, g_a.indices, g_a.data)

    def solve(self, r_e: np.ndarray, g_a: sp.csr_matrix, r_a: np.ndarray):
        """Return (Λ_E, Λ_A) for right-hand sides r_e (m_E,), r_a (m_A,) and active rows g_a."""
        m_a = g_a.shape[0]
        if m_a == 0:
            return self.solve_equality(r_e), np.zeros(0)
        minv = self.inv_mass

        def ga_m() -> sp.csr_matrix:
            # G_A M⁻¹ by scaling its entries (no diagonal matrix, no product), for the sparse
            # factorisations only (a matrix object a step cost more than the dense Schur path)
            return sp.csr_matrix((g_a.data * minv[g_a.indices], g_a.indices.copy(),
                                  g_a.indptr.copy()), shape=g_a.shape)  # fmt: skip

        if not self._shares_equality_dofs(g_a):
            # no dof shared with the equality rows (a wall and a symmetry axis), or no equality
            # rows: the active rows' block alone
            def build_aa():
                if m_a <= self._DENSE_SCHUR:
                    # dense: a chattering contact changes its rows every few steps, and a
                    # sparse factorisation cost 330 µs against ~15 µs (Taylor bar, 8 rows)
                    gram = _dense_gram(g_a, minv, self._pattern_of(g_a))
                    diag = np.diagonal(gram)
                    if np.count_nonzero(gram) == np.count_nonzero(diag):
                        return _DiagonalFactor(diag, m_a)  # independent rows (a wall)
                    return _DenseFactor(self._cholesky(gram, m_a))
                s_aa = (ga_m() @ g_a.T).tocsr()
                return factor_checked(s_aa, "the impulse matrix of the active rows", spd=True)

            lam_a = self._cached(build_aa, g_a).solve(r_a)
            return (self.solve_equality(r_e) if self.m_e else np.zeros(0)), lam_a
        if m_a <= self._DENSE_SCHUR:
            e_rows, shared, bt = self._shared_part(g_a)
            if self._free[e_rows].all():
                # the equality rows the active rows meet (a symmetry axis under the contact)
                # are decoupled in S_EE (divisions): the Schur complement and the corrections
                # on those rows alone, dense, built, factorised and solved compiled
                # (active_schur: a deforming contact's rows are new at every step)
                pat = self._pattern_of(g_a)

                def build_decoupled():
                    return ActiveSchur(g_a, minv, pat["pos"], pat["cols"].size, shared, e_rows,
                                       bt, self._free_diag[e_rows])  # fmt: skip

                factor = self._cached(build_decoupled, g_a)
                y = self.lu.solve(r_e)
                return y, factor.solve(r_a, y)
        s_ae = self._s_ae(g_a)
        if m_a <= self._DENSE_SCHUR:

            def build_schur():
                schur = _dense_gram(g_a, minv, self._pattern_of(g_a))
                # only the active rows that share a dof with the equality rows have a non-zero
                # column in (B M⁻¹ G_Aᵀ): solve for those alone (a few near a symmetry axis)
                coupled = np.nonzero(np.diff(s_ae.indptr))[0]
                x = self.lu.solve(_dense_rows_t(s_ae, coupled, self.m_e)) if coupled.size \
                    else np.zeros((self.m_e, 0))  # fmt: skip
                if coupled.size:
                    schur[:, coupled] -= s_ae @ x
                return coupled, x, self._cholesky(schur, m_a)

            coupled, x, cho = self._cached(build_schur, g_a)
            y = self.lu.solve(r_e)
            # a non-finite right-hand side gives NaN impulses, as on the other paths
            lam_a = _DenseFactor(cho).solve(r_a - s_ae @ y)
            if coupled.size:
                y = y - x @ lam_a[coupled]
            return y, lam_a

        s_ae = s_ae.tocsr()

        def build_full():
            s_aa = (ga_m() @ g_a.T).tocsr()
            full = sp.bmat([[self.s_ee, s_ae.T], [s_ae, s_aa]], format="csc")
            return factor_checked(full, "the impulse matrix with the active rows", spd=True)

        sol = self._cached(build_full, g_a).solve(np.concatenate([r_e, r_a]))
        return sol[: self.m_e], sol[self.m_e :]

    @staticmethod
    def _cholesky(schur: np.ndarray, m_a: int) -> tuple[np.ndarray, bool]:
        """Upper Cholesky factor of the dense (Schur complement) matrix of the ``m_a`` active
        rows, as ``(U, False)`` for :func:`~arlequin.linalg.factor.dense_cho_solve`
        (:func:`~arlequin.linalg.active_schur.cholesky_checked`: raises
        :class:`ConstraintError` if it is not finite or positive definite, or a row depends
        on the others)."""
        return cholesky_checked(schur), False

    def _pattern_of(self, g_a: sp.csr_matrix) -> dict:
        """Arrays that depend on the pattern of the active rows G_A alone (their columns, the
        row of each entry, ...), kept for the last pattern: a deforming contact's rows are new
        at every step but on the same pattern (the same read-only index arrays,
        :func:`~arlequin.contract.same_pattern`) while its points keep their facets."""
        last = self._pattern
        if last is not None and (last[0] is g_a or same_pattern(last[0], g_a)):
            return last[1]
        m = g_a.shape[0]
        cols, pos = np.unique(g_a.indices, return_inverse=True)
        arrays = {"cols": cols, "pos": pos, "row": np.repeat(np.arange(m), np.diff(g_a.indptr))}
        self._pattern = (g_a, arrays)
        return arrays

    def _shared_part(self, g_a: sp.csr_matrix) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(the equality rows e that share a dof with the active rows, each entry's column among
        those shared dofs or −1 (nnz,), Bᵀ on the shared dofs and the rows e dense
        (n_shared, len(e))): arrays of the rows' pattern, kept with it."""
        pat = self._pattern_of(g_a)
        if "shared" not in pat:
            on_eq = self._eq_mask[g_a.indices]
            shared = np.full(g_a.indices.size, -1, dtype=np.int64)
            if on_eq.any():
                sh, shared[on_eq] = np.unique(g_a.indices[on_eq], return_inverse=True)
            else:
                sh = np.zeros(0, dtype=np.int64)
            # Bᵀ's rows on those dofs, dense on the equality rows they touch: the same few
            # (the axis under the contact) step after step
            cached = self._eq_t_rows
            if cached is None or not np.array_equal(cached[0], sh):
                part = self._eq_t[sh].tocsc()
                e_rows = np.nonzero(np.diff(part.indptr))[0]
                cached = (sh, e_rows, np.ascontiguousarray(part[:, e_rows].toarray()))
                self._eq_t_rows = cached
            pat["shared"] = (cached[1], shared, cached[2])
        return pat["shared"]

    def _s_ae(self, g_a: sp.csr_matrix) -> sp.csr_matrix:
        """S_AE = G_A M⁻¹ Bᵀ (m_A, m_E) from the entries of G_A on dofs the equality rows touch
        (a few, on a symmetry axis), not from a product with every equality row (147 µs a step
        of the ball impact's deformable contact, against a few here)."""
        shared = self._eq_mask[g_a.indices]
        m_a = g_a.shape[0]
        if not shared.any():
            return sp.csr_matrix((m_a, self.m_e))
        cols, pos = np.unique(g_a.indices[shared], return_inverse=True)
        row = np.repeat(np.arange(m_a), np.diff(g_a.indptr))[shared]
        indptr = np.zeros(m_a + 1, dtype=np.int64)
        np.cumsum(np.bincount(row, minlength=m_a), out=indptr[1:])
        data = g_a.data[shared] * self.inv_mass[g_a.indices[shared]]
        part = sp.csr_matrix((data, pos, indptr), shape=(m_a, cols.size))
        return (part @ self._eq_t[cols]).tocsr()


class _DenseFactor:
    """A dense Cholesky factor with the ``solve`` of the sparse factorisations: a non-finite
    right-hand side gives non-finite impulses, as theirs do (the integrator's finite-state
    check then fails the step), rather than a ``ValueError`` from LAPACK's wrapper."""

    __slots__ = ("cho",)

    def __init__(self, cho: tuple[np.ndarray, bool]) -> None:
        self.cho = cho

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        rhs = np.asarray(rhs, dtype=float)
        if not np.isfinite(rhs).all():
            return np.full(rhs.shape, np.nan)
        return dense_cho_solve(self.cho, rhs)


class _DiagonalFactor:
    """Independent rows: x = (1 / d) r, the arithmetic of :class:`ScaledLU`'s diagonal path,
    with its test of an empty row. The diagonal d comes from a dense product: the same bits as
    the sparse product's when each row has one non-zero entry (walls along an axis), to
    round-off otherwise."""

    __slots__ = ("inv",)

    def __init__(self, diag: np.ndarray, m_a: int) -> None:
        scale = np.max(np.abs(diag))
        small = np.nonzero(~(np.abs(diag) > 1e-14 * scale))[0]
        if small.size:
            raise ConstraintError(
                f"the impulse matrix of the active rows has an empty row {int(small[0])} "
                f"({m_a} active rows)"
            )
        self.inv = 1.0 / diag

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        return self.inv * rhs


def _dense_gram(g: sp.csr_matrix, minv: np.ndarray, pattern: dict) -> np.ndarray:
    """G M⁻¹ Gᵀ (m, m) of a few sparse rows, dense: the rows scattered on the columns they
    touch, one matrix product (scipy's sparse product and its conversion cost more, every
    step of a deformable contact); ``pattern``: :meth:`ImpulseSolver._pattern_of` of G."""
    cols, pos = pattern["cols"], pattern["pos"]
    m = g.shape[0]
    dense = np.zeros((m, cols.size))
    dense[pattern["row"], pos] = g.data
    return (dense * minv[cols]) @ dense.T


def _dense_rows_t(mat: sp.csr_matrix, rows: np.ndarray, n: int) -> np.ndarray:
    """``mat[rows].T.toarray()`` (n, len(rows)) of a CSR matrix without duplicate entries,
    scattered from its arrays (scipy's row indexing and transpose cost more than the solve
    they feed, every step of a deformable contact)."""
    start = mat.indptr[rows]
    cnt = mat.indptr[rows + 1] - start
    pos = np.repeat(start - (np.cumsum(cnt) - cnt), cnt) + np.arange(int(cnt.sum()))
    out = np.zeros((n, rows.size), order="F")  # the layout of toarray's: the same products
    out[mat.indices[pos], np.repeat(np.arange(rows.size), cnt)] = mat.data[pos]
    return out
