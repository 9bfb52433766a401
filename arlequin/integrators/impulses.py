"""The impulse solve of the explicit scheme: (B M⁻¹ Bᵀ) Λ = r for the equality rows plus the
active unilateral rows (contact), with the equality block factorised once and the active rows
added by a Schur complement (dense, cached by the rows' content) or one sparse factorisation
when there are many of them."""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from ..contract import ConstraintError
from .linalg import dense_cho_factor, dense_cho_solve, factor_checked, factor_rows
from .rows import rows_key, transposed

__all__ = ["ImpulseSolver"]


class ImpulseSolver:
    """Solves (B M⁻¹ Bᵀ) Λ = r for the equality rows E plus the active unilateral rows A.

    The equality block S_EE is factorised once (:func:`~arlequin.integrators.linalg.factor_rows`:
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
        self._cache: dict[Any, Any] = {}
        self._last_key: tuple[Any, bytes] | None = None
        self._eq_mask = np.zeros(inv_mass.size, dtype=bool)
        if self.m_e:
            self._eq_mask[rows.cols] = True

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

    def _cached(self, key: bytes, build):
        fac = self._cache.get(key)
        if fac is None:
            fac = build()
            self._cache = {key: fac}
        return fac

    def _key(self, g_a: sp.csr_matrix) -> bytes:
        last = self._last_key
        if last is not None and last[0] is g_a:  # the same stacked rows as last time
            return last[1]
        key = rows_key(g_a)
        self._last_key = (g_a, key)
        return key

    def solve(self, r_e: np.ndarray, g_a: sp.csr_matrix, r_a: np.ndarray):
        """Return (Λ_E, Λ_A) for right-hand sides r_e (m_E,), r_a (m_A,) and active rows g_a."""
        m_a = g_a.shape[0]
        if m_a == 0:
            return self.solve_equality(r_e), np.zeros(0)
        key = self._key(g_a)
        minv = self.inv_mass
        # G_A M⁻¹ by scaling its entries (no diagonal matrix, no product): reused below
        ga_m = sp.csr_matrix((g_a.data * minv[g_a.indices], g_a.indices.copy(),
                              g_a.indptr.copy()), shape=g_a.shape)  # fmt: skip
        if self.m_e and not self._eq_mask[g_a.indices].any():
            # no dof shared with the equality rows (a wall and a symmetry axis): two blocks
            def build_aa_only():
                s_aa = (ga_m @ g_a.T).tocsr()
                return factor_checked(s_aa, "the impulse matrix of the active rows", spd=True)

            return self.solve_equality(r_e), self._cached(key, build_aa_only).solve(r_a)
        if self.m_e == 0:

            def build_aa():
                s_aa = (ga_m @ g_a.T).tocsr()
                return factor_checked(s_aa, "the impulse matrix of the active rows", spd=True)

            return np.zeros(0), self._cached(key, build_aa).solve(r_a)
        s_ae = (ga_m @ self._eq_t).tocsr()
        if m_a <= self._DENSE_SCHUR:

            def build_schur():
                # G_Aᵀ from the shared cache: the integrator applies it to Λ_A right after
                s_aa = (ga_m @ transposed(g_a)).tocsr()
                # only the active rows that share a dof with the equality rows have a non-zero
                # column in (B M⁻¹ G_Aᵀ): solve for those alone (a few near a symmetry axis)
                coupled = np.nonzero(np.diff(s_ae.indptr))[0]
                x = self.lu.solve(_dense_rows_t(s_ae, coupled, self.m_e)) if coupled.size \
                    else np.zeros((self.m_e, 0))  # fmt: skip
                schur = s_aa.toarray()
                if coupled.size:
                    schur[:, coupled] -= s_ae @ x
                try:
                    cho = dense_cho_factor(schur)
                except np.linalg.LinAlgError as exc:
                    raise ConstraintError(
                        "active unilateral rows are dependent on each other or on the equality "
                        f"rows ({m_a} active rows)"
                    ) from exc
                return coupled, x, cho

            coupled, x, cho = self._cached(key, build_schur)
            y = self.lu.solve(r_e)
            lam_a = dense_cho_solve(cho, r_a - s_ae @ y)
            if coupled.size:
                y = y - x @ lam_a[coupled]
            return y, lam_a

        def build_full():
            s_aa = (ga_m @ g_a.T).tocsr()
            full = sp.bmat([[self.s_ee, s_ae.T], [s_ae, s_aa]], format="csc")
            return factor_checked(full, "the impulse matrix with the active rows", spd=True)

        sol = self._cached(key, build_full).solve(np.concatenate([r_e, r_a]))
        return sol[: self.m_e], sol[self.m_e :]




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
