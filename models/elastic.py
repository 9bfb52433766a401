"""Small-strain linear elasticity on one mesh, with an optional weight at quadrature points.

The model knows nothing about Arlequin: every assembled quantity takes an optional ``weight``
(the energy partition weight α of the coupling core, default 1) evaluated at the quadrature
points of the model's basis. Units are SI throughout: lengths in m, Young's modulus and stresses
in Pa, density in kg/m³, forces in N.

Kinematics (``kind``):

``"1d"``
    A bar along x with cross-section ``area`` (m²): energy ½∫ E A (u')² dx.
``"plane_strain"``, ``"plane_stress"``
    2D in (x, y), unit thickness (energies per metre of thickness).
``"axisymmetric"``
    Meridional coordinates (r, z) = (x[0], x[1]); integrals carry the full 2π r factor;
    strains (ε_rr, ε_zz, ε_rz, ε_θθ = u_r / r).
``"3d"``
    Full 3D.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
from skfem import Basis, BilinearForm, ElementVector, FacetBasis, LinearForm, Mesh
from skfem.helpers import dot, grad

from arlequin.geometry.meshcheck import check_mesh
from arlequin.geometry.reference import scalar_element_for

__all__ = [
    "KINDS",
    "IsotropicElastic",
    "LinearElastic",
    "element_critical_step",
    "scalar_element_for",
]

KINDS = ("1d", "plane_strain", "plane_stress", "axisymmetric", "3d")


@dataclass(frozen=True)
class IsotropicElastic:
    """Isotropic linear elastic material.

    Parameters
    ----------
    young : float
        Young's modulus E (Pa), > 0.
    poisson : float
        Poisson's ratio ν, in (-1, 0.5).
    density : float
        Mass density ρ (kg/m³), ≥ 0.
    """

    young: float
    poisson: float = 0.3
    density: float = 1.0

    def __post_init__(self) -> None:
        for name in ("young", "poisson", "density"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.number)):
                raise ValueError(f"{name} must be a number (SI units), got {value!r}")
        if not np.isfinite(self.young) or self.young <= 0.0:
            raise ValueError(f"Young's modulus must be positive and finite, got young={self.young}")
        if not -1.0 < self.poisson < 0.5:
            raise ValueError(f"Poisson's ratio must lie in (-1, 0.5), got poisson={self.poisson}")
        if not np.isfinite(self.density) or self.density < 0.0:
            raise ValueError(f"density must be non-negative and finite, got density={self.density}")

    @property
    def shear_modulus(self) -> float:
        """Shear modulus μ = E / (2(1+ν)) (Pa)."""
        return self.young / (2.0 * (1.0 + self.poisson))

    @property
    def lame_lambda(self) -> float:
        """First Lamé parameter λ = Eν / ((1+ν)(1−2ν)) (Pa)."""
        return self.young * self.poisson / ((1.0 + self.poisson) * (1.0 - 2.0 * self.poisson))

    @property
    def bulk_modulus(self) -> float:
        """Bulk modulus K = E / (3(1−2ν)) (Pa)."""
        return self.young / (3.0 * (1.0 - 2.0 * self.poisson))


WeightLike = float | np.ndarray | Callable[[np.ndarray], np.ndarray] | None


class LinearElastic:
    """Linear elastic model on one first-order mesh (P1 simplices, Q1 quads/hexes).

    Implements :class:`arlequin.contract.Model` with the capabilities ``"tangent"`` (its
    stiffness) and ``"critical_time_step"`` (the element eigenvalue bound).

    Parameters
    ----------
    mesh : skfem.Mesh
        MeshLine (``kind="1d"``), MeshTri/MeshQuad (2D kinds), MeshTet/MeshHex (``"3d"``).
    material : IsotropicElastic
    kind : str
        One of :data:`KINDS`. Defaults to ``"1d"``, ``"plane_strain"`` or ``"3d"`` by dimension.
    area : float
        Cross-section area (m²) of a 1D bar; ignored otherwise.
    intorder : int, optional
        Quadrature order (polynomial degree integrated exactly). Default 3 (4 for hexahedra):
        exact for a first-order weight times the stiffness of a linear field on P1/Q1 cells.
    validate : bool
        Check the mesh (:func:`arlequin.geometry.meshcheck.check_mesh`: non-finite or unused nodes,
        degenerate and folded cells, coincident nodes) and raise ``MeshError`` naming the node
        or cell.
    allow_seams : bool
        Accept coincident nodes (a crack meant to be open).

    Notes
    -----
    Degrees of freedom are interleaved by node (scikit-fem's ``ElementVector`` ordering):
    dof ``d * node + component``.
    """

    #: The internal force is ``stiffness() @ u`` (see :class:`arlequin.contract.DynamicModel`).
    is_linear = True

    def __init__(
        self,
        mesh: Mesh,
        material: IsotropicElastic,
        kind: str | None = None,
        area: float = 1.0,
        intorder: int | None = None,
        *,
        validate: bool = True,
        allow_seams: bool = False,
    ) -> None:
        if not isinstance(mesh, Mesh):
            raise ValueError(f"mesh must be a scikit-fem Mesh, got {type(mesh).__name__}")
        if not isinstance(material, IsotropicElastic):
            raise ValueError(
                f"material must be an IsotropicElastic(young, poisson, density), got "
                f"{type(material).__name__}"
            )
        dim = mesh.dim()
        if kind is None:
            kind = {1: "1d", 2: "plane_strain", 3: "3d"}[dim]
        if kind not in KINDS:
            raise ValueError(f"kind must be one of {KINDS}, got kind={kind!r}")
        expected_dim = {"1d": 1, "plane_strain": 2, "plane_stress": 2, "axisymmetric": 2, "3d": 3}
        if expected_dim[kind] != dim:
            raise ValueError(
                f"kind={kind!r} needs a {expected_dim[kind]}D mesh, got a {dim}D "
                f"{type(mesh).__name__}"
            )
        if area <= 0.0:
            raise ValueError(f"cross-section area must be positive, got area={area}")
        if validate:
            check_mesh(mesh, f"the {type(mesh).__name__} of the model", allow_seams)
        if kind == "axisymmetric" and np.min(mesh.p[0]) < -1e-12 * np.ptp(mesh.p[0]):
            raise ValueError(
                f"axisymmetric mesh must have r = x[0] >= 0, got min r = {np.min(mesh.p[0])}"
            )
        self.mesh = mesh
        self.material = material
        self.kind = kind
        self.area = float(area)
        if intorder is None:
            intorder = 4 if mesh.t.shape[0] == 8 else 3
        self.intorder = int(intorder)
        self.dim = dim
        self.scalar_element = scalar_element_for(mesh)
        self.element = ElementVector(self.scalar_element, dim=dim)
        self._basis: Basis | None = None
        self._scalar_basis: Basis | None = None
        # scikit-fem's nvertices is a property computed on each call (28 µs): asked every step
        self._n_nodes = int(mesh.nvertices)

    @property
    def basis(self) -> Basis:
        """Vector first-order basis with the model's quadrature, built on first use.

        Lazy because it is the model's largest object (12 functions with their gradients at
        every quadrature point of a tetrahedral mesh: 1.4 GB at 200k cells), and a model used
        only to weigh or measure (an overlap's integration model before assembly) never needs
        it.
        """
        if self._basis is None:
            self._basis = Basis(self.mesh, self.element, intorder=self.intorder)
        return self._basis

    def scalar_basis(self) -> Basis:
        """Scalar first-order basis with the model's quadrature (weights at quadrature points),
        built once (the same quadrature as :attr:`basis`)."""
        if self._scalar_basis is None:
            self._scalar_basis = Basis(self.mesh, self.scalar_element, intorder=self.intorder)
        return self._scalar_basis

    # ------------------------------------------------------------------ construction helpers
    def with_mesh(self, mesh: Mesh) -> LinearElastic:
        """Same material and kinematics on another mesh (used for overlap integration)."""
        # integration meshes of overlaps are built by the core (intersection meshes give each
        # cell its own nodes on purpose): not validated again
        return LinearElastic(
            mesh, self.material, self.kind, self.area, self.intorder, validate=False
        )

    @property
    def n_dofs(self) -> int:
        """Number of displacement degrees of freedom."""
        return self.dim * self._n_nodes

    @property
    def n_components(self) -> int:
        """Displacement components per node."""
        return self.dim

    def quadrature_points(self) -> np.ndarray:
        """Physical quadrature points, shape (dim, n_elems, n_qp), in m."""
        return np.asarray(self.basis.global_coordinates())

    def nodal_dofs(self) -> np.ndarray:
        """Dof indices per node, shape (dim, n_nodes)."""
        # interleaved by node (scikit-fem's ElementVector order), without building the basis
        n = self._n_nodes
        return np.arange(self.dim * n).reshape(n, self.dim).T

    def dofs_where(self, where: Callable[[np.ndarray], np.ndarray], components=None) -> np.ndarray:
        """Dofs of the nodes ``x`` (shape (dim, n)) where ``where(x)`` is true.

        Parameters
        ----------
        where : callable
            Boolean predicate on node coordinates, shape (dim, n_nodes) -> (n_nodes,).
        components : sequence of int, optional
            Displacement components to keep (default: all).
        """
        nodes = np.nonzero(np.asarray(where(self.mesh.p), dtype=bool))[0]
        comps = range(self.dim) if components is None else list(components)
        return np.sort(self.nodal_dofs()[list(comps)][:, nodes].ravel())

    # ------------------------------------------------------------------ weights
    def weight_at_quadrature(self, weight: WeightLike, basis=None) -> np.ndarray:
        """Evaluate ``weight`` at the quadrature points of ``basis`` (default: the cell basis).

        Returns an array of shape (n_elems, n_qp). ``None`` means 1.
        """
        basis = self.basis if basis is None else basis
        shape = basis.dx.shape
        if weight is None:
            return np.ones(shape)
        if callable(weight):
            values = np.asarray(weight(np.asarray(basis.global_coordinates())), dtype=float)
            values = np.broadcast_to(values, shape)
        else:
            values = np.broadcast_to(np.asarray(weight, dtype=float), shape)
        if not np.all(np.isfinite(values)):
            raise ValueError("weight has non-finite values at quadrature points")
        return np.ascontiguousarray(values)

    def _measure(self, w) -> Any:
        """Volume measure factor per unit reference measure: A (1D), 2πr (axi), 1 otherwise."""
        if self.kind == "axisymmetric":
            return 2.0 * np.pi * w.x[0]
        if self.kind == "1d":
            return self.area
        return 1.0

    # ------------------------------------------------------------------ constitutive law
    def _lame(self) -> tuple[float, float]:
        lam, mu = self.material.lame_lambda, self.material.shear_modulus
        if self.kind == "plane_stress":
            lam = 2.0 * lam * mu / (lam + 2.0 * mu)
        if self.kind == "1d":
            # uniaxial stress: σ = E ε
            lam, mu = 0.0, 0.5 * self.material.young
        return lam, mu

    def _strain(self, u, w):
        """Return (ε matrix (dim, dim, ...), hoop strain or 0)."""
        g = grad(u)
        eps = 0.5 * (g + np.swapaxes(g, 0, 1))
        hoop = u[0] / w.x[0] if self.kind == "axisymmetric" else 0.0
        return eps, hoop

    def _energy_density_form(self, u, v, w):
        lam, mu = self._lame()
        eu, hu = self._strain(u, w)
        ev, hv = self._strain(v, w)
        tr_u = np.einsum("ii...", eu) + hu
        tr_v = np.einsum("ii...", ev) + hv
        return lam * tr_u * tr_v + 2.0 * mu * (np.einsum("ij...,ij...", eu, ev) + hu * hv)

    # ------------------------------------------------------------------ assembled operators
    def stiffness(self, weight: WeightLike = None) -> sp.csr_matrix:
        """Weighted stiffness matrix ∫ α σ(u):ε(v), shape (n_dofs, n_dofs), N/m."""
        alpha = self.weight_at_quadrature(weight)

        @BilinearForm
        def form(u, v, w):
            return w.alpha * self._energy_density_form(u, v, w) * self._measure(w)

        return form.assemble(self.basis, alpha=alpha).tocsr()

    def mass(self, weight: WeightLike = None, lumped: bool = False):
        """Weighted mass ∫ α ρ u·v (kg).

        Returns a sparse matrix (n_dofs, n_dofs), or its row sums (n_dofs,) when ``lumped``.
        """
        alpha = self.weight_at_quadrature(weight)
        rho = self.material.density

        @BilinearForm
        def form(u, v, w):
            return w.alpha * rho * dot(u, v) * self._measure(w)

        m = form.assemble(self.basis, alpha=alpha).tocsr()
        if lumped:
            return np.asarray(m.sum(axis=1)).ravel()
        return m

    def internal_force(self, u: np.ndarray, state=None, weight: WeightLike = None):
        """Internal force K(α) u (N) and the (unchanged) state, for the integrators."""
        return self.stiffness(weight) @ u, state

    def tangent(self, u: np.ndarray, state=None, weight: WeightLike = None) -> sp.csr_matrix:
        """Consistent tangent (N/m): the stiffness, whatever u (capability ``"tangent"``)."""
        return self.stiffness(weight)

    def initial_state(self, weight: WeightLike = None) -> None:
        """No state at quadrature points."""
        return None

    def critical_time_step(self, u: np.ndarray | None = None, state=None) -> float:
        """Lower bound (s) of the lumped-mass central-difference critical step of the model alone.

        ``2 / max_e √λ_max(K_e, M_e)`` over the cells (element stiffness and row-sum lumped
        element mass, weight 1): the assembled system's largest eigenvalue never exceeds the
        largest element one (Irons' theorem), and supports only lower it. Small strain: the
        same in every configuration (u is ignored). Capability ``"critical_time_step"``.
        """
        if getattr(self, "_critical_step", None) is None:
            self._critical_step = element_critical_step(self, self.basis)
        return self._critical_step

    def strain_energy(self, u: np.ndarray, weight: WeightLike = None) -> float:
        """Weighted strain energy ½ uᵀ K(α) u (J)."""
        return 0.5 * float(u @ (self.stiffness(weight) @ u))

    def body_force_vector(self, force, weight: WeightLike = None) -> np.ndarray:
        """Load vector ∫ α f·v (N) for a body force density ``force`` (N/m³).

        ``force`` is a constant vector (dim,) or a callable of x (dim, n_elems, n_qp) returning
        (dim, n_elems, n_qp). For 1D bars the force is per unit volume (multiplied by the area).
        """
        alpha = self.weight_at_quadrature(weight)
        fq = _vector_field(force, np.asarray(self.basis.global_coordinates()), self.dim)

        @LinearForm
        def form(v, w):
            return w.alpha * dot(w.f, v) * self._measure(w)

        return form.assemble(self.basis, alpha=alpha, f=fq)

    def facet_basis(self, facets: np.ndarray) -> FacetBasis:
        """scikit-fem facet basis on the given boundary facets."""
        return FacetBasis(
            self.mesh, self.element, facets=np.asarray(facets), intorder=self.intorder
        )

    def traction_vector(
        self, facets: np.ndarray, traction, weight: WeightLike = None
    ) -> np.ndarray:
        """Load vector ∫_Γ α t·v (N) for a traction ``t`` (Pa) on boundary ``facets``.

        ``traction`` is a constant vector (dim,) or a callable of (x, n) with x and the outward
        normal n of shape (dim, n_facets, n_qp), returning (dim, n_facets, n_qp).
        """
        facets = np.asarray(facets, dtype=np.int64)
        if facets.size == 0:
            return np.zeros(self.n_dofs)
        fb = self.facet_basis(facets)
        alpha = self.weight_at_quadrature(weight, basis=fb)
        x = np.asarray(fb.global_coordinates())
        n = np.asarray(fb.normals)
        if callable(traction):
            tq = np.asarray(traction(x, n), dtype=float)
        else:
            tq = _vector_field(traction, x, self.dim)
        tq = np.broadcast_to(tq, x.shape)

        @LinearForm
        def form(v, w):
            return w.alpha * dot(w.t, v) * self._measure(w)

        return form.assemble(fb, alpha=alpha, t=np.ascontiguousarray(tq))

    # ------------------------------------------------------------------ post-processing
    def stress_at_quadrature(self, u: np.ndarray) -> np.ndarray:
        """Cauchy stress at quadrature points, shape (3, 3, n_elems, n_qp) (Pa).

        2D kinds fill the (x, y) block plus σ_zz (plane strain: λ tr ε; axisymmetric: σ_θθ);
        1D fills σ_xx only.
        """
        lam, mu = self._lame()
        uq = self.basis.interpolate(u)
        g = uq.grad
        d = self.dim
        eps = 0.5 * (g + np.swapaxes(g, 0, 1))
        out = np.zeros((3, 3, *g.shape[2:]))
        hoop = 0.0
        if self.kind == "axisymmetric":
            x = np.asarray(self.basis.global_coordinates())
            hoop = np.asarray(uq)[0] / x[0]
        tr = np.einsum("ii...", eps) + hoop
        out[:d, :d] = 2.0 * mu * eps
        for i in range(d):
            out[i, i] += lam * tr
        if self.kind == "plane_strain":
            out[2, 2] = lam * tr
        elif self.kind == "axisymmetric":
            out[2, 2] = lam * tr + 2.0 * mu * hoop
        return out

    def nodal_stress(self, u: np.ndarray) -> np.ndarray:
        """Stress recovered at the nodes by lumped L2 projection, shape (3, 3, n_nodes) (Pa)."""
        sq = self.stress_at_quadrature(u)
        sbasis = self.scalar_basis()

        @BilinearForm
        def mass(u_, v_, w):
            return u_ * v_

        @LinearForm
        def rhs(v_, w):
            return w.s * v_

        lumped = np.asarray(mass.assemble(sbasis).sum(axis=1)).ravel()
        out = np.zeros((3, 3, self.mesh.nvertices))
        for i in range(3):
            for j in range(i, 3):
                vals = rhs.assemble(sbasis, s=sq[i, j]) / lumped
                out[i, j] = out[j, i] = vals[: self.mesh.nvertices]
        return out


def _vector_field(value, x: np.ndarray, dim: int) -> np.ndarray:
    """Constant vector or callable of x -> array of shape x.shape (dim, ...)."""
    if callable(value):
        out = np.asarray(value(x), dtype=float)
    else:
        vec = np.asarray(value, dtype=float).reshape(-1)
        if vec.size != dim:
            raise ValueError(f"vector data must have {dim} components, got {vec.size}")
        out = vec.reshape((dim,) + (1,) * (x.ndim - 1))
    return np.ascontiguousarray(np.broadcast_to(out, x.shape))


def element_critical_step(
    model: LinearElastic, basis: Basis, mass_basis: Basis | None = None, per_cell: bool = False
):
    """2 / √(max over cells of λ_max(K_e, M_e)) (s): the element bound of the critical step.

    Parameters
    ----------
    model : LinearElastic
        Material and kinematics (its stiffness and mass integrands; its own mesh is not used).
    basis : skfem.Basis
        Vector basis of the cells for the stiffness (e.g. on a deformed mesh).
    mass_basis : skfem.Basis, optional
        Vector basis for the row-sum lumped element masses (default ``basis``).
    per_cell : bool
        Return each cell's own bound, shape (n_cells,), instead of their minimum.
    """
    rho = model.material.density

    @BilinearForm
    def stiff(u, v, w):
        return model._energy_density_form(u, v, w) * model._measure(w)

    @BilinearForm
    def mass(u, v, w):
        return rho * dot(u, v) * model._measure(w)

    k_e = stiff.elemental(basis).tolocal()  # (n_el, nd, nd)
    m_e = mass.elemental(basis if mass_basis is None else mass_basis).tolocal().sum(axis=2)
    d = 1.0 / np.sqrt(np.maximum(m_e, 1e-300))
    scaled = k_e * d[:, :, None] * d[:, None, :]
    lam = np.linalg.eigvalsh(0.5 * (scaled + np.swapaxes(scaled, 1, 2)))[:, -1]
    steps = np.where(lam > 0.0, 2.0 / np.sqrt(np.maximum(lam, 1e-300)), np.inf)
    return steps if per_cell else float(np.min(steps))
