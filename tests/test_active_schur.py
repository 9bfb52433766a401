"""The compiled factor of the active rows' impulse matrix (arlequin/linalg/active_schur.py)
against its dense numpy/LAPACK reference (the lines of ImpulseSolver it replaced)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from arlequin.contract import ConstraintError
from arlequin.linalg.active_schur import ActiveSchur


def _rows(seed: int, m: int = 7, n: int = 40, per_row: int = 5) -> sp.csr_matrix:
    """m random rows of ``per_row`` entries each on n dofs (a contact's rows: a few each)."""
    rng = np.random.default_rng(seed)
    g = np.zeros((m, n))
    for i in range(m):
        g[i, rng.choice(n, per_row, replace=False)] = rng.standard_normal(per_row)
    return sp.csr_matrix(g)


def _pattern(g: sp.csr_matrix):
    cols, pos = np.unique(g.indices, return_inverse=True)
    return cols, pos


def _plain(g: sp.csr_matrix) -> ActiveSchur:
    """The factor of rows g alone (unit inverse masses, no equality rows)."""
    cols, pos = _pattern(g)
    return ActiveSchur(g, np.ones(g.shape[1]), pos, cols.size)


def _shared(g: sp.csr_matrix, on_eq: np.ndarray):
    shared = np.full(g.indices.size, -1, dtype=np.int64)
    mask = on_eq[g.indices]
    sh, shared[mask] = np.unique(g.indices[mask], return_inverse=True)
    return sh, shared


def test_independent_rows_match_lapack():
    g = _rows(0)
    minv = np.random.default_rng(1).uniform(0.5, 2.0, g.shape[1])
    cols, pos = _pattern(g)
    fac = ActiveSchur(g, minv, pos, cols.size)
    dense = g.toarray()
    s = (dense * minv) @ dense.T
    # the factor is LAPACK's (dpotrf, upper) to round-off: only the order of the sums differs
    np.testing.assert_allclose(fac.u, sla.cholesky(s), rtol=1e-13, atol=1e-14)
    r = np.random.default_rng(2).standard_normal(g.shape[0])
    np.testing.assert_allclose(fac.solve(r), np.linalg.solve(s, r), rtol=1e-12)


def test_decoupled_equality_rows_match_the_whole_system():
    # 7 active rows meeting 3 equality rows of a diagonal block (single-dof rows: a symmetry
    # axis) on the dofs 0, 1 and 2: the solve of the whole system (equality rows first)
    # exactly, from the equality rows' own solve y corrected in place
    rng = np.random.default_rng(3)
    n = 40
    g = _rows(4, n=n)
    g = (g + sp.csr_matrix((np.full(3, 0.8), ([0, 2, 5], [0, 1, 2])), shape=g.shape)).tocsr()
    g.sum_duplicates()
    minv = rng.uniform(0.5, 2.0, n)
    eq = sp.csr_matrix((np.ones(3), ([0, 1, 2], [0, 1, 2])), shape=(3, n))
    on_eq = np.zeros(n, dtype=bool)
    on_eq[:3] = True
    cols, pos = _pattern(g)
    sh, shared = _shared(g, on_eq)
    bt = eq.T.tocsr()[sh].toarray()
    e_rows = np.arange(3)
    d_e = minv[:3]  # diag(B M⁻¹ Bᵀ) of single-dof rows
    fac = ActiveSchur(g, minv, pos, cols.size, shared, e_rows, bt, d_e)
    full = sp.vstack([eq, g]).toarray()
    s = (full * minv) @ full.T
    r_e, r_a = rng.standard_normal(3), rng.standard_normal(g.shape[0])
    y = r_e / d_e
    lam_a = fac.solve(r_a, y)
    ref = np.linalg.solve(s, np.concatenate([r_e, r_a]))
    np.testing.assert_allclose(np.concatenate([y, lam_a]), ref, rtol=1e-11, atol=1e-12)


def test_dependent_rows_are_refused():
    g = _rows(5).tolil()
    g[3] = 2.0 * g[1]  # row 3 a multiple of row 1: the matrix is singular
    with pytest.raises(ConstraintError, match="dependent"):
        _plain(g.tocsr())


def test_non_finite_rows_are_refused_and_a_nan_rhs_gives_nan():
    g = _rows(6)
    r = np.ones(g.shape[0])
    r[2] = np.nan
    assert np.isnan(_plain(g).solve(r)).any()  # the integrator's finite-state check then fails
    g.data[0] = np.inf
    with pytest.raises(ConstraintError, match="not finite"):
        _plain(g)


def test_duplicate_entries_are_summed():
    # a row with two entries on one dof is the row with their sum (the exact matrix)
    g = _rows(7)
    ref = _plain(g)
    i, j = g.indptr[2], g.indptr[2] + 1
    half = g.data[i] / 2.0
    dup = sp.csr_matrix(
        (np.insert(g.data, i, half), np.insert(g.indices, i, g.indices[i]),
         np.concatenate([g.indptr[:3], g.indptr[3:] + 1])), shape=g.shape,
    )  # fmt: skip
    dup.data[j] = half  # the original entry split in two halves
    np.testing.assert_allclose(_plain(dup).u, ref.u, rtol=1e-14, atol=1e-15)


def test_sizes_and_diagonal_are_checked():
    rng = np.random.default_rng(8)
    g = _rows(9)
    n = g.shape[1]
    on_eq = np.zeros(n, dtype=bool)
    on_eq[np.unique(g.indices)[:2]] = True
    cols, pos = _pattern(g)
    sh, shared = _shared(g, on_eq)
    bt = np.eye(2)[: sh.size]
    fac = ActiveSchur(g, np.ones(n), pos, cols.size, shared, np.array([3, 5]), bt, np.ones(2))
    with pytest.raises(ValueError, match="r_a must have shape"):
        fac.solve(np.ones(g.shape[0] + 1), np.zeros(6))
    with pytest.raises(ValueError, match="y must be a float vector"):
        fac.solve(np.ones(g.shape[0]))  # the equality rows' impulses are needed
    with pytest.raises(ValueError, match="y must be a float vector"):
        fac.solve(np.ones(g.shape[0]), np.zeros(5))  # row 5 outside
    assert np.isfinite(fac.solve(rng.standard_normal(g.shape[0]), np.zeros(6))).all()
    with pytest.raises(ConstraintError, match="non-positive or non-finite diagonal"):
        ActiveSchur(g, np.ones(n), pos, cols.size, shared, np.array([3, 5]), bt, np.zeros(2))
