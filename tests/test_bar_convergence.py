"""1D bar under a body load with a refined patch (issue 2, item 3).

−(E A u')' = A f on (0, 1), u(0) = u(1) = 0, f(x) = f0 sin(πx): exact u = f0 sin(πx) / (E π²).
The exact fields, with λ = E u' α_c' on the gluing band, solve the continuous Arlequin problem
(same material on both models), so the fine model's error on the patch's free zone converges at
the P1 rates: 2 in L2 and 1 in the H1 seminorm (the issue's bounds 2 ± 0.1 and 1 ± 0.1). Both
meshes are refined together at the fixed ratio 4 (nested patch, 2 refinement levels), ramp
weights, coarse mediator.
"""

from __future__ import annotations

import numpy as np
import pytest
import skfem

from arlequin.coupling.patches import refine_region
from arlequin.models import IsotropicElastic, LinearElastic
from arlequin.problem.arlequin_problem import ArlequinProblem, Patch
from arlequin.solvers.statics.static import solve_static

E, F0 = 1.0e9, 1.0e6


def exact(x):
    return F0 * np.sin(np.pi * x) / (E * np.pi**2)


def exact_grad(x):
    return F0 * np.cos(np.pi * x) / (E * np.pi)


def free_zone_errors(n_coarse: int, coupling: str) -> tuple[float, float]:
    coarse_mesh = skfem.MeshLine(np.linspace(0.0, 1.0, n_coarse + 1))
    fine_mesh = refine_region(coarse_mesh, levels=2, box=((0.3,), (0.7,)))
    material = IsotropicElastic(young=E, poisson=0.0, density=1.0)
    coarse = LinearElastic(coarse_mesh, material, "1d", area=1.0)
    fine = LinearElastic(fine_mesh, material, "1d", area=1.0)
    problem = ArlequinProblem(
        coarse,
        [Patch(fine, gluing_width=0.1, weights="ramp", coupling=coupling, mediator="coarse")],
    )
    problem.add_body_force(lambda x: F0 * np.sin(np.pi * x))
    problem.add_dirichlet("coarse", lambda x: (x[0] < 1e-12) | (x[0] > 1 - 1e-12))
    result = solve_static(problem)
    pc = problem.couplings[0]
    # free zone: fine cells beyond the gluing band
    centroids = fine_mesh.p[:, fine_mesh.t].mean(axis=1)
    free = np.nonzero(pc.distance(centroids) > pc.gluing_width)[0]
    basis = skfem.Basis(fine_mesh, skfem.ElementLineP1(), elements=free, intorder=6)
    uh = basis.interpolate(result.displacements[pc.name])
    x = np.asarray(basis.global_coordinates())[0]
    l2 = np.sqrt(np.sum((np.asarray(uh) - exact(x)) ** 2 * basis.dx))
    h1 = np.sqrt(np.sum((np.asarray(uh.grad)[0] - exact_grad(x)) ** 2 * basis.dx))
    return l2, h1


@pytest.mark.parametrize("coupling", ["L2", "H1"])
def test_free_zone_error_converges_at_p1_rates(coupling):
    ns = np.array([10, 20, 40, 80, 160])
    errs = np.array([free_zone_errors(int(n), coupling) for n in ns])
    h = 1.0 / ns
    slope_l2 = np.polyfit(np.log(h), np.log(errs[:, 0]), 1)[0]
    slope_h1 = np.polyfit(np.log(h), np.log(errs[:, 1]), 1)[0]
    assert slope_l2 == pytest.approx(2.0, abs=0.1), errs
    assert slope_h1 == pytest.approx(1.0, abs=0.1), errs
