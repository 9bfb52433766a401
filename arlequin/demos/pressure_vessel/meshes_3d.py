"""The eighth of a thick sphere (x, y, z ≥ 0, a ≤ ρ ≤ b) in hexahedra.

The octant of a sphere's surface is a spherical triangle; three quadrilaterals split it, meeting
at its centre (1, 1, 1)/√3 and at the midpoints of its three edges (a cubed-sphere octant, no
degenerate cell at the poles). Each is an n × n grid, mapped bilinearly from its corners on the
unit sphere's octant and projected onto the sphere; the surface grid is extruded radially into
``n_radial`` shells. The nodes the three blocks share are merged, so the mesh is conforming.
The symmetry planes x = 0, y = 0, z = 0 are exactly at zero.
"""

from __future__ import annotations

import numpy as np
import skfem

__all__ = ["octant_sphere_mesh"]

_CORNERS = np.eye(3)  # the octant's vertices on the unit sphere


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=0)


def _blocks() -> list[np.ndarray]:
    """The three quadrilaterals of the octant: corners (3, 4), counter-clockwise seen from
    outside, each a vertex, two edge midpoints and the centre."""
    c = _unit(np.ones((3, 1)))[:, 0]
    mid = {(i, j): _unit((_CORNERS[i] + _CORNERS[j])[:, None])[:, 0]
           for i in range(3) for j in range(3) if i < j}  # fmt: skip
    quads = []
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        mij, mik = mid[tuple(sorted((i, j)))], mid[tuple(sorted((i, k)))]
        quads.append(np.stack([_CORNERS[i], mij, c, mik], axis=1))
    return quads


def _surface_grid(corners: np.ndarray, n: int) -> np.ndarray:
    """(3, n+1, n+1) nodes of a block: bilinear in its corners, projected on the sphere."""
    s = np.linspace(0.0, 1.0, n + 1)
    u, v = np.meshgrid(s, s, indexing="ij")
    p0, p1, p2, p3 = (corners[:, m][:, None, None] for m in range(4))
    pts = (1 - u) * (1 - v) * p0 + u * (1 - v) * p1 + u * v * p2 + (1 - u) * v * p3
    return pts / np.linalg.norm(pts, axis=0)


def octant_sphere_mesh(a: float, b: float, n: int, n_radial: int) -> skfem.MeshHex:
    """The octant of the shell a ≤ ρ ≤ b: 3 n² cells per shell, ``n_radial`` shells."""
    if n < 1 or n_radial < 1:
        raise ValueError(f"n and n_radial must be >= 1, got n={n}, n_radial={n_radial}")
    radii = np.linspace(a, b, n_radial + 1)
    pts, cells = [], []
    offset = 0
    for corners in _blocks():
        surf = _surface_grid(corners, n).reshape(3, -1)  # index i * (n+1) + j
        m = surf.shape[1]
        pts.append((surf[:, None, :] * radii[None, :, None]).reshape(3, -1))  # shell-major
        i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
        q = np.stack([i * (n + 1) + j, (i + 1) * (n + 1) + j, (i + 1) * (n + 1) + j + 1,
                      i * (n + 1) + j + 1]).reshape(4, -1)  # fmt: skip
        for k in range(n_radial):
            lower, upper = offset + k * m + q, offset + (k + 1) * m + q
            cells.append(np.vstack([lower, upper]))
        offset += m * (n_radial + 1)
    p = np.hstack(pts)
    t = np.hstack(cells)
    # merge the nodes the blocks share (on their common edges)
    key = np.round(p / (1e-9 * b)).astype(np.int64)
    _, first, inverse = np.unique(key, axis=1, return_index=True, return_inverse=True)
    p, t = p[:, first], inverse.ravel()[t]
    p[np.abs(p) < 1e-12 * b] = 0.0
    # skfem's hexahedron: the bottom face (0, 1, 2, 3)... ordered as MeshHex expects
    t = _skfem_order(p, t)
    return skfem.MeshHex(p, t)


def _skfem_order(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Reorder cells given as (bottom quad 0-1-2-3, top quad 4-5-6-7) into scikit-fem's
    hexahedron numbering, with a positive Jacobian."""
    ref = skfem.MeshHex.init_tensor(np.array([0.0, 1.0]), np.array([0.0, 1.0]),
                                    np.array([0.0, 1.0]))  # fmt: skip
    x = ref.p[:, ref.t[:, 0]]  # the reference cell's corners in scikit-fem's order
    # corner c of our ordering at (ξ, η, ζ): 0 (0,0,0) 1 (1,0,0) 2 (1,1,0) 3 (0,1,0), then ζ = 1
    ours = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                     [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=float).T  # fmt: skip
    perm = [int(np.argmin(np.linalg.norm(ours - x[:, k][:, None], axis=0))) for k in range(8)]
    out = t[perm]
    # a left-handed cell (the block's orientation): mirror ξ ↔ η
    e0 = p[:, out[1]] - p[:, out[0]]
    jac = np.einsum("ij,ij->j", np.cross(e0.T, (p[:, out[3]] - p[:, out[0]]).T).T,
                    p[:, out[4]] - p[:, out[0]])  # fmt: skip
    if np.any(jac < 0):
        swap = jac < 0
        mirror = [int(np.argmin(np.linalg.norm(ours[[1, 0, 2]] - x[:, k][:, None], axis=0)))
                  for k in range(8)]  # fmt: skip
        out[:, swap] = t[mirror][:, swap]
    return out
