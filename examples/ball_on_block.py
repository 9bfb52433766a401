"""A steel ball striking a thick steel block, built step by step with the public API (the
tutorial of docs/ball_impact.md).

Two bodies in one problem (:class:`arlequin.MultiBodyProblem`), each a coarse linear-elastic
model of the whole body plus a refined patch at the contact point (nested, its boundary nodes on
the sphere for the ball), glued by the fine mediator in a band at the patch's edge; the
level-set contact between the two patches. With ``plastic=True`` the block is copper and its
patch, larger (0.8 R: the plastic zone), carries finite-strain J2 plasticity while its coarse
model stays elastic. This is what ``arlequin.demos.run_ball_impact(coarse_size=...,
fine_size=...)`` builds (``regime="plastic"`` for the second; the test suite checks that both
give the same runs). ``run(**params) -> dict``; ``python examples/ball_on_block.py`` prints the
peak force and contact duration against Hertz's (about 25 s), ``python
examples/ball_on_block.py plastic`` the plastic impact's dent and restitution. Axisymmetric
(r, z); SI units.
"""

from __future__ import annotations

import json
import math
import sys

import numpy as np
import skfem

import arlequin
from arlequin.models import (
    ContactSurface,
    DeformableContactPair,
    FiniteStrainJ2,
    IsotropicElastic,
    J2Material,
    LevelSetContact,
    LinearElastic,
)
from arlequin.solvers import solve

#: The pictures of this example in the documentation's gallery (paths under docs/).
GALLERY_IMAGES = ["gallery/ball_impact.png"]


def ball_mesh(radius: float, n: int) -> skfem.MeshQuad:
    """The meridional half disk of the ball, centre (0, R): an O-grid of 6 n² quads (an inner
    block and three outer ones blended onto the arc), every boundary node on the sphere."""
    s = 0.45 * radius
    inner = skfem.MeshQuad.init_tensor(np.linspace(0, s, n + 1), np.linspace(-s, s, 2 * n + 1))
    pts, cells = [inner.p], [inner.t]
    line = np.linspace(0.0, 1.0, n + 1)
    edges = [(np.stack([s * line, np.full(n + 1, -s)]), -90.0, -45.0, n),
             (np.stack([np.full(2 * n + 1, s), np.linspace(-s, s, 2 * n + 1)]), -45.0, 45.0, 2 * n),
             (np.stack([s * (1 - line), np.full(n + 1, s)]), 45.0, 90.0, n)]  # fmt: skip
    offset = inner.nvertices
    for edge, t0, t1, k in edges:
        th = np.radians(np.linspace(t0, t1, k + 1))
        arc = radius * np.stack([np.cos(th), np.sin(th)])
        w = np.linspace(0.0, 1.0, n + 1)
        p = (1 - w)[None, :, None] * edge[:, None, :] + w[None, :, None] * arc[:, None, :]
        i, j = np.meshgrid(np.arange(k), np.arange(n), indexing="ij")
        a = (j * (k + 1) + i).ravel()
        pts.append(p.reshape(2, -1))
        cells.append(np.stack([a, a + 1, a + k + 2, a + k + 1]) + offset)
        offset += (k + 1) * (n + 1)
    p, t = np.concatenate(pts, axis=1), np.concatenate(cells, axis=1)
    # merge the nodes the blocks share
    _, first, inverse = np.unique(np.round(p / (1e-9 * radius)).astype(np.int64), axis=1,
                                  return_index=True, return_inverse=True)  # fmt: skip
    p = p[:, first]
    p[1] += radius
    p[0, np.abs(p[0]) < 1e-12 * radius] = 0.0
    return skfem.MeshQuad(np.ascontiguousarray(p), np.ascontiguousarray(inverse.ravel()[t]))


def run(
    n: int = 20,
    levels: int = 2,
    velocity: float | None = None,
    block_size: float | None = None,
    plastic: bool = False,
) -> dict:
    """Peak contact force (N) and contact duration (s) of a steel ball (R = 10 mm) striking a
    block (radius = height = ``block_size``, default 10 R, or 2 R when plastic) at ``velocity``
    (m/s, default 1, or 10 when plastic), with Hertz's values (the elastic steel block) or the
    dent depth (m) and the maximum ε̄p (the copper J2 block); ``n``: the ball's O-grid at the
    coarse size π R/(4 n), ``levels``: the patches' refinements."""
    R = 0.01
    steel = IsotropicElastic(210e9, 0.3, 7850.0)
    # the plastic block: the Taylor bar's copper, σ_y = 0.4 GPa, linear hardening 0.1 GPa
    copper = J2Material(117e9, 0.35, 8930.0, yield_stress=0.4e9, hardening_modulus=0.1e9)
    velocity = (10.0 if plastic else 1.0) if velocity is None else velocity
    block_size = (2 * R if plastic else 10 * R) if block_size is None else block_size
    h_c = 0.25 * math.pi * R / n  # coarse size along the ball's arc
    reach, band = (0.4 if plastic else 0.2) * R, 2 * h_c  # the patches' radius, gluing band
    # the block's patch covers the plastic zone, which reaches beyond the contact radius
    block_reach = min(0.8 * R, 0.5 * block_size) if plastic else reach
    zone = reach - band - h_c  # the contact surfaces: inside the patches, below the bands
    tol = 1e-9 * R

    # 1. the ball: a coarse model of it all, a patch refining the coarse cells near the pole,
    #    its new boundary nodes moved onto the sphere (within the sagitta of a coarse facet)
    def within(radius):
        return lambda x: np.hypot(x[0], x[1]) - radius  # < 0 within radius of the contact point

    ball_coarse = ball_mesh(R, n)
    ball_patch = arlequin.refine_region(ball_coarse, levels, level_set=within(reach))
    p = ball_patch.p.copy()
    d = np.hypot(p[0], p[1] - R)
    edge = np.unique(ball_patch.facets[:, ball_patch.boundary_facets()])
    near = edge[(R - d[edge] < 1.5 * h_c**2 / (8 * R)) & (d[edge] > 0)]
    p[0, near] *= R / d[near]
    p[1, near] = R + (p[1, near] - R) * R / d[near]
    ball_patch = skfem.MeshQuad(p, ball_patch.t)

    # 2. the block: a tensor grid graded away from the contact point, the same kind of patch
    # cells of h_c over the patch, then growing by 15%, the last node on the block's edge
    growth, n_u = 1.15, math.ceil(block_reach / h_c - 1e-9)
    start = n_u * h_c
    k = round(math.log1p((block_size - start) * (growth - 1) / h_c) / math.log(growth))
    x = np.concatenate([[0.0], np.cumsum(h_c * growth ** np.arange(k))])
    r = np.concatenate([h_c * np.arange(n_u), start + x * ((block_size - start) / x[-1])])
    block_coarse = skfem.MeshQuad.init_tensor(r, np.concatenate([-r[::-1][:-1], [0.0]]))
    block_patch = arlequin.refine_region(block_coarse, levels, level_set=within(block_reach))

    # 3. each body an Arlequin problem: coarse elastic model, fine patch (elastic, or J2 with
    #    F-bar for the copper block: its coarse model keeps the elastic part), u_r = 0 on the axis
    def body(coarse_mesh, patch_mesh, material):
        if isinstance(material, J2Material):
            coarse = LinearElastic(coarse_mesh, material.elastic, kind="axisymmetric")
            fine = FiniteStrainJ2(patch_mesh, material, "axisymmetric", fbar=True)
        else:
            coarse = LinearElastic(coarse_mesh, material, kind="axisymmetric")
            fine = LinearElastic(patch_mesh, material, kind="axisymmetric")
        patch = arlequin.Patch(fine, gluing_width=band, coupling="L2", mediator="fine",
                               overlap_method="nested", name="patch")  # fmt: skip
        problem = arlequin.ArlequinProblem(coarse, [patch], mediator_dirichlet="drop")
        for block in ("coarse", "patch"):
            problem.add_dirichlet(block, lambda x: x[0] < tol, components=[0])
        return problem

    ball = body(ball_coarse, ball_patch, steel)
    block = body(block_coarse, block_patch, copper if plastic else steel)
    block.add_dirichlet("coarse", lambda x: x[1] < -block_size + tol, components=[1])  # rollers

    # 4. both bodies in one system; the contact between the patches on its dof map
    bodies = arlequin.MultiBodyProblem({"ball": ball, "block": block})
    system = bodies.system()
    dm = system.dofmap
    slave = ContactSurface(ball_patch, offset=dm["ball.patch"], axisymmetric=True,
                           where=lambda x: (np.hypot(x[0], x[1] - R) > R - 0.05 * h_c / 2**levels)
                           & (np.hypot(x[0], x[1]) < zone))  # fmt: skip
    master = ContactSurface(block_patch, offset=dm["block.patch"], axisymmetric=True,
                            where=lambda x: (x[1] > -tol) & (x[0] < zone))  # fmt: skip
    pair = DeformableContactPair(slave, master, dm)
    contact = LevelSetContact(pair, material=steel, name="contact")

    # 5. Hertz's impact: E* of the two bodies, the ball's mass, the block taken as infinite
    ball_z = np.concatenate([dm["ball.coarse"].component_dofs(1),
                             dm["ball.patch"].component_dofs(1)])  # fmt: skip
    mass = np.asarray(system.mass(lumped=True))[ball_z]
    e_star = steel.young / (2 * (1 - steel.poisson**2))
    delta = (15 * mass.sum() * velocity**2 / (16 * e_star * math.sqrt(R))) ** 0.4
    hertz_force = 4 / 3 * e_star * math.sqrt(R) * delta**1.5
    hertz_duration = 2.9432 * delta / velocity

    # 6. the explicit run: the ball at −v0, the contact force from the multipliers
    v0 = np.zeros(dm.n_dofs)
    v0[ball_z] = -velocity
    force = []

    def record(integ) -> None:
        lam = integ.multipliers.get("contact")
        force.append((integ.t, 0.0 if lam is None else float(-(lam * pair.weights).sum())))

    t_end = 1.4 * hertz_duration
    if plastic:
        # a fully plastic contact (mean pressure 3 σ_y over π a², a² = 2 R δ) is a spring
        # k = 6π R σ_y: its half period π √(m/k) loads, 1.5 × it covers the unloading too
        t_end = 1.5 * math.pi * math.sqrt(mass.sum() / (6 * math.pi * R * copper.yield_stress))
    res = solve(system, "explicit", t_end=t_end, v0=v0, constraints=[contact], on_step=[record],
                t_eval=np.linspace(0.0, t_end, 11)[1:])  # fmt: skip
    t, f = np.array(force).T
    duration = float(t[f > 0.0][-1])
    out = {"peak_force": float(f.max()), "contact_duration": duration,
           "rebound_velocity": float(mass @ res.v[ball_z] / mass.sum()),
           "n_steps": int(res.n_steps)}  # fmt: skip
    if not plastic:
        out.update(hertz_peak_force=hertz_force, hertz_contact_duration=hertz_duration)
        return out
    # 7. the dent (the block's top point on the axis) and the patch's plastic strain
    pole = int(np.nonzero((block_patch.p[0] < tol) & (block_patch.p[1] > -tol))[0][0])
    state = res.states["block.patch"][0]
    out.update(
        dent_depth=float(-res.u[dm["block.patch"].offset + 2 * pole + 1]),
        restitution=out["rebound_velocity"] / velocity,
        max_plastic_strain=float(state.eqps.max()),
    )
    return out


if __name__ == "__main__":
    print(json.dumps(run(plastic=len(sys.argv) > 1 and sys.argv[1] == "plastic"), indent=2))
