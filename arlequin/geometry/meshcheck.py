"""Validation of meshes on entry: what would otherwise give silently wrong results.

:func:`check_mesh` refuses, with a :class:`MeshError` naming the node or the cell,

* non-finite node coordinates;
* nodes used by no cell (they would hold dofs with no stiffness and no mass);
* cells of zero measure (degenerate);
* folded cells: a quadrilateral or hexahedron whose Jacobian changes sign inside it, or two
  cells on the same side of the facet they share (a mesh folded over itself; the orientation
  of the cells may vary, as in scikit-fem's refined triangles);
* coincident nodes: two distinct nodes at the same place split the cells around them into
  pieces that are not connected (a seam), unless ``allow_seams=True`` (an intended crack).

Everything is vectorised over the cells; coincident nodes are found with a KD-tree. It is a pure
helper (no Arlequin concept), so models call it on their meshes.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree
from skfem import Mesh

from .facets import facet_coordinates, facet_normals
from .reference import reference_element

__all__ = ["MeshError", "check_mesh", "corner_jacobians"]


class MeshError(ValueError):
    """A mesh is unusable as given (the message names the node or cell and a fix)."""


def corner_jacobians(mesh: Mesh) -> np.ndarray:
    """det of the isoparametric map's Jacobian at every vertex of every cell, (n_v, n_cells).

    Simplices: the constant det of the edge vectors; quadrilaterals and hexahedra: the det at
    each corner from the edges meeting there (in the reference element's axis order).
    """
    ref = reference_element(mesh)
    x = mesh.p[:, mesh.t]  # (dim, n_v, n_cells)
    dim, n_v = x.shape[0], x.shape[1]
    if ref.simplex:
        if dim == 1:
            det = x[0, 1] - x[0, 0]
        else:
            det = np.linalg.det(np.moveaxis(x[:, 1:] - x[:, :1], (0, 1), (-1, -2)))
        return np.broadcast_to(det, (n_v, x.shape[2])).copy()
    v = ref.vertices  # (n_v, dim), corners of the unit square / cube
    out = np.empty((n_v, x.shape[2]))
    for a in range(n_v):
        edges = []
        for k in range(dim):
            target = v[a].copy()
            target[k] = 1.0 - target[k]
            b = int(np.nonzero(np.all(v == target, axis=1))[0][0])
            # the edge along reference axis k, oriented along +k
            edges.append((x[:, b] - x[:, a]) * (1.0 if target[k] > v[a, k] else -1.0))
        # rows: coordinates, columns: the edges; one matrix per cell -> (n_cells, dim, dim)
        out[a] = np.linalg.det(np.moveaxis(np.stack(edges, axis=-1), 1, 0))
    return out


def check_mesh(mesh: Mesh, what: str = "mesh", allow_seams: bool = False) -> None:
    """Raise :class:`MeshError` if the mesh has one of the defects of the module docstring.

    Parameters
    ----------
    mesh : skfem.Mesh
        A first-order mesh (coordinates in m).
    what : str
        Name of the mesh in the message (``"the patch mesh"``...).
    allow_seams : bool
        Accept coincident nodes (a crack or an interface meant to be open).
    """
    p = np.asarray(mesh.p, dtype=float)
    bad = np.nonzero(~np.all(np.isfinite(p), axis=0))[0]
    if bad.size:
        raise MeshError(
            f"{what}: node {int(bad[0])} has non-finite coordinates {p[:, bad[0]].tolist()} "
            f"({bad.size} such nodes)"
        )
    used = np.zeros(p.shape[1], dtype=bool)
    used[mesh.t.ravel()] = True
    if not used.all():
        k = int(np.nonzero(~used)[0][0])
        raise MeshError(
            f"{what}: node {k} at x = {p[:, k].tolist()} is used by no cell "
            f"({int((~used).sum())} unused nodes): remove them (mesh.remove_unused_nodes())"
        )
    jac = corner_jacobians(mesh)  # (n_v, n_cells)
    size = np.max(np.ptp(p, axis=1)) if p.shape[1] > 1 else 1.0
    tiny = 1e-12 * size ** mesh.dim()
    degenerate = np.all(np.abs(jac) <= tiny, axis=0) | (np.max(np.abs(jac), axis=0) <= tiny)
    if degenerate.any():
        c = int(np.nonzero(degenerate)[0][0])
        raise MeshError(
            f"{what}: cell {c} (nodes {mesh.t[:, c].tolist()}) has zero measure "
            f"({int(degenerate.sum())} degenerate cells)"
        )
    sign = np.sign(jac)
    folded = np.any(sign != sign[:1], axis=0)
    if folded.any():
        c = int(np.nonzero(folded)[0][0])
        raise MeshError(
            f"{what}: cell {c} (nodes {mesh.t[:, c].tolist()}) is folded: its Jacobian changes "
            f"sign inside it ({int(folded.sum())} such cells)"
        )
    # a mesh folded over itself: two cells sharing a facet lie on the same side of it
    inner = np.nonzero(mesh.f2t[1] >= 0)[0]
    if inner.size:
        xf = np.transpose(facet_coordinates(mesh, inner), (2, 0, 1))  # (dim, n_f, n_v)
        mid = xf.mean(axis=2)
        if mesh.dim() == 1:
            n = np.ones((1, inner.size))
        else:
            n, _ = facet_normals(xf)
        c0 = p[:, mesh.t[:, mesh.f2t[0, inner]]].mean(axis=1)
        c1 = p[:, mesh.t[:, mesh.f2t[1, inner]]].mean(axis=1)
        same = np.sum(n * (c0 - mid), axis=0) * np.sum(n * (c1 - mid), axis=0) > 0.0
        if same.any():
            f = int(inner[np.nonzero(same)[0][0]])
            a, b = (int(c) for c in mesh.f2t[:, f])
            raise MeshError(
                f"{what}: cells {a} and {b} overlap across their common facet {f}: the mesh is "
                f"folded over itself ({int(same.sum())} such facets)"
            )
    if not allow_seams:
        h = np.min(np.abs(jac)) ** (1.0 / mesh.dim())
        pairs = cKDTree(p.T).query_pairs(r=1e-9 * max(h, 1e-300), output_type="ndarray")
        if pairs.size:
            i, j = (int(v) for v in pairs[0])
            raise MeshError(
                f"{what}: nodes {i} and {j} coincide at x = {p[:, i].tolist()} "
                f"({len(pairs)} such pairs): a seam disconnects the cells around them; merge "
                "them (mesh.remove_duplicate_nodes()), or pass allow_seams=True for an "
                "intended crack"
            )
