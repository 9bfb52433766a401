"""Bounded-memory point location in first-order scikit-fem meshes.

scikit-fem's ``Mesh.element_finder`` builds dense (points × candidates) work arrays that can need
tens of GB for realistic transfer problems. :func:`locate_points` instead

1. queries a :class:`scipy.spatial.cKDTree` of cell centroids for the ``k`` nearest centroids of
   each point, with ``k`` escalated (8, 32, 128, 512, then ×4 up to the number of cells) only for
   the points not yet found;
2. discards candidates whose centroid is farther from the point than the cell's reach (the
   radius of its vertex ball plus the boundary tolerance) — such a cell can neither contain the
   point nor lie within the tolerance of it; this also tells when the escalation can stop: once
   the ``k``-th centroid is beyond the largest reach, every relevant cell has been examined;
3. runs an exact inclusion test on the remaining (point, candidate) pairs: closed-form
   barycentric coordinates for lines, triangles and tetrahedra, Newton inversion of the
   isoparametric map (to 1e-12) for bilinear quadrilaterals and trilinear hexahedra.

Work arrays hold at most ``chunk_size × k_candidates[0]`` (point, candidate) pairs, whatever
``k`` the escalation reaches (the points of later rounds are processed in smaller batches).

Points outside every cell but within ``tol × h`` of the nearest cell (``h`` its diameter) are
accepted and evaluated in that cell with *unclipped* reference coordinates, i.e. the
isoparametric map is extrapolated: this is what a faceted mesh of a curved boundary needs when a
finer patch's nodes lie on the true boundary.

Distances from a point to a cell are exact for lines, triangles, tetrahedra and (planar)
quadrilaterals: the closest point of each face of the simplex (or each edge of the quadrilateral)
is found by projecting onto every sub-simplex and keeping the feasible projections. For
hexahedra each (generally non-planar, bilinear) face is split along a diagonal into two
triangles, so the distance is exact for planar faces and otherwise accurate to the face warping.

Size: one concept (the bounded locator: candidates, inclusion tests, distances, the outside
points) whose pieces share the work-array bounds; splitting it would scatter that invariant.
"""

from __future__ import annotations

import itertools
import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree
from skfem import Mesh

from .facets import cyclic_quad_faces
from .reference import (
    ReferenceElement,
    _inverse_small,
    reference_element,
    shape_functions,
    shape_gradients,
)

__all__ = ["LocateResult", "cell_centroids", "cell_sizes", "locate_points"]

logger = logging.getLogger(__name__)

_INSIDE_EPS = 1e-10  # tolerance on reference / barycentric coordinates for inclusion
_NEWTON_TOL = 1e-12  # Newton step tolerance (reference coordinates)
_NEWTON_MAX_ITER = 30


@dataclass(frozen=True, eq=False)
class LocateResult:
    """Cells and reference coordinates of located points.

    Attributes
    ----------
    cells : ndarray of int64, shape (n_points,)
        Containing (or, for points accepted within the tolerance, nearest) cell; ``-1`` for
        points outside the mesh beyond the tolerance.
    ref : ndarray, shape (dim, n_points)
        Reference coordinates in ``cells`` (unclipped, i.e. slightly outside the reference
        domain for points accepted within the tolerance); ``nan`` where ``cells == -1``.
    inside : ndarray of bool, shape (n_points,)
        Point lies in a cell (reference coordinates within 1e-10 of the reference domain).
    found : ndarray of bool, shape (n_points,)
        ``inside`` or accepted within ``tol × h`` of its nearest cell.
    distance : ndarray, shape (n_points,)
        Distance (m) from the point to the nearest cell (0 for inside points; always finite).
        Exact for points within reach of some cell; points far from the mesh get the distance
        to the cell of the nearest centroid, an upper bound of their distance to the mesh.
    points : ndarray, shape (dim, n_points)
        The located points (m).
    tolerance : ndarray, shape (n_points,)
        Absolute acceptance distance ``tol × h`` (m) of each point's nearest cell (0 for inside
        points).
    tol : float
        Relative tolerance used.
    """

    cells: np.ndarray
    ref: np.ndarray
    inside: np.ndarray
    found: np.ndarray
    distance: np.ndarray
    points: np.ndarray
    tolerance: np.ndarray
    tol: float

    @property
    def n_outside(self) -> int:
        """Number of points not found (outside beyond the tolerance)."""
        return int(np.count_nonzero(~self.found))

    def raise_if_outside(self, what: str = "point") -> None:
        """Raise ``ValueError`` if any point lies outside the mesh beyond the tolerance.

        Parameters
        ----------
        what : str
            Name of the points for the message (e.g. ``"evaluation point"``).
        """
        n_out = self.n_outside
        if n_out == 0:
            return
        i = int(np.nonzero(~self.found)[0][0])
        raise ValueError(
            f"{n_out} {what}(s) of {self.found.size} lie outside the mesh beyond the boundary "
            f"tolerance; first: {what} {i} at x = {self.points[:, i].tolist()}, distance "
            f"{self.distance[i]:.4g} m to the nearest cell > tolerance {self.tolerance[i]:.4g} m "
            f"(tol = {self.tol:g} × local cell size)"
        )


def cell_centroids(mesh: Mesh) -> np.ndarray:
    """Vertex average of each cell (the image of the reference centre for Q1 cells).

    Returns
    -------
    ndarray, shape (dim, n_cells)
        Centroids (m).
    """
    return mesh.p[:, mesh.t].mean(axis=1)


def cell_sizes(mesh: Mesh) -> np.ndarray:
    """Cell diameters: the largest distance between two vertices of each cell.

    Returns
    -------
    ndarray, shape (n_cells,)
        Diameters (m).
    """
    x = mesh.p[:, mesh.t]  # (dim, n_nodes, n_cells)
    h = np.zeros(mesh.t.shape[1])
    for i, j in itertools.combinations(range(mesh.t.shape[0]), 2):  # <= 28 vertex pairs
        h = np.maximum(h, np.linalg.norm(x[:, i] - x[:, j], axis=0))
    return h


def _as_points(mesh: Mesh, points: np.ndarray) -> np.ndarray:
    dim = mesh.dim()
    x = np.asarray(points, dtype=float)
    if x.ndim == 1:
        x = x.reshape(1, -1) if dim == 1 else x[:, None]
    if x.ndim != 2 or x.shape[0] != dim:
        got = x.shape[0] if x.ndim == 2 else x.ndim
        raise ValueError(
            f"points have dimension {got} (shape {np.shape(points)}) but the mesh is {dim}D; "
            f"pass points as an array of shape ({dim}, n_points)"
        )
    if not np.all(np.isfinite(x)):
        k = int(np.nonzero(~np.all(np.isfinite(x), axis=0))[0][0])
        raise ValueError(f"points contain NaN or inf values (first at column {k}: {x[:, k]})")
    return x


class _Locator:
    """Per-mesh data shared by the batches of one :func:`locate_points` call."""

    def __init__(self, mesh: Mesh, tol: float):
        self.mesh = mesh
        self.ref_el: ReferenceElement = reference_element(mesh)
        self.dim = mesh.dim()
        self.n_cells = mesh.nelements
        self.xc = mesh.p[:, mesh.t]  # (dim, n_nodes, n_cells) vertex coordinates
        centroids = self.xc.mean(axis=1)
        self.h = cell_sizes(mesh)
        radius = np.linalg.norm(self.xc - centroids[:, None, :], axis=0).max(axis=0)
        # a cell can contain a point, or lie within tol*h of it, only if |x - centroid| <= reach
        self.reach = radius + (tol + 1e-8) * self.h
        self.max_reach = float(self.reach.max())
        self.tree = cKDTree(centroids.T)
        if self.ref_el.simplex:
            # x = v0 + A xi with A = [v1 - v0, ..., vd - v0]
            a = np.transpose(self.xc[:, 1:, :] - self.xc[:, :1, :], (2, 0, 1))
            self.a_inv, det = _inverse_small(a)
            scale = np.abs(a).max(axis=(1, 2)) ** self.dim
            self.degenerate = ~(np.abs(det) > 1e-14 * scale)
        self.pieces = _boundary_subsets(self.ref_el)

    # ---------------------------------------------------------------- reference coordinates
    def reference_coordinates(
        self, x: np.ndarray, cells: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Invert the cell maps for (point, cell) pairs.

        Parameters
        ----------
        x : ndarray, shape (dim, n_pairs)
        cells : ndarray of int, shape (n_pairs,)

        Returns
        -------
        ref : ndarray, shape (dim, n_pairs)
        ok : ndarray of bool, shape (n_pairs,)
            Inversion succeeded (non-degenerate cell; Newton converged).
        """
        if self.ref_el.simplex:
            ref = np.einsum("nde,en->dn", self.a_inv[cells], x - self.xc[:, 0, cells])
            ok = ~self.degenerate[cells]
            return np.where(ok, ref, np.nan), ok
        return self._newton(x, cells)

    def _newton(self, x: np.ndarray, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n = cells.size
        xi = np.full((self.dim, n), 0.5)
        ok = np.zeros(n, dtype=bool)
        active = np.arange(n)
        xv = self.xc[:, :, cells]  # (dim, n_nodes, n)
        # round-off floor of the residual: coordinates magnitude times machine epsilon
        floor = 8.0 * np.finfo(float).eps * (np.abs(x).max(axis=0) + self.h[cells])
        for _ in range(_NEWTON_MAX_ITER):
            if active.size == 0:
                break
            xa, xia, xva = x[:, active], xi[:, active], xv[:, :, active]
            phi = shape_functions(self.mesh, xia)
            dphi = shape_gradients(self.mesh, xia)
            res = np.einsum("din,in->dn", xva, phi) - xa
            jac = np.einsum("din,ein->nde", xva, dphi)
            inv, det = _inverse_small(jac)
            with np.errstate(invalid="ignore"):
                step = -np.einsum("nde,en->dn", inv, res)
            step_norm = np.abs(step).max(axis=0)
            small_res = np.abs(res).max(axis=0) <= floor[active]
            good = np.isfinite(step_norm) & (det != 0.0)
            xi[:, active] = np.where(good, xia + step, xia)
            done = good & ((step_norm <= _NEWTON_TOL) | small_res)
            ok[active[done]] = True
            # drop converged pairs, failed ones (singular Jacobian) and runaway iterates
            diverged = ~good | (np.abs(xi[:, active]).max(axis=0) > 1e3)
            active = active[~(done | diverged)]
        return np.where(ok, xi, np.nan), ok

    # ---------------------------------------------------------------- distances
    def distance(self, x: np.ndarray, cells: np.ndarray) -> np.ndarray:
        """Distance (m) from points to cells, for (point, cell) pairs.

        Minimum over the sub-simplices (vertices, edges, faces, and for simplices the cell
        itself) of the cell or its faceted boundary of the distance to their affine-hull
        projection, among projections falling inside the sub-simplex (the vertices always do).

        Parameters
        ----------
        x : ndarray, shape (dim, n_pairs)
        cells : ndarray of int, shape (n_pairs,)

        Returns
        -------
        ndarray, shape (n_pairs,)
        """
        best = np.full(cells.size, np.inf)
        xv = self.xc[:, :, cells]  # (dim, n_nodes, n)
        for subset in self.pieces:
            v0 = xv[:, subset[0], :]
            r = x - v0
            if len(subset) == 1:
                d = np.linalg.norm(r, axis=0)
            else:
                e = np.stack([xv[:, j, :] - v0 for j in subset[1:]], axis=0)  # (m, dim, n)
                g = np.einsum("adn,bdn->nab", e, e)
                rhs = np.einsum("adn,dn->na", e, r)
                g_inv, det = _inverse_small(g)
                scale = np.abs(g).max(axis=(1, 2)) ** g.shape[1]
                with np.errstate(invalid="ignore"):
                    c = np.einsum("nab,nb->an", g_inv, rhs)  # (m, n)
                    feasible = (
                        (np.abs(det) > 1e-14 * scale)
                        & np.all(c >= 0.0, axis=0)
                        & (c.sum(axis=0) <= 1.0)
                    )
                    d = np.linalg.norm(r - np.einsum("adn,an->dn", e, c), axis=0)
                d = np.where(feasible, d, np.inf)
            np.minimum(best, d, out=best)
        return best


def _boundary_subsets(ref_el: ReferenceElement) -> list[tuple[int, ...]]:
    """Vertex subsets (sub-simplices) whose union is the cell (simplex) or its faceted boundary.

    Simplices: every non-empty subset of the vertices (the cell itself included, which makes
    the distance of an interior point 0). Quadrilaterals: vertices and the 4 edges (the cell is
    a planar polygon). Hexahedra: vertices, edges and face diagonals, and the two triangles of
    each face split along a diagonal.
    """
    n = ref_el.n_nodes
    if ref_el.simplex:
        pieces = [tuple(range(n))]
    else:
        v = ref_el.vertices
        if ref_el.dim == 2:
            order = [0, 1, 2, 3]
            pieces = [(order[i], order[(i + 1) % 4]) for i in range(4)]
        else:
            pieces = []
            for axis, side in itertools.product(range(3), (0.0, 1.0)):
                face = [i for i in range(n) if v[i, axis] == side]
                face = cyclic_quad_faces(v.T, np.array(face)[:, None])[:, 0].tolist()
                pieces += [(face[0], face[1], face[2]), (face[0], face[2], face[3])]
    subsets: set[tuple[int, ...]] = set()
    for piece in pieces:
        for m in range(1, len(piece) + 1):
            subsets.update(tuple(sorted(s)) for s in itertools.combinations(piece, m))
    return sorted(subsets, key=lambda s: (len(s), s))


def _first_per_point(point_idx: np.ndarray, n: int) -> np.ndarray:
    """Index of the first pair of each point (pairs sorted by point), -1 if none; shape (n,)."""
    first = np.full(n, -1, dtype=np.int64)
    uniq, idx = np.unique(point_idx, return_index=True)
    first[uniq] = idx
    return first


def locate_points(
    mesh: Mesh,
    points: np.ndarray,
    tol: float = 0.05,
    chunk_size: int = 50_000,
    k_candidates: Sequence[int] = (8, 32, 128, 512),
) -> LocateResult:
    """Find the cell and reference coordinates of each point.

    Parameters
    ----------
    mesh : skfem.Mesh
        First-order ``MeshLine``, ``MeshTri``, ``MeshQuad``, ``MeshTet`` or ``MeshHex``.
    points : ndarray, shape (dim, n_points) or (dim,)
        Physical points (m), scikit-fem convention (for a 1D mesh a flat array is a row of
        points).
    tol : float
        Points outside the mesh but within ``tol × h`` of their nearest cell (``h`` its
        diameter) are accepted and evaluated in that cell by extrapolation; 0 accepts only
        points inside (up to round-off).
    chunk_size : int
        Number of points per batch in the first round; work arrays hold at most
        ``chunk_size × k_candidates[0]`` (point, candidate) pairs.
    k_candidates : sequence of int
        Increasing numbers of nearest centroids tried for the points not yet found; after the
        last one, ``k`` keeps growing ×4 (up to the number of cells) for the few points that
        may still be inside or near a cell (graded meshes), so the search is exhaustive.

    Returns
    -------
    LocateResult
        Arrays of length n_points (1 for a single point).

    Raises
    ------
    ValueError
        Unsupported mesh type, dimension mismatch, non-finite points, invalid parameters.
    """
    x = _as_points(mesh, points)
    if not (np.isfinite(tol) and tol >= 0.0):
        raise ValueError(f"tol must be a finite non-negative number, got tol={tol}")
    if chunk_size < 1:
        raise ValueError(f"chunk_size must be a positive integer, got chunk_size={chunk_size}")
    ks = [int(k) for k in k_candidates]
    if not ks or min(ks) < 1 or any(b <= a for a, b in itertools.pairwise(ks)):
        raise ValueError(f"k_candidates must be increasing positive integers, got {k_candidates}")
    if mesh.nelements == 0:
        raise ValueError("cannot locate points in a mesh without cells")

    loc = _Locator(mesh, float(tol))
    dim, n = x.shape
    cells = np.full(n, -1, dtype=np.int64)
    ref = np.full((dim, n), np.nan)
    inside = np.zeros(n, dtype=bool)
    distance = np.zeros(n)
    tolerance = np.zeros(n)
    budget = chunk_size * ks[0]

    pending = np.arange(n)
    k = ks[0]
    level = 0
    while pending.size:
        k = min(k, loc.n_cells)
        final = k >= loc.n_cells
        batch = max(1, budget // k)
        unresolved = []
        for start in range(0, pending.size, batch):
            idx = pending[start : start + batch]
            out = (cells, ref, inside, distance, tolerance)
            unresolved.append(_locate_batch(loc, x, idx, k, final, float(tol), out))
        pending = np.concatenate(unresolved) if unresolved else pending[:0]
        if pending.size:
            logger.debug("locate_points: %d point(s) retried with k > %d", pending.size, k)
        level += 1
        k = ks[level] if level < len(ks) else 4 * k
    found = cells >= 0
    return LocateResult(
        cells=cells,
        ref=ref,
        inside=inside,
        found=found,
        distance=distance,
        points=x,
        tolerance=tolerance,
        tol=float(tol),
    )


def _locate_batch(
    loc: _Locator,
    x: np.ndarray,
    idx: np.ndarray,
    k: int,
    final: bool,
    tol: float,
    out: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
) -> np.ndarray:
    """Locate the points ``x[:, idx]`` among their ``k`` nearest centroids.

    Writes the results of the points it settles into the output arrays
    ``out = (cells, ref, inside, distance, tolerance)`` (in place) and returns the indices of
    the points that need a larger ``k``.
    """
    cells, ref, inside = out[:3]
    nb = idx.size
    xb = x[:, idx]
    dist, cand = loc.tree.query(xb.T, k=k, distance_upper_bound=loc.max_reach)
    dist = dist.reshape(nb, k)
    cand = cand.reshape(nb, k)
    valid = cand < loc.n_cells
    valid[valid] = dist[valid] <= loc.reach[cand[valid]]
    rp_all = np.full((loc.dim, nb, k), np.nan)
    ok_all = np.zeros((nb, k), dtype=bool)
    hit = np.zeros(nb, dtype=bool)
    # candidates by increasing centroid distance, in groups of ranks [0], [1], [2, 4), [4, 8), ...
    # so that most points (inside their nearest-centroid cell) are settled by the first group
    lo = 0
    while lo < k:
        hi = min(k, max(1, 2 * lo))
        pi, ki = np.nonzero(valid[:, lo:hi] & ~hit[:, None])  # sorted by point, then rank
        ki += lo
        pc = cand[pi, ki]
        rp, ok = loc.reference_coordinates(xb[:, pi], pc)
        rp_all[:, pi, ki] = rp
        ok_all[pi, ki] = ok
        contains = ok & loc.ref_el.contains(np.where(ok, rp, -1.0), _INSIDE_EPS)
        # points inside a cell: the first (nearest-centroid) containing candidate
        first = _first_per_point(pi[contains], nb)
        new = first >= 0
        sel = np.nonzero(contains)[0][first[new]]
        cells[idx[new]] = pc[sel]
        ref[:, idx[new]] = rp[:, sel]
        inside[idx[new]] = True
        hit |= new
        lo = hi

    # every cell within reach examined? (fewer than k centroids within the largest reach)
    complete = np.isinf(dist[:, -1]) | final
    retry = ~hit & ~complete
    settle = ~hit & complete
    if np.any(settle):
        pi, ki = np.nonzero(valid & settle[:, None])
        pairs = (pi, cand[pi, ki], rp_all[:, pi, ki], ok_all[pi, ki])
        _settle_outside(loc, xb, idx, settle, pairs, tol, out)
    return idx[retry]


def _settle_outside(
    loc: _Locator,
    xb: np.ndarray,
    idx: np.ndarray,
    settle: np.ndarray,
    pairs: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    tol: float,
    out: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
) -> None:
    """Nearest cell, distance and tolerance test of points outside every candidate cell.

    ``pairs = (point, cell, ref, ok)`` are the examined (point, candidate) pairs of the batch.
    """
    pi, pc, rp, ok = pairs
    cells, ref, _, distance, tolerance = out
    nb = idx.size
    d = loc.distance(xb[:, pi], pc)

    def nearest(key: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pair of smallest ``key`` of each point (ties: nearest centroid), and the mask."""
        order = np.lexsort((key, pi))
        first = _first_per_point(pi[order], nb)
        has = first >= 0
        best = np.full(nb, -1, dtype=np.int64)
        best[has] = order[first[has]]
        return best, has

    # nearest examined cell (reported distance), and nearest cell with a valid inverse map
    best, has = nearest(d)
    best_ok, _ = nearest(np.where(ok, d, np.inf))
    accept = np.zeros(nb, dtype=bool)
    b = best_ok[has]
    accept[has] = ok[b] & (d[b] <= tol * loc.h[pc[b]])
    a = np.nonzero(accept)[0]
    cells[idx[a]] = pc[best_ok[a]]
    ref[:, idx[a]] = rp[:, best_ok[a]]
    distance[idx[a]] = d[best_ok[a]]
    tolerance[idx[a]] = tol * loc.h[pc[best_ok[a]]]

    rejected = settle & ~accept
    near = np.nonzero(rejected & has)[0]
    distance[idx[near]] = d[best[near]]
    tolerance[idx[near]] = tol * loc.h[pc[best[near]]]
    far = np.nonzero(rejected & ~has)[0]
    if far.size:
        # no cell within reach: report the distance to the cell of the nearest centroid
        _, c = loc.tree.query(xb[:, far].T, k=1)
        c = np.asarray(c, dtype=np.int64).reshape(-1)
        distance[idx[far]] = loc.distance(xb[:, far], c)
        tolerance[idx[far]] = tol * loc.h[c]
