"""Boundary geometry: boundary facets as coordinates, and distances from points to facet sets.

Distances are exact (to round-off) for the faceted geometry: 1D by sorted search, 2D by shapely's
STRtree nearest-segment query, 3D by trimesh's closest-point query on the triangulated facets.
Points are given in scikit-fem's convention, shape (dim, n_points), in m.
"""

from __future__ import annotations

import numpy as np
from skfem import Mesh, MeshHex, MeshQuad

__all__ = ["boundary_distance", "distance_to_facets", "facet_coordinates"]


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
        f = _cyclic_quad_faces(mesh.p, f)
    return np.transpose(mesh.p[:, f], (2, 1, 0))


def _cyclic_quad_faces(p: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Reorder the 4 vertices of each quadrilateral face so that they go around the face."""
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


def distance_to_facets(points: np.ndarray, facets: np.ndarray) -> np.ndarray:
    """Euclidean distance from each point to the nearest facet.

    Parameters
    ----------
    points : ndarray, shape (dim, n_points)
    facets : ndarray, shape (n_facets, n_vertices_per_facet, dim)
        Points (1D), segments (2D), triangles or quadrilaterals (3D).

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
    if dim == 2:
        import shapely

        segments = shapely.linestrings(facets)
        tree = shapely.STRtree(segments)
        pts = shapely.points(points.T)
        (ip, _), dist = tree.query_nearest(pts, return_distance=True, all_matches=False)
        out = np.full(n, np.inf)
        out[ip] = dist
        return out
    import trimesh

    if facets.shape[1] == 4:
        tri = np.concatenate([facets[:, [0, 1, 2]], facets[:, [0, 2, 3]]], axis=0)
    else:
        tri = facets
    vertices = tri.reshape(-1, 3)
    faces = np.arange(vertices.shape[0]).reshape(-1, 3)
    surface = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
    _, dist, _ = trimesh.proximity.closest_point(surface, points.T)
    return np.asarray(dist, dtype=float)


def boundary_distance(mesh: Mesh, points: np.ndarray) -> np.ndarray:
    """Distance (m) from points (dim, n) to the boundary of ``mesh``, shape (n,)."""
    return distance_to_facets(points, facet_coordinates(mesh))


def is_quad_like(mesh: Mesh) -> bool:
    """True for tensor-product cells (quadrilaterals, hexahedra)."""
    return isinstance(mesh, MeshQuad | MeshHex)
