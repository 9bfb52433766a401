"""The Arlequin Taylor bar built step by step with the public API (the tutorial of
docs/arlequin_taylor.md).

A coarse linear-elastic model of the whole bar, a refined finite-strain J2 patch over the
impacted end glued in a band at its top, the level-set wall on the patch. This is what
``arlequin.demos.run_taylor_bar(model="arlequin")`` builds (the test suite checks that both give
the same run). ``run(**params) -> dict``; ``python examples/arlequin_taylor_bar.py`` prints the
result as JSON (80 µs at 10 fine cells across the radius: about 25 s). SI units.
"""

from __future__ import annotations

import json

import numpy as np
import skfem

import arlequin
from arlequin.models import (
    ContactSurface,
    FiniteStrainJ2,
    J2Material,
    LevelSetContact,
    LinearElastic,
    PlaneObstacle,
    RigidContactPair,
    make_hardening,
)
from arlequin.solvers import CriticalFraction, solve

#: The pictures of this example in the documentation's gallery (paths under docs/).
GALLERY_IMAGES = ["gallery/arlequin_taylor_bar.png", "gallery/arlequin_taylor_bar_history.png"]


def run(fine_radial: int = 10, t_end: float = 80e-6) -> dict:
    """Final length and footprint radius (m) of the bar at ``t_end`` (s), ``fine_radial`` patch
    cells across the radius (even: the coarse cells are twice as large)."""
    if fine_radial < 2 or fine_radial % 2:
        raise ValueError(f"fine_radial must be an even number >= 2, got {fine_radial}")
    L, R, v0 = 32.4e-3, 3.2e-3, 227.0
    law = make_hardening("linear", yield_stress=0.4e9, modulus=0.1e9)
    copper = J2Material.with_law(117e9, 0.35, 8930.0, law)
    # 1. the coarse model of the whole structure: nearly square elastic cells, twice the fine size
    n_rc = fine_radial // 2
    n_zc = round(L / (R / n_rc))
    coarse_mesh = skfem.MeshQuad.init_tensor(np.linspace(0, R, n_rc + 1),
                                             np.linspace(0, L, n_zc + 1))  # fmt: skip
    coarse = LinearElastic(coarse_mesh, copper.elastic, kind="axisymmetric")
    # 2. the patch over 90% of the bar, on whole coarse rows: each coarse cell split in 2 x 2
    rows = round(0.9 * n_zc)
    z_patch = rows * L / n_zc
    fine_mesh = skfem.MeshQuad.init_tensor(np.linspace(0, R, 2 * n_rc + 1),
                                           np.linspace(0, z_patch, 2 * rows + 1))  # fmt: skip
    fine = FiniteStrainJ2(fine_mesh, copper, "axisymmetric")
    # 3. glued in a band of two coarse rows at the patch's top, the weights ramped across it;
    #    both models and the mediator space keep u_r = 0 on the axis
    band = 2 * L / n_zc
    patch = arlequin.Patch(fine, gluing_width=band, weights="ramp", mediator="fine",
                           coupling="H1", overlap_method="nested", name="patch")  # fmt: skip
    problem = arlequin.ArlequinProblem(coarse, [patch], mediator_dirichlet="drop")
    for block in ("coarse", "patch"):
        problem.add_dirichlet(block, lambda x: x[0] < 1e-9 * R, components=[0])
    system = problem.system()
    dofs = system.dofmap
    # 4. the rigid wall z = 0 on the patch's impact face and lower lateral surface
    lateral = min(0.3 * L, z_patch - band)
    surface = ContactSurface(
        fine_mesh,
        where=lambda x: (x[1] < 1e-9 * R) | ((x[0] > R * (1 - 1e-9)) & (x[1] < lateral)),
        offset=dofs["patch"],
        axisymmetric=True,
    )
    plane = PlaneObstacle(np.zeros(2), np.array([0.0, 1.0]))
    wall = LevelSetContact(RigidContactPair(surface, plane, dofs), material=copper.elastic,
                           name="wall")  # fmt: skip
    # 5. everything moves at −v0; central differences at 0.8 of the critical step, re-estimated
    #    every 10 steps from the current configuration; records every 0.5 µs
    v = np.zeros(dofs.n_dofs)
    for block in ("coarse", "patch"):
        v[dofs[block].component_dofs(1)] = -v0
    t_eval = np.linspace(0.0, t_end, max(1, round(t_end / 0.5e-6)) + 1)[1:]
    result = solve(system, "explicit", t_end=t_end, v0=v, constraints=[wall],
                   step_controller=CriticalFraction(0.8, 10), t_eval=t_eval)  # fmt: skip
    uc, uf = result.u[dofs["coarse"].slice], result.u[dofs["patch"].slice]
    top = int(np.argmax(coarse_mesh.p[1] - coarse_mesh.p[0]))  # the node (0, L)
    face = np.nonzero(fine_mesh.p[1] < 1e-9 * R)[0]
    return {
        "final_length": float(L + uc[2 * top + 1]),
        "mushroom_radius": float((fine_mesh.p[0, face] + uf[2 * face]).max()),
        "max_plastic_strain": float(result.states["patch"][0].eqps.max()),
        "n_steps": int(result.n_steps),
    }


if __name__ == "__main__":
    print(json.dumps(run(), indent=2))
