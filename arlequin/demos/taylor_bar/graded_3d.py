"""The graded 3D Taylor bar: one conforming hexahedral mesh, fine over the patch region, coarse
above, with three sheets of 2:1 transition templates.

The 2D template of :func:`~arlequin.demos.taylor_bar.meshes.graded_bar_mesh` (four fine edges below,
two coarse edges above, six quadrilaterals) halves one direction; extruded along the other
in-plane direction it is a sheet of hexahedra that halves that direction of a structured block.
Each block of the O-grid section (:mod:`arlequin.demos.taylor_bar.meshes_3d`) has two directions to
halve, and the three blocks meet along interfaces that must be halved in the same sheet on both
sides: with two sheets the cycle inner block – outer block – outer block cannot be consistent,
with three it is:

=========  ===============  ==================  ==================
sheet      inner block      outer block (x)     outer block (y)
=========  ===============  ==================  ==================
1          x                                    tangential
2          y                tangential
3                           radial              radial
=========  ===============  ==================  ==================

(a block passes a sheet through, unchanged, when it halves nothing in it). Each sheet is one
coarse layer tall, so the transition takes three coarse layers above the patch. All nodes are
the coarse O-grid's cells refined (their trilinear midpoints, the lateral ones moved radially
onto the cylinder as :func:`~arlequin.demos.taylor_bar.meshes_3d.refined_bar_mesh` does): the fine
region is the Arlequin patch's mesh node for node, the coarse region the coarse model's. The
blocks' coarse counts must be even (the templates pair coarse cells). SI units.
"""

from __future__ import annotations

import numpy as np
import skfem

from .meshes import ArlequinBarSizes
from .meshes_3d import quarter_section_counts, section_blocks

__all__ = [
    "TRANSITION_LAYERS",
    "check_graded_sizes",
    "graded_bar_mesh_3d",
]

#: Coarse layers the three transition sheets take above the patch.
TRANSITION_LAYERS = 3

# the 2D template on [0, 4] x [0, 1] (fine units along the halved direction, sheet height):
# node coordinates and six quadrilaterals, each (0,0), (1,0), (1,1), (0,1) in its own frame
_NODES = np.array([[0, 0], [1, 0], [2, 0], [3, 0], [4, 0], [1, 0.5], [2, 0.5], [3, 0.5],
                   [0, 1], [2, 1], [4, 1]], dtype=float)  # fmt: skip
_QUADS = np.array([[0, 1, 5, 8], [1, 2, 6, 5], [5, 6, 9, 8], [2, 3, 7, 6], [3, 4, 10, 7],
                   [6, 7, 10, 9]])  # fmt: skip
# scikit-fem's hexahedron corners (MeshHex.init_tensor's order), in reference coordinates
_HEX = np.array([[0, 0, 0], [0, 1, 0], [1, 0, 0], [0, 0, 1], [1, 1, 0], [0, 1, 1], [1, 0, 1],
                 [1, 1, 1]])  # fmt: skip
# the sheet in which each block halves its (first, second) parameter direction (table above)
_SHEETS = ((1, 2), (3, 2), (1, 3))
_QUAD_CORNER = {(0, 0): 0, (1, 0): 1, (1, 1): 2, (0, 1): 3}


def _cells(block: int, counts, steps, sheet: int, z0: float, height: float):
    """The hexahedra of one block in one layer: corner parameters (8, 3, n) as (fine index
    along the block's first and second directions, z), and the steps after the layer."""
    halved = [a for a in (0, 1) if _SHEETS[block][a] == sheet] if sheet else []
    steps = list(steps)
    cells = []
    if not halved:  # a pass-through (or fine, or coarse) layer of the block's current grid
        i0 = np.arange(0, 2 * counts[0], steps[0])
        i1 = np.arange(0, 2 * counts[1], steps[1])
        g0, g1 = (g.ravel() for g in np.meshgrid(i0, i1, indexing="ij"))
        for c0, c1, c2 in _HEX:
            cells.append(np.stack([g0 + c0 * steps[0], g1 + c1 * steps[1],
                                   np.full(g0.shape, z0 + c2 * height)]))  # fmt: skip
        return np.stack(cells), steps
    a = halved[0]
    e = 1 - a
    units = np.arange(0, 2 * counts[a], 4)  # one template per pair of coarse cells
    e0 = np.arange(0, 2 * counts[e], steps[e])
    u, q, ev = (g.ravel() for g in np.meshgrid(units, np.arange(6), e0, indexing="ij"))
    for ref in _HEX:
        ref_d, ref_e, ref_z = (ref[0], ref[1], ref[2]) if a == 0 else (ref[1], ref[0], ref[2])
        node = _QUADS[q, _QUAD_CORNER[(ref_d, ref_z)]]
        d = u + _NODES[node, 0]
        ee = ev + ref_e * steps[e]
        z = z0 + _NODES[node, 1] * height
        cells.append(np.stack([d, ee, z] if a == 0 else [ee, d, z]))
    steps[a] = 2
    return np.stack(cells), steps


def check_graded_sizes(sizes: ArlequinBarSizes) -> tuple[int, int]:
    """The O-grid's block counts (n_s, n_o) of the 3D graded mesh's coarse section.

    Raises
    ------
    ValueError
        Unless the coarse size is twice the fine size, the blocks' coarse counts are even, and
        the patch leaves at least the three transition layers above it.
    """
    s = sizes
    n_s, n_o = quarter_section_counts(s.coarse_radial)
    if s.ratio != 2:
        raise ValueError(f"the graded mesh joins fine and coarse cells of ratio 2 (2:1 "
                         f"templates); got coarse size {s.coarse_size} m = {s.ratio} x the fine "
                         f"size")  # fmt: skip
    if n_s % 2 or n_o % 2:
        raise ValueError(f"the 3D graded mesh pairs coarse cells: the O-grid with "
                         f"{s.coarse_radial} coarse cells across the radius has blocks of "
                         f"{n_s} and {n_o}: use 4, 6, 10, 14 or 16 across")  # fmt: skip
    above = s.coarse_axial - s.patch_rows
    if above < TRANSITION_LAYERS:
        raise ValueError(f"the 3D graded mesh needs {TRANSITION_LAYERS} coarse layers above the "
                         f"patch for its transition, the patch leaves {above}")  # fmt: skip
    return n_s, n_o


def graded_bar_mesh_3d(length: float, radius: float, sizes: ArlequinBarSizes) -> skfem.MeshHex:
    """One conforming mesh of the quarter bar: fine below ``patch_length``, three transition
    sheets, the coarse O-grid above (module docstring).

    Raises
    ------
    ValueError
        Unless the coarse size is twice the fine size, the blocks' coarse counts are even, and
        the patch leaves at least the three transition layers above it.
    """
    s = sizes
    n_s, n_o = check_graded_sizes(s)
    above = s.coarse_axial - s.patch_rows
    hz = s.axial_size
    z_layers = [(0, 0.5 * hz * k, 0.5 * hz) for k in range(2 * s.patch_rows)]  # fine
    z_p = s.patch_length
    z_layers += [(k, z_p + (k - 1) * hz, hz) for k in (1, 2, 3)]  # the sheets
    z_layers += [(0, z_p + (TRANSITION_LAYERS + k) * hz, hz) for k in range(above - 3)]
    blocks = section_blocks(radius, n_s, n_o)
    points, conn = [], []
    for b, (counts, to_xy) in enumerate(blocks):
        steps = [1, 1]
        for sheet, z0, height in z_layers:
            corners, steps = _cells(b, counts, steps, sheet, z0, height)  # (8, 3, n)
            n = corners.shape[2]
            flat = corners.transpose(0, 2, 1).reshape(-1, 3).T  # (3, 8 n)
            xy = _section_point(to_xy, counts, flat[0], flat[1])
            base = sum(p.shape[1] for p in points)
            points.append(np.vstack([xy, flat[2], flat[:2], np.full(flat.shape[1], b)]))
            conn.append(base + np.arange(8 * n).reshape(8, n))
    p = np.hstack(points)
    t = np.hstack(conn)
    _project_lateral(p, blocks, radius)
    key = np.round(p[:3] / (1e-7 * radius)).astype(np.int64)
    _, first, inverse = np.unique(key, axis=1, return_index=True, return_inverse=True)
    xyz = np.ascontiguousarray(p[:3, first])
    return skfem.MeshHex(xyz, np.ascontiguousarray(inverse.ravel()[t]))


def _section_point(to_xy, counts, f0: np.ndarray, f1: np.ndarray) -> np.ndarray:
    """(x, y) of fine-index parameters: bilinear in the coarse cell containing them (the
    midpoints of the coarse O-grid's cells, as a uniform refinement)."""
    c0, c1 = counts
    i = np.minimum(f0 // 2, c0 - 1)
    j = np.minimum(f1 // 2, c1 - 1)
    xi, eta = f0 / 2 - i, f1 / 2 - j
    corner = [to_xy((i + a) / c0, (j + b) / c1) for a, b in ((0, 0), (1, 0), (0, 1), (1, 1))]
    w = [(1 - xi) * (1 - eta), xi * (1 - eta), (1 - xi) * eta, xi * eta]
    return sum(wk * ck for wk, ck in zip(w, corner, strict=True))


def _project_lateral(p: np.ndarray, blocks, radius: float) -> None:
    """Move the nodes on the arc (outer blocks' radial parameter at its end) onto r = R."""
    on_arc = ((p[-1] == 1) & (p[3] == 2 * blocks[1][0][0])) \
        | ((p[-1] == 2) & (p[4] == 2 * blocks[2][0][1]))  # fmt: skip
    r = np.hypot(p[0, on_arc], p[1, on_arc])
    p[:2, on_arc] *= radius / r
