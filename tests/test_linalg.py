"""The integrators' sparse factorisation (arlequin/linalg/factor.py) against dense solves."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from arlequin.contract import ConstraintError
from arlequin.linalg.factor import ScaledLU


def _spd_with_isolated_rows(n: int, isolated: np.ndarray, seed: int = 0) -> sp.csr_matrix:
    rng = np.random.default_rng(seed)
    a = rng.standard_normal((n, n))
    a = a @ a.T + n * np.eye(n)
    a[isolated, :] = 0.0
    a[:, isolated] = 0.0
    a[isolated, isolated] = rng.uniform(1.0, 1e6, isolated.size)  # rows of mixed units
    return sp.csr_matrix(a)


@pytest.mark.parametrize("isolated", [[0, 3, 7], [5], list(range(12))])
def test_scaled_lu_solves_rows_of_mixed_units(isolated):
    idx = np.asarray(isolated)
    mat = _spd_with_isolated_rows(12, idx)
    lu = ScaledLU(mat, "test matrix", spd=True)
    rhs = np.random.default_rng(1).standard_normal((12, 3))
    # exact up to round-off: the dense solve of the same matrix
    assert np.allclose(lu.solve(rhs), np.linalg.solve(mat.toarray(), rhs), rtol=1e-12, atol=0)
    assert np.allclose(lu.solve(rhs[:, 0]), np.linalg.solve(mat.toarray(), rhs[:, 0]),
                       rtol=1e-12, atol=0)  # fmt: skip


def test_dependent_rows_are_refused():
    mat = _spd_with_isolated_rows(6, np.array([0])).tolil()
    mat[5, :] = mat[4, :]
    mat[:, 5] = mat[:, 4]  # rows 4 and 5 equal: singular
    with pytest.raises(ConstraintError, match="linearly dependent"):
        ScaledLU(mat.tocsr(), "test matrix", names=lambda i: f"row {i}", spd=True)


def _fine_mediator_rows(n_coarse: int, ratio: int, seed: int = 0):
    """Rows shaped like a nested 1D L2 fine-mediator coupling plus a few axis-like rows.

    Row i (a fine node) touches the fine dofs i−1, i, i+1 (a mass-matrix stencil) and the two
    coarse dofs of the coarse cell that holds it, each shared by about ``ratio`` rows; three
    more rows touch one dof each that nothing else touches (a symmetry axis off the band).
    """
    rng = np.random.default_rng(seed)
    n_fine = n_coarse * ratio + 1
    rows, cols, vals = [], [], []
    for i in range(n_fine):
        for j in (i - 1, i, i + 1):
            if 0 <= j < n_fine:
                rows.append(i)
                cols.append(j)
                vals.append(4.0 if j == i else 1.0)
        cell = min(i // ratio, n_coarse - 1)
        for k in (cell, cell + 1):
            rows.append(i)
            cols.append(n_fine + k)
            vals.append(-rng.uniform(1.0, 3.0))
    n_dofs = n_fine + n_coarse + 1
    for r in range(3):
        rows.append(n_fine + r)
        cols.append(n_dofs + r)
        vals.append(1.0)
    b = sp.csr_matrix((vals, (rows, cols)), shape=(n_fine + 3, n_dofs + 3))
    inv_mass = rng.uniform(0.5, 2.0, n_dofs + 3)
    return b, inv_mass


def test_factor_rows_splits_isolated_rows_and_shared_dofs():
    from arlequin.linalg.factor import IsolatedRowsSolver, LowRankSplitSolver, factor_rows

    b, inv_mass = _fine_mediator_rows(n_coarse=6, ratio=64)
    s = (b @ sp.diags(inv_mass) @ b.T).toarray()
    solver = factor_rows(b, inv_mass, "test rows")
    # the three single-dof rows are divisions, the coarse dofs (shared by 64 rows) go to U
    assert isinstance(solver, IsolatedRowsSolver)
    assert solver.isolated.tolist() == [b.shape[0] - 3, b.shape[0] - 2, b.shape[0] - 1]
    assert isinstance(solver.rest_solver, LowRankSplitSolver)
    assert solver.rest_solver.n_heavy == 7
    rng = np.random.default_rng(2)
    for rhs in (rng.standard_normal(b.shape[0]), rng.standard_normal((b.shape[0], 4))):
        # exact up to round-off: the dense solve of B M⁻¹ Bᵀ (condition number about 1e3)
        assert np.allclose(solver.solve(rhs), np.linalg.solve(s, rhs), rtol=1e-10, atol=1e-12)
    # a right-hand side on the isolated rows alone: x = r / S_ii there, zero elsewhere
    rhs = np.zeros(b.shape[0])
    rhs[-2] = 3.0
    x = solver.solve(rhs)
    assert x[-2] == 3.0 / s[-2, -2] and not np.any(x[:-2]) and x[-1] == 0.0


def test_factor_rows_without_shared_dofs_is_one_lu():
    from arlequin.linalg.factor import factor_rows

    b, inv_mass = _fine_mediator_rows(n_coarse=6, ratio=2)  # coarse dofs in 2-3 rows: light
    solver = factor_rows(b[:-3], inv_mass, "test rows")
    assert isinstance(solver, ScaledLU)
    s = (b[:-3] @ sp.diags(inv_mass) @ b[:-3].T).toarray()
    rhs = np.random.default_rng(3).standard_normal(s.shape[0])
    assert np.allclose(solver.solve(rhs), np.linalg.solve(s, rhs), rtol=1e-12, atol=0)


def test_factor_rows_names_dependent_rows():
    from arlequin.linalg.factor import factor_rows

    b, inv_mass = _fine_mediator_rows(n_coarse=4, ratio=64)
    b = sp.vstack([b, b[10]]).tocsr()  # row 10 twice: the split's A is singular, then S
    with pytest.raises(ConstraintError, match="linearly dependent"):
        factor_rows(b, inv_mass, "test rows", names=lambda i: f"row {i}")


def _pivot_basis_rows(n_groups: int, n_rows: int, n_shared: int, seed: int = 0):
    """Rows [I | P] in groups: row i of a group has a dof of its own and touches 2-4 of the
    group's ``n_shared`` dofs (the interpolation of a coarse field), the groups apart."""
    rng = np.random.default_rng(seed)
    blocks = []
    for _ in range(n_groups):
        p = np.zeros((n_rows, n_shared))
        for i in range(n_rows):
            cols = rng.choice(n_shared, size=rng.integers(2, 5), replace=False)
            p[i, cols] = -rng.uniform(0.1, 1.0, cols.size)
        blocks.append(np.hstack([np.eye(n_rows), p]))
    b = sp.block_diag(blocks, format="csr")
    inv_mass = rng.uniform(0.5, 2.0, b.shape[1])
    return b, inv_mass


@pytest.mark.parametrize("n_groups,n_shared", [(1, 12), (3, 12), (4, 40)])
def test_factor_rows_diagonal_plus_low_rank(n_groups, n_shared):
    from arlequin.linalg.factor import DiagonalLowRankSolver, factor_rows

    b, inv_mass = _pivot_basis_rows(n_groups, n_rows=60, n_shared=n_shared)
    solver = factor_rows(b, inv_mass, "test rows")
    # the shared dofs of more than one row go to U (a random one may have a single row)
    counts = np.diff(b.tocsc().indptr)
    assert isinstance(solver, DiagonalLowRankSolver) and solver.k == int((counts > 1).sum())
    # groups of rows apart make C block diagonal: one factor a group (dense at these sizes)
    assert len(solver._groups) == n_groups and all(dense for *_, dense in solver._groups)
    s = (b @ sp.diags(inv_mass) @ b.T).toarray()
    rng = np.random.default_rng(4)
    for rhs in (rng.standard_normal(b.shape[0]), rng.standard_normal((b.shape[0], 3))):
        # Woodbury is exact: the dense solve to round-off (C's eigenvalues are at least 1)
        assert np.allclose(solver.solve(rhs), np.linalg.solve(s, rhs), rtol=1e-12, atol=1e-14)


def test_factor_rows_diagonal_path_needs_a_private_dof_in_every_row():
    from arlequin.linalg.factor import DiagonalLowRankSolver, factor_rows

    b, inv_mass = _pivot_basis_rows(1, n_rows=40, n_shared=10)
    # two rows share their own dofs: no longer private, the other paths take the rows
    b = b.tolil()
    b[1, 0] = 0.5
    b[0, 1] = 0.5
    b = b.tocsr()
    solver = factor_rows(b, inv_mass, "test rows")
    assert not isinstance(solver, DiagonalLowRankSolver)
    s = (b @ sp.diags(inv_mass) @ b.T).toarray()
    rhs = np.random.default_rng(5).standard_normal(b.shape[0])
    assert np.allclose(solver.solve(rhs), np.linalg.solve(s, rhs), rtol=1e-11, atol=1e-13)


def test_diagonal_low_rank_groups_beyond_the_dense_size_are_sparse():
    from arlequin.linalg import factor

    b, inv_mass = _pivot_basis_rows(2, n_rows=800, n_shared=350)
    solver = factor.factor_rows(b, inv_mass, "test rows")
    assert [dense for *_, dense in solver._groups] == [False, False]  # 350 > 300 shared dofs
    s = (b @ sp.diags(inv_mass) @ b.T).toarray()
    rhs = np.random.default_rng(6).standard_normal(b.shape[0])
    assert np.allclose(solver.solve(rhs), np.linalg.solve(s, rhs), rtol=1e-11, atol=1e-13)


@pytest.mark.parametrize("touch", ["decoupled", "coupled", "none"])
def test_impulse_solver_schur_paths_against_the_dense_system(touch):
    # equality rows in their pivot basis plus single-dof rows, active rows touching the
    # single-dof rows' dofs (decoupled in S_EE: divisions), a band's dofs (coupled: the
    # general Schur path) or neither: the impulses of the whole system solved dense
    from types import SimpleNamespace

    from arlequin.linalg.impulses import ImpulseSolver

    b, inv_mass = _pivot_basis_rows(1, n_rows=50, n_shared=10)
    n_b = b.shape[1]
    singles = sp.csr_matrix((np.ones(4), (np.arange(4), n_b + np.arange(4))), shape=(4, n_b + 8))
    eq = sp.vstack([sp.hstack([b, sp.csr_matrix((50, 8))]), singles]).tocsr()
    n = eq.shape[1]
    rng = np.random.default_rng(7)
    inv_mass = np.concatenate([inv_mass, rng.uniform(0.5, 2.0, 8)])
    cols = np.unique(eq.indices)
    rows = SimpleNamespace(m=eq.shape[0], matrix=eq, matrix_cols=eq[:, cols].tocsr(), cols=cols,
                           row_name=lambda i: f"row {i}")  # fmt: skip
    solver = ImpulseSolver(rows, inv_mass)
    own = {"decoupled": [n_b, n_b + 1], "coupled": [0, 60], "none": []}[touch]
    g = np.zeros((3, n))
    for i, c in enumerate([n_b + 4, n_b + 5, n_b + 6]):  # dofs of the active rows alone
        g[i, c] = 1.0
    for i, c in enumerate(own):
        g[i, c] = -0.7
    g_a = sp.csr_matrix(g)
    full = sp.vstack([eq, g_a]).toarray()
    s = full @ np.diag(inv_mass) @ full.T
    r_e, r_a = rng.standard_normal(eq.shape[0]), rng.standard_normal(3)
    lam_e, lam_a = solver.solve(r_e, g_a, r_a)
    ref = np.linalg.solve(s, np.concatenate([r_e, r_a]))
    np.testing.assert_allclose(np.concatenate([lam_e, lam_a]), ref, rtol=1e-11, atol=1e-12)
