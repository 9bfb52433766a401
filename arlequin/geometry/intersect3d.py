"""Exact intersections of two tetrahedral meshes: each pair of overlapping cells' convex
polyhedron, cut into tetrahedra (the integration mesh of a non-nested 3D patch).

Each candidate pair (a fine cell A, a coarse cell B) is first classified from the barycentric
coordinates of each cell's vertices in the other: *separated* when all vertices of one lie on
the outer side of a face plane of the other (no volume in common: most bounding-box candidates),
*contained* when all vertices of one lie in the other (A ∩ B is that cell: one tetrahedron, the
most common case when the fine cells are several times smaller), and *cut* otherwise. Only cut
pairs are clipped:

the vertices of A ∩ B are among 56 candidates: the 4 + 4 vertices of A and B, and the 24 + 24
points where an edge of one crosses a face plane of the other; a candidate is a vertex if it
lies in both cells (barycentric coordinates ≥ −tol). Each face of the polyhedron lies on one
of the 8 face planes: its vertices are the candidates on that plane, ordered by angle about
their centroid, duplicates dropped, and fanned into triangles (a plane both cells have, as on a
common boundary, counted once); each triangle with an apex makes one tetrahedron. The apex is
one of the polyhedron's vertices, so the triangles of the faces through it are flat and
dropped: a convex polyhedron is the cone of its other faces from any of its vertices (a prism
cut from a tetrahedron by one plane gives 3 tetrahedra, against 8 from its centroid).

Everything is vectorised over the pairs, in chunks of :data:`CHUNK` pairs (about 100 MB of
temporaries); the candidate pairs come from a KD-tree on the coarse cells' centroids, filtered
by bounding boxes.
"""

from __future__ import annotations

import itertools

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["CHUNK", "candidate_pairs", "classify_pairs", "tetrahedra_intersections"]

#: Cell pairs intersected at once.
CHUNK = 8000
#: Barycentric tolerance: a candidate within it of a cell's face counts as on it.
TOL = 1e-10
#: Most distinct vertices a face of the intersection of two tetrahedra can have (a triangle
#: clipped by four planes), plus one for safety.
_FACE_MAX = 8

# the 6 edges of a tetrahedron (local vertex pairs)
_EDGES = np.array([[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]])


def candidate_pairs(
    fine_cells: np.ndarray, coarse_cells: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Pairs (fine, coarse) of cells whose bounding boxes overlap.

    Parameters
    ----------
    fine_cells, coarse_cells : ndarray, shape (n, 4, 3)
        The cells' vertex coordinates (m).

    Returns
    -------
    fi, ci : ndarray of int
    """
    c_mid = coarse_cells.mean(axis=1)
    f_mid = fine_cells.mean(axis=1)
    r_c = np.max(np.linalg.norm(coarse_cells - c_mid[:, None], axis=2), axis=1)
    r_f = np.max(np.linalg.norm(fine_cells - f_mid[:, None], axis=2), axis=1)
    tree = cKDTree(c_mid)
    lo_c, hi_c = coarse_cells.min(axis=1), coarse_cells.max(axis=1)
    out_f, out_c = [], []
    # by chunks of fine cells: the KD-tree's lists of candidates (Python lists of Python ints)
    # are the largest objects here, 0.7 GB at 200k fine cells in one query
    for start in range(0, len(fine_cells), _PAIR_CHUNK):
        stop = min(start + _PAIR_CHUNK, len(fine_cells))
        lists = tree.query_ball_point(f_mid[start:stop], r_f[start:stop] + r_c.max() * (1 + 1e-9))
        sizes = np.fromiter(map(len, lists), dtype=np.int64, count=len(lists))
        fi = start + np.repeat(np.arange(len(lists)), sizes)
        ci = np.fromiter(itertools.chain.from_iterable(lists), dtype=np.int64,
                         count=int(sizes.sum()))  # fmt: skip
        del lists
        lo_f, hi_f = fine_cells[fi].min(axis=1), fine_cells[fi].max(axis=1)
        pad = 1e-9 * (hi_f - lo_f).max(axis=1)[:, None]
        keep = np.all((lo_f <= hi_c[ci] + pad) & (lo_c[ci] <= hi_f + pad), axis=1)
        out_f.append(fi[keep])
        out_c.append(ci[keep])
    if not out_f:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.concatenate(out_f), np.concatenate(out_c)


#: Fine cells whose candidate pairs are found at once.
_PAIR_CHUNK = 20_000


def _barycentric_planes(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """λ_k(x) = g_k · x + h_k of tetrahedra v (m, 4, 3): g (m, 4, 3), h (m, 4)."""
    jac = np.transpose(v[:, 1:] - v[:, :1], (0, 2, 1))  # columns v_k − v_0
    inv = np.linalg.inv(jac)  # rows: the gradients of λ_1..λ_3
    h = -np.einsum("mij,mj->mi", inv, v[:, 0])
    g = np.concatenate([-inv.sum(axis=1, keepdims=True), inv], axis=1)
    h = np.concatenate([1.0 - h.sum(axis=1, keepdims=True), h], axis=1)
    return g, h


def _edge_plane_points(v: np.ndarray, lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where the edges of tetrahedra v (m, 4, 3) cross the 4 planes λ_k = 0 whose values at
    v's vertices are lam (m, 4 vertices, 4 planes): points (m, 24, 3) and validity (m, 24)."""
    p0, p1 = v[:, _EDGES[:, 0]], v[:, _EDGES[:, 1]]  # (m, 6, 3)
    l0, l1 = lam[:, _EDGES[:, 0]], lam[:, _EDGES[:, 1]]  # (m, 6, 4)
    den = l0 - l1
    crossing = (l0 * l1 <= 0.0) & (np.abs(den) > 0.0)
    s = np.where(crossing, l0 / np.where(crossing, den, 1.0), 0.0)  # (m, 6, 4)
    pts = p0[:, :, None] + s[..., None] * (p1 - p0)[:, :, None]  # (m, 6, 4, 3)
    return pts.reshape(len(v), 24, 3), crossing.reshape(len(v), 24)


def classify_pairs(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Classify m pairs of tetrahedra a, b (m, 4, 3), see the module docstring.

    Returns
    -------
    ndarray of int8, shape (m,)
        0 separated (no common volume), 1 a inside b, 2 b inside a, 3 cut.
    """
    ga, ha = _barycentric_planes(a)
    gb, hb = _barycentric_planes(b)
    lam_b_at_a = np.einsum("mpj,mkj->mpk", a, gb) + hb[:, None]  # (m, 4 vertices, 4 planes)
    lam_a_at_b = np.einsum("mpj,mkj->mpk", b, ga) + ha[:, None]
    out = np.full(len(a), 3, dtype=np.int8)
    out[np.all(lam_a_at_b >= -TOL, axis=(1, 2))] = 2
    out[np.all(lam_b_at_a >= -TOL, axis=(1, 2))] = 1
    separated = np.any(np.all(lam_b_at_a <= TOL, axis=1), axis=1)
    separated |= np.any(np.all(lam_a_at_b <= TOL, axis=1), axis=1)
    out[separated] = 0
    return out


def _positive(v: np.ndarray) -> np.ndarray:
    """Tetrahedra v (k, 4, 3) with their last two vertices swapped where negatively oriented."""
    e = v[:, 1:] - v[:, :1]
    neg = np.einsum("kj,kj->k", np.cross(e[:, 0], e[:, 1]), e[:, 2]) < 0.0
    v = v.copy()
    v[neg] = v[neg][:, [0, 1, 3, 2]]
    return v


def _chunk(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tetrahedra of A ∩ B for m cut pairs of cells a, b (m, 4, 3): (tets (k, 4, 3), pair (k,))."""
    m = len(a)
    ga, ha = _barycentric_planes(a)
    gb, hb = _barycentric_planes(b)
    lam_b_at_a = np.einsum("mpj,mkj->mpk", a, gb) + hb[:, None]  # (m, 4, 4)
    lam_a_at_b = np.einsum("mpj,mkj->mpk", b, ga) + ha[:, None]
    pa, va = _edge_plane_points(a, lam_b_at_a)
    pb, vb = _edge_plane_points(b, lam_a_at_b)
    pts = np.concatenate([a, b, pa, pb], axis=1)  # (m, 56, 3)
    lam_a = np.einsum("mpj,mkj->mpk", pts, ga) + ha[:, None]  # (m, 56, 4)
    lam_b = np.einsum("mpj,mkj->mpk", pts, gb) + hb[:, None]
    lam = np.concatenate([lam_a, lam_b], axis=2)  # (m, 56, 8 planes)
    valid = np.concatenate([np.ones((m, 8), bool), va, vb], axis=1)
    valid &= np.all(lam >= -TOL, axis=2)
    n_valid = valid.sum(axis=1)
    # the apex of the cones: a vertex of the polyhedron (every valid candidate is one)
    centre = pts[np.arange(m), np.argmax(valid, axis=1)]
    # the faces: candidates on each of the 8 planes
    on = valid[:, :, None] & (np.abs(lam) <= TOL)  # (m, 56, 8)
    on = np.transpose(on, (0, 2, 1))  # (m, 8, 56)
    # a face plane of B that is also one of A (cells sharing a face plane, as on a common
    # boundary) holds the same points: count that face once
    same = np.all(on[:, 4:, None] == on[:, None, :4], axis=3).any(axis=2)  # (m, 4)
    on[:, 4:] &= ~same[..., None]
    normal = np.concatenate([ga, gb], axis=1)  # (m, 8, 3)
    normal /= np.linalg.norm(normal, axis=2, keepdims=True)
    helper = np.where(np.abs(normal[..., :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    e1 = np.cross(normal, helper)
    e1 /= np.linalg.norm(e1, axis=2, keepdims=True)
    e2 = np.cross(normal, e1)
    count = on.sum(axis=2)  # (m, 8)
    face_mid = np.einsum("mfp,mpj->mfj", on.astype(float), pts) / np.maximum(count, 1)[..., None]
    rel = pts[:, None] - face_mid[:, :, None]  # (m, 8, 56, 3)
    ang = np.arctan2(np.einsum("mfpj,mfj->mfp", rel, e2), np.einsum("mfpj,mfj->mfp", rel, e1))
    ang = np.where(on, ang, np.inf)
    order = np.argsort(ang, axis=2, kind="stable")
    sorted_pts = np.take_along_axis(pts[:, None], order[..., None], axis=2)  # (m, 8, 56, 3)
    sorted_on = np.take_along_axis(on, order, axis=2)
    # drop consecutive duplicates (coincident candidates sort next to each other)
    scale = np.max(np.linalg.norm(a - a.mean(axis=1, keepdims=True), axis=2), axis=1)
    gap = np.linalg.norm(np.diff(sorted_pts, axis=2), axis=3)  # (m, 8, 55)
    fresh = np.concatenate([sorted_on[..., :1], sorted_on[..., 1:] & (gap > 1e-9
                                                                      * scale[:, None, None])],
                           axis=2)  # fmt: skip
    pick = np.argsort(~fresh, axis=2, kind="stable")[..., :_FACE_MAX]
    face = np.take_along_axis(sorted_pts, pick[..., None], axis=2)  # (m, 8, K, 3)
    n_face = np.minimum(fresh.sum(axis=2), _FACE_MAX)  # (m, 8)
    j = np.arange(1, _FACE_MAX - 1)
    tri_ok = (j[None, None, :] + 1 < n_face[..., None]) & (n_valid >= 4)[:, None, None]
    q0 = np.broadcast_to(face[:, :, :1], (m, 8, j.size, 3))
    q1, q2 = face[:, :, j], face[:, :, j + 1]
    c = np.broadcast_to(centre[:, None, None], q0.shape)
    tets = np.stack([c, q0, q1, q2], axis=3)  # (m, 8, K−2, 4, 3)
    vol = np.einsum("mftj,mftj->mft", np.cross(q1 - c, q2 - c), q0 - c) / 6.0
    cell_vol = np.abs(np.linalg.det(np.transpose(a[:, 1:] - a[:, :1], (0, 2, 1)))) / 6.0
    keep = tri_ok & (np.abs(vol) > 1e-12 * cell_vol[:, None, None])
    pair = np.broadcast_to(np.arange(m)[:, None, None], keep.shape)[keep]
    tets, vol = tets[keep], vol[keep]
    flip = vol < 0.0
    tets[flip] = tets[flip][:, [0, 1, 3, 2]]
    return tets, pair


def tetrahedra_intersections(fine_cells: np.ndarray, coarse_cells: np.ndarray,
                             pairs: tuple[np.ndarray, np.ndarray] | None = None,
                             backend: str = "numba",
                             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """The tetrahedra of every non-empty intersection of a fine and a coarse cell.

    Parameters
    ----------
    fine_cells, coarse_cells : ndarray, shape (n, 4, 3)
        Vertex coordinates (m) of the two meshes' tetrahedra.
    pairs : (ndarray of int, ndarray of int), optional
        The candidate pairs (fine, coarse) to intersect; default :func:`candidate_pairs`.
    backend : {"numba", "numpy"}
        The cut pairs clipped by the compiled kernel (:mod:`arlequin.geometry.clip3d`) or by the
        numpy path of this module (its reference: the same pieces, tetrahedralised alike).

    Returns
    -------
    tets : ndarray, shape (k, 4, 3)
        Positively oriented tetrahedra (m) tiling the intersections.
    fine, coarse : ndarray of int, shape (k,)
        The fine and the coarse cell each lies in.
    """
    if backend not in ("numba", "numpy"):
        raise ValueError(f"backend must be 'numba' or 'numpy', got {backend!r}")
    clip = _chunk
    if backend == "numba":
        from .clip3d import clip_pairs

        def clip(a, b):
            return clip_pairs(a, b, TOL)

    fi, ci = candidate_pairs(fine_cells, coarse_cells) if pairs is None else pairs
    out_t, out_f, out_c = [], [], []
    for start in range(0, fi.size, 4 * CHUNK):
        f, c = fi[start : start + 4 * CHUNK], ci[start : start + 4 * CHUNK]
        kind = classify_pairs(fine_cells[f], coarse_cells[c])
        for which, cells in ((1, fine_cells), (2, coarse_cells)):  # one cell inside the other
            sel = kind == which
            out_t.append(_positive(cells[f[sel] if which == 1 else c[sel]]))
            out_f.append(f[sel])
            out_c.append(c[sel])
        cut = kind == 3
        f, c = f[cut], c[cut]
        for lo in range(0, f.size, CHUNK):
            fc, cc = f[lo : lo + CHUNK], c[lo : lo + CHUNK]
            tets, pair = clip(fine_cells[fc], coarse_cells[cc])
            out_t.append(tets)
            out_f.append(fc[pair])
            out_c.append(cc[pair])
    if not out_t:
        return np.zeros((0, 4, 3)), np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.concatenate(out_t), np.concatenate(out_f), np.concatenate(out_c)
