"""The iterative static solve (issue 43): GMRES with an augmented-Lagrangian smoothed-aggregation
multigrid preconditioner (``solve_static(..., linear_solver="amg")``) against SuperLU.

Expected values: both solve the same saddle point, the iterative one to a true relative residual
of 1e-10 (measured 5e-13 to 1e-11), so the displacements and multipliers agree to the issue's
1e-8 (measured 5e-13 to 6e-12 on these configurations).
"""

from __future__ import annotations

import numpy as np
import pytest

from arlequin import LinearSolverError, solve_static
from arlequin.demos.patch_test import build_patch_test_problem


def _relative(a, b) -> float:
    return float(np.linalg.norm(a - b) / max(np.linalg.norm(b), 1e-300))


def _agree(problem):
    direct = solve_static(problem, linear_solver="superlu")
    iterative = solve_static(problem, linear_solver="amg")
    assert direct.linear_solver == "superlu" and iterative.linear_solver == "amg"
    assert iterative.krylov.residual <= 1e-10
    assert _relative(iterative.u, direct.u) <= 1e-8
    for name, lam in direct.multipliers.items():
        assert _relative(iterative.multipliers[name], lam) <= 1e-8, name
    return direct, iterative


@pytest.mark.parametrize("mediator", ["coarse", "fine"])
def test_nested_2d_patch_test_agrees(mediator):
    problem, exact = build_patch_test_problem(dim="2", coupling="H1", mediator=mediator)
    _, iterative = _agree(problem)
    # and it is the uniform state
    mesh = problem.coarse.mesh
    u = iterative.displacements["coarse"]
    ref = np.asarray(exact(mesh.p)).T.ravel()
    assert np.max(np.abs(u - ref)) <= 1e-9 * np.max(np.abs(ref))


def test_nonnested_triangle_patch_agrees():
    problem, _ = build_patch_test_problem(dim="2", coupling="L2", mediator="fine", mesh="nonnested")
    assert problem.patches[0].model.mesh.t.shape[0] == 3  # triangles
    _agree(problem)


def test_nested_3d_patch_agrees():
    _agree(build_patch_test_problem(dim="3", coupling="H1", mediator="coarse")[0])


def test_axisymmetric_patch_agrees():
    _agree(build_patch_test_problem(dim="axi", coupling="L2", mediator="fine")[0])


def test_patch_without_support_of_its_own_agrees():
    # an interior square patch, glued all around: every Dirichlet row is on the coarse model,
    # the patch's stiffness alone is singular (held only by the mediator rows)
    problem, _ = build_patch_test_problem(dim="2", layout="square", ratio=2, mediator="fine")
    system = problem.system()
    patch = next(b for b in system.blocks if b.name != "coarse")
    for c in system.constraints:
        if c.kind == "dirichlet":
            assert c.matrix.tocsc()[:, patch.dofs].nnz == 0
    _agree(problem)


def test_mesh_ratio_8_agrees():
    problem, _ = build_patch_test_problem(dim="2", layout="strip", ratio=8, mediator="coarse")

    def spacing(mesh):
        return np.min(np.diff(np.unique(np.round(mesh.p[0], 12))))

    ratio = spacing(problem.coarse.mesh) / spacing(problem.patches[0].model.mesh)
    assert ratio == pytest.approx(8.0)  # three levels of refinement
    _agree(problem)


def test_unconverged_solve_raises_naming_the_residual():
    problem, _ = build_patch_test_problem(dim="2", mediator="fine")
    with pytest.raises(LinearSolverError, match=r"relative residual .* after 2 iteration"):
        solve_static(problem, linear_solver="amg", linear_solver_options={"maxiter": 2})


def test_bad_solver_name_and_options_are_refused():
    problem, _ = build_patch_test_problem(dim="2")
    with pytest.raises(ValueError, match=r"linear_solver must be one of \('auto', 'superlu'"):
        solve_static(problem, linear_solver="cg")
    with pytest.raises(ValueError, match="unknown option"):
        solve_static(problem, linear_solver="amg", linear_solver_options={"tol": 1e-8})


def test_auto_keeps_the_direct_solver_on_small_systems():
    problem, _ = build_patch_test_problem(dim="3")
    assert solve_static(problem).linear_solver == "superlu"


def test_auto_switches_above_the_thresholds_in_3d_only(monkeypatch):
    from arlequin.solvers.statics import static

    coupled = build_patch_test_problem(dim="3")[0]
    n = solve_static(coupled).saddle_point.matrix.shape[0]
    monkeypatch.setattr(static, "AMG_MIN_UNKNOWNS", 1)
    assert solve_static(coupled).linear_solver == "superlu"  # multipliers: the other threshold
    monkeypatch.setattr(static, "AMG_MIN_UNKNOWNS_COUPLED", n)
    assert solve_static(coupled).linear_solver == "amg"
    monkeypatch.setattr(static, "AMG_MIN_UNKNOWNS_COUPLED", 1)
    assert solve_static(build_patch_test_problem(dim="2")[0]).linear_solver == "superlu"
