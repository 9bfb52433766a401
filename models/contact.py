"""Frictionless dynamic contact: the level-set (Signorini–Moreau) model and a Signorini baseline.

Conventions (SI units; see ``docs/contact.md``)
-----------------------------------------------
``d_n``
    Signed normal distance (m) at a contact collocation point, **negative when the bodies are
    apart** (the paper's convention), positive when they overlap.
``[[v_n]]``
    Normal velocity jump ``ḋ_n`` (m/s), **positive when the bodies approach**.
``λ_v``
    Normal contact pressure (Pa), ``λ_v ≤ 0`` in contact; reports give
    ``contact_pressure = −λ_v ≥ 0``.
``κ`` (``kappa``, Pa·s/m)
    Parameter of the velocity indicator ``S_v = 1(λ_v − κ[[v_n]] ≤ 0)``, κ > 0; default the
    acoustic impedance ρc of the material, so that both terms have the same size.
``η`` (``eta``, Pa·s/m)
    Parameter of ``λ_v = S_d S_v (λ_v − η[[v_n]])``, η ≠ 0 (default κ).
``S_d = 1(d_n ≥ 0)``
    Gap indicator, evaluated on the predicted end-of-step gap.
Rigid obstacles
    A level-set function φ(x) (m), φ > 0 in free space, with its gradient; ``d_n = −φ`` (φ should
    be a signed distance near the surface for the reported gaps to be distances).

Discretisation
--------------
The contact collocation points are the nodes of the slave surface Γ_c: the quadrature on Γ_c is
the vertex (nodal) rule of its facets, weights ``w_k = Σ_F |F|/n_v`` (m² in 3D, m per unit
thickness in plane 2D, 2πr|F|/n_v in axisymmetry, the cross-section in 1D). λ_v lives in the
nodal (P1/Q1 trace) space of Γ_c, the trace of the displacement space (inf–sup compatible: one
multiplier per collocation point, no over-constraint). The paper's weak equation

    −(1/η) ∫_Γc [λ_v − S_d S_v (λ_v − η[[v_n]])] λ* dΓ = 0

integrated with that rule separates by node: ``w_k[(1 − S_k) λ_k + S_k η [[v_n]]_k] / η = 0``,
i.e. ``λ_k = 0`` where ``S_k = S_d S_v = 0`` and ``[[v_n]]_k = 0`` where ``S_k = 1``: active
velocity rows of the integrators' unilateral protocol. The force on the bodies is
``Σ_k w_k S_k λ_k [[w_n]]_k``, the same rule applied to ``∫_Γc S_d S_v λ_v [[w_n]] dΓ``.

Rows and signs: with ``G`` (m × n) the map ``v ↦ [[v_n]]`` at the collocation points and
``W = diag(w)``, the constraint rows are ``B = −W G`` and the multiplier of row k is ``λ_k``
itself, so that the integrators' force ``−Bᵀλ = Gᵀ W λ`` is the paper's contact force and
``λ ≤ 0`` is a pressure.

Per time step (:meth:`LevelSetContact.begin_step` … :meth:`LevelSetContact.end_step`) the
statuses ``S = S_d S_v`` are found by a fixed point driven by the integrator: freeze them, solve,
update ``S_v`` from ``λ_v − κ[[v_n]]`` of the solution, repeat until no status changes.
``S_d`` is evaluated once per step on the predicted end-of-step gap ``d_n + Δt [[v_n]]`` (free
flight from the start-of-step velocity; the explicit scheme passes its free mid-step velocity),
and stays 1 for a point that was active in the previous step: an active point has
``[[v_n]] = 0`` so its gap is frozen (no drift), and it is released only through ``S_v``
(tension). At activation a θ-scheme point penetrates by at most ``(1 − θ) Δt [[v_n]]``.

Contact work is accumulated from the multipliers, never as an energy-balance residual: an impulse
``Λ = Δt λ`` that takes the velocities from ``v⁻`` to ``v⁺`` does the work
``−Λ·B (v⁻ + v⁺)/2 = Λ·W G (v⁻ + v⁺)/2`` (J), exactly the kinetic-energy change it causes.

Pairs: :class:`RigidContactPair` (a deformable surface against an :class:`Obstacle`: plane,
sphere, any φ with its gradient) and :class:`DeformableContactPair` (slave nodes against master
facets: node-to-node in 1D, point-to-segment in 2D, point-to-facet in 3D; closest-point
projection in the current configuration).

:class:`SignoriniContact` is the displacement-level baseline (Newmark + Signorini with a
Lagrange multiplier, primal–dual active set on ``d_n(u_{n+1}) ≤ 0``).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
from skfem import Mesh

from arlequin.integrators.base import SimulationError
from arlequin.integrators.constraints import UnilateralConstraint

__all__ = [
    "ContactConvergenceError",
    "ContactSurface",
    "DeformableContactPair",
    "LevelSetContact",
    "LevelSetObstacle",
    "Obstacle",
    "PlaneObstacle",
    "RigidContactPair",
    "SignoriniContact",
    "SphereObstacle",
    "acoustic_impedance",
]

logger = logging.getLogger(__name__)


class ContactConvergenceError(SimulationError):
    """The status fixed point of a contact constraint did not converge (``on_failure="raise"``)."""


def acoustic_impedance(young: float, density: float, poisson: float | None = None) -> float:
    """Acoustic impedance ρ c (Pa·s/m), the default κ of :class:`LevelSetContact`.

    Parameters
    ----------
    young : float
        Young's modulus E (Pa).
    density : float
        Density ρ (kg/m³).
    poisson : float, optional
        Poisson's ratio: c is then the dilatational speed √((λ + 2μ)/ρ); without it the bar
        speed √(E/ρ).
    """
    if not (young > 0.0 and density > 0.0):
        raise ValueError(
            f"acoustic impedance needs young > 0 and density > 0, got {young}, {density}"
        )
    modulus = young
    if poisson is not None:
        modulus = young * (1.0 - poisson) / ((1.0 + poisson) * (1.0 - 2.0 * poisson))
    return float(np.sqrt(modulus * density))


# ---------------------------------------------------------------------------------------------
# rigid obstacles
# ---------------------------------------------------------------------------------------------
class Obstacle:
    """A rigid obstacle given by a level-set function φ (m), φ > 0 in free space.

    Subclasses implement :meth:`phi` and :meth:`gradient`; points are arrays of shape (dim, m).
    """

    def phi(self, x: np.ndarray) -> np.ndarray:
        """φ(x) (m), shape (m,)."""
        raise NotImplementedError

    def gradient(self, x: np.ndarray) -> np.ndarray:
        """∇φ(x) (dimensionless), shape (dim, m)."""
        raise NotImplementedError


class PlaneObstacle(Obstacle):
    """Half-space obstacle: free space is ``n·(x − p) > 0``.

    Parameters
    ----------
    point : array_like, shape (dim,)
        A point of the plane (m).
    normal : array_like, shape (dim,)
        Normal pointing into free space (normalised here).
    """

    def __init__(self, point, normal) -> None:
        self.point = np.asarray(point, dtype=float).ravel()
        n = np.asarray(normal, dtype=float).ravel()
        norm = float(np.linalg.norm(n))
        if not norm > 0.0 or n.size != self.point.size:
            raise ValueError(
                f"plane normal must be non-zero with {self.point.size} components, got {normal}"
            )
        self.normal = n / norm

    def phi(self, x: np.ndarray) -> np.ndarray:
        return self.normal @ (np.asarray(x, dtype=float) - self.point[:, None])

    def gradient(self, x: np.ndarray) -> np.ndarray:
        return np.repeat(self.normal[:, None], np.asarray(x).shape[1], axis=1)


class SphereObstacle(Obstacle):
    """Rigid ball (``inside=False``: free space outside) or spherical cavity (``inside=True``).

    Parameters
    ----------
    center : array_like, shape (dim,)
        Centre (m); a circle in 2D, a point pair in 1D.
    radius : float
        Radius (m), > 0.
    inside : bool
        Free space is inside the sphere (a container) instead of outside.
    """

    def __init__(self, center, radius: float, inside: bool = False) -> None:
        self.center = np.asarray(center, dtype=float).ravel()
        if not radius > 0.0:
            raise ValueError(f"sphere radius must be positive, got radius={radius}")
        self.radius = float(radius)
        self.sign = -1.0 if inside else 1.0

    def _r(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rel = np.asarray(x, dtype=float) - self.center[:, None]
        r = np.sqrt(np.sum(rel * rel, axis=0))
        return rel, r

    def phi(self, x: np.ndarray) -> np.ndarray:
        _, r = self._r(x)
        return self.sign * (r - self.radius)

    def gradient(self, x: np.ndarray) -> np.ndarray:
        rel, r = self._r(x)
        if np.any(r == 0.0):
            raise ValueError("sphere obstacle: gradient undefined at the centre")
        return self.sign * rel / r


class LevelSetObstacle(Obstacle):
    """Obstacle from callables ``phi(x) -> (m,)`` and ``gradient(x) -> (dim, m)``, x: (dim, m)."""

    def __init__(self, phi: Callable[[np.ndarray], np.ndarray],
                 gradient: Callable[[np.ndarray], np.ndarray]) -> None:
        self._phi = phi
        self._grad = gradient

    def phi(self, x: np.ndarray) -> np.ndarray:
        return np.asarray(self._phi(x), dtype=float).reshape(np.asarray(x).shape[1])

    def gradient(self, x: np.ndarray) -> np.ndarray:
        return np.asarray(self._grad(x), dtype=float).reshape(np.asarray(x).shape)


# ---------------------------------------------------------------------------------------------
# contact surfaces
# ---------------------------------------------------------------------------------------------
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
    offset : int
        First global dof of the body (its block offset in a :class:`CoupledSystem`).
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
        offset: int = 0,
        area: float = 1.0,
        axisymmetric: bool = False,
    ) -> None:
        self.mesh = mesh
        self.dim = int(mesh.p.shape[0])
        self.offset = int(offset)
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
            fn = _cyclic_quads(mesh.p, fn)
        self.facet_nodes = fn
        # outward orientation sign of the facet normal computed from the node order
        elem = mesh.f2t[0, facets]
        centroid = mesh.p[:, mesh.t[:, elem]].mean(axis=1)  # (dim, n_f)
        n_ref, _ = _facet_normals(_facet_points(mesh.p, fn))
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
        if axisymmetric:
            contrib = contrib * 2.0 * np.pi * mesh.p[0, fn.ravel()]
        self.weights = np.bincount(inv, contrib, minlength=nodes.size)

    @property
    def n_points(self) -> int:
        return int(self.nodes.size)

    def node_dofs(self, nodes: np.ndarray) -> np.ndarray:
        """Global dofs of mesh nodes, shape (dim, len(nodes))."""
        nodes = np.asarray(nodes, dtype=np.int64)
        return self.offset + self.dim * nodes[None, :] + np.arange(self.dim)[:, None]

    def positions(self, u: np.ndarray, nodes: np.ndarray | None = None) -> np.ndarray:
        """Current positions X + u of mesh nodes (default: surface nodes), shape (dim, k) (m)."""
        nodes = self.nodes if nodes is None else np.asarray(nodes, dtype=np.int64)
        return self.mesh.p[:, nodes] + u[self.node_dofs(nodes)]


def _facet_points(p: np.ndarray, fn: np.ndarray) -> np.ndarray:
    """Facet vertex coordinates, shape (dim, n_f, n_v)."""
    return p[:, fn]


def _cyclic_quads(p: np.ndarray, fn: np.ndarray) -> np.ndarray:
    """Reorder the (sorted) vertices of quadrilateral facets cyclically."""
    x = p[:, fn]  # (3, n_f, 4)
    c = x.mean(axis=2, keepdims=True)
    rel = x - c
    n = np.cross(rel[:, :, 1] - rel[:, :, 0], rel[:, :, 2] - rel[:, :, 0], axis=0)
    e1 = rel[:, :, 0] / np.linalg.norm(rel[:, :, 0], axis=0)
    e2 = np.cross(n, e1, axis=0)
    e2 /= np.linalg.norm(e2, axis=0)
    ang = np.arctan2(np.einsum("df,dfv->fv", e2, rel), np.einsum("df,dfv->fv", e1, rel))
    order = np.argsort(ang, axis=1)
    return np.take_along_axis(fn, order, axis=1)


def _facet_normals(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals (from the vertex order) and measures of facets x (dim, n_f, n_v)."""
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


def _facet_measure(x: np.ndarray) -> np.ndarray:
    return _facet_normals(x)[1]


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
    """

    rows: sp.csr_matrix
    gap: np.ndarray
    normal: np.ndarray


class ContactPair:
    """Base of the contact pairs: a slave surface (its nodes are the collocation points)."""

    slave: ContactSurface
    n_dofs: int

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
    n_dofs : int
        Size of the global dof vector.
    """

    def __init__(self, slave: ContactSurface, obstacle: Obstacle, n_dofs: int) -> None:
        self.slave = slave
        self.obstacle = obstacle
        self.n_dofs = int(n_dofs)
        m, d = slave.n_points, slave.dim
        self._r = np.repeat(np.arange(m), d)
        self._c = slave.node_dofs(slave.nodes).T.ravel()

    def geometry(self, u: np.ndarray) -> ContactGeometry:
        x = self.slave.positions(u)
        phi = self.obstacle.phi(x)
        g = self.obstacle.gradient(x)
        gn = np.linalg.norm(g, axis=0)
        if np.any(~(gn > 0.0)):
            raise ValueError("obstacle gradient vanishes at a contact point")
        n = g / gn
        vals = (-n).T.ravel()
        rows = sp.csr_matrix((vals, (self._r, self._c)), shape=(self.slave.n_points, self.n_dofs))
        return ContactGeometry(rows, -phi, n)


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
    n_dofs : int
        Size of the global dof vector.
    """

    def __init__(self, slave: ContactSurface, master: ContactSurface, n_dofs: int) -> None:
        if slave.dim != master.dim:
            raise ValueError(f"slave and master dimensions differ: {slave.dim} and {master.dim}")
        self.slave = slave
        self.master = master
        self.n_dofs = int(n_dofs)
        fn = master.facet_nodes
        if master.dim == 3 and fn.shape[1] == 4:
            tri = np.concatenate([fn[:, [0, 1, 2]], fn[:, [0, 2, 3]]])
            orient = np.concatenate([master._orient, master._orient])
            self._tris, self._orient = tri, orient
        else:
            self._tris, self._orient = fn, master._orient

    def _project(self, xs: np.ndarray, u: np.ndarray):
        """Closest master facet of each slave point: (facet, shape values (m, n_v), x_m, normal)."""
        master = self.master
        fn = self._tris
        xf = master.mesh.p[:, fn] + u[master.node_dofs(fn.ravel())].reshape((master.dim, *fn.shape))
        nv = fn.shape[1]
        if nv == 1:
            xm = xf[:, None, :, 0]  # (d, 1, nf)
            dist = np.sum((xs[:, :, None] - xm) ** 2, axis=0)
            k = np.argmin(dist, axis=1)
            shape = np.ones((xs.shape[1], 1))
            normal = np.repeat(self._orient[k][None, :], 1, axis=0)
            return k, shape, xf[:, k, 0], normal
        if nv == 2:
            a, b = xf[:, None, :, 0], xf[:, None, :, 1]
            t = np.sum((xs[:, :, None] - a) * (b - a), axis=0) / np.sum((b - a) ** 2, axis=0)
            t = np.clip(t, 0.0, 1.0)
            xp = a + t[None] * (b - a)
            dist = np.sum((xs[:, :, None] - xp) ** 2, axis=0)
            k = np.argmin(dist, axis=1)
            idx = np.arange(xs.shape[1])
            tk = t[idx, k]
            shape = np.stack([1.0 - tk, tk], axis=1)
        else:
            bary, dist = _closest_on_triangles(xs, xf)
            k = np.argmin(dist, axis=1)
            shape = bary[np.arange(xs.shape[1]), k]
        nrm, _ = _facet_normals(xf[:, k])
        nrm = nrm * self._orient[k]
        xm = np.einsum("dkv,kv->dk", xf[:, k], shape)
        return k, shape, xm, nrm

    def geometry(self, u: np.ndarray) -> ContactGeometry:
        s = self.slave
        xs = s.positions(u)
        k, shape, xm, n = self._project(xs, u)
        gap = -np.sum(n * (xs - xm), axis=0)
        m, d = s.n_points, s.dim
        nv = shape.shape[1]
        # slave part: −n·v_s
        r_s = np.repeat(np.arange(m), d)
        c_s = s.node_dofs(s.nodes).T.ravel()
        v_s = (-n).T.ravel()
        # master part: +N_j n·v_j
        fn = self._tris[k]  # (m, nv)
        c_m = self.master.node_dofs(fn.ravel()).T.reshape(m, nv, d)  # (m, nv, d)
        v_m = shape[:, :, None] * n.T[:, None, :]
        r_m = np.repeat(np.arange(m), nv * d)
        vals = np.concatenate([v_s, v_m.ravel()])
        ij = (np.concatenate([r_s, r_m]), np.concatenate([c_s, c_m.ravel()]))
        rows = sp.csr_matrix((vals, ij), shape=(m, self.n_dofs))
        return ContactGeometry(rows, gap, n)


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


# ---------------------------------------------------------------------------------------------
# constraints
# ---------------------------------------------------------------------------------------------
@dataclass
class ContactHistory:
    """Per-step records of a contact constraint (one entry per accepted step).

    All arrays have a leading axis of length n_steps; point arrays have shape (n_steps, m).

    Attributes
    ----------
    t : ndarray
        Time of the step's end (s) (the explicit scheme: the time of the impulse).
    iterations : ndarray of int
        Status (fixed-point) iterations of the step.
    converged : ndarray of bool
    active : ndarray of bool
        Statuses S = S_d S_v used in the accepted solve.
    s_d, s_v : ndarray of bool
        Indicator fields at the collocation points.
    gap : ndarray
        d_n at the end of the step (m), from the geometry (not the linearised rows).
    gap_start : ndarray
        d_n at the start of the step (m).
    vn_start : ndarray
        [[v_n]] at the start of the step (m/s) (the explicit scheme: free mid-step velocity).
    vn : ndarray
        [[v_n]] of the accepted solution (m/s).
    lam : ndarray
        λ_v (Pa), ≤ 0 in contact.
    work : ndarray
        Accumulated contact work (J) up to the end of the step (≤ 0: dissipated).
    dt : ndarray
        Time step (s).
    """

    t: np.ndarray
    iterations: np.ndarray
    converged: np.ndarray
    active: np.ndarray
    s_d: np.ndarray
    s_v: np.ndarray
    gap: np.ndarray
    gap_start: np.ndarray
    vn_start: np.ndarray
    vn: np.ndarray
    lam: np.ndarray
    work: np.ndarray
    dt: np.ndarray


class _ContactConstraint(UnilateralConstraint):
    """Shared machinery: geometry per step, records, contact work."""

    def __init__(
        self,
        pair: ContactPair,
        *,
        name: str,
        level: str,
        max_iterations: int,
        on_failure: str,
        update_geometry: bool,
    ) -> None:
        super().__init__(name=name, level=level, max_iterations=max_iterations, kind="contact")
        if on_failure not in ("warn", "raise"):
            raise ValueError(f"on_failure must be 'warn' or 'raise', got {on_failure!r}")
        self.pair = pair
        self.on_failure = on_failure
        self.update_geometry = bool(update_geometry)
        self._geo = pair.geometry(np.zeros(pair.n_dofs))
        self._b = self._make_b(self._geo.rows)
        self.active = np.zeros(pair.n_points, dtype=bool)
        self.work = 0.0
        self._records: list[dict[str, Any]] = []
        self._pending: dict[str, Any] | None = None
        self._v_last: np.ndarray | None = None

    # rows
    def _make_b(self, g: sp.csr_matrix) -> sp.csr_matrix:
        return sp.csr_matrix(sp.diags(-self.pair.weights) @ g)

    def matrix(self) -> sp.csr_matrix:
        """Rows B = −W G, shape (m, n) (m², or m per unit thickness in plane 2D)."""
        return self._b

    @property
    def n_rows(self) -> int:
        return self.pair.n_points

    def _set_geometry(self, u: np.ndarray) -> None:
        if not self.update_geometry:
            gap0 = self._geo0_gap + self._g0 @ (u - self._u0)
            self._geo = ContactGeometry(self._g0, gap0, self._geo.normal)
            return
        geo = self.pair.geometry(u)
        old = self._geo.rows
        same = (
            old.shape == geo.rows.shape
            and old.nnz == geo.rows.nnz
            and np.array_equal(old.indptr, geo.rows.indptr)
            and np.array_equal(old.indices, geo.rows.indices)
            and np.allclose(old.data, geo.rows.data, rtol=0.0, atol=1e-15)
        )
        if same:  # keep the matrix object: the integrators cache factorisations by its id
            geo = ContactGeometry(old, geo.gap, geo.normal)
        else:
            self._b = self._make_b(geo.rows)
        self._geo = geo

    def gaps(self, u: np.ndarray) -> np.ndarray:
        """d_n (m) at the collocation points for displacement u, shape (m,)."""
        if not self.update_geometry:
            return self._geo0_gap + self._g0 @ (u - self._u0)
        return self.pair.geometry(u).gap

    # records
    def _close_pending(self, factor: float) -> None:
        p = self._pending
        self._pending = None
        if p is None or p.get("v_plus") is None:
            return
        lam = p["lam"]
        vsum = p["v_minus"] + p["v_plus"]
        lam_w = p.get("lam_work", lam)
        w = -factor * p["dt"] * float(lam_w @ (p["b"] @ vsum)) * 0.5
        self.work += w
        self._v_last = p["v_plus"]
        gap = self.gaps(p["u_end"]) if p.get("u_end") is not None else p["gap_pred"]
        self._records.append(
            {
                "t": p["t_end"], "iterations": p["calls"], "converged": not p["changed"],
                "active": p["used"], "s_d": p["s_d"], "s_v": p["s_v"], "gap": gap,
                "gap_start": p["gap_start"], "vn_start": p["vn_start"], "vn": p["vn"],
                "lam": lam, "work": self.work, "dt": p["dt"],
            }
        )

    def _start(self, t: float, dt: float, u: np.ndarray, v: np.ndarray) -> None:
        if self._pending is not None and self._pending.get("v_plus") is not None:
            if self._pending["t"] == t:
                # the integrator re-initialised (same start time): forget the unfinished solve
                self._pending = None
                self.active = self._pending_active0
            else:
                # an impulse without end_step: the explicit scheme's initial half step (Δt/2)
                self._pending["t_end"] = self._pending["t"]
                self._close_pending(0.5)
        self._pending_active0 = self.active.copy()
        self._set_geometry(u)
        vn0 = self._geo.rows @ v
        # v⁻ of the impulse: the previous step's accepted velocity (θ-scheme, Newmark: v^n;
        # central differences: v^{n−1/2}, so that Λ·B(v^{n−1/2} + v^{n+1/2})/2 is the kinetic
        # energy change of the impulse in the velocity-Verlet splitting of the step)
        v_minus = v if self._v_last is None else self._v_last
        self._pending = {
            "t": float(t), "dt": float(dt), "u_start": u.copy(), "v_minus": v_minus.copy(),
            "gap_start": self._geo.gap.copy(), "vn_start": vn0, "b": self._b, "g": self._geo.rows,
            "calls": 0,
            "changed": False, "v_plus": None, "t_end": float(t) + float(dt),
            "gap_pred": self._geo.gap + dt * vn0,
        }

    def _finish(self, t: float, u: np.ndarray) -> None:
        p = self._pending
        if p is None:
            return
        p["t_end"] = float(t)
        p["u_end"] = u.copy()
        if p["changed"]:
            msg = (
                f"contact {self.name!r}: status fixed point not converged after {p['calls']} "
                f"iterations in the step ending at t = {t:.6e} s "
                f"(step {len(self._records) + 1})"
            )
            if self.on_failure == "raise":
                self._pending = None
                raise ContactConvergenceError(msg, len(self._records) + 1, t)
            logger.warning(msg)
        self._close_pending(1.0)

    def end_step(self, t: float, u: np.ndarray, v: np.ndarray, multipliers: np.ndarray) -> None:
        self._finish(t, u)

    @property
    def history(self) -> ContactHistory:
        """The per-step records as arrays (see :class:`ContactHistory`)."""
        m = self.pair.n_points
        keys = ContactHistory.__dataclass_fields__.keys()
        if not self._records:
            point_keys = ("active", "s_d", "s_v", "gap", "gap_start", "vn_start", "vn", "lam")
            empty = {k: np.zeros((0, m)) if k in point_keys else np.zeros(0) for k in keys}
            return ContactHistory(**empty)
        return ContactHistory(**{k: np.array([r[k] for r in self._records]) for k in keys})

    def reset(self) -> None:
        """Forget statuses, records and work (before reusing the object in another run)."""
        self.active = np.zeros(self.pair.n_points, dtype=bool)
        self.work = 0.0
        self._records = []
        self._pending = None
        self._v_last = None


class LevelSetContact(_ContactConstraint):
    """Level-set (Signorini–Moreau) frictionless contact, velocity-level rows.

    Statuses per collocation point (see the module docstring):
    ``S_d = 1(d_pred ≥ 0)`` (or the point was active in the previous step),
    ``S_v = 1(λ_v − κ[[v_n]] ≤ 0)``, active ⇔ ``S_d S_v = 1``; an active row enforces
    ``[[v_n]] = 0`` on the end-of-step velocity (θ-scheme) or on the next mid-step velocity
    (central differences), an inactive one ``λ_v = 0``.

    Parameters
    ----------
    pair : ContactPair
        Geometry (:class:`RigidContactPair` or :class:`DeformableContactPair`).
    kappa : float, optional
        κ > 0 (Pa·s/m). Default: :func:`acoustic_impedance` of ``material``.
    eta : float, optional
        η ≠ 0 (Pa·s/m) of ``λ_v = S_d S_v (λ_v − η[[v_n]])`` (default κ). With the nodal
        collocation the discrete solution does not depend on η; it scales
        :meth:`weak_residual`.
    material : IsotropicElastic, optional
        Used for the default κ (bar speed in 1D, dilatational speed otherwise).
    name : str
    max_iterations : int
        Cap of the status fixed point per step (default 25).
    on_failure : {"warn", "raise"}
        Non-convergence of the fixed point: a warning naming the step and time (the integrator
        also counts it in ``n_status_failures``), or :class:`ContactConvergenceError`.
    update_geometry : bool
        Recompute the pairing, normals and gaps in the current configuration at every step
        (default); False freezes the reference geometry (small-displacement contact).
    """

    def __init__(
        self,
        pair: ContactPair,
        kappa: float | None = None,
        eta: float | None = None,
        *,
        material: Any = None,
        name: str = "contact",
        max_iterations: int = 25,
        on_failure: str = "warn",
        update_geometry: bool = True,
    ) -> None:
        if kappa is None:
            if material is None:
                raise ValueError(
                    "LevelSetContact needs kappa (Pa·s/m) or a material for the default ρc"
                )
            nu = None if pair.slave.dim == 1 else material.poisson
            kappa = acoustic_impedance(material.young, material.density, nu)
        if not (np.isfinite(kappa) and kappa > 0.0):
            raise ValueError(f"kappa must be positive (Pa·s/m), got kappa={kappa}")
        eta = float(kappa) if eta is None else float(eta)
        if eta == 0.0 or not np.isfinite(eta):
            raise ValueError(f"eta must be non-zero and finite (Pa·s/m), got eta={eta}")
        self.kappa = float(kappa)
        self.eta = eta
        super().__init__(pair, name=name, level="velocity", max_iterations=max_iterations,
                         on_failure=on_failure, update_geometry=update_geometry)
        m = pair.n_points
        self.s_d = np.zeros(m, dtype=bool)
        self.s_v = np.zeros(m, dtype=bool)
        self._was_active = np.zeros(m, dtype=bool)
        if not update_geometry:
            self._g0 = self._geo.rows
            self._geo0_gap = self._geo.gap.copy()
            self._u0 = np.zeros(pair.n_dofs)

    def rhs(self, t: float) -> np.ndarray:
        return np.zeros(self.pair.n_points)

    def begin_step(self, t: float, dt: float, u: np.ndarray, v: np.ndarray) -> None:
        p = self._pending
        if p is not None and p.get("v_plus") is not None:
            if p["t"] == t:  # re-initialisation of the integrator
                self._was_active = self._was_active_prev
            else:  # the explicit scheme's initial half-step impulse, closed in _start
                self._was_active = p["used"].copy()
        self._start(t, dt, u, v)
        self._was_active_prev = self._was_active.copy()
        p = self._pending
        # S_d on the predicted end-of-step gap; an active point keeps S_d = 1 (frozen gap)
        self.s_d = (p["gap_pred"] >= 0.0) | self._was_active
        # initial guess of the statuses: persistent contacts and newly closed approaching points
        self.active = self.s_d & (self._was_active | (p["vn_start"] > 0.0))

    def update_status(self, u: np.ndarray, v: np.ndarray, multipliers: np.ndarray) -> bool:
        p = self._pending
        lam = np.asarray(multipliers, dtype=float)
        vn = p["g"] @ v  # [[v_n]] with the step's rows
        used = self.active.copy()
        self.s_v = lam - self.kappa * vn <= 0.0
        new = self.s_d & self.s_v
        changed = bool(np.any(new != used))
        self.active = new
        p.update(calls=p["calls"] + 1, changed=changed, v_plus=v.copy(), lam=lam.copy(), used=used,
                 vn=vn, s_d=self.s_d.copy(), s_v=self.s_v.copy())
        return changed

    def end_step(self, t: float, u: np.ndarray, v: np.ndarray, multipliers: np.ndarray) -> None:
        used = self._pending["used"] if self._pending and "used" in self._pending else self.active
        self._finish(t, u)
        self._was_active = used.copy()
        # statuses at the start of the next step are decided in begin_step
        self.active = used.copy()

    def weak_residual(
        self, v: np.ndarray, multipliers: np.ndarray, status: np.ndarray | None = None
    ) -> np.ndarray:
        """Residual of the weak λ_v equation at each collocation point, shape (m,) (m³/s or m²/s).

        ``−(1/η) w_k [λ_k − S_k (λ_k − η[[v_n]]_k)]`` with ``S = status`` (default: the
        current statuses); zero for a converged step.
        """
        s = self.active if status is None else np.asarray(status, dtype=bool)
        vn = self._geo.rows @ v
        lam = np.asarray(multipliers, dtype=float)
        return -(self.pair.weights / self.eta) * (lam - s * (lam - self.eta * vn))

    def reset(self) -> None:
        super().reset()
        self._was_active = np.zeros(self.pair.n_points, dtype=bool)


class SignoriniContact(_ContactConstraint):
    """Baseline: Signorini conditions on displacements with a Lagrange multiplier.

    ``d_n(u_{n+1}) ≤ 0``, ``λ_v ≤ 0``, ``λ_v d_n = 0`` at the collocation points, the gap
    linearised at the start of each step: an active row enforces
    ``d_n(u^n) + G (u^{n+1} − u^n) = 0``. Primal–dual active set: an inactive point becomes
    active when its predicted gap is positive (overlap), an active point is released when
    ``λ_v > 0`` (tension). Used with :class:`~arlequin.integrators.Newmark` (trapezoidal) or
    :class:`~arlequin.integrators.HHTAlpha` as in the paper's Figure 1.

    Parameters
    ----------
    pair : ContactPair
    name, max_iterations, on_failure, update_geometry : see :class:`LevelSetContact`
    gap_tol : float
        Activation threshold on the predicted gap (m), default 0.
    """

    def __init__(
        self,
        pair: ContactPair,
        *,
        name: str = "contact",
        max_iterations: int = 25,
        on_failure: str = "warn",
        update_geometry: bool = True,
        gap_tol: float = 0.0,
    ) -> None:
        super().__init__(pair, name=name, level="displacement", max_iterations=max_iterations,
                         on_failure=on_failure, update_geometry=update_geometry)
        self.gap_tol = float(gap_tol)
        self._rhs = np.zeros(pair.n_points)
        self._lam_old = np.zeros(pair.n_points)
        if not update_geometry:
            self._g0 = self._geo.rows
            self._geo0_gap = self._geo.gap.copy()
            self._u0 = np.zeros(pair.n_dofs)

    def rhs(self, t: float) -> np.ndarray:
        """B u^{n+1} = −W (G u^n − d_n(u^n)) ⇔ linearised d_n(u^{n+1}) = 0, shape (m,)."""
        return self._rhs

    def begin_step(self, t: float, dt: float, u: np.ndarray, v: np.ndarray) -> None:
        self._start(t, dt, u, v)
        g = self._geo.rows
        self._rhs = -self.pair.weights * (g @ u - self._geo.gap)
        self._rhs_t = t

    def update_status(self, u: np.ndarray, v: np.ndarray, multipliers: np.ndarray) -> bool:
        p = self._pending
        g = self._geo.rows
        lam = np.asarray(multipliers, dtype=float)
        gap = p["gap_start"] + g @ (u - p["u_start"])
        used = self.active.copy()
        new = np.where(used, lam <= 0.0, gap > self.gap_tol)
        changed = bool(np.any(new != used))
        self.active = new
        # work with the trapezoidal mean of the end-point multipliers (Newmark's force average)
        p.update(calls=p["calls"] + 1, changed=changed, v_plus=v.copy(),
                 lam=lam.copy(), lam_work=0.5 * (lam + self._lam_old), lam_end=lam.copy(),
                 used=used, vn=g @ v,
                 s_d=gap > self.gap_tol, s_v=lam <= 0.0)
        return changed

    def end_step(self, t: float, u: np.ndarray, v: np.ndarray, multipliers: np.ndarray) -> None:
        lam_end = self._pending.get("lam_end") if self._pending else None
        used = self._pending.get("used") if self._pending else None
        self._finish(t, u)
        if lam_end is not None:
            self._lam_old = lam_end
        if used is not None:
            self.active = used.copy()

    def reset(self) -> None:
        super().reset()
        self._lam_old = np.zeros(self.pair.n_points)
