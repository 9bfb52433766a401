"""Meshes of the quarter plate with a hole: graded rings around the hole, in quadrilaterals or
triangles; the nested refinements with the hole nodes projected onto the circle; the graded
conforming mesh.

The quarter plate [0, W]² minus the quarter disc r < a is meshed in polar-like rings: node
(i, j) lies on the segment from the hole point a (cos θ_j, sin θ_j) to a point of the outer
edges (x = W for θ ≤ 45°, y = W beyond), at a geometrically graded fraction f_i of its length
(the first ring about as deep as the hole cells are wide). Ring i = 0 … n_radial − 1 goes
outwards from the hole. Every hole node lies on the circle.

:func:`refine_projected` refines (some of) the cells one level at a time, moving the new hole
nodes radially onto the circle after each level: the Arlequin patch (the first rings), the
single fine mesh (every ring). :func:`graded_plate_mesh` is one conforming mesh: the patch's
cells exactly, and beyond them the coarse rings split angularly only (the fine angular
resolution carried out to the plate's edges, the coarse radial one), so that no node hangs.

Sizes in m (any unit: the functions are scale-free).
"""

from __future__ import annotations

import numpy as np
import skfem
from scipy.spatial import cKDTree

from ...coupling.patches import refine_region

__all__ = [
    "graded_plate_mesh",
    "hole_nodes",
    "project_hole_nodes",
    "quarter_plate_mesh",
    "refine_projected",
    "ring_fractions",
]


def _grading(n: int, first: float) -> np.ndarray:
    """Fractions 0 = f_0 < … < f_n = 1 with geometric spacing whose first step is ``first``.

    Parameters
    ----------
    n : int
        Number of steps.
    first : float
        First step as a fraction of the total, in (0, 1/n]: 1/n gives a uniform spacing.
    """
    if first * n >= 1.0 - 1e-12:
        return np.linspace(0.0, 1.0, n + 1)
    lo, hi = 1.0 + 1e-12, 10.0
    for _ in range(200):  # bisection on the ratio q: first (q^n - 1) / (q - 1) = 1
        q = 0.5 * (lo + hi)
        if first * (q**n - 1.0) / (q - 1.0) > 1.0:
            hi = q
        else:
            lo = q
    steps = first * q ** np.arange(n)
    f = np.concatenate([[0.0], np.cumsum(steps)])
    return f / f[-1]


def ring_fractions(a: float, n_theta: int, n_radial: int, half_width: float) -> np.ndarray:
    """The fractions f_0 = 0 < … < f_n = 1 of the ring boundaries along each segment: the first
    ring about as deep (on the x axis) as the hole cells are wide."""
    return _grading(n_radial, min((0.25 * np.pi * a / n_theta) / (half_width - a), 1.0 / n_radial))


def _end_points(a: float, n_theta: int, half_width: float, split: int = 1):
    """The segments' ends: on the hole (the coarse points on the circle, the points between
    them on its chords) and on the outer edges, ``2 n_theta split + 1`` of each, (2, n)."""
    n_ang = 2 * n_theta
    theta = np.linspace(0.0, 0.5 * np.pi, n_ang + 1)
    inner = a * np.stack([np.cos(theta), np.sin(theta)])
    s = np.linspace(0.0, n_ang, n_ang * split + 1)
    j = np.minimum(np.floor(s).astype(int), n_ang - 1)
    inner = inner[:, j] + (s - j) * (inner[:, j + 1] - inner[:, j])
    t = s / n_theta  # 0 … 2 along the outer edges
    outer = half_width * np.stack([np.minimum(2.0 - t, 1.0), np.minimum(t, 1.0)])
    inner[1, 0] = inner[0, -1] = 0.0  # the symmetry lines exactly
    return inner, outer


def _structured(p: np.ndarray, n_rings: int, n_ang: int, element: str):
    """Cells of a structured (ring, angle) node grid ``p`` (2, (n_rings + 1) (n_ang + 1))."""
    node = np.arange((n_rings + 1) * (n_ang + 1)).reshape(n_rings + 1, n_ang + 1)
    v00, v10 = node[:-1, :-1].ravel(), node[1:, :-1].ravel()
    v11, v01 = node[1:, 1:].ravel(), node[:-1, 1:].ravel()
    ring = np.repeat(np.arange(n_rings), n_ang)
    if element == "quad":
        return skfem.MeshQuad(p, np.stack([v00, v10, v11, v01])), ring
    t1 = np.stack([v00, v10, v11])
    t2 = np.stack([v00, v11, v01])
    return skfem.MeshTri(p, np.concatenate([t1, t2], axis=1)), np.concatenate([ring, ring])


def quarter_plate_mesh(
    a: float = 1.0,
    n_theta: int = 8,
    n_radial: int = 12,
    element: str = "tri",
    half_width: float | None = None,
) -> tuple[skfem.Mesh, np.ndarray, np.ndarray]:
    """Structured mesh of the quarter plate [0, W]² minus the quarter disc r < a.

    Parameters
    ----------
    a : float
        Hole radius (m).
    n_theta : int
        Cells along each 45° sector of the hole (2 n_theta along the quarter circle).
    n_radial : int
        Cell rings from the hole to the outer edges, geometrically graded so that the first ring
        is about as deep as the cells are wide on the hole.
    element : {"tri", "quad"}
        Triangles (each quad split along its diagonal) or bilinear quadrilaterals.
    half_width : float, optional
        W (m), the plate's half width; default 5a.

    Returns
    -------
    mesh : skfem.MeshTri or skfem.MeshQuad
    ring : ndarray of int, shape (n_cells,)
        Ring index (0 next to the hole) of each cell.
    radii : ndarray, shape (n_radial + 1,)
        x coordinate (m) of the ring boundaries on the x axis (θ = 0), from a to W.
    """
    if element not in ("tri", "quad"):
        raise ValueError(f"element must be 'tri' or 'quad', got {element!r}")
    w = 5.0 * a if half_width is None else float(half_width)
    inner, outer = _end_points(a, n_theta, w)
    f = ring_fractions(a, n_theta, n_radial, w)
    p = inner[:, None, :] + f[None, :, None] * (outer - inner)[:, None, :]  # (2, i, j)
    mesh, ring = _structured(p.reshape(2, -1), n_radial, 2 * n_theta, element)
    return mesh, ring, a + (w - a) * f


def hole_nodes(mesh: skfem.Mesh, a: float) -> np.ndarray:
    """Nodes of the boundary facets lying on the hole (chords of the circle r = a).

    A facet is on the hole when its midpoint is not farther than a from the origin (a chord's
    midpoint lies inside the circle; facets on the symmetry axes leave the circle).
    """
    bf = mesh.boundary_facets()
    mid = mesh.p[:, mesh.facets[:, bf]].mean(axis=1)
    on_hole = np.linalg.norm(mid, axis=0) <= a * (1.0 + 1e-9)
    return np.unique(mesh.facets[:, bf[on_hole]])


def project_hole_nodes(mesh: skfem.Mesh, a: float) -> skfem.Mesh:
    """The mesh with its hole nodes moved radially onto the circle r = a (m)."""
    nodes = hole_nodes(mesh, a)
    p = mesh.p.copy()
    p[:, nodes] *= a / np.linalg.norm(p[:, nodes], axis=0)
    return type(mesh)(p, mesh.t)


def refine_projected(
    mesh: skfem.Mesh, levels: int, a: float, cells: np.ndarray | None = None
) -> skfem.Mesh:
    """Refine (the given cells of) ``mesh`` one level at a time, projecting hole nodes each time.

    Parameters
    ----------
    mesh : skfem.Mesh
    levels : int
        Uniform refinement levels.
    a : float
        Hole radius (m).
    cells : ndarray of int, optional
        Cells of ``mesh`` to keep and refine (default all): the patch region.

    Returns
    -------
    skfem.Mesh
    """
    cells = np.arange(mesh.nelements) if cells is None else np.asarray(cells)
    out = refine_region(mesh, levels=0, cells=cells)
    for _ in range(levels):
        out = project_hole_nodes(refine_region(out, levels=1, cells=np.arange(out.nelements)), a)
    return out


def graded_plate_mesh(
    a: float, n_theta: int, n_radial: int, half_width: float, levels: int, n_fine_rings: int
) -> tuple[skfem.MeshQuad, np.ndarray]:
    """One conforming quadrilateral mesh: the first ``n_fine_rings`` coarse rings refined
    ``levels`` times (exactly the cells of the nested patch, :func:`refine_projected`), and the
    other rings split angularly only (2^levels cells for each coarse one), out to the edges.

    Returns
    -------
    mesh : skfem.MeshQuad
    fine : ndarray of int
        The cells of the refined rings (the patch region), the first ones of the mesh.
    """
    coarse, ring, _ = quarter_plate_mesh(a, n_theta, n_radial, "quad", half_width)
    fine = refine_projected(coarse, levels, a, cells=np.nonzero(ring < n_fine_rings)[0])
    if n_fine_rings >= n_radial:
        return fine, np.arange(fine.nelements)
    split = 2**levels
    inner, outer = _end_points(a, n_theta, half_width, split)
    f = ring_fractions(a, n_theta, n_radial, half_width)[n_fine_rings:]
    p = (inner[:, None, :] + f[None, :, None] * (outer - inner)[:, None, :]).reshape(2, -1)
    n_ang = 2 * n_theta * split
    outside, _ = _structured(p, f.size - 1, n_ang, "quad")
    # the first row of the outside grid is the refined rings' outer boundary: merge its nodes
    tree = cKDTree(fine.p.T)
    dist, match = tree.query(outside.p[:, : n_ang + 1].T)
    if dist.max() > 1e-9 * half_width:
        raise RuntimeError(f"graded mesh: the rings do not meet (gap {dist.max():.3g})")
    index = np.concatenate([match, fine.nvertices + np.arange(outside.nvertices - n_ang - 1)])
    p_all = np.hstack([fine.p, outside.p[:, n_ang + 1 :]])
    t_all = np.hstack([fine.t, index[outside.t]])
    return skfem.MeshQuad(p_all, t_all), np.arange(fine.nelements)
