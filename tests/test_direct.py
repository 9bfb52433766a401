"""The sparse direct solvers of the Newton systems (arlequin.linalg.direct): SuperLU always,
PARDISO where the optional pypardiso is installed, checked on the saddle point of a small
Arlequin problem (a coarse plate and a glued patch: symmetric indefinite, with multipliers)
against a dense solve (exact up to round-off), and their errors."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import skfem

from arlequin import ArlequinProblem, Patch, refine_region, solve_quasi_static
from arlequin.linalg import direct
from arlequin.linalg.direct import SparseDirectSolver, resolve_linear_solver
from arlequin.models import IsotropicElastic, LinearElastic
from arlequin.solvers import QuasiStaticSolver

STEEL = IsotropicElastic(young=210e9, poisson=0.3, density=7850.0)


def _problem():
    cm = skfem.MeshQuad.init_tensor(np.linspace(0, 2, 9), np.linspace(0, 1, 5))
    fm = refine_region(cm, levels=1, box=((1.0, 0.0), (2.0, 1.0)))
    problem = ArlequinProblem(
        LinearElastic(cm, STEEL, "plane_strain"),
        [Patch(LinearElastic(fm, STEEL, "plane_strain"), gluing_width=0.25)],
    )
    problem.add_dirichlet("coarse", lambda x: np.isclose(x[0], 0.0))
    problem.add_traction([1e8, 0.0], where=lambda x: np.isclose(x[0], 2.0))
    return problem


def _saddle_point(scale: float = 1.0) -> sp.csc_matrix:
    """The coupled saddle point [[K, Bᵀ], [B, 0]] of the quasi-static solver (Dirichlet dofs
    eliminated, rows scaled to the stiffness); ``scale`` multiplies K (same pattern)."""
    solver = QuasiStaticSolver(_problem(), condense=False, linear_solver="superlu")
    sad = solver.saddle
    k = solver.ops.initial_stiffness()[sad.free][:, sad.free]
    return sp.bmat([[scale * k, sad._bf.T], [sad._bf, None]], format="csc")


def _check_against_dense(solver: SparseDirectSolver, mat: sp.csc_matrix) -> np.ndarray:
    rng = np.random.default_rng(0)
    rhs = rng.standard_normal((mat.shape[0], 2))
    exact = np.linalg.solve(mat.toarray(), rhs)  # dense LU with partial pivoting
    x = solver.factor(mat).solve(rhs)
    assert x.shape == rhs.shape
    assert np.linalg.norm(x - exact) <= 1e-10 * np.linalg.norm(exact)
    x1 = solver.factor(mat).solve(rhs[:, 0])
    assert np.linalg.norm(x1 - exact[:, 0]) <= 1e-10 * np.linalg.norm(exact[:, 0])
    return x


def test_superlu_solves_the_saddle_point():
    mat = _saddle_point()
    assert mat.shape[0] > 200 and np.count_nonzero(mat.diagonal() == 0.0) > 10  # multipliers
    solver = SparseDirectSolver("superlu")
    _check_against_dense(solver, mat)
    assert solver.name == "superlu" and solver.factorisations == 2
    assert solver.timings["factorisation_s"] > 0.0 and solver.timings["solve_s"] > 0.0


def test_pardiso_agrees_with_superlu_and_keeps_its_analysis():
    pytest.importorskip("pypardiso")
    solver = SparseDirectSolver("pardiso")
    x = _check_against_dense(solver, _saddle_point())
    y = _check_against_dense(SparseDirectSolver("superlu"), _saddle_point())
    assert np.linalg.norm(x - y) <= 1e-10 * np.linalg.norm(y)
    # new values on the same pattern (a new Newton tangent): no new symbolic analysis
    _check_against_dense(solver, _saddle_point(scale=3.0))
    assert (solver.analyses, solver.factorisations) == (1, 4)
    solver.renew_analysis()  # as at each load step: the next factor analyses again
    _check_against_dense(solver, _saddle_point(scale=2.0))
    assert (solver.analyses, solver.factorisations) == (2, 6)
    assert resolve_linear_solver("auto") == "pardiso"


def test_a_singular_matrix_raises_linalgerror():
    mat = _saddle_point().tolil()
    mat[:, 0] = 0.0  # a dof with neither stiffness nor constraint: a mechanism
    mat[0, 1] = 1.0  # its row kept non-empty (an empty row is another error)
    mat = mat.tocsc()
    backends = ["superlu"] + (["pardiso"] if direct.pardiso_available() else [])
    for name in backends:
        with pytest.raises(np.linalg.LinAlgError):
            SparseDirectSolver(name).factor(mat).solve(np.ones(mat.shape[0]))


def test_a_replaced_factor_is_refused():
    solver = SparseDirectSolver("superlu")
    first = solver.factor(_saddle_point())
    solver.factor(_saddle_point(scale=2.0))
    with pytest.raises(RuntimeError, match="replaced"):
        first.solve(np.ones(first._handle[0].shape[0]))


def test_bad_names_are_named(monkeypatch):
    with pytest.raises(ValueError, match=r"linear_solver.*'umfpack'"):
        resolve_linear_solver("umfpack")
    with pytest.raises(ValueError, match=r"linear_solver.*'mumps'"):
        solve_quasi_static(_problem(), linear_solver="mumps")
    monkeypatch.setattr(direct, "pardiso_available", lambda: False)
    with pytest.raises(ValueError, match=r"linear_solver='pardiso'.*pypardiso"):
        SparseDirectSolver("pardiso")
    assert resolve_linear_solver("auto") == "superlu"


def test_the_quasi_static_result_records_its_solver_and_timings():
    res = solve_quasi_static(_problem(), steps=2, linear_solver="superlu")
    assert res.linear_solver == "superlu"
    assert set(res.timings) == {"constitutive_and_tangent_s", "factorisation_s", "solve_s",
                                "other_s"}  # fmt: skip
    assert all(v >= 0.0 for v in res.timings.values())
    assert res.timings["factorisation_s"] > 0.0
    if direct.pardiso_available():
        other = solve_quasi_static(_problem(), steps=2, linear_solver="pardiso")
        assert other.linear_solver == "pardiso"
        assert np.linalg.norm(other.u - res.u) <= 1e-10 * np.linalg.norm(res.u)
