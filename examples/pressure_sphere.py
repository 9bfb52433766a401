"""A thick sphere under internal pressure, built step by step with the public API (the
tutorial of docs/quasi_static.md).

A coarse linear-elastic model of the whole wall (the meridional quarter of the sphere,
axisymmetric) and a refined small-strain J2 patch from the bore to 185 mm, glued by a coarse
mediator in the patch's outermost coarse ring; the pressure raised to 300 MPa in 10 load steps,
each solved by Newton with the consistent tangents (:func:`arlequin.solve_quasi_static`).
Against Hill's solution: the plastic front c and the outer displacement u_b. This is what
``arlequin pressure-vessel`` builds (the test suite checks that both give the same numbers).
``run(**params) -> dict``; ``python examples/pressure_sphere.py`` prints the comparison (about
10 s). SI units.
"""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import skfem

import arlequin
from arlequin.demos.pressure_vessel import hill
from arlequin.demos.pressure_vessel.meshes import refine_projected
from arlequin.models import IsotropicElastic, J2Material, LinearElastic, SmallStrainJ2


def quarter_annulus(a: float, b: float, n_radial: int, n_angular: int) -> skfem.MeshQuad:
    """The meridional quarter a ≤ ρ ≤ b, 0 ≤ θ ≤ π/2 as a polar grid of quadrilaterals
    (x = r the distance from the axis, y = z along it)."""
    grid = skfem.MeshQuad.init_tensor(np.linspace(a, b, n_radial + 1),
                                      np.linspace(0.0, 0.5 * math.pi, n_angular + 1))  # fmt: skip
    rho, theta = grid.p
    p = np.vstack([rho * np.cos(theta), rho * np.sin(theta)])
    p[np.abs(p) < 1e-12 * b] = 0.0  # the axis and the equator exactly at zero
    return skfem.MeshQuad(p, grid.t)


def run(a: float = 0.1, b: float = 0.2, pressure: float = 300e6, steps: int = 10,
        coarse_cells: int = 8, levels: int = 3, patch_rings: int = 7) -> dict:  # fmt: skip
    """Build and solve the sphere; return c and u_b at the final pressure with Hill's."""
    young, poisson, yield_stress = 210e9, 0.3, 240e6
    # 1. the coarse mesh: coarse_cells rings, cells about as long as wide at the mean radius
    ring = (b - a) / coarse_cells
    coarse_mesh = quarter_annulus(a, b, coarse_cells, round(0.25 * math.pi * (a + b) / ring))
    # 2. the patch: the inner rings refined `levels` times, its bore nodes on the circle
    centres = np.linalg.norm(coarse_mesh.p[:, coarse_mesh.t].mean(axis=1), axis=0)
    patch_mesh = refine_projected(
        coarse_mesh, levels, (a,), np.nonzero(centres < a + patch_rings * ring)[0]
    )
    # 3. the models: the coarse one elastic, the patch small-strain J2 (B-bar: no locking)
    coarse = LinearElastic(coarse_mesh, IsotropicElastic(young, poisson, 7850.0), "axisymmetric")
    steel = J2Material(young, poisson, 7850.0, yield_stress)
    patch = SmallStrainJ2(patch_mesh, steel, "axisymmetric", bbar=True)
    # 4. the Arlequin problem: glued in the patch's outermost coarse ring (a curved band: the
    # coarse mediator is not exact for a uniform stress there, which this problem is not)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", arlequin.ExactnessWarning)
        problem = arlequin.ArlequinProblem(
            coarse, [arlequin.Patch(patch, gluing_width=ring, overlap_method="nested")]
        )
        problem.couplings  # noqa: B018  (built here, under the filter)
    # 5. symmetry: u_r = 0 on the axis, u_z = 0 on the equator, on both models
    for block in ("coarse", "patch0"):
        problem.add_dirichlet(block, lambda x: np.isclose(x[0], 0.0, atol=1e-12 * b), [0])
        problem.add_dirichlet(block, lambda x: np.isclose(x[1], 0.0, atol=1e-12 * b), [1])
    # 6. the pressure on the bore, −P n (the load at load factor 1)
    problem.add_traction(lambda x, n: -pressure * n,
                         where=lambda x: np.linalg.norm(x, axis=0) <= a * (1 + 1e-9))  # fmt: skip
    # 7. load steps, Newton in each
    result = arlequin.solve_quasi_static(problem, load=1.0, steps=steps)
    # 8. the answers: u_b at the node (b, 0) of the coarse model; c from the patch's ε̄p
    u = result.displacements
    outer = int(np.argmin(np.linalg.norm(coarse_mesh.p - np.array([[b], [0.0]]), axis=0)))
    state = result.states["patch0"][0]
    radius = np.linalg.norm(patch.quadrature_points(), axis=0)
    plastic = radius[state.eqps > 0.0]
    return {
        "outer_displacement": float(u["coarse"][2 * outer]),
        "outer_displacement_hill": hill.sphere_outer_displacement(
            pressure, a, b, young, poisson, yield_stress
        ),
        "plastic_radius_last_point": float(plastic.max()) if plastic.size else a,
        "plastic_radius_hill": hill.sphere_plastic_radius(pressure, a, b, yield_stress),
        "newton_iterations": result.newton_iterations,
        "status": result.status,
    }


if __name__ == "__main__":
    print(json.dumps(run(), indent=2))
