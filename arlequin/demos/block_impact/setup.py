"""The block impact's set-up: the block (and the target block), the contact pair and model, the
step, the initial velocity (SI units).

The block (height H in the impact direction, the last coordinate; width aspect·H) has
``elements`` elements along H and ``round(aspect·elements)`` (≥ 2) across; plane strain in 2D
(MeshQuad), hexahedra in 3D. It starts at a gap of ``gap_steps`` v₀Δt (so that the activation
falls inside a step) and moves at −v₀. Δt = cfl·h/c_d (dilatational speed).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import skfem

from ...models import (
    ContactSurface,
    DeformableContactPair,
    IsotropicElastic,
    LevelSetContact,
    LinearElastic,
    PlaneObstacle,
    RigidContactPair,
)
from ...problem.system import Block, BlockTerm, CoupledSystem

if TYPE_CHECKING:
    from .config import BlockImpactConfig

__all__ = ["BlockImpactSetup", "build_block_impact"]


@dataclass
class BlockImpactSetup:
    """A built block impact: the system, the contact model, the initial velocity (m/s), the
    element size h (m), the step Δt (s) and the end time (s)."""

    system: CoupledSystem
    contact: LevelSetContact
    v0: np.ndarray
    h: float
    dt: float
    t_end: float
    elements: int


def _contact_model(config: BlockImpactConfig, system: CoupledSystem, top: LinearElastic,
                   target: Any, g0: float, h: float, material) -> LevelSetContact:  # fmt: skip
    """The level-set contact of the block's bottom with the plane or the target's top."""
    dim = config.dim
    dofmap = system.dofmap
    slave = ContactSurface(top.mesh, where=lambda x: x[-1] < g0 + 0.25 * h, offset=dofmap["block"])
    if config.target == "plane":
        pair = RigidContactPair(slave, PlaneObstacle(np.zeros(dim), np.eye(dim)[-1]), dofmap)
    else:
        master = ContactSurface(
            target.mesh, where=lambda x: x[-1] > -0.25 * h, offset=dofmap["target"]
        )
        pair = DeformableContactPair(slave, master, dofmap)
    return LevelSetContact(pair, material=material)


def build_block_impact(config: BlockImpactConfig) -> BlockImpactSetup:
    """The bodies, system, contact and initial state of a (checked) configuration."""
    dim, poisson, density = config.dim, config.poisson, config.density
    material = IsotropicElastic(config.young, poisson, density)
    ne = int(config.elements)
    nw = max(2, round(config.aspect * ne))
    H = float(config.height)
    W = config.aspect * H
    h = H / ne
    c_d = math.sqrt(material.young * (1 - poisson) / ((1 + poisson) * (1 - 2 * poisson)) / density)
    dt = config.cfl * h / c_d
    g0 = config.gap_steps * config.velocity * dt
    lateral = [np.linspace(0.0, W, nw + 1)] * (dim - 1)

    def make(z0: float) -> LinearElastic:
        z = np.linspace(z0, z0 + H, ne + 1)
        mesh = (skfem.MeshQuad if dim == 2 else skfem.MeshHex).init_tensor(*lateral, z)
        return LinearElastic(mesh, material, kind="plane_strain" if dim == 2 else "3d")

    top = make(g0)
    bodies = [top]
    names = ["block"]
    if config.target == "block":
        bodies.append(make(-H))
        names.append("target")
    system = CoupledSystem([Block(n, b, [BlockTerm(b)]) for n, b in zip(names, bodies)])
    target = bodies[1] if len(bodies) > 1 else None
    con = _contact_model(config, system, top, target, g0, h, material)
    dofmap = system.dofmap
    v0 = np.zeros(dofmap.n_dofs)
    v0[dofmap["block"].component_dofs(dim - 1)] = -config.velocity
    c_bar = math.sqrt(config.young / density)
    t_end = g0 / config.velocity + 3.0 * H / c_bar if config.t_end is None else float(config.t_end)
    return BlockImpactSetup(system, con, v0, h, dt, t_end, ne)
