"""A coarse plane-strain plate with a refined patch at one end, under uniform tension.

The user guide's example (docs/user-guide.md). ``run(**params) -> dict`` so that the test suite runs
it; ``python examples/refined_patch.py`` prints the result as JSON.
"""

from __future__ import annotations

import json

import numpy as np
import skfem

import arlequin
from arlequin.models import IsotropicElastic, LinearElastic


def run(n: int = 8, levels: int = 2, traction: float = 1.0e6, coupling: str = "H1") -> dict:
    """Plate [0, 2] x [0, 1] m, patch on x > 1 refined ``levels`` times, traction (Pa) at x = 2."""
    steel = IsotropicElastic(young=210e9, poisson=0.3, density=7850.0)
    coarse_mesh = skfem.MeshQuad.init_tensor(np.linspace(0, 2, 2 * n + 1), np.linspace(0, 1, n + 1))
    patch_mesh = arlequin.refine_region(coarse_mesh, levels=levels, box=((1.0, 0.0), (2.0, 1.0)))
    coarse = LinearElastic(coarse_mesh, steel, kind="plane_strain")
    fine = LinearElastic(patch_mesh, steel, kind="plane_strain")
    patch = arlequin.Patch(fine, gluing_width=0.25, weights="ramp", coupling=coupling)
    problem = arlequin.ArlequinProblem(coarse, [patch])
    problem.add_dirichlet("coarse", where=lambda x: np.isclose(x[0], 0.0), components=[0])
    problem.add_dirichlet("coarse", where=lambda x: np.isclose(x[0], 0.0) & np.isclose(x[1], 0.0))
    problem.add_traction([traction, 0.0], where=lambda x: np.isclose(x[0], 2.0))
    result = arlequin.solve_static(problem)
    tip = arlequin.evaluate_field(patch_mesh, result.displacements["patch0"], [2.0, 0.5], 2)
    # plane strain, uniaxial stress σ_xx = t with ε_zz = 0: u_x(2) = 2 t (1 − ν²) / E
    exact = 2.0 * traction * (1 - steel.poisson**2) / steel.young
    return {
        "tip_displacement": float(tip[0, 0]),
        "exact_tip_displacement": exact,
        "relative_error": float(abs(tip[0, 0] - exact) / exact),
        "strain_energy": result.strain_energy,
        "residual": result.residual,
    }


if __name__ == "__main__":
    print(json.dumps(run(), indent=2))
