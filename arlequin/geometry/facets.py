"""Boundary geometry: boundary facets as coordinates, and distances from points to facet sets.

Distances are exact (to round-off) for the faceted geometry: 1D by sorted search, 2D and 3D by
vectorised point-to-segment / point-to-triangle distances on KD-tree candidates (bounded memory).
Points are given in scikit-fem's convention, shape (dim, n_points), in m.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree
from skfem import Mesh, MeshHex

__all__ = [
    "boundary_distance",
    "cyclic_quad_faces",
    "distance_to_facets",
    "facet_coordinates",
    "facet_normals",
    "outward_normals",
]


def facet_coordinates(mesh: Mesh, facets: np.ndarray | None = None) -> np.ndarray:
    """Vertex coordinates of facets, shape (n_facets, n_vertices_per_facet, dim) (m).

    ``facets`` defaults to the mesh's boundary facets. Facet vertices of quadrilateral faces
    (hexahedral meshes) are returned in cyclic order.
    """
    if facets is None:
        facets = mesh.boundary_facets()
    facets = np.asarray(facets, dtype=np.int64)
    f = mesh.facets[:, facets]
    if isinstance(mesh, MeshHex) and f.shape[0] == 4:
        f = cyclic_quad_faces(mesh.p, f)
    return np.transpose(mesh.p[:, f], (2, 1, 0))


def cyclic_quad_faces(p: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Reorder the 4 vertices of each quadrilateral face so that they go around the face.

    Parameters
    ----------
    p : ndarray, shape (3, n_points)
        Point coordinates.
    f : ndarray of int, shape (4, n_faces)
        Vertex indices of each planar (or nearly planar) quadrilateral face, in any order.

    Returns
    -------
    ndarray of int, shape (4, n_faces)
        The same vertices in cyclic order (by angle about the face centre).
    """
    # scikit-fem stores hex faces with sorted vertex indices; order them by angle about the centre.
    xyz = p[:, f]  # (3, 4, nf)
    c = xyz.mean(axis=1, keepdims=True)
    e1 = xyz[:, 0:1] - c
    n = np.cross(xyz[:, 1] - xyz[:, 0], xyz[:, 2] - xyz[:, 0], axis=0)[:, None]
    e2 = np.cross(n, e1, axis=0)
    rel = xyz - c
    ang = np.arctan2(np.sum(rel * e2, axis=0), np.sum(rel * e1, axis=0))
    order = np.argsort(ang, axis=0)
    return np.take_along_axis(f, order, axis=0)


def _segment_distance(x: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from x to segments [a, b]; arrays (..., dim) broadcast together."""
    ab = b - a
    t = np.einsum("...d,...d->...", x - a, ab) / np.einsum("...d,...d->...", ab, ab)
    t = np.clip(t, 0.0, 1.0)
    return np.linalg.norm(x - a - t[..., None] * ab, axis=-1)


def _triangle_distance(x: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Distance from x to triangles (a, b, c); arrays (..., 3) broadcast together."""
    n = np.cross(b - a, c - a)
    nn = np.einsum("...d,...d->...", n, n)
    s = np.einsum("...d,...d->...", x - a, n) / nn
    y = x - s[..., None] * n  # projection onto the triangle's plane

    def signed(p, q, r):
        return np.einsum("...d,...d->...", np.cross(q - p, r - p), n)

    inside = (signed(y, b, c) >= 0) & (signed(a, y, c) >= 0) & (signed(a, b, y) >= 0)
    edges = np.minimum(
        np.minimum(_segment_distance(x, a, b), _segment_distance(x, b, c)),
        _segment_distance(x, c, a),
    )
    return np.where(inside, np.abs(s) * np.sqrt(nn), edges)


def distance_to_facets(
    points: np.ndarray,
    facets: np.ndarray,
    cap: float | None = None,
    chunk_size: int = 20_000,
) -> np.ndarray:
    """Euclidean distance from each point to the nearest facet.

    Candidates come from a KD-tree over the facet centroids, nearest first, and grow by 4 until
    the distance found is provably the minimum: every facet not yet tested has its centroid at
    least ρ_k away (ρ_k the k-th candidate's centroid distance), hence lies at least ρ_k − R away
    (R the largest centroid-to-vertex distance). Memory is bounded by ``chunk_size`` × k.

    Parameters
    ----------
    points : ndarray, shape (dim, n_points)
    facets : ndarray, shape (n_facets, n_vertices_per_facet, dim)
        Points (1D), segments (2D), triangles or quadrilaterals (3D; split into two triangles).
    cap : float, optional
        Distances are exact where they are ≤ ``cap``; beyond it the returned value is only a
        lower bound that exceeds ``cap`` (enough for weights that saturate at a band width, and
        much cheaper for points far from the facets). Default: exact everywhere.

    Returns
    -------
    ndarray, shape (n_points,)
        Distances (m); ``inf`` if there are no facets.
    """
    points = np.atleast_2d(np.asarray(points, dtype=float))
    dim, n = points.shape
    if facets.shape[0] == 0:
        return np.full(n, np.inf)
    if facets.shape[-1] != dim:
        raise ValueError(f"points are {dim}D but facets are {facets.shape[-1]}D")
    if dim == 1:
        xs = np.sort(facets[:, 0, 0])
        idx = np.searchsorted(xs, points[0])
        lo = xs[np.clip(idx - 1, 0, len(xs) - 1)]
        hi = xs[np.clip(idx, 0, len(xs) - 1)]
        return np.minimum(np.abs(points[0] - lo), np.abs(points[0] - hi))
    if dim == 3 and facets.shape[1] == 4:
        facets = np.concatenate([facets[:, [0, 1, 2]], facets[:, [0, 2, 3]]], axis=0)
    cap = np.inf if cap is None else float(cap)
    x = np.ascontiguousarray(points.T)
    centroids = facets.mean(axis=1)
    radius = float(np.linalg.norm(facets - centroids[:, None, :], axis=2).max())
    tree = cKDTree(centroids)
    n_facets = facets.shape[0]
    out = np.empty(n)
    todo = np.arange(n)
    k = 8
    while todo.size:
        kk = min(k, n_facets)
        pending = []
        for start in range(0, todo.size, chunk_size):
            idx = todo[start : start + chunk_size]
            rho, cand = tree.query(x[idx], k=kk)
            rho = rho.reshape(idx.size, kk)
            cand = cand.reshape(idx.size, kk)
            far = rho[:, 0] - radius > cap
            out[idx[far]] = rho[far, 0] - radius
            idx, rho, cand = idx[~far], rho[~far], cand[~far]
            f = facets[cand]  # (m, kk, n_vertices, dim)
            xp = x[idx][:, None, :]
            if dim == 2:
                d = _segment_distance(xp, f[:, :, 0], f[:, :, 1]).min(axis=1)
            else:
                d = _triangle_distance(xp, f[:, :, 0], f[:, :, 1], f[:, :, 2]).min(axis=1)
            bound = rho[:, -1] - radius
            done = (bound >= d) | (bound > cap) | (kk == n_facets)
            out[idx[done]] = d[done]
            pending.append(idx[~done])
        todo = np.concatenate(pending)
        k *= 4
    return out


def boundary_distance(mesh: Mesh, points: np.ndarray) -> np.ndarray:
    """Distance (m) from points (dim, n) to the boundary of ``mesh``, shape (n,)."""
    return distance_to_facets(points, facet_coordinates(mesh))


def facet_normals(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals (oriented by the vertex order) and measures of facets.

    Parameters
    ----------
    x : ndarray, shape (dim, n_facets, n_vertices)
        Facet vertex coordinates (m); quadrilateral faces in cyclic order.

    Returns
    -------
    normals : ndarray, shape (dim, n_facets)
    measures : ndarray, shape (n_facets,)
        Length (2D), area (3D), 1 (1D points).
    """
    dim, nf, nv = x.shape
    if dim == 1:
        return np.ones((1, nf)), np.ones(nf)
    if dim == 2:
        t = x[:, :, 1] - x[:, :, 0]
        n = np.stack([t[1], -t[0]])
        ln = np.linalg.norm(n, axis=0)
        return n / ln, ln
    if nv == 3:
        n = np.cross(x[:, :, 1] - x[:, :, 0], x[:, :, 2] - x[:, :, 0], axis=0)
        ln = np.linalg.norm(n, axis=0)
        return n / ln, 0.5 * ln
    # quadrilateral: mean normal of the two diagonals' cross product; area of its two triangles
    n = 0.5 * np.cross(x[:, :, 2] - x[:, :, 0], x[:, :, 3] - x[:, :, 1], axis=0)
    e1, e2, e3 = (x[:, :, i] - x[:, :, 0] for i in (1, 2, 3))
    a1 = 0.5 * np.linalg.norm(np.cross(e1, e2, axis=0), axis=0)
    a2 = 0.5 * np.linalg.norm(np.cross(e2, e3, axis=0), axis=0)
    return n / np.linalg.norm(n, axis=0), a1 + a2


def outward_normals(mesh: Mesh, facets: np.ndarray) -> np.ndarray:
    """Unit normals of boundary facets pointing out of the mesh, shape (dim, n_facets).

    Oriented away from the centroid of the cell each facet belongs to (1D: ±1).
    """
    facets = np.asarray(facets, dtype=np.int64)
    x = np.transpose(facet_coordinates(mesh, facets), (2, 0, 1))  # (dim, n_f, n_v)
    mid = x.mean(axis=2)
    cells = mesh.f2t[0, facets]
    centroid = mesh.p[:, mesh.t[:, cells]].mean(axis=1)
    if mesh.dim() == 1:
        n = np.sign(mid - centroid)
    else:
        n, _ = facet_normals(x)
    sign = np.sign(np.sum(n * (mid - centroid), axis=0))
    sign[sign == 0.0] = 1.0
    return n * sign
