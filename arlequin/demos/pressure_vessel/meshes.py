"""Meshes of the pressure vessels: the quarter annulus a ≤ ρ ≤ b, 0 ≤ θ ≤ π/2, in quadrilaterals
(the sphere's octant in hexahedra: :mod:`~arlequin.demos.pressure_vessel.meshes_3d`).

The same section serves both vessels: the meridional quarter of the sphere (x = r, the radius
from the axis, y = z along the axis; axisymmetric) and the quarter of the cylinder's cross
section (plane strain). The coarse mesh is a polar grid, its nodes on the circles ρ = const; the
patch is a nested refinement of the coarse rings from the bore outwards (the nodes it adds on
the bore projected onto the circle, as the hole of the plate example); the single fine mesh is
the whole coarse mesh refined the same way (bore and outer nodes projected).

Sizes are in m; the cell counts follow the wall thickness b − a, so other radii run at the same
resolution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import skfem

from ...coupling.patches import refine_region
from .meshes_3d import octant_sphere_mesh

__all__ = [
    "VesselMeshes",
    "annulus_mesh",
    "project_boundary_nodes",
    "refine_projected",
    "vessel_meshes",
]


def annulus_mesh(a: float, b: float, n_radial: int, n_angular: int) -> skfem.MeshQuad:
    """The quarter annulus as a polar grid of n_radial × n_angular quadrilaterals."""
    rho = np.linspace(a, b, n_radial + 1)
    theta = np.linspace(0.0, 0.5 * math.pi, n_angular + 1)
    grid = skfem.MeshQuad.init_tensor(rho, theta)
    r, t = grid.p
    p = np.vstack([r * np.cos(t), r * np.sin(t)])
    # the axis (θ = π/2) exactly at x = 0 and the equator exactly at y = 0
    p[0, np.isclose(t, 0.5 * math.pi)] = 0.0
    p[1, t == 0.0] = 0.0
    return skfem.MeshQuad(p, grid.t)


def project_boundary_nodes(mesh: skfem.Mesh, radius: float) -> skfem.Mesh:
    """The mesh with the nodes of its boundary facets on the sphere ``radius`` (every node of
    the facet within 1% of it, the facet running along it) moved radially onto it."""
    bf = mesh.boundary_facets()
    nodes = mesh.facets[:, bf]
    rr = np.linalg.norm(mesh.p[:, nodes], axis=0)  # (n_facet_nodes, n_bf)
    size = np.linalg.norm(mesh.p[:, nodes[0]] - mesh.p[:, nodes[1]], axis=0)
    near = np.all(np.abs(rr - radius) <= 0.01 * radius, axis=0)
    along = np.ptp(rr, axis=0) < 0.5 * size
    on = np.unique(nodes[:, near & along])
    p = mesh.p.copy()
    p[:, on] *= radius / np.linalg.norm(p[:, on], axis=0)
    return type(mesh)(p, mesh.t)


def refine_projected(mesh: skfem.Mesh, levels: int, circles: tuple[float, ...],
                     cells: np.ndarray | None = None) -> skfem.Mesh:  # fmt: skip
    """Refine (the given cells of) ``mesh`` ``levels`` times, one level at a time, moving the
    new boundary nodes on the ``circles`` (radii, m) onto them after each level."""
    cells = np.arange(mesh.nelements) if cells is None else np.asarray(cells)
    out = refine_region(mesh, levels=0, cells=cells)
    for _ in range(levels):
        out = refine_region(out, levels=1, cells=np.arange(out.nelements))
        for radius in circles:
            out = project_boundary_nodes(out, radius)
    return out


@dataclass(frozen=True)
class VesselMeshes:
    """The meshes of one run.

    Attributes
    ----------
    coarse : skfem.MeshQuad or skfem.MeshHex
        The polar grid of the whole wall.
    patch : skfem.Mesh or None
        The refined rings from the bore to ``patch_outer`` (model ``arlequin``).
    mono : skfem.Mesh or None
        The whole wall at the patch's resolution (model ``mono``).
    patch_outer : float
        The patch's outer radius (m): the outer circle of the last ring it covers.
    ring_width : float
        The coarse rings' radial width (m).
    levels : int
        Refinement levels of the patch (each halves the cells).
    """

    coarse: skfem.Mesh
    patch: skfem.Mesh | None
    mono: skfem.Mesh | None
    patch_outer: float
    ring_width: float
    levels: int


def vessel_meshes(a: float, b: float, coarse_size: float, fine_size: float,
                  patch_outer: float, model: str, dim: int = 2) -> VesselMeshes:  # fmt: skip
    """The coarse grid (radial cells of about ``coarse_size``, the others of about the same
    length at the mean radius: the quarter annulus in 2D, the sphere's octant in 3D), and the
    patch (shells whose mid-radius is below ``patch_outer``) or the single mesh,
    ``log2(coarse_size / fine_size)`` levels finer."""
    n_radial = max(1, round((b - a) / coarse_size))
    if dim == 2:
        n_angular = max(2, round(0.25 * math.pi * (a + b) / coarse_size))
        coarse = annulus_mesh(a, b, n_radial, n_angular)
    else:
        # 3 n² surface cells share the octant's area π ρ²/2 at the mean radius
        n = max(1, round(0.5 * (a + b) * math.sqrt(math.pi / 6.0) / coarse_size))
        coarse = octant_sphere_mesh(a, b, n, n_radial)
    levels = max(0, round(math.log2(coarse_size / fine_size)))
    ring = (b - a) / n_radial
    n_rings = min(n_radial, max(1, round((patch_outer - a) / ring)))
    r_cells = np.linalg.norm(coarse.p[:, coarse.t].mean(axis=1), axis=0)  # cell centres
    patch = mono = None
    if model == "mono":
        mono = refine_projected(coarse, levels, (a, b))
    else:
        cells = np.nonzero(r_cells < a + n_rings * ring)[0]
        patch = refine_projected(coarse, levels, (a,), cells)
    return VesselMeshes(coarse, patch, mono, a + n_rings * ring, ring, levels)
