"""Small-strain J2 elastoplasticity: radial return and its consistent tangent, with a weight.

Additive split ε = ε_e + ε_p, σ = K tr ε_e 1 + 2G dev ε_e, von Mises yield with isotropic
hardening (any law of :mod:`arlequin.models.plasticity.hardening`) and linear kinematic
hardening (Prager/Ziegler, back stress β, β̇ = ⅔ H_kin ε̇_p):

    f = q(σ − β) − σ_y(ε̄p),  q(η) = √(3/2) ‖dev η‖.

The return (de Souza Neto, Perić & Owen 2008, box 7.3, with the back stress): from the trial
relative stress η^tr = 2G dev(ε − ε_p,n) − β_n and q^tr = √(3/2)‖η^tr‖, the plastic multiplier Δγ
(= Δε̄p) solves q^tr − (3G + H_kin) Δγ − σ_y(ε̄p,n + Δγ) = 0 (closed form for linear laws, Newton
safeguarded by bisection otherwise); with n = η^tr/‖η^tr‖,

    ε_p = ε_p,n + √(3/2) Δγ n,  β = β_n + √(2/3) H_kin Δγ n,  σ = σ^tr − √6 G Δγ n.

The consistent tangent (box 7.4, H̄ = σ_y'(ε̄p) + H_kin at the end of the step):

    D = K 1⊗1 + 2G (1 − a) I_dev + c n⊗n,  a = 3GΔγ/q^tr,  c = 2G a − 6G²/(3G + H̄),

the elastic moduli where the point stays elastic. Rate-dependent laws are evaluated at a
vanishing plastic strain rate (quasi-static).

Symmetric tensors are Mandel vectors (the shear components times √2, so that σ:ε is a dot
product): 4 components (xx, yy, zz, xy) for the planar kinds, zz the out-of-plane strain
(plane strain: ε_zz = 0, σ_zz carried by the state) or the hoop strain u_r/r (axisymmetric: x
is r, y is z, zz is θθ); 6 (xx, yy, zz, yz, xz, xy) in 3D. Quadrature-point arrays have shape
(components…, n_elems, n_qp). Units: SI (Pa, m, N, J).

Size: the point function, its tangent and the model on top of them stay together (under 600
lines), each small; the mass, loads and bases are those of :class:`LinearElastic`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
from skfem import Basis, Mesh

from arlequin.contract import CellStates, StateError

from ..assembly import CellPattern
from ..elastic import LinearElastic, WeightLike
from .hardening import Hardening
from .j2 import J2Material
from .small_strain_kernel import small_strain_tangent_kernel

__all__ = [
    "SMALL_STRAIN_KINDS",
    "ReturnResult",
    "SmallStrainJ2",
    "SmallStrainState",
    "consistent_tangent",
    "from_mandel",
    "small_strain_return",
    "to_mandel",
]

#: Kinematics of :class:`SmallStrainJ2`.
SMALL_STRAIN_KINDS = ("plane_strain", "axisymmetric", "3d")

_R2 = np.sqrt(2.0)
_R32 = np.sqrt(1.5)
#: Mandel shear components (row, column) after the three normal ones
_SHEARS = {4: ((0, 1),), 6: ((1, 2), (0, 2), (0, 1))}


def to_mandel(tensor: np.ndarray, planar: bool = False) -> np.ndarray:
    """Mandel vector (6, ...) of symmetric (3, 3, ...) tensors; (4, ...) with ``planar`` (the
    xz and yz components dropped)."""
    t = np.asarray(tensor, dtype=float)
    shears = _SHEARS[4 if planar else 6]
    normal = [t[i, i] for i in range(3)]
    return np.stack(normal + [_R2 * t[i, j] for i, j in shears])


def from_mandel(vector: np.ndarray) -> np.ndarray:
    """Symmetric (3, 3, ...) tensors of Mandel vectors (4 or 6, ...)."""
    v = np.asarray(vector, dtype=float)
    out = np.zeros((3, 3, *v.shape[1:]))
    for i in range(3):
        out[i, i] = v[i]
    for k, (i, j) in enumerate(_SHEARS[v.shape[0]]):
        out[i, j] = out[j, i] = v[3 + k] / _R2
    return out


def _trace(v: np.ndarray) -> np.ndarray:
    return v[0] + v[1] + v[2]


def _dev(v: np.ndarray) -> np.ndarray:
    out = np.array(v, dtype=float)
    out[:3] -= _trace(v) / 3.0
    return out


@dataclass(frozen=True)
class SmallStrainState:
    """State at the quadrature points (never mutated: the arrays are read-only; the solver
    commits the trial states that :meth:`SmallStrainJ2.internal_force` returns).

    Attributes
    ----------
    plastic_strain : ndarray, shape (ns, n_elems, n_qp)
        ε_p as Mandel vectors (ns = 4 planar, 6 in 3D), dimensionless, traceless.
    eqps : ndarray, shape (n_elems, n_qp)
        Equivalent plastic strain ε̄p.
    back_stress : ndarray, shape (ns, n_elems, n_qp)
        β (Pa), Mandel, deviatoric.
    stress : ndarray, shape (ns, n_elems, n_qp)
        σ (Pa) of the last evaluation, Mandel (σ_zz of plane strain included).
    plastic_work : ndarray, shape (n_elems, n_qp)
        Accumulated dissipation Σ σ_y(ε̄p) Δε̄p per unit volume (J/m³).
    """

    plastic_strain: np.ndarray
    eqps: np.ndarray
    back_stress: np.ndarray
    stress: np.ndarray
    plastic_work: np.ndarray

    def __post_init__(self) -> None:
        for name in ("plastic_strain", "eqps", "back_stress", "stress", "plastic_work"):
            value = np.asarray(getattr(self, name), dtype=float)
            if value.flags.writeable:  # a read-only view: the state cannot be changed through it
                value = value.view()
                value.flags.writeable = False
            object.__setattr__(self, name, value)

    @property
    def stress_tensor(self) -> np.ndarray:
        """σ (Pa) as symmetric tensors, shape (3, 3, n_elems, n_qp)."""
        return from_mandel(self.stress)

    @property
    def von_mises(self) -> np.ndarray:
        """√(3/2) ‖dev σ‖ (Pa), shape (n_elems, n_qp)."""
        return _R32 * np.sqrt(np.sum(_dev(self.stress) ** 2, axis=0))


class ReturnResult(NamedTuple):
    """What :func:`small_strain_return` returns (arrays over the points, Mandel vectors first).

    ``stress``, ``plastic_strain``, ``back_stress`` (ns, ...); ``eqps``, ``delta_gamma`` (the
    plastic multiplier Δγ = Δε̄p, 0 where elastic), ``dissipation`` (σ_y(ε̄p) Δγ, J/m³),
    ``reduction`` (a = 3GΔγ/q^tr) and ``normal_coefficient`` (c, Pa) (...); ``normal`` (n, the
    unit Mandel normal, ns, ...): the consistent tangent is K 1⊗1 + 2G(1 − a) I_dev + c n⊗n.
    """

    stress: np.ndarray
    plastic_strain: np.ndarray
    eqps: np.ndarray
    back_stress: np.ndarray
    delta_gamma: np.ndarray
    dissipation: np.ndarray
    normal: np.ndarray
    reduction: np.ndarray
    normal_coefficient: np.ndarray


def small_strain_return(
    strain: np.ndarray,
    plastic_strain: np.ndarray,
    eqps: np.ndarray,
    back_stress: np.ndarray,
    material: J2Material,
    kinematic_modulus: float = 0.0,
    *,
    tol: float = 1e-12,
    max_iter: int = 50,
) -> ReturnResult:
    """Radial return of small-strain J2 with isotropic and linear kinematic hardening.

    Parameters
    ----------
    strain : ndarray, shape (ns, ...)
        Total strain ε at the end of the step, Mandel (ns = 4: xx, yy, zz, xy; 6: xx, yy, zz,
        yz, xz, xy).
    plastic_strain, eqps, back_stress : ndarray, shapes (ns, ...), (...), (ns, ...)
        The committed state: ε_p, ε̄p, β (Pa).
    material : J2Material
        E, ν and the isotropic law σ_y(ε̄p) (``material.law``).
    kinematic_modulus : float
        H_kin (Pa), ≥ 0.
    tol : float
        Relative tolerance of Newton on Δγ (nonlinear laws; linear ones are solved exactly).
    max_iter : int

    Returns
    -------
    ReturnResult

    Raises
    ------
    StateError
        If Newton on Δγ does not converge.
    """
    strain = np.asarray(strain, dtype=float)
    K, G = material.bulk_modulus, material.shear_modulus
    law, hk = material.law, float(kinematic_modulus)
    elastic = strain - plastic_strain
    s_trial = 2.0 * G * _dev(elastic)
    eta = s_trial - back_stress
    norm = np.sqrt(np.sum(eta**2, axis=0))
    q_trial = _R32 * norm
    eqps = np.asarray(eqps, dtype=float)
    plastic = q_trial - law.flow_stress(eqps) > 0.0
    dgamma = np.zeros_like(q_trial)
    if np.any(plastic):
        dgamma[plastic] = _multiplier(q_trial[plastic], eqps[plastic], law, 3.0 * G + hk, tol,
                                      max_iter)  # fmt: skip
    normal = eta / np.where(norm > 0.0, norm, 1.0)
    step = _R32 * dgamma * normal  # Δε_p
    ns = strain.shape[0]
    one = np.r_[np.ones(3), np.zeros(ns - 3)].reshape((ns,) + (1,) * (strain.ndim - 1))  # 1
    stress = K * _trace(elastic) * one + s_trial - 2.0 * G * step
    eqps_new = eqps + dgamma
    q_safe = np.where(plastic, q_trial, 1.0)
    reduction = np.where(plastic, 3.0 * G * dgamma / q_safe, 0.0)
    hbar = law.slope(eqps_new) + hk
    coef = np.where(plastic, 2.0 * G * reduction - 6.0 * G**2 / (3.0 * G + hbar), 0.0)
    work = np.where(plastic, law.flow_stress(eqps_new) * dgamma, 0.0)
    return ReturnResult(stress, plastic_strain + step, eqps_new,
                        back_stress + (2.0 / 3.0) * hk * step, dgamma, work, normal, reduction,
                        coef)  # fmt: skip


def _multiplier(q_trial, eqps, law: Hardening, stiff: float, tol: float, max_iter: int):
    """Δγ > 0 with r(Δγ) = q^tr − stiff Δγ − σ_y(ε̄p + Δγ) = 0, stiff = 3G + H_kin.

    r decreases strictly, r(0) > 0 and r(q^tr/stiff) < 0: Newton, bisecting when a step leaves
    the bracket. Linear laws: one exact step.
    """
    dg = (q_trial - law.flow_stress(eqps)) / (stiff + law.slope(eqps))
    if law.kernel_code == 0:
        return dg
    scale = law.flow_stress(eqps)
    lo, hi = np.zeros_like(dg), q_trial / stiff
    dg = np.clip(dg, 0.0, hi)
    for _ in range(max_iter):
        r = q_trial - stiff * dg - law.flow_stress(eqps + dg)
        done = (np.abs(r) <= tol * scale) | (hi - lo <= 1e-15 * hi)
        if np.all(done):
            return dg
        lo = np.where(r > 0.0, dg, lo)
        hi = np.where(r < 0.0, dg, hi)
        newton = dg + r / (stiff + law.slope(eqps + dg))
        inside = (newton > lo) & (newton < hi)
        dg = np.where(done, dg, np.where(inside, newton, 0.5 * (lo + hi)))
    raise StateError(
        f"small-strain J2 return: Newton on the plastic multiplier not converged in {max_iter} "
        f"iterations (residual {float(np.max(np.abs(r))):.3e} Pa)"
    )


def consistent_tangent(result: ReturnResult, material: J2Material) -> np.ndarray:
    """The consistent tangent dσ/dε as Mandel matrices, shape (ns, ns, ...) (Pa)."""
    K, G = material.bulk_modulus, material.shear_modulus
    n = result.normal
    ns = n.shape[0]
    one = np.r_[np.ones(3), np.zeros(ns - 3)]  # the Mandel vector of 1
    extra = (1,) * (n.ndim - 1)
    eye = np.eye(ns).reshape((ns, ns, *extra))
    oo = np.outer(one, one).reshape((ns, ns, *extra))
    g2 = 2.0 * G * (1.0 - result.reduction)
    return K * oo + g2 * (eye - oo / 3.0) + result.normal_coefficient * n[:, None] * n[None, :]


class SmallStrainJ2(CellStates):
    """Small-strain J2 elastoplastic model on one first-order mesh (quasi-static and implicit).

    Implements :class:`arlequin.contract.Model` with the capabilities ``"tangent"`` (the
    consistent tangent of the radial return) and ``"critical_time_step"`` (the elastic element
    bound, a lower bound whatever the state: plastic flow only softens the cells).

    Parameters
    ----------
    mesh : skfem.Mesh
        MeshTri/MeshQuad (planar kinds) or MeshTet/MeshHex (``"3d"``), in m.
    material : J2Material
        E, ν, ρ, σ_y0 and the isotropic hardening law.
    kind : {"plane_strain", "axisymmetric", "3d"}
        Default ``"plane_strain"`` in 2D, ``"3d"`` in 3D.
    hardening : Hardening, optional
        Another isotropic law, replacing the material's (its σ_y(0) becomes σ_y0).
    kinematic_modulus : float
        H_kin (Pa), ≥ 0: linear kinematic hardening.
    intorder : int
        Quadrature order (default 3: 2×2 / 2×2×2 Gauss points on quads / hexahedra).
    bbar : bool
        Mean-dilatation B-bar (volumetric strain averaged over each cell, ∫ dV-weighted):
        bilinear cells then do not lock under isochoric plastic flow. Default False.
    validate, allow_seams : bool
        Mesh checks (see :class:`~arlequin.models.LinearElastic`).

    Notes
    -----
    Mass, loads and bases come from a :class:`~arlequin.models.LinearElastic` on the same mesh
    and quadrature; :meth:`stiffness` is the virgin state's tangent. The state is a
    :class:`SmallStrainState`; :meth:`internal_force` returns the trial state at u from the
    committed one, :meth:`tangent` the derivative of that force. Without ``bbar`` (full
    integration) cells stiffen under isochoric plastic flow (volumetric locking).
    """

    is_linear = False

    def __init__(
        self, mesh: Mesh, material: J2Material, kind: str | None = None, *,
        hardening: Hardening | None = None, kinematic_modulus: float = 0.0, intorder: int = 3,
        bbar: bool = False, validate: bool = True, allow_seams: bool = False,
    ) -> None:  # fmt: skip
        if not isinstance(material, J2Material):
            raise ValueError(f"material must be a J2Material, got {type(material).__name__}")
        if hardening is not None:
            if not isinstance(hardening, Hardening):
                raise ValueError(f"hardening must be a Hardening law, got {hardening!r}")
            material = J2Material.with_law(material.young, material.poisson, material.density,
                                           hardening)  # fmt: skip
        slope0 = float(np.asarray(material.law.slope(np.zeros(1)))[0])
        if not slope0 >= 0.0:
            raise ValueError(f"hardening slope must be >= 0 (softening is out of scope), got "
                             f"dσ_y/dε̄p = {slope0} Pa at ε̄p = 0")  # fmt: skip
        hk = kinematic_modulus
        if isinstance(hk, bool) or not isinstance(hk, (int, float, np.number)):
            raise ValueError(f"kinematic_modulus must be a number (Pa), got {hk!r}")
        if not (np.isfinite(hk) and hk >= 0.0):
            raise ValueError(f"kinematic hardening modulus must be >= 0 (softening is out of "
                             f"scope), got kinematic_modulus={hk}")  # fmt: skip
        dim = mesh.dim() if isinstance(mesh, Mesh) else None
        kind = ("plane_strain" if dim == 2 else "3d") if kind is None else kind
        if kind not in SMALL_STRAIN_KINDS:
            raise ValueError(f"kind must be one of {SMALL_STRAIN_KINDS}, got kind={kind!r}")
        self.material = material
        self.kinematic_modulus = float(hk)
        checks = {"validate": validate, "allow_seams": allow_seams}
        self.elastic = LinearElastic(mesh, material.elastic, kind, intorder=intorder, **checks)
        self.mesh, self.kind, self.dim, self.intorder = mesh, kind, mesh.dim(), int(intorder)
        self.ns = 6 if self.dim == 3 else 4
        basis = self.elastic.scalar_basis()
        t = np.asarray(mesh.t)
        self._grad = np.stack([basis.basis[a][0].grad for a in range(t.shape[0])])
        self._val = np.stack([np.asarray(basis.basis[a][0]) for a in range(t.shape[0])])
        x = np.asarray(basis.global_coordinates())
        self._rinv = 1.0 / x[0] if kind == "axisymmetric" else None
        self._dv = np.asarray(basis.dx) * (2.0 * np.pi * x[0] if kind == "axisymmetric" else 1.0)
        # local dof m = dim * a + i of cell e: global dim * node + i
        self._cell_dofs = (self.dim * t.T[:, :, None] + np.arange(self.dim)).reshape(t.shape[1], -1)
        self._pattern: CellPattern | None = None  # computed at the first tangent
        self.bbar = bool(bbar)
        if self.bbar:  # div N_a e_i at the points and its cell mean (mean dilatation)
            div = self._grad.copy()
            if self._rinv is not None:
                div[:, 0] += self._val * self._rinv
            self._div = div
            self._div_mean = np.einsum("aieq,eq->aie", div, self._dv) / self._dv.sum(axis=1)

    # ------------------------------------------------------------------ model protocol
    @property
    def n_dofs(self) -> int:
        """Number of displacement dofs."""
        return self.elastic.n_dofs

    @property
    def n_components(self) -> int:
        """Displacement components per node."""
        return self.dim

    @property
    def shape(self) -> tuple[int, int]:
        """(n_elems, n_qp) of the quadrature-point arrays."""
        return self._dv.shape

    @property
    def basis(self) -> Basis:
        """The vector basis (of the elastic model)."""
        return self.elastic.basis

    def with_mesh(self, mesh: Mesh) -> SmallStrainJ2:
        """Same material, hardening, kinematics and quadrature on another mesh."""
        return SmallStrainJ2(mesh, self.material, self.kind, intorder=self.intorder,
                             kinematic_modulus=self.kinematic_modulus, bbar=self.bbar,
                             validate=False)  # fmt: skip

    def scalar_basis(self) -> Basis:
        """Scalar first-order basis with the model's quadrature."""
        return self.elastic.scalar_basis()

    def quadrature_points(self) -> np.ndarray:
        """Quadrature points, shape (dim, n_elems, n_qp) (m)."""
        return self.elastic.quadrature_points()

    def nodal_dofs(self) -> np.ndarray:
        """Dof indices per node, shape (dim, n_nodes)."""
        return self.elastic.nodal_dofs()

    def dofs_where(self, where, components=None) -> np.ndarray:
        """Dofs of the nodes where ``where(x)`` holds (see :meth:`LinearElastic.dofs_where`)."""
        return self.elastic.dofs_where(where, components)

    def mass(self, weight: WeightLike = None, lumped: bool = False):
        """Weighted mass ∫ α ρ u·v (kg); row sums when ``lumped``."""
        return self.elastic.mass(weight, lumped=lumped)

    def stiffness(self, weight: WeightLike = None) -> sp.csr_matrix:
        """Weighted elastic stiffness (N/m): the virgin state's tangent (B̄ with ``bbar``)."""
        zero = np.zeros(self.shape)
        virgin = ReturnResult(*(None,) * 6, np.zeros((self.ns, *self.shape)), zero, zero)
        return self._assemble_tangent(virgin, self._weights(weight))

    def body_force_vector(self, force, weight: WeightLike = None) -> np.ndarray:
        """Load vector ∫ α f·v (N) of a body force density (N/m³)."""
        return self.elastic.body_force_vector(force, weight)

    def traction_vector(self, facets: np.ndarray, traction, weight: WeightLike = None):
        """Load vector ∫_Γ α t·v (N) of a traction (Pa) on boundary ``facets``."""
        return self.elastic.traction_vector(facets, traction, weight)

    def critical_time_step(self, u: np.ndarray | None = None, state=None) -> float:
        """The elastic element bound of the explicit critical step (s), whatever u and the
        state (capability ``"critical_time_step"``)."""
        return self.elastic.critical_time_step(u, state)

    def initial_state(self, weight: WeightLike = None) -> SmallStrainState:
        """Virgin state: no plastic strain, ε̄p = 0, β = 0, σ = 0, no dissipation."""
        ne, nq = self.shape
        vec, scal = np.zeros((self.ns, ne, nq)), np.zeros((ne, nq))
        return SmallStrainState(vec, scal, vec, vec, scal)

    # ------------------------------------------------------------------ kinematics and forces
    def strain(self, u: np.ndarray) -> np.ndarray:
        """Total strain at the quadrature points, Mandel, shape (ns, n_elems, n_qp) (with
        ``bbar``, its volumetric part replaced by the cell's mean dilatation)."""
        u = np.asarray(u, dtype=float)
        if u.shape != (self.n_dofs,):
            raise ValueError(f"displacement must have shape ({self.n_dofs},), got {u.shape}")
        t = self.mesh.t
        ue = u.reshape(-1, self.dim).T[:, t]  # (dim, nen, ne)
        h = np.einsum("iae,ajeq->ijeq", ue, self._grad)
        if self.dim == 3:
            eps = np.stack([h[0, 0], h[1, 1], h[2, 2], (h[1, 2] + h[2, 1]) / _R2,
                            (h[0, 2] + h[2, 0]) / _R2, (h[0, 1] + h[1, 0]) / _R2])  # fmt: skip
        else:
            hoop = np.zeros_like(h[0, 0])
            if self._rinv is not None:
                hoop = np.einsum("ae,aeq->eq", ue[0], self._val) * self._rinv
            eps = np.stack([h[0, 0], h[1, 1], hoop, (h[0, 1] + h[1, 0]) / _R2])
        if self.bbar:
            theta = _trace(eps)
            mean = np.sum(theta * self._dv, axis=1, keepdims=True) / self._dv.sum(axis=1)[:, None]
            eps[:3] += (mean - theta) / 3.0
        return eps

    def _force(self, stress: np.ndarray, w: np.ndarray) -> np.ndarray:
        """Σ_qp w Bᵀσ: the nodal force (N) of a Mandel stress field with weights w (m³)."""
        sig = from_mandel(stress)[: self.dim, : self.dim] * w
        fe = np.einsum("ijeq,ajeq->eai", sig, self._grad)
        if self._rinv is not None:
            fe[:, :, 0] += np.einsum("eq,aeq->ea", stress[2] * w * self._rinv, self._val)
        if self.bbar:  # B̄ = B + ⅓ 1 ⊗ (div̄ − div): the pressure times (div̄ − div) N_a
            wp = _trace(stress) / 3.0 * w
            fe += np.einsum("aie,e->eai", self._div_mean, wp.sum(axis=1))
            fe -= np.einsum("aieq,eq->eai", self._div, wp)
        return np.bincount(self._cell_dofs.ravel(), fe.reshape(fe.shape[0], -1).ravel(),
                           minlength=self.n_dofs)  # fmt: skip

    def _return(self, u: np.ndarray, state: SmallStrainState | None) -> ReturnResult:
        state = self.initial_state() if state is None else state
        return small_strain_return(
            self.strain(u), state.plastic_strain, state.eqps, state.back_stress, self.material,
            self.kinematic_modulus,
        )  # fmt: skip

    def _weights(self, weight: WeightLike) -> np.ndarray:
        if weight is None:
            return self._dv
        return self.elastic.weight_at_quadrature(weight, self.scalar_basis()) * self._dv

    @staticmethod
    def _trial_state(ret: ReturnResult, state: SmallStrainState | None) -> SmallStrainState:
        work = ret.dissipation if state is None else state.plastic_work + ret.dissipation
        return SmallStrainState(ret.plastic_strain, ret.eqps, ret.back_stress, ret.stress, work)

    def internal_force(
        self, u: np.ndarray, state: SmallStrainState | None = None, weight: WeightLike = None
    ) -> tuple[np.ndarray, SmallStrainState]:
        """Internal force ∫ α σ:ε(v) (N), shape (n_dofs,), and the trial state at u (m) from
        the committed ``state`` (default: virgin).

        Raises
        ------
        StateError
            If the return map fails.
        """
        ret = self._return(u, state)
        return self._force(ret.stress, self._weights(weight)), self._trial_state(ret, state)

    def tangent(
        self, u: np.ndarray, state: SmallStrainState | None = None, weight: WeightLike = None
    ) -> sp.csr_matrix:
        """Consistent tangent ∂f_int/∂u (N/m) at u from the committed state, sparse
        (n_dofs, n_dofs) (capability ``"tangent"``)."""
        return self._assemble_tangent(self._return(u, state), self._weights(weight))

    def linearization(
        self, u: np.ndarray, state: SmallStrainState | None = None, weight: WeightLike = None
    ) -> tuple[np.ndarray, sp.csr_matrix, SmallStrainState]:
        """:meth:`internal_force` and :meth:`tangent` from one return map: (f, K, trial state)."""
        ret = self._return(u, state)
        w = self._weights(weight)
        return self._force(ret.stress, w), self._assemble_tangent(ret, w), self._trial_state(
            ret, state)  # fmt: skip

    def _assemble_tangent(self, ret: ReturnResult, w: np.ndarray) -> sp.csr_matrix:
        """Σ_qp w B̄ᵀ D B̄ compiled into the CSR pattern computed at the first call."""
        if self._pattern is None:
            self._pattern = CellPattern(self.mesh.t.T, self.dim, self.mesh.p.shape[1])
        pat, K = self._pattern, self.material.bulk_modulus
        g2 = 2.0 * self.material.shear_modulus * (1.0 - ret.reduction) * w
        tt = (0.0 if self.bbar else K * w) - g2 / 3.0
        rinv = self._rinv if self._rinv is not None else np.zeros((1, 1))
        data = small_strain_tangent_kernel(
            np.zeros(pat.nnz), pat.cells, pat.base, pat.row_stride, pat.order, pat.colour_ptr,
            self._grad, self._val, rinv, self._rinv is not None, g2, tt,
            ret.normal_coefficient * w, ret.normal, self.bbar, self._dv, K * w.sum(axis=1),
        )  # fmt: skip
        return pat.matrix(data)

    # ------------------------------------------------------------------ post-processing
    def von_mises(self, state: SmallStrainState) -> np.ndarray:
        """Von Mises stress (Pa) at the quadrature points, shape (n_elems, n_qp)."""
        return state.von_mises

    def yield_stress(self, state: SmallStrainState | None = None) -> np.ndarray:
        """σ_y(ε̄p) (Pa), shape (n_elems, n_qp); σ_y0 for None (adaptive patches' member)."""
        eqps = np.zeros(self.shape) if state is None else np.asarray(state.eqps)
        return np.asarray(self.material.law.flow_stress(eqps), dtype=float) + 0.0 * eqps

    def equivalent_plastic_strain(self, state: SmallStrainState) -> np.ndarray:
        """ε̄p at the quadrature points, shape (n_elems, n_qp)."""
        return np.asarray(state.eqps)

    def stress_at_quadrature(self, state: SmallStrainState) -> np.ndarray:
        """σ (Pa) of a state as tensors, shape (3, 3, n_elems, n_qp) (zz: σ_zz or σ_θθ)."""
        return state.stress_tensor

    def stored_energy(self, state: SmallStrainState, weight: WeightLike = None) -> float:
        """Stored energy Σ α dV ψ (J) of a state: elastic, ψ_e = (tr σ)²/(18K) + ‖dev σ‖²/(4G),
        plus that of the back stress, ψ_kin = 3 β:β/(4 H_kin)."""
        K, G = self.material.bulk_modulus, self.material.shear_modulus
        s = state.stress
        psi = _trace(s) ** 2 / (18.0 * K) + np.sum(_dev(s) ** 2, axis=0) / (4.0 * G)
        if self.kinematic_modulus > 0.0:
            psi = psi + 0.75 * np.sum(state.back_stress**2, axis=0) / self.kinematic_modulus
        return float(np.sum(self._weights(weight) * psi))

    def stored_energy_of_state(self, state: SmallStrainState, weight: WeightLike = None) -> float:
        """:meth:`stored_energy` (J): the energy member of ``contract.DynamicModel``."""
        return self.stored_energy(state, weight)

    def plastic_dissipation(self, state: SmallStrainState, weight: WeightLike = None) -> float:
        """Accumulated plastic dissipation Σ α dV Σ_steps σ_y(ε̄p) Δε̄p (J)."""
        return float(np.sum(self._weights(weight) * state.plastic_work))
