"""The 3D Arlequin Taylor bar built with the public API, its patch region a closed surface (the
tutorial of docs/taylor_3d.md).

A coarse linear-elastic quarter bar of hexahedra (x, y ≥ 0, symmetry conditions on x = 0 and
y = 0), a refined finite-strain J2 patch on the coarse cells inside a closed triangulated surface
(here a trimesh box around the impacted end; any watertight STL/OBJ/PLY works), glued in a band
at the patch's top, the level-set wall on the patch. This is what
``arlequin.demos.run_taylor_bar(model="arlequin", geometry="3d", patch_surface=...)`` builds
(the test suite checks that both give the same run). ``run(**params) -> dict``;
``python examples/taylor_bar_3d.py`` prints the result as JSON. SI units.
"""

from __future__ import annotations

import json

import numpy as np
import trimesh

import arlequin
from arlequin.coupling.patches import select_cells
from arlequin.demos.taylor_bar.meshes_3d import quarter_bar_mesh, refined_bar_mesh
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

L, R, V0 = 32.4e-3, 3.2e-3, 227.0


def patch_box(height: float) -> trimesh.Trimesh:
    """A closed box around the quarter bar's end z ∈ [0, height] (m), wider than the bar."""
    box = trimesh.creation.box(extents=(4 * R, 4 * R, 2 * height))  # centred on the origin
    return box


def run(fine_radial: int = 8, t_end: float = 80e-6, surface=None) -> dict:
    """Final length and footprint radius (m) at ``t_end`` (s); ``fine_radial`` patch cells
    across the radius (even, ≥ 8: the coarse O-grid has half as many, at least 4);
    ``surface`` the patch region (default :func:`patch_box` of 0.9 L)."""
    if fine_radial < 8 or fine_radial % 2:
        raise ValueError(f"fine_radial must be an even number >= 8, got {fine_radial}")
    law = make_hardening("linear", yield_stress=0.4e9, modulus=0.1e9)
    copper = J2Material.with_law(117e9, 0.35, 8930.0, law)
    # 1. the coarse quarter bar: an O-grid of hexahedra, cells about twice the fine size
    #    (any hexahedral mesh works, e.g. arlequin.io.read_mesh("bar.msh"))
    n_c = fine_radial // 2
    n_z = round(L / (R / n_c))
    coarse_mesh = quarter_bar_mesh(L, R, n_c, n_z)
    coarse = LinearElastic(coarse_mesh, copper.elastic, kind="3d")
    # 2. the patch: the coarse cells inside the surface, each split into 8, the new nodes of
    #    the lateral surface moved onto the cylinder (Patch.from_surface does the same without
    #    that move, for straight-sided bodies)
    rows = round(0.9 * n_z)
    cells = select_cells(coarse_mesh, surface=surface or patch_box(rows * L / n_z))
    fine_mesh = refined_bar_mesh(coarse_mesh.restrict(cells), R, levels=1)
    fine = FiniteStrainJ2(fine_mesh, copper, "3d")
    # 3. glued in a band of two coarse layers at the patch's top, the weights ramped across it;
    #    the symmetry conditions on both models (and not in the mediator space)
    band = 2 * L / n_z
    patch = arlequin.Patch(fine, gluing_width=band, weights="ramp", mediator="fine",
                           coupling="H1", overlap_method="nested", name="patch")  # fmt: skip
    problem = arlequin.ArlequinProblem(coarse, [patch], mediator_dirichlet="drop")
    for block in ("coarse", "patch"):
        problem.add_dirichlet(block, lambda x: np.abs(x[0]) < 1e-9 * R, components=[0])
        problem.add_dirichlet(block, lambda x: np.abs(x[1]) < 1e-9 * R, components=[1])
    system = problem.system()
    dofs = system.dofmap
    # 4. the rigid wall z = 0 on the patch's impact face and lower lateral surface (the facet
    #    midpoints of the lateral surface lie a chord's sagitta inside r = R)
    z_out = coarse_mesh.p[2, np.delete(coarse_mesh.t, cells, axis=1)].min()
    lateral = min(0.3 * L, z_out - band)
    h_min = float(np.min(np.linalg.norm(np.diff(fine_mesh.p[:, fine_mesh.facets[:2]], axis=1),
                                        axis=0)))  # fmt: skip

    def on_wall_side(x):
        return (x[2] < 1e-9 * R) | ((np.hypot(x[0], x[1]) > R - 0.25 * h_min) & (x[2] < lateral))

    surface_fine = ContactSurface(fine_mesh, where=on_wall_side, offset=dofs["patch"])
    plane = PlaneObstacle(np.zeros(3), np.array([0.0, 0.0, 1.0]))
    wall = LevelSetContact(RigidContactPair(surface_fine, plane, dofs), material=copper.elastic,
                           name="wall")  # fmt: skip
    # 5. everything moves at −v0 along z; central differences at 0.8 of the critical step,
    #    re-estimated every 10 steps; records every 0.5 µs
    v = np.zeros(dofs.n_dofs)
    for block in ("coarse", "patch"):
        v[dofs[block].component_dofs(2)] = -V0
    t_eval = np.linspace(0.0, t_end, max(1, round(t_end / 0.5e-6)) + 1)[1:]
    result = solve(system, "explicit", t_end=t_end, v0=v, constraints=[wall],
                   step_controller=CriticalFraction(0.8, 10), t_eval=t_eval)  # fmt: skip
    uc = result.u[dofs["coarse"].slice].reshape(-1, 3).T
    uf = result.u[dofs["patch"].slice].reshape(-1, 3).T
    p = coarse_mesh.p
    top = int(np.nonzero((np.hypot(p[0], p[1]) < 1e-9 * R) & (p[2] > L * (1 - 1e-9)))[0][0])
    face = np.nonzero(fine_mesh.p[2] < 1e-9 * R)[0]
    x_face = fine_mesh.p[:, face] + uf[:, face]
    return {
        "final_length": float(L + uc[2, top]),
        "mushroom_radius": float(np.hypot(x_face[0], x_face[1]).max()),
        "max_plastic_strain": float(result.states["patch"][0].eqps.max()),
        "n_steps": int(result.n_steps),
        "coarse_elements": int(coarse_mesh.nelements),
        "fine_elements": int(fine_mesh.nelements),
    }


if __name__ == "__main__":
    print(json.dumps(run(), indent=2))
