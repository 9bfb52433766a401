"""Contact geometry: potential contact surfaces and the pairs that give gaps and velocity jumps.

The collocation points of a contact constraint are the nodes of its slave surface; at each, a
pair gives the signed distance ``d_n`` (m, negative when apart) and the row of the map
``v ↦ [[v_n]]`` (the normal velocity jump, positive when approaching) in the current
configuration. :class:`RigidContactPair`: a surface against a rigid obstacle
(:mod:`arlequin.models.contact.obstacles`); :class:`DeformableContactPair`: slave nodes against
master facets (node-to-node in 1D, point-to-segment in 2D, point-to-facet in 3D). Dofs follow the
layout of :mod:`arlequin.dofs` (``offset + dim * node + component``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
from skfem import Mesh

from arlequin.contract import csr_pattern, csr_with_data, node_dofs
from arlequin.geometry.facets import cyclic_quad_faces, facet_normals

from .kernel import plane_gaps, project_segments, segment_geometry
from .obstacles import Obstacle, PlaneObstacle

__all__ = [
    "ContactGeometry",
    "ContactPair",
    "ContactSurface",
    "DeformableContactPair",
    "RigidContactPair",
]


def _offset(offset: Any) -> int:
    """A block offset from an int or a :class:`arlequin.dofs.DofBlock`."""
    return int(getattr(offset, "offset", offset))


def _n_dofs(n_dofs: Any) -> int:
    """A global dof count from an int, a :class:`arlequin.dofs.DofMap` or a system."""
    return int(getattr(n_dofs, "n_dofs", n_dofs))


class ContactSurface:
    """Potential contact surface of one body: boundary facets of its mesh and its dof offset.

    Parameters
    ----------
    mesh : skfem.Mesh
        First-order mesh of the body (MeshLine, MeshTri/MeshQuad, MeshTet/MeshHex); dofs are
        interleaved by node (``offset + dim * node + component``, as :class:`LinearElastic`).
    facets : array_like of int, optional
        Indices into ``mesh.facets`` (boundary facets). Default: the boundary facets whose
        midpoint satisfies ``where`` (all boundary facets without ``where``).
    where : callable, optional
        Predicate on facet midpoints, shape (dim, n_f) -> (n_f,) bool.
    offset : int or DofBlock
        First global dof of the body: its block offset in a :class:`CoupledSystem`, or the
        block itself (``system.dofmap["name"]``).
    area : float
        Cross-section (m²) of a 1D bar: the weight of its end points.
    axisymmetric : bool
        Weights carry 2πr (meridional (r, z) meshes).

    Attributes
    ----------
    facets : ndarray of int, shape (n_f,)
    facet_nodes : ndarray of int, shape (n_f, n_v)
        Node indices of each facet (quads of 3D meshes in cyclic order).
    nodes : ndarray of int, shape (m,)
        Surface nodes (the collocation points when the surface is a slave).
    weights : ndarray, shape (m,)
        Vertex-quadrature weights of the nodes (m², m, or m² for 1D).
    """

    def __init__(
        self,
        mesh: Mesh,
        facets=None,
        *,
        where: Callable[[np.ndarray], np.ndarray] | None = None,
        offset: Any = 0,
        area: float = 1.0,
        axisymmetric: bool = False,
    ) -> None:
        self.mesh = mesh
        self.dim = int(mesh.p.shape[0])
        self.offset = _offset(offset)
        self.area = float(area)
        if facets is None:
            facets = mesh.boundary_facets()
            if where is not None:
                mid = mesh.p[:, mesh.facets[:, facets]].mean(axis=1)
                facets = facets[np.asarray(where(mid), dtype=bool)]
        facets = np.asarray(facets, dtype=np.int64).ravel()
        if facets.size == 0:
            raise ValueError("contact surface has no facets (check 'facets' or 'where')")
        self.facets = facets
        fn = mesh.facets[:, facets].T.copy()  # (n_f, n_v)
        if self.dim == 3 and fn.shape[1] == 4:
            fn = cyclic_quad_faces(mesh.p, fn.T).T
        self.facet_nodes = fn
        # outward orientation sign of the facet normal computed from the node order
        elem = mesh.f2t[0, facets]
        centroid = mesh.p[:, mesh.t[:, elem]].mean(axis=1)  # (dim, n_f)
        n_ref, _ = facet_normals(_facet_points(mesh.p, fn))
        fmid = _facet_points(mesh.p, fn).mean(axis=2)  # (dim, n_f)
        s = np.sign(np.sum(n_ref * (fmid - centroid), axis=0))
        s[s == 0.0] = 1.0
        self._orient = s
        # vertex-quadrature weights
        nodes, inv = np.unique(fn.ravel(), return_inverse=True)
        self.nodes = nodes
        self._facet_local = inv.reshape(fn.shape)
        if self.dim == 1:
            meas = np.full(facets.size, self.area)
        else:
            meas = _facet_measure(_facet_points(mesh.p, fn))
        nv = fn.shape[1]
        contrib = np.repeat(meas / nv, nv)
        self.axisymmetric = bool(axisymmetric)
        if axisymmetric:
            if self.dim != 2:
                raise ValueError(
                    f"axisymmetric surfaces are meridional (2D), got a {self.dim}D mesh"
                )
            # ∫ N_a 2πr ds on each segment (exact for r linear): 2πℓ(2r_a + r_b)/6; unlike
            # 2πr_a ℓ/2 it is positive at a node on the axis, whose row would be void
            r = mesh.p[0, fn]  # (n_f, 2)
            contrib = (2.0 * np.pi * meas[:, None] * (2.0 * r + r[:, ::-1]) / 6.0).ravel()
        self.weights = np.bincount(inv, contrib, minlength=nodes.size)
        self._dofs = self.node_dofs(nodes)  # (dim, m): the pairs' geometry needs them each step
        self._x_ref = mesh.p[:, nodes]  # (dim, m), likewise

    @property
    def n_points(self) -> int:
        return int(self.nodes.size)

    def node_dofs(self, nodes: np.ndarray) -> np.ndarray:
        """Global dofs of mesh nodes, shape (dim, len(nodes))."""
        return node_dofs(nodes, self.dim, offset=self.offset)

    def positions(self, u: np.ndarray, nodes: np.ndarray | None = None) -> np.ndarray:
        """Current positions X + u of mesh nodes (default: surface nodes), shape (dim, k) (m)."""
        if nodes is None:
            return self._x_ref + u[self._dofs]
        nodes = np.asarray(nodes, dtype=np.int64)
        return self.mesh.p[:, nodes] + u[self.node_dofs(nodes)]


def _facet_points(p: np.ndarray, fn: np.ndarray) -> np.ndarray:
    """Facet vertex coordinates, shape (dim, n_f, n_v)."""
    return p[:, fn]


def _facet_measure(x: np.ndarray) -> np.ndarray:
    return facet_normals(x)[1]


# ---------------------------------------------------------------------------------------------
# contact pairs: the geometry (gaps and velocity-jump rows) at the collocation points
# ---------------------------------------------------------------------------------------------
@dataclass
class ContactGeometry:
    """Gap data at the collocation points in one configuration.

    Attributes
    ----------
    rows : csr_matrix, shape (m, n)
        G: global velocity (m/s) -> normal velocity jump [[v_n]] (m/s) (also du -> dd_n).
    gap : ndarray, shape (m,)
        d_n (m), negative when apart.
    normal : ndarray, shape (dim, m)
        Contact normal (unit), pointing from the obstacle/master into the slave side.
    jump : callable, optional
        ``jump(e)`` for directions e (dim, m): the rows (m, n) of v ↦ e_k·(v_s − v_m) at each
        point, the slave's velocity relative to the obstacle (0) or to the master point it is
        paired with in this configuration (``rows`` is ``jump(−normal)``). Friction uses it with
        the tangents.
    """

    rows: sp.csr_matrix
    gap: np.ndarray
    normal: np.ndarray
    jump: Callable[[np.ndarray], sp.csr_matrix] | None = None


class ContactPair:
    """Base of the contact pairs: a slave surface (its nodes are the collocation points)."""

    slave: ContactSurface
    n_dofs: int
    #: The global dofs the geometry depends on (sorted), or None (a pair that does not say):
    #: a constraint reuses the last geometry when u is unchanged on them.
    geometry_dofs: np.ndarray | None = None

    @property
    def n_points(self) -> int:
        return self.slave.n_points

    @property
    def weights(self) -> np.ndarray:
        """Quadrature weights of the collocation points, shape (m,) (m², or m in plane 2D)."""
        return self.slave.weights

    @property
    def points(self) -> np.ndarray:
        """Reference coordinates of the collocation points, shape (dim, m) (m)."""
        return self.slave.mesh.p[:, self.slave.nodes]

    def geometry(self, u: np.ndarray) -> ContactGeometry:
        """Gaps and rows at displacement ``u`` (m), shape (n,)."""
        raise NotImplementedError


class RigidContactPair(ContactPair):
    """A deformable surface against a rigid :class:`Obstacle`.

    ``d_n = −φ(x)``, normal ``∇φ/|∇φ|``, ``[[v_n]] = −n·v`` at each slave node.

    Parameters
    ----------
    slave : ContactSurface
    obstacle : Obstacle
    n_dofs : int or DofMap
        Size of the global dof vector (or the system's dof map).
    """

    def __init__(self, slave: ContactSurface, obstacle: Obstacle, n_dofs: Any) -> None:
        self.slave = slave
        self.obstacle = obstacle
        self.n_dofs = _n_dofs(n_dofs)
        m, d = slave.n_points, slave.dim
        self._r = np.repeat(np.arange(m), d)
        self._c = slave.node_dofs(slave.nodes).T.ravel()
        self._rows_cache: tuple[np.ndarray, sp.csr_matrix] | None = None
        self.geometry_dofs = np.unique(self._c)
        # each row: a node's d dofs, increasing (node_dofs), no duplicates
        index_dtype = np.int32 if max(self.n_dofs, m * d) < np.iinfo(np.int32).max else np.int64
        self._template = csr_pattern(self._c.astype(index_dtype),
                                     np.arange(0, m * d + 1, d, dtype=index_dtype),
                                     (m, self.n_dofs))  # fmt: skip
        # the velocity-jump rows depend on the reference configuration alone
        self._jump = _JumpRows((self._r, self._c), (m, self.n_dofs))
        # an obstacle whose normal is the same everywhere (a plane): the normals and the rows
        # made once here, the same objects at every step (the integrators' caches keyed on
        # them hold), only φ computed per step (the normals took half of a step's geometry)
        self._fixed: tuple[np.ndarray, sp.csr_matrix] | None = None
        if getattr(obstacle, "constant_normal", False):
            n = self._normals(slave.positions(np.zeros(self.n_dofs)))
            n.flags.writeable = False
            self._fixed = (n, csr_with_data(self._template, (-n).T.ravel()))
        # the plane's arrays in the compiled gaps' types (its exact class: a subclass may
        # change phi)
        self._plane: tuple[np.ndarray, ...] | None = None
        if type(obstacle) is PlaneObstacle and self._fixed is not None:
            c = np.ascontiguousarray
            self._plane = (
                c(slave._x_ref, dtype=float),
                c(slave._dofs, dtype=np.int64),
                c(obstacle.normal, dtype=float),
                c(obstacle.point, dtype=float),
            )

    def _normals(self, x: np.ndarray) -> np.ndarray:
        """Unit normals ∇φ/|∇φ| at the points x (dim, m)."""
        g = self.obstacle.gradient(x)
        gn = np.linalg.norm(g, axis=0)
        if np.any(~(gn > 0.0)):
            raise ValueError("obstacle gradient vanishes at a contact point")
        return g / gn

    def geometry(self, u: np.ndarray) -> ContactGeometry:
        if self._plane is not None and u.dtype == np.float64 and u.shape == (self.n_dofs,):
            # a plane: the gaps in one compiled pass (the numpy lines below, their reference)
            x_ref, dofs, normal, point = self._plane
            n, rows = self._fixed
            return ContactGeometry(rows, plane_gaps(x_ref, dofs, u, normal, point), n,
                                   self._jump)  # fmt: skip
        x = self.slave.positions(u)
        phi = self.obstacle.phi(x)
        if self._fixed is not None:
            n, rows = self._fixed
            return ContactGeometry(rows, -phi, n, self._jump)
        n = self._normals(x)
        cached = self._rows_cache
        if cached is not None and np.array_equal(cached[0], n):
            rows = cached[1]  # same normals (a resting contact): same rows
        else:
            rows = csr_with_data(self._template, (-n).T.ravel())
            self._rows_cache = (n.copy(), rows)
        return ContactGeometry(rows, -phi, n, self._jump)


class DeformableContactPair(ContactPair):
    """Two deformable bodies: slave nodes against master facets (closest-point projection).

    Node-to-node in 1D, point-to-segment in 2D, point-to-facet in 3D (triangles; quadrilaterals
    are split into two triangles, exact at the nodes and on planar parallelograms' diagonals).
    With the master's outward unit normal n at the projection x_m:
    ``d_n = −n·(x_s − x_m)``, ``[[v_n]] = n·(v_m(x_m) − v_s)``.

    Parameters
    ----------
    slave, master : ContactSurface
        Their ``offset`` locate each body in the global dof vector.
    n_dofs : int or DofMap
        Size of the global dof vector (or the system's dof map).
    compiled : bool
        Point-to-segment projection by the compiled kernel
        (:func:`~arlequin.models.contact.kernel.project_segments`, default) or the numpy path
        (its reference: the same results bit for bit).
    """

    def __init__(self, slave: ContactSurface, master: ContactSurface, n_dofs: Any,
                 compiled: bool = True) -> None:  # fmt: skip
        if slave.dim != master.dim:
            raise ValueError(f"slave and master dimensions differ: {slave.dim} and {master.dim}")
        self.compiled = bool(compiled)
        self.slave = slave
        self.master = master
        self.n_dofs = _n_dofs(n_dofs)
        fn = master.facet_nodes
        if master.dim == 3 and fn.shape[1] == 4:
            tri = np.concatenate([fn[:, [0, 1, 2]], fn[:, [0, 2, 3]]])
            orient = np.concatenate([master._orient, master._orient])
            self._tris, self._orient = tri, orient
        else:
            self._tris, self._orient = fn, master._orient
        # per-step index arrays that depend on the reference configuration only
        nt, nv = self._tris.shape
        self._tri_dofs = master.node_dofs(self._tris.ravel())  # (dim, n_t·n_v)
        self._tri_dofs_by_point = self._tri_dofs.T.reshape(nt, nv, master.dim)
        self._tri_p = master.mesh.p[:, self._tris]  # (dim, n_t, n_v)
        m, d = slave.n_points, slave.dim
        self._r_s = np.repeat(np.arange(m), d)
        self._c_s = slave._dofs.T.ravel()
        self._r_m = np.repeat(np.arange(m), nv * d)
        self._pattern: tuple | None = None  # the rows' pattern for the last facets (geometry)
        self._vals: np.ndarray | None = None  # the rows' values by point (m, w), a buffer
        self._orient_f = np.ascontiguousarray(self._orient, dtype=float)
        # 2D segments: the compiled geometry's arrays (segment_geometry)
        self._segments: tuple[np.ndarray, ...] | None = None
        if self.compiled and master.dim == 2 and nv == 2:
            self._segments = (
                np.ascontiguousarray(slave._x_ref, dtype=float),
                np.ascontiguousarray(slave._dofs, dtype=np.int64),
                np.ascontiguousarray(self._tri_p, dtype=float),
                np.ascontiguousarray(self._tri_dofs, dtype=np.int64),
            )
        self.geometry_dofs = np.unique(np.concatenate([self._c_s, self._tri_dofs.ravel()]))

    def _project(self, xs: np.ndarray, u: np.ndarray):
        """Closest master facet of each slave point: (facet, shape values (m, n_v), x_m, normal)."""
        master = self.master
        fn = self._tris
        xf = self._tri_p + u[self._tri_dofs].reshape((master.dim, *fn.shape))
        nv = fn.shape[1]
        if nv == 1:
            xm = xf[:, None, :, 0]  # (d, 1, nf)
            dist = np.sum((xs[:, :, None] - xm) ** 2, axis=0)
            k = np.argmin(dist, axis=1)
            shape = np.ones((xs.shape[1], 1))
            normal = np.repeat(self._orient[k][None, :], 1, axis=0)
            return k, shape, xf[:, k, 0], normal
        if nv == 2:
            if self.compiled:
                k, tk, nrm, xm = project_segments(
                    np.ascontiguousarray(xs), np.ascontiguousarray(xf[..., 0]),
                    np.ascontiguousarray(xf[..., 1]), self._orient_f)  # fmt: skip
                return k, np.stack([1.0 - tk, tk], axis=1), xm, nrm
            else:  # the reference of the compiled projection
                a, b = xf[:, None, :, 0], xf[:, None, :, 1]
                t = np.sum((xs[:, :, None] - a) * (b - a), axis=0) / np.sum((b - a) ** 2, axis=0)
                t = np.clip(t, 0.0, 1.0)
                xp = a + t[None] * (b - a)
                dist = np.sum((xs[:, :, None] - xp) ** 2, axis=0)
                k = np.argmin(dist, axis=1)
                tk = t[np.arange(xs.shape[1]), k]
            shape = np.stack([1.0 - tk, tk], axis=1)
        else:
            bary, dist = _closest_on_triangles(xs, xf)
            k = np.argmin(dist, axis=1)
            shape = bary[np.arange(xs.shape[1]), k]
        nrm, _ = facet_normals(xf[:, k])
        nrm = nrm * self._orient[k]
        xm = np.einsum("dkv,kv->dk", xf[:, k], shape)
        return k, shape, xm, nrm

    def _pattern_for(self, k: np.ndarray, nv: int) -> tuple:
        """(facets, COO indices, :func:`_row_pattern`) of the rows when the points project on
        the facets k (m,): the rows' columns depend on those alone (the same from one step to
        the next, mostly), so their order and arrays are made once for them."""
        pattern = self._pattern
        if pattern is None or not np.array_equal(pattern[0], k):
            m, d = self.slave.n_points, self.slave.dim
            c_m = self._tri_dofs_by_point[k]  # (m, nv, d)
            ij = (np.concatenate([self._r_s, self._r_m]),
                  np.concatenate([self._c_s, c_m.ravel()]))  # fmt: skip
            cols = np.hstack([self._c_s.reshape(m, d), c_m.reshape(m, nv * d)])
            pattern = (k.copy(), ij, _row_pattern(cols, self.n_dofs))
            self._pattern = pattern
        return pattern

    def geometry(self, u: np.ndarray) -> ContactGeometry:
        s = self.slave
        m, d = s.n_points, s.dim
        if self._segments is not None and u.dtype == np.float64 and u.shape == (self.n_dofs,):
            # 2D segments: everything up to the rows' values in one compiled call (the numpy
            # lines below are its reference, the same numbers bit for bit)
            x_ref, s_dofs, seg_ref, seg_dofs = self._segments
            vals = self._vals
            if vals is None or vals.shape != (m, 6):
                vals = self._vals = np.empty((m, 6))
            k, shape, n, gap = segment_geometry(x_ref, s_dofs, seg_ref, seg_dofs, u,
                                                self._orient_f, vals)  # fmt: skip
            _, ij, by_point = self._pattern_for(k, 2)
            if by_point is not None:
                flat, template = by_point
                rows = csr_with_data(template, vals.ravel()[flat])
                return ContactGeometry(rows, gap, n, _JumpRows(ij, (m, self.n_dofs), shape))
            v_s, v_m = vals[:, :2], vals[:, 2:].reshape(m, 2, 2)
        else:
            xs = s.positions(u)
            k, shape, xm, n = self._project(xs, u)
            gap = -np.sum(n * (xs - xm), axis=0)
            # slave part: −n·v_s; master part: +N_j n·v_j
            v_s = (-n).T  # (m, d)
            v_m = shape[:, :, None] * n.T[:, None, :]
        nv = shape.shape[1]
        pattern = self._pattern_for(k, nv)
        _, ij, by_point = pattern
        if by_point is None:  # a dof twice in a row (a surface against itself): summed by COO
            vals = np.concatenate([v_s.ravel(), v_m.ravel()])
            rows = sp.csr_matrix((vals, ij), shape=(m, self.n_dofs))
        else:
            flat, template = by_point
            # the entries in the pattern's order by one gather from a kept buffer (the data
            # array itself is new: earlier rows, kept by states, stay as they were)
            vals = self._vals
            if vals is None or vals.shape != (m, d + nv * d):
                vals = self._vals = np.empty((m, d + nv * d))
            vals[:, :d] = v_s
            vals[:, d:] = v_m.reshape(m, nv * d)
            rows = csr_with_data(template, vals.ravel()[flat])
        return ContactGeometry(rows, gap, n, _JumpRows(ij, (m, self.n_dofs), shape))


def _row_pattern(cols: np.ndarray, n: int):
    """The CSR pattern of rows with entries in the columns ``cols`` (m, w), row by row: (the
    positions (m w,) in the row-major values (m, w) of the entries sorted by column in each row,
    its template (:func:`csr_pattern`)), or None if a row has a column twice (the caller sums
    them by COO).

    ``csr_with_data(template, values.ravel()[positions])``
    is ``sp.csr_matrix((vals, (rows, cols)))`` (columns sorted in each row, explicit zeros
    kept) without its COO conversion and duplicate summation (the deformable pair's geometry
    took 150 µs a step with them, 110 without, at 26 points), and the arrays are kept while the
    points project on the same facets.
    """
    order = np.argsort(cols, axis=1)
    cols = np.take_along_axis(cols, order, axis=1)
    if cols.shape[1] > 1 and np.any(cols[:, 1:] == cols[:, :-1]):
        return None
    m, w = cols.shape
    index_dtype = np.int32 if max(n, m * w) < np.iinfo(np.int32).max else np.int64
    indptr = np.arange(0, m * w + 1, w, dtype=index_dtype)
    # the sorted entries' positions in the row-major (m, w) values: one gather a step
    flat = (np.arange(m)[:, None] * w + order).ravel()
    return flat, csr_pattern(cols.ravel().astype(index_dtype), indptr, (m, n))


@dataclass(frozen=True)
class _JumpRows:
    """``jump(e)`` of a :class:`ContactGeometry`: the rows of e_k·(v_s − Σ_j N_j v_j) at each
    point, on the pattern ``ij`` of the normal rows (slave dofs, then the master's, whose shape
    values are ``master_shape`` (m, n_v); None against an obstacle). A picklable object, so
    that constraint states with their geometry go into checkpoints."""

    ij: tuple[np.ndarray, np.ndarray]
    shape: tuple[int, int]
    master_shape: np.ndarray | None = None

    def __call__(self, e: np.ndarray) -> sp.csr_matrix:
        e = np.asarray(e)
        vals = e.T.ravel()
        if self.master_shape is not None:
            vals = np.concatenate(
                [vals, (-self.master_shape[:, :, None] * e.T[:, None, :]).ravel()]
            )
        return sp.csr_matrix((vals, self.ij), shape=self.shape)


def _closest_on_triangles(p: np.ndarray, xf: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Barycentric coordinates (m, nf, 3) of the closest point of each triangle, squared distances.

    p: (3, m) points; xf: (3, nf, 3) triangles.
    """
    a, b, c = xf[:, None, :, 0], xf[:, None, :, 1], xf[:, None, :, 2]
    x = p[:, :, None]
    e0, e1, r = b - a, c - a, x - a
    d00 = np.sum(e0 * e0, axis=0)
    d01 = np.sum(e0 * e1, axis=0)
    d11 = np.sum(e1 * e1, axis=0)
    d20 = np.sum(r * e0, axis=0)
    d21 = np.sum(r * e1, axis=0)
    den = d00 * d11 - d01 * d01
    v = (d11 * d20 - d01 * d21) / den
    w = (d00 * d21 - d01 * d20) / den
    bary = np.stack([1.0 - v - w, v, w], axis=-1)
    inside = (bary >= 0.0).all(axis=-1)
    best = np.where(inside, 0.0, np.inf)
    xp = a + v[None] * e0 + w[None] * e1
    dist = np.where(inside, np.sum((x - xp) ** 2, axis=0), np.inf)
    out = np.where(inside[..., None], bary, 0.0)
    for i, j in ((0, 1), (1, 2), (2, 0)):
        pa, pb = xf[:, None, :, i], xf[:, None, :, j]
        t = np.clip(np.sum((x - pa) * (pb - pa), axis=0) / np.sum((pb - pa) ** 2, axis=0), 0.0, 1.0)
        q = pa + t[None] * (pb - pa)
        dq = np.sum((x - q) ** 2, axis=0)
        better = dq < dist
        dist = np.where(better, dq, dist)
        cand = np.zeros_like(out)
        cand[..., i] = 1.0 - t
        cand[..., j] = t
        out = np.where(better[..., None], cand, out)
    del best
    return out, dist
