"""Meshes of the quarter plate with a hole: the quasi-uniform coarse mesh of the demo, the
polar ring mesh (of ``examples/plate_with_hole.py``, and the demo's rings around the hole), the
nested refinements with the hole nodes projected onto the circle, the graded conforming mesh.

:func:`quarter_plate_mesh` meshes [0, W]² minus the quarter disc r < a in polar-like rings:
node (i, j) lies on the segment from the hole point a (cos θ_j, sin θ_j) to a point of the outer
edges (x = W for θ ≤ 45°, y = W beyond), at a geometrically graded fraction f_i of its length
(the first ring about as deep as the hole cells are wide). Every ring has the same number of
cells, so its cells grow with the distance from the hole.

:func:`plate_mesh`, the demo's coarse mesh, uses those rings only in the square [0, 2a]² around
the hole (their outer edges the square's sides, n_theta cells along each) and meshes the rest of
the plate with a structured grid of the same lines: cells of 2a / n_theta everywhere away from
the hole, so that refining the whole mesh (``mono``) is uniformly fine at the patch's
resolution. The patch is the coarse cells in a square [0, R]² (R a grid line:
:func:`square_radius`).

:func:`refine_projected` refines (some of) the cells one level at a time, moving the new hole
nodes radially onto the circle after each level: the Arlequin patch, the single fine mesh.
:func:`graded_plate_mesh` is one conforming mesh: the patch's cells exactly, and beyond them
the tensor grid whose lines are refined below R only (the strips along the patch split in one
direction, the rest coarse), so that no node hangs.

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
    "plate_lines",
    "plate_mesh",
    "project_hole_nodes",
    "quarter_plate_mesh",
    "refine_projected",
    "ring_fractions",
    "square_radius",
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


def _merge(first: skfem.MeshQuad, second: skfem.MeshQuad, scale: float) -> skfem.MeshQuad:
    """One mesh of the cells of ``first`` then those of ``second``, the nodes of ``second`` that
    coincide with nodes of ``first`` (to 1e-9 ``scale``) merged into them."""
    dist, match = cKDTree(first.p.T).query(second.p.T)
    shared = dist <= 1e-9 * scale
    index = np.empty(second.nvertices, dtype=np.int64)
    index[shared] = match[shared]
    index[~shared] = first.nvertices + np.arange(np.count_nonzero(~shared))
    p = np.hstack([first.p, second.p[:, ~shared]])
    return skfem.MeshQuad(p, np.hstack([first.t, index[second.t]]))


def _outside(lines: np.ndarray, inner: float) -> skfem.MeshQuad:
    """The tensor grid of ``lines`` × ``lines`` without its cells inside [0, inner]²."""
    grid = skfem.MeshQuad.init_tensor(lines, lines)
    centre = grid.p[:, grid.t].mean(axis=1)
    return grid.restrict(np.nonzero(centre.max(axis=0) > inner)[0])


def plate_lines(a: float, n_theta: int, half_width: float, block: float) -> np.ndarray:
    """The grid lines (m, the same in x and y) of the quasi-uniform part of the plate: ``n_theta``
    equal cells across the hole's block [0, block], then cells of about the same size
    (block / n_theta) out to W."""
    h = block / n_theta
    k = max(1, int(np.ceil((half_width - block) / h - 1e-9)))
    return np.concatenate([np.linspace(0.0, block, n_theta + 1),
                           np.linspace(block, half_width, k + 1)[1:]])  # fmt: skip


def plate_mesh(
    a: float, n_theta: int, n_rings: int, half_width: float, block: float
) -> tuple[skfem.MeshQuad, np.ndarray]:
    """The quasi-uniform coarse mesh of the quarter plate [0, W]² minus the quarter disc r < a.

    The square [0, block]² around the hole holds the rings of :func:`quarter_plate_mesh` (its
    ``half_width`` = ``block``: 2 ``n_theta`` cells along the quarter hole, ``n_rings`` rings
    blending the circle into the square's sides, ``n_theta`` cells along each), and the rest of
    the plate a structured grid of the same lines (:func:`plate_lines`): cells of size
    block / n_theta everywhere away from the hole, conforming with the rings.

    Returns
    -------
    mesh : skfem.MeshQuad
        The ring cells first.
    lines : ndarray
        The grid lines (m).
    """
    rings, _, _ = quarter_plate_mesh(a, n_theta, n_rings, "quad", block)
    lines = plate_lines(a, n_theta, half_width, block)
    return _merge(rings, _outside(lines, block), half_width), lines


def square_radius(mesh: skfem.Mesh) -> np.ndarray:
    """Each cell's largest max(x, y) over its vertices (m): the cells with square_radius ≤ R
    tile [0, R]² minus the hole (R a grid line)."""
    return mesh.p[:, mesh.t].max(axis=(0, 1))


def graded_plate_mesh(
    coarse: skfem.MeshQuad, lines: np.ndarray, a: float, levels: int, patch: np.ndarray
) -> tuple[skfem.MeshQuad, np.ndarray]:
    """One conforming quadrilateral mesh: the ``patch`` cells of the coarse mesh refined
    ``levels`` times (exactly the nested patch, :func:`refine_projected`), which must tile
    [0, R]² minus the hole (R a grid line), and the tensor grid outside it whose lines are the
    coarse ones refined 2^levels times below R, the coarse ones beyond: the strips beside the
    patch split along it only, the rest coarse, no node hanging.

    Returns
    -------
    mesh : skfem.MeshQuad
    fine : ndarray of int
        The cells of the refined region (the patch's), the first ones of the mesh.
    """
    fine = refine_projected(coarse, levels, a, cells=patch)
    r = float(square_radius(coarse)[patch].max())
    inner = lines[lines <= r * (1.0 + 1e-12)]
    split = 2**levels
    s = np.linspace(0.0, inner.size - 1, (inner.size - 1) * split + 1)
    j = np.minimum(np.floor(s).astype(int), inner.size - 2)
    fine_lines = inner[j] + (s - j) * (inner[j + 1] - inner[j])
    all_lines = np.concatenate([fine_lines, lines[lines > r * (1.0 + 1e-12)]])
    if all_lines.size == fine_lines.size:
        return fine, np.arange(fine.nelements)
    mesh = _merge(fine, _outside(all_lines, r), float(lines[-1]))
    return mesh, np.arange(fine.nelements)
