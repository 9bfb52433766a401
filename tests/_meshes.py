"""Mesh helpers shared by the tests."""

from __future__ import annotations

import numpy as np
import skfem


def perturb(mesh: skfem.Mesh, spacing: float, amount: float, seed: int) -> skfem.Mesh:
    """Move interior nodes randomly by up to ``amount * spacing`` per coordinate.

    Boundary nodes stay put, so the domain stays the box (planar boundary faces).
    """
    rng = np.random.default_rng(seed)
    p = mesh.p.copy()
    interior = np.setdiff1d(np.arange(mesh.nvertices), mesh.boundary_nodes())
    p[:, interior] += amount * spacing * rng.uniform(-1.0, 1.0, (mesh.dim(), interior.size))
    return type(mesh)(p, mesh.t)
