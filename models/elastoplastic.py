"""Finite-strain J2 elastoplasticity (Simo 1992), total Lagrangian, with an optional weight.

Multiplicative split F = F_e F_p, elastic left Cauchy–Green tensor b_e = F_e F_eᵀ, Hencky
(logarithmic) elastic strain ε_e = ½ ln b_e and the quadratic energy
ψ = ½ K (tr ε_e)² + G ‖dev ε_e‖², so the Kirchhoff stress is τ = K tr ε_e 1 + 2G dev ε_e.
Von Mises yield f = ‖dev τ‖ − √(2/3) σ_y(ε̄p) with linear isotropic hardening
σ_y(ε̄p) = σ_y0 + H ε̄p, and the exponential-map radial return in principal logarithmic strains
(exact for any step size under proportional loading). The state at each quadrature point is the
inverse plastic right Cauchy–Green tensor C_p⁻¹ and ε̄p, in an immutable :class:`PlasticState`.

Volumetric locking under isochoric plastic flow is avoided by the F-bar method on bilinear
quadrilaterals and trilinear hexahedra, F̄ = (J̄/J)^{1/3} F, with the mean dilatation of the cell
J̄ = v_e / V_e = ∫ J dV₀ / ∫ dV₀ (current over reference volume). In plane strain J̄ equals
det F at the cell centre (the classical F-bar). Axisymmetric and 3D cells need the volume
average: with the centre value a uniform stress leaves interior nodal forces on distorted cells
(the patch test fails), and with J̄ it does not. The consistent internal force
(reference configuration, weight w₀ = α dV₀) is

    f_a = Σ_qp w₀ [τ ∇ₓN_a + p (div̄N_a − div N_a) e],     p = tr τ / 3,

with ∇ₓN_a = F⁻ᵀ ∇_X N_a, div N_a e_i its i-th component (plus N_a / r for the radial component
in axisymmetry), and div̄ the cell average of div weighted by J dV₀. Axisymmetric kinematics add
the hoop stretch F_θθ = r/R = 1 + u_r/R and the hoop term τ_θθ N_a / r.

Units: SI (m, kg, s, Pa, N). Quadrature-point arrays have shape (components…, n_elems, n_qp).
The model knows nothing about Arlequin: ``weight`` (α at quadrature points, default 1) scales
every integrand.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
from skfem import Basis, Mesh, MeshHex, MeshQuad

from arlequin.contract import StateError

from .elastic import IsotropicElastic, LinearElastic, WeightLike, element_critical_step

__all__ = [
    "FiniteStrainJ2",
    "InvertedElementError",
    "J2Material",
    "PlasticState",
    "hencky_j2_return",
]

KINDS = ("plane_strain", "axisymmetric", "3d")
SQRT23 = np.sqrt(2.0 / 3.0)


class InvertedElementError(StateError):
    """A cell's Jacobian det F became non-positive (or non-finite) at a quadrature point."""


@dataclass(frozen=True)
class J2Material:
    """Isotropic elastoplastic material with von Mises yield and linear isotropic hardening.

    Parameters
    ----------
    young : float
        Young's modulus E (Pa), > 0.
    poisson : float
        Poisson's ratio ν, in (-1, 0.5).
    density : float
        Reference mass density ρ₀ (kg/m³), ≥ 0.
    yield_stress : float
        Initial yield stress σ_y0 (Pa, in Kirchhoff stress), > 0.
    hardening_modulus : float
        Linear isotropic hardening modulus H = dσ_y/dε̄p (Pa), ≥ 0.
    """

    young: float
    poisson: float
    density: float
    yield_stress: float
    hardening_modulus: float = 0.0

    def __post_init__(self) -> None:
        # reuse the elastic checks (numbers, E > 0, ν in (-1, 0.5), ρ ≥ 0)
        IsotropicElastic(self.young, self.poisson, self.density)
        for name in ("yield_stress", "hardening_modulus"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.number)):
                raise ValueError(f"{name} must be a number (Pa), got {value!r}")
        if not np.isfinite(self.yield_stress) or self.yield_stress <= 0.0:
            raise ValueError(f"yield stress must be positive, got yield_stress={self.yield_stress}")
        if not np.isfinite(self.hardening_modulus) or self.hardening_modulus < 0.0:
            raise ValueError(
                f"hardening modulus must be >= 0, got hardening_modulus={self.hardening_modulus}"
            )

    @property
    def elastic(self) -> IsotropicElastic:
        """The elastic part as an :class:`IsotropicElastic`."""
        return IsotropicElastic(self.young, self.poisson, self.density)

    @property
    def shear_modulus(self) -> float:
        """G = E / (2(1+ν)) (Pa)."""
        return self.elastic.shear_modulus

    @property
    def bulk_modulus(self) -> float:
        """K = E / (3(1−2ν)) (Pa)."""
        return self.elastic.bulk_modulus

    @property
    def dilatational_wave_speed(self) -> float:
        """c_d = √((K + 4G/3)/ρ₀) (m/s), the speed that sets the explicit stable step."""
        return float(np.sqrt((self.bulk_modulus + 4.0 * self.shear_modulus / 3.0) / self.density))


@dataclass(frozen=True)
class PlasticState:
    """State at the quadrature points (never mutated; the integrator commits trial states).

    Attributes
    ----------
    cp_inv : ndarray, shape (3, 3, n_elems, n_qp)
        Inverse plastic right Cauchy–Green tensor C_p⁻¹ (dimensionless, det = 1).
    eqps : ndarray, shape (n_elems, n_qp)
        Equivalent plastic strain ε̄p (dimensionless).
    kirchhoff : ndarray, shape (3, 3, n_elems, n_qp)
        Kirchhoff stress τ = J σ (Pa) of the last evaluation (post-processing only).
    jacobian : ndarray, shape (n_elems, n_qp)
        det F of the last evaluation (post-processing: σ = τ / J).
    """

    cp_inv: np.ndarray
    eqps: np.ndarray
    kirchhoff: np.ndarray
    jacobian: np.ndarray

    @property
    def cauchy(self) -> np.ndarray:
        """Cauchy stress σ = τ / J (Pa), shape (3, 3, n_elems, n_qp)."""
        return self.kirchhoff / self.jacobian


def _sym_eig(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigen-decomposition of symmetric (3, 3, ...) tensors.

    Returns values (3, ...) and vectors (3, 3, ...), the i-th vector being ``vectors[:, i]``.
    """
    w, v = np.linalg.eigh(np.moveaxis(a, (0, 1), (-2, -1)))
    # contiguous copies: einsum on the strided views is an order of magnitude slower
    return (
        np.ascontiguousarray(np.moveaxis(w, -1, 0)),
        np.ascontiguousarray(np.moveaxis(v, (-2, -1), (0, 1))),
    )


def _sym_eig_planar(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """As :func:`_sym_eig` for tensors whose third axis is principal (a_02 = a_12 = 0).

    Closed form for the in-plane 2×2 block (plane strain, axisymmetry), about 4× faster than
    LAPACK's batched ``eigh`` here.
    """
    a00, a11, a01 = a[0, 0], a[1, 1], a[0, 1]
    mean = 0.5 * (a00 + a11)
    radius = np.hypot(0.5 * (a00 - a11), a01)
    angle = 0.5 * np.arctan2(2.0 * a01, a00 - a11)
    cos, sin = np.cos(angle), np.sin(angle)
    values = np.stack([mean + radius, mean - radius, a[2, 2]])
    vectors = np.zeros_like(a)
    vectors[0, 0], vectors[1, 0] = cos, sin
    vectors[0, 1], vectors[1, 1] = -sin, cos
    vectors[2, 2] = 1.0
    return values, vectors


def _from_principal(values: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """Σ_i values_i n_i ⊗ n_i with n_i = vectors[:, i]; shapes (3, ...), (3, 3, ...)."""
    return np.einsum("ik...,k...,jk...->ij...", vectors, values, vectors)


def hencky_j2_return(
    be_trial: np.ndarray, eqps: np.ndarray, material: J2Material, planar: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Exponential-map radial return from a trial elastic left Cauchy–Green tensor.

    Parameters
    ----------
    be_trial : ndarray, shape (3, 3, ...)
        Trial b_e = F̄ C_p⁻¹ F̄ᵀ (symmetric positive definite).
    eqps : ndarray, shape (...)
        Equivalent plastic strain at the start of the step.
    material : J2Material
    planar : bool
        The third axis is principal (plane strain, axisymmetry): closed-form 2×2 eigenvalues.

    Returns
    -------
    tau : ndarray (3, 3, ...)
        Kirchhoff stress (Pa).
    be : ndarray (3, 3, ...)
        Updated elastic left Cauchy–Green tensor.
    eqps_new : ndarray (...)
    delta_gamma : ndarray (...)
        Plastic multiplier of the step (0 where elastic).
    """
    lam2, vec = _sym_eig_planar(be_trial) if planar else _sym_eig(be_trial)
    if not np.all(lam2 > 0.0):
        raise InvertedElementError(
            f"trial elastic stretch tensor is not positive definite (min eigenvalue "
            f"{float(np.min(lam2)):.3e})"
        )
    eps = 0.5 * np.log(lam2)  # principal Hencky strains, (3, ...)
    K, G, H = material.bulk_modulus, material.shear_modulus, material.hardening_modulus
    tr = eps.sum(axis=0)
    dev = eps - tr / 3.0
    s_trial = 2.0 * G * dev  # principal dev τ
    norm = np.sqrt(np.sum(s_trial**2, axis=0))
    f = norm - SQRT23 * (material.yield_stress + H * eqps)
    plastic = f > 0.0
    dgamma = np.where(plastic, f / (2.0 * G + 2.0 / 3.0 * H), 0.0)
    # unit return direction; where elastic (or ‖dev τ‖ = 0) it is multiplied by dgamma = 0
    direction = s_trial / np.where(norm > 0.0, norm, 1.0)
    eps_new = eps - dgamma * direction
    tau_principal = K * tr + 2.0 * G * (eps_new - tr / 3.0)
    tau = _from_principal(tau_principal, vec)
    be = _from_principal(np.exp(2.0 * eps_new), vec)
    return tau, be, eqps + SQRT23 * dgamma, dgamma


def _inv3(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverse and determinant of (3, 3, ...) tensors by cofactors (vectorised)."""
    c = np.empty_like(a)
    c[0, 0] = a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]
    c[0, 1] = a[0, 2] * a[2, 1] - a[0, 1] * a[2, 2]
    c[0, 2] = a[0, 1] * a[1, 2] - a[0, 2] * a[1, 1]
    c[1, 0] = a[1, 2] * a[2, 0] - a[1, 0] * a[2, 2]
    c[1, 1] = a[0, 0] * a[2, 2] - a[0, 2] * a[2, 0]
    c[1, 2] = a[0, 2] * a[1, 0] - a[0, 0] * a[1, 2]
    c[2, 0] = a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]
    c[2, 1] = a[0, 1] * a[2, 0] - a[0, 0] * a[2, 1]
    c[2, 2] = a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]
    det = a[0, 0] * c[0, 0] + a[0, 1] * c[1, 0] + a[0, 2] * c[2, 0]
    return c / det, det


class FiniteStrainJ2:
    """Finite-strain J2 elastoplastic model with F-bar on one Q1 mesh (explicit dynamics).

    Parameters
    ----------
    mesh : skfem.MeshQuad or skfem.MeshHex
        Reference (undeformed) mesh, in m. Axisymmetric meshes use (r, z) = (x[0], x[1]).
    material : J2Material
    kind : {"axisymmetric", "plane_strain", "3d"}
        Default ``"axisymmetric"`` for quads and ``"3d"`` for hexahedra.
    fbar : bool
        Use the F-bar deformation gradient (default). Without it, isochoric plastic flow
        locks the bilinear cells.

    Notes
    -----
    Quadrature: 2×2 (2×2×2) Gauss points; F-bar uses the cell's mean dilatation J̄. Dofs are
    interleaved by node like :class:`~arlequin.models.LinearElastic`
    (``dim * node + component``), and :meth:`mass`, :meth:`stiffness` (small-strain elastic, for
    stable-step estimates) come from a :class:`~arlequin.models.LinearElastic` on the same mesh
    and quadrature. Capabilities (:mod:`arlequin.contract`): ``"critical_time_step"`` in the
    current configuration; no ``"tangent"``: the model is meant for explicit central
    differences (implicit schemes refuse it, or use ``newton="initial"``).
    """

    is_linear = False

    def __init__(
        self, mesh: Mesh, material: J2Material, kind: str | None = None, fbar: bool = True, *,
        validate: bool = True, allow_seams: bool = False,
    ) -> None:  # fmt: skip
        if not isinstance(mesh, MeshQuad | MeshHex):
            raise ValueError(
                f"FiniteStrainJ2 needs a MeshQuad (axisymmetric, plane strain) or a MeshHex (3d) "
                f"mesh, got {type(mesh).__name__}: linear simplices lock under plastic flow"
            )
        dim = mesh.dim()
        if kind is None:
            kind = "axisymmetric" if dim == 2 else "3d"
        if kind not in KINDS or (kind == "3d") != (dim == 3):
            raise ValueError(f"kind={kind!r} does not fit a {dim}D mesh; use one of {KINDS}")
        self.mesh = mesh
        self.material = material
        self.kind = kind
        self.fbar = bool(fbar)
        self.dim = dim
        self.intorder = 3
        # checks r >= 0 in axisymmetry; gives the mass, the small-strain stiffness and the bases
        checks = {"validate": validate, "allow_seams": allow_seams}
        self.elastic = LinearElastic(mesh, material.elastic, kind, intorder=self.intorder, **checks)
        self.basis = self.elastic.basis
        sb = self.elastic.scalar_basis()
        self._t = np.asarray(mesh.t)  # (n_nodes_per_cell, n_elems)
        nen = self._t.shape[0]
        # reference gradients ∇_X N_a and values N_a: (nen, dim, ne, nq), (nen, ne, nq)
        self._grad = np.stack([sb.basis[a][0].grad for a in range(nen)])
        self._val = np.stack([np.asarray(sb.basis[a][0]) for a in range(nen)])
        x = np.asarray(sb.global_coordinates())
        self._radius = x[0] if kind == "axisymmetric" else None  # R at qp, (ne, nq)
        measure = 2.0 * np.pi * x[0] if kind == "axisymmetric" else 1.0
        self._dv0 = np.asarray(sb.dx) * measure  # reference volume per qp (m³ or m² per m)
        self._dofs = np.asarray(self.elastic.basis.nodal_dofs)  # (dim, n_nodes)
        self._cell_dofs = self._dofs[:, self._t]  # (dim, nen, ne)

    # ------------------------------------------------------------------ model protocol
    @property
    def n_dofs(self) -> int:
        """Number of displacement dofs."""
        return self.elastic.n_dofs

    @property
    def n_components(self) -> int:
        return self.dim

    @property
    def shape(self) -> tuple[int, int]:
        """(n_elems, n_qp) of the quadrature-point arrays."""
        return self._dv0.shape

    def with_mesh(self, mesh: Mesh) -> FiniteStrainJ2:
        """Same material, kinematics and F-bar choice on another mesh."""
        return FiniteStrainJ2(mesh, self.material, self.kind, self.fbar, validate=False)

    def nodal_dofs(self) -> np.ndarray:
        """Dof indices per node, shape (dim, n_nodes)."""
        return self._dofs

    def dofs_where(self, where, components=None) -> np.ndarray:
        """Dofs of the nodes where ``where(x)`` holds (see :meth:`LinearElastic.dofs_where`)."""
        return self.elastic.dofs_where(where, components)

    def scalar_basis(self) -> Basis:
        """Scalar Q1 basis with the model's quadrature."""
        return self.elastic.scalar_basis()

    def quadrature_points(self) -> np.ndarray:
        """Reference quadrature points, shape (dim, n_elems, n_qp) (m)."""
        return self.elastic.quadrature_points()

    def mass(self, weight: WeightLike = None, lumped: bool = False):
        """Weighted reference mass ∫ α ρ₀ u·v dV₀ (kg); row sums when ``lumped``."""
        return self.elastic.mass(weight, lumped=lumped)

    def stiffness(self, weight: WeightLike = None) -> sp.csr_matrix:
        """Small-strain elastic stiffness (N/m): the initial tangent, for stable-step estimates."""
        return self.elastic.stiffness(weight)

    def body_force_vector(self, force, weight: WeightLike = None) -> np.ndarray:
        """Dead body load ∫ α ρ₀b·v dV₀ (N) for a force density (N/m³ of reference volume)."""
        return self.elastic.body_force_vector(force, weight)

    def traction_vector(self, facets: np.ndarray, traction, weight: WeightLike = None):
        """Dead traction load (N) for a nominal traction (Pa, per reference area) on ``facets``."""
        return self.elastic.traction_vector(facets, traction, weight)

    def initial_state(self, weight: WeightLike = None) -> PlasticState:
        """Virgin state: C_p⁻¹ = 1, ε̄p = 0, τ = 0, J = 1."""
        ne, nq = self.shape
        eye = np.broadcast_to(np.eye(3)[:, :, None, None], (3, 3, ne, nq)).copy()
        zeros = np.zeros((ne, nq))
        return PlasticState(eye, zeros, np.zeros((3, 3, ne, nq)), np.ones((ne, nq)))

    # ------------------------------------------------------------------ kinematics
    def _cell_displacements(self, u: np.ndarray) -> np.ndarray:
        """Nodal displacements per cell, shape (dim, nen, ne)."""
        u = np.asarray(u, dtype=float)
        if u.shape != (self.n_dofs,):
            raise ValueError(f"displacement must have shape ({self.n_dofs},), got {u.shape}")
        return u[self._cell_dofs]

    def deformation_gradient(self, u: np.ndarray) -> np.ndarray:
        """Deformation gradient at the quadrature points, shape (3, 3, n_elems, n_qp).

        In 2D, F_zz = 1 (plane strain) or F_θθ = 1 + u_r/R (axisymmetric).
        """
        ue = self._cell_displacements(u)
        d = self.dim
        F = np.zeros((3, 3, *self.shape))
        F[:d, :d] = np.einsum("iae,ajeq->ijeq", ue, self._grad)
        for i in range(3):
            F[i, i] += 1.0
        if self.kind == "axisymmetric":
            F[2, 2] += np.einsum("ae,aeq->eq", ue[0], self._val) / self._radius
        return F

    def _kinematics(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, Any]:
        """F, F⁻¹, J = det F (checked > 0) and the F-bar factor (J̄/J)^{1/3} (1 without F-bar)."""
        F = self.deformation_gradient(u)
        Finv, J = _inv3(F)
        self._check_jacobian(J)
        scale = np.cbrt(self._mean_dilatation(J) / J) if self.fbar else 1.0
        return F, Finv, J, scale

    # ------------------------------------------------------------------ internal force
    def internal_force(
        self, u: np.ndarray, state: PlasticState | None = None, weight: WeightLike = None
    ) -> tuple[np.ndarray, PlasticState]:
        """Internal force (N) at displacement ``u`` from the committed ``state``.

        Parameters
        ----------
        u : ndarray, shape (n_dofs,)
            Displacement from the reference configuration (m).
        state : PlasticState, optional
            Committed state (default: virgin).
        weight : float, array (n_elems, n_qp) or callable, optional
            Partition weight α at the quadrature points.

        Returns
        -------
        f : ndarray, shape (n_dofs,)
        trial_state : PlasticState
            The state after this evaluation, to be committed by the integrator.

        Raises
        ------
        InvertedElementError
            When det F ≤ 0 (or is not finite) at a quadrature point, naming the cell.
        """
        state = self.initial_state() if state is None else state
        alpha = self.elastic.weight_at_quadrature(weight)
        F, Finv, J, scale = self._kinematics(u)
        # spatial gradients ∇ₓN_a = F⁻ᵀ ∇_X N_a (in-plane block) and the hoop term N_a / r
        d = self.dim
        gx = np.einsum("akeq,kjeq->ajeq", self._grad, Finv[:d, :d])
        hoop = None
        if self.kind == "axisymmetric":
            hoop = self._val / (self._radius * F[2, 2])  # N_a / r, (nen, ne, nq)
        Fbar = F * scale
        be_trial = np.einsum("ikeq,kleq,jleq->ijeq", Fbar, state.cp_inv, Fbar)
        tau, be, eqps, _ = hencky_j2_return(
            be_trial, state.eqps, self.material, planar=self.dim == 2
        )
        Fbar_inv = Finv / scale
        cp_inv = np.einsum("ikeq,kleq,jleq->ijeq", Fbar_inv, be, Fbar_inv)
        w0 = alpha * self._dv0
        # f_{a,i} = Σ w0 [τ_ij ∇ₓN_a,j + (hoop) + p (div̄ − div) δ_i]
        fe = np.einsum("ijeq,ajeq,eq->iae", tau[:d, :d], gx, w0)
        if self.kind == "axisymmetric":
            fe[0] += np.einsum("eq,aeq,eq->ae", tau[2, 2], hoop, w0)
        if self.fbar:
            # div N_a e_i = ∇ₓN_a,i (+ N_a / r for i = r); div̄ its J-weighted cell average
            div = gx.copy()
            if self.kind == "axisymmetric":
                div[:, 0] += hoop
            jw = J * self._dv0
            div_mean = np.einsum("aieq,eq->aie", div, jw) / jw.sum(axis=1)
            p = np.einsum("iieq->eq", tau) / 3.0
            fe += np.einsum("eq,aieq,eq->iae", p, div_mean[..., None] - div, w0)
        f = np.bincount(self._cell_dofs.ravel(), weights=fe.ravel(), minlength=self.n_dofs)
        return f, PlasticState(cp_inv, eqps, tau, J)

    def _mean_dilatation(self, J: np.ndarray) -> np.ndarray:
        """J̄ = v_e / V_e per cell (current over reference volume), shape (n_elems, 1)."""
        return (J * self._dv0).sum(axis=1, keepdims=True) / self._dv0.sum(axis=1, keepdims=True)

    def _check_jacobian(self, J: np.ndarray) -> None:
        bad = ~(J > 0.0)
        if np.any(bad):
            cell = int(np.nonzero(bad.any(axis=1))[0][0])
            raise InvertedElementError(
                f"inverted or degenerate cell {cell}: det F = {float(np.min(J[cell])):.3e} "
                f"({int(bad.any(axis=1).sum())} such cells)"
            )

    # ------------------------------------------------------------------ post-processing
    def stored_energy(self, u: np.ndarray, state: PlasticState, weight: WeightLike = None) -> float:
        """Elastic stored energy Σ w₀ ψ(ε_e) of a committed state at ``u`` (J)."""
        alpha = self.elastic.weight_at_quadrature(weight)
        F, _, _, scale = self._kinematics(u)
        Fbar = F * scale
        be = np.einsum("ikeq,kleq,jleq->ijeq", Fbar, state.cp_inv, Fbar)
        eps = 0.5 * np.log((_sym_eig_planar(be) if self.dim == 2 else _sym_eig(be))[0])
        tr = eps.sum(axis=0)
        K, G = self.material.bulk_modulus, self.material.shear_modulus
        psi = 0.5 * K * tr**2 + G * np.sum((eps - tr / 3.0) ** 2, axis=0)
        return float(np.sum(alpha * self._dv0 * psi))

    def critical_time_step(self, u: np.ndarray, state: PlasticState | None = None) -> float:
        """Element estimate (s) of the explicit critical step in the configuration X + u.

        The element eigenvalue bound of :func:`~arlequin.models.elastic.element_critical_step`
        with the small-strain elastic stiffness of the current cells and the reference lumped
        masses (total Lagrangian): it follows cells that are crushed during a run. At u = 0 it
        is a lower bound of the model's critical step. Capability ``"critical_time_step"``.
        """
        current = type(self.mesh)(self.current_coordinates(u), self.mesh.t)
        # the elastic integrands (material and kinematics) on the current cells
        basis = Basis(current, self.elastic.element, intorder=self.intorder)
        return element_critical_step(self.elastic, basis, mass_basis=self.basis)

    def current_coordinates(self, u: np.ndarray) -> np.ndarray:
        """Node positions x = X + u, shape (dim, n_nodes) (m)."""
        return self.mesh.p + np.asarray(u)[self._dofs]
