"""Meshes of the pressure vessels: the quarter annulus a ≤ ρ ≤ b, 0 ≤ θ ≤ π/2, in quadrilaterals.

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

__all__ = ["VesselMeshes", "annulus_mesh", "refine_projected", "vessel_meshes"]


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


def _project(mesh: skfem.Mesh, radius: float) -> skfem.Mesh:
    """The mesh with the nodes of its boundary facets along the circle ``radius`` moved
    radially onto it: the facets whose ends lie within 1% of the radius from it and that run
    along it (their ends' radii differ by less than half their length; the radial facets of
    the symmetry lines do not)."""
    bf = mesh.boundary_facets()
    ends = mesh.p[:, mesh.facets[:, bf]]  # (dim, 2, n_bf)
    rr = np.linalg.norm(ends, axis=0)  # (2, n_bf)
    length = np.linalg.norm(ends[:, 0] - ends[:, 1], axis=0)
    near = np.all(np.abs(rr - radius) <= 0.01 * radius, axis=0)
    along = np.abs(rr[0] - rr[1]) < 0.5 * length
    nodes = np.unique(mesh.facets[:, bf[near & along]])
    p = mesh.p.copy()
    p[:, nodes] *= radius / np.linalg.norm(p[:, nodes], axis=0)
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
            out = _project(out, radius)
    return out


@dataclass(frozen=True)
class VesselMeshes:
    """The meshes of one run.

    Attributes
    ----------
    coarse : skfem.MeshQuad
        The polar grid of the whole wall.
    patch : skfem.MeshQuad or None
        The refined rings from the bore to ``patch_outer`` (model ``arlequin``).
    mono : skfem.MeshQuad or None
        The whole wall at the patch's resolution (model ``mono``).
    patch_outer : float
        The patch's outer radius (m): the outer circle of the last ring it covers.
    ring_width : float
        The coarse rings' radial width (m).
    levels : int
        Refinement levels of the patch (each halves the cells).
    """

    coarse: skfem.MeshQuad
    patch: skfem.MeshQuad | None
    mono: skfem.MeshQuad | None
    patch_outer: float
    ring_width: float
    levels: int


def vessel_meshes(a: float, b: float, coarse_size: float, fine_size: float,
                  patch_outer: float, model: str) -> VesselMeshes:  # fmt: skip
    """The coarse grid (radial cells of about ``coarse_size``, angular ones of about the same
    length at the mean radius), and the patch (rings whose mid-radius is below
    ``patch_outer``) or the single mesh, ``log2(coarse_size / fine_size)`` levels finer."""
    n_radial = max(1, round((b - a) / coarse_size))
    n_angular = max(2, round(0.25 * math.pi * (a + b) / coarse_size))
    coarse = annulus_mesh(a, b, n_radial, n_angular)
    levels = max(0, round(math.log2(coarse_size / fine_size)))
    ring = (b - a) / n_radial
    n_rings = min(n_radial, max(1, round((patch_outer - a) / ring)))
    r_cells = np.linalg.norm(coarse.p[:, coarse.t].mean(axis=1), axis=0)
    patch = mono = None
    if model == "mono":
        mono = refine_projected(coarse, levels, (a, b))
    else:
        cells = np.nonzero(r_cells < a + n_rings * ring)[0]
        patch = refine_projected(coarse, levels, (a,), cells)
    return VesselMeshes(coarse, patch, mono, a + n_rings * ring, ring, levels)
