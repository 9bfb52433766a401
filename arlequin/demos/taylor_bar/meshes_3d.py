"""The 3D meshes of the Taylor bar: a quarter bar of hexahedra on an O-grid cross-section.

The cross-section is the quarter disc x, y ≥ 0, x² + y² ≤ R² (the planes x = 0 and y = 0
carry the symmetry conditions), split into three structured blocks (the "butterfly" O-grid):

* an inner block, the Coons patch of the two radii [0, b] on the axes and two curved edges
  C(s) = (1 − β)(a, s a) + β a√2 (cos(sπ/4), sin(sπ/4)) (s ∈ [0, 1], a = R/2, β = 1/2,
  b = C(0)_x ≈ 0.60 R), and its mirror image about the diagonal;
* two outer blocks, each the linear blend (1 − t) C(s) + t R (cos(sπ/4), sin(sπ/4)) between a
  curved edge and the arc (and its mirror image).

With n cells across the radius the inner block has n_s = round(0.6 n) cells a side and the
outer blocks n_o = n − n_s cells radially: the cells along the axes are about R/n wide, the
largest (tangential, at the arc) about 1.3 R/n, the thinnest (radial, at the diagonal) about
0.7 R/n. The section is extruded along z ∈ [0, L] in round(L n / R) layers. A curved inner edge
keeps the cells at the block corners from the near-flat angles of a straight square (a = b).

:func:`refined_bar_mesh` refines such a mesh (each hexahedron into eight) and moves the new
nodes of the lateral surface radially onto the cylinder r = R, level after level: the nested
patches of the Arlequin bar, and the single-mesh reference with the patch's nodes. Cells are
scikit-fem's ``MeshHex`` (first-order, positively oriented). SI units.
"""

from __future__ import annotations

import math

import numpy as np
import skfem

__all__ = [
    "lateral_nodes",
    "patch_levels",
    "quarter_bar_mesh",
    "quarter_section_counts",
    "refined_bar_mesh",
    "section_blocks",
]

#: a = R/2 (the inner block's corner at (a, a)) and the bulge β of its curved edges.
_CORNER, _BULGE = 0.5, 0.5


def quarter_section_counts(elements_radial: int) -> tuple[int, int]:
    """(n_s, n_o): the inner block's cells a side and the outer blocks' radial cells.

    Raises
    ------
    ValueError
        Unless ``elements_radial`` is an integer ≥ 2 (one cell per block and direction).
    """
    n = elements_radial
    if isinstance(n, bool) or int(n) != n or n < 2:
        raise ValueError(f"the quarter O-grid needs at least 2 cells across the radius, got "
                         f"elements_radial={n!r}")  # fmt: skip
    n_s = min(int(n) - 1, max(1, round(0.6 * n)))
    return n_s, int(n) - n_s


def patch_levels(ratio: int) -> int:
    """Refinement levels k with 2^k = ``ratio`` (fine cells per coarse edge).

    Raises
    ------
    ValueError
        Unless ``ratio`` is a power of two: each level splits a hexahedron into eight.
    """
    levels = round(math.log2(ratio)) if ratio >= 1 else -1
    if levels < 0 or 2**levels != ratio:
        raise ValueError(f"the 3D patch refines each coarse hexahedron into 8 per level: the "
                         f"coarse size must be a power-of-two multiple of the fine size, got "
                         f"ratio {ratio}")  # fmt: skip
    return levels


def _curve(s: np.ndarray, radius: float) -> np.ndarray:
    """The inner block's curved edge C(s), shape (2, len(s)) (m)."""
    a = _CORNER * radius
    theta = 0.25 * np.pi * s
    straight = np.stack([np.full_like(s, a), a * s])
    round_ = a * np.sqrt(2.0) * np.stack([np.cos(theta), np.sin(theta)])
    return (1.0 - _BULGE) * straight + _BULGE * round_


def _inner(s1: np.ndarray, s2: np.ndarray, radius: float) -> np.ndarray:
    """Coons patch of the inner block at parameters (s1, s2) (arrays of one shape)."""
    b = float(_curve(np.zeros(1), radius)[0, 0])
    a = _CORNER * radius
    right = _curve(s2, radius)  # x ≈ b edge, parameter s2
    top = _curve(s1, radius)[::-1]  # its mirror image (y ≈ b edge), parameter s1
    left = np.stack([np.zeros_like(s2), b * s2])
    bottom = np.stack([b * s1, np.zeros_like(s1)])
    corners = np.stack([s1 * (1 - s2) * b + s1 * s2 * a, (1 - s1) * s2 * b + s1 * s2 * a])
    return (1 - s1) * left + s1 * right + (1 - s2) * bottom + s2 * top - corners


def _outer(t: np.ndarray, s: np.ndarray, radius: float) -> np.ndarray:
    """The outer block next to the x axis: radial parameter t, tangential s."""
    theta = 0.25 * np.pi * s
    arc = radius * np.stack([np.cos(theta), np.sin(theta)])
    return (1 - t) * _curve(s, radius) + t * arc


def section_blocks(radius: float, n_s: int, n_o: int) -> tuple:
    """The O-grid's three blocks: ((cells along the first and second parameter), map
    (u, w) ∈ [0, 1]² -> (x, y)) for the inner block (u ~ x, w ~ y), the outer block next to the
    x axis (u radial, w tangential) and its mirror image (u tangential, w radial)."""
    return (
        ((n_s, n_s), lambda u, w: _inner(u, w, radius)),
        ((n_o, n_s), lambda u, w: _outer(u, w, radius)),
        ((n_s, n_o), lambda u, w: _outer(w, u, radius)[::-1]),  # mirror: orientation kept
    )


def quarter_bar_mesh(length: float, radius: float, elements_radial: int,
                     elements_axial: int | None = None) -> skfem.MeshHex:  # fmt: skip
    """The quarter bar x, y ≥ 0, z ∈ [0, L] on the O-grid section (module docstring).

    Parameters
    ----------
    length, radius : float
        L and R (m).
    elements_radial : int
        n ≥ 2, cells across the radius along the axes.
    elements_axial : int, optional
        Layers along z (default round(L n / R): cells about as long as they are wide).

    Returns
    -------
    skfem.MeshHex
        About (n_s² + 2 n_s n_o) × layers hexahedra.
    """
    n_s, n_o = quarter_section_counts(elements_radial)
    n_z = max(1, round(length * elements_radial / radius)) if elements_axial is None \
        else int(elements_axial)  # fmt: skip
    z = np.linspace(0.0, length, n_z + 1)
    points, cells, offset = [], [], 0
    for (c1, c2), to_xy in section_blocks(radius, n_s, n_o):
        grid = skfem.MeshHex.init_tensor(np.linspace(0, 1, c1 + 1), np.linspace(0, 1, c2 + 1), z)
        xy = to_xy(grid.p[0], grid.p[1])
        points.append(np.vstack([xy, grid.p[2]]))
        cells.append(grid.t + offset)
        offset += grid.p.shape[1]
    p = np.hstack(points)
    t = np.hstack(cells)
    key = np.round(p / (1e-7 * radius)).astype(np.int64)
    _, first, inverse = np.unique(key, axis=1, return_index=True, return_inverse=True)
    p = p[:, first]
    p[:, np.abs(p[0]) < 1e-9 * radius] *= np.array([[0.0], [1.0], [1.0]])  # exact planes
    p[:, np.abs(p[1]) < 1e-9 * radius] *= np.array([[1.0], [0.0], [1.0]])
    return skfem.MeshHex(np.ascontiguousarray(p), np.ascontiguousarray(inverse.ravel()[t]))


def lateral_nodes(mesh: skfem.Mesh, radius: float) -> np.ndarray:
    """Nodes of the boundary facets of a quarter bar off the planes x = 0, y = 0 and the end
    faces: the lateral surface (the nodes on its edges with the symmetry planes included)."""
    facets = mesh.facets[:, mesh.boundary_facets()]
    mid = mesh.p[:, facets].mean(axis=1)
    z0, z1 = mesh.p[2].min(), mesh.p[2].max()
    tol = 1e-9 * radius
    planar = (np.abs(mid[0]) < tol) | (np.abs(mid[1]) < tol) | (np.abs(mid[2] - z0) < tol) \
        | (np.abs(mid[2] - z1) < tol)  # fmt: skip
    return np.unique(facets[:, ~planar])


def refined_bar_mesh(mesh: skfem.MeshHex, radius: float, levels: int = 1) -> skfem.MeshHex:
    """``mesh`` refined ``levels`` times (each hexahedron into eight), the new lateral nodes
    moved radially onto the cylinder r = ``radius`` after each level (module docstring)."""
    for _ in range(int(levels)):
        mesh = mesh.refined()
        nodes = lateral_nodes(mesh, radius)
        p = mesh.p.copy()
        r = np.hypot(p[0, nodes], p[1, nodes])
        p[:2, nodes] *= radius / r
        mesh = skfem.MeshHex(p, mesh.t)
    return mesh
