"""J2 plasticity at a material point: Hencky elasticity, von Mises yield, exponential-map return.

A pure point function (in the manner of material-model libraries): given the trial elastic left
Cauchy–Green tensor b_e = F̄ C_p⁻¹ F̄ᵀ and the state at the start of the step, return the
Kirchhoff stress and the new state; the kinematics (axisymmetric, plane strain, 3D, F-bar) live
in :mod:`arlequin.models.plasticity.kinematics` and are shared by every material.

Multiplicative split F = F_e F_p, Hencky (logarithmic) elastic strain ε_e = ½ ln b_e and the
quadratic energy ψ = ½ K (tr ε_e)² + G ‖dev ε_e‖², so τ = K tr ε_e 1 + 2G dev ε_e. Von Mises
yield f = ‖dev τ‖ − √(2/3) σ_y(ε̄p, ε̄̇p) with any isotropic hardening law
(:mod:`arlequin.models.plasticity.hardening`); the return in principal logarithmic strains is radial
(exact for any step size under proportional loading), Δγ from the scalar consistency equation
(closed form for linear hardening, Newton otherwise). The plastic work per unit reference volume
of the step is σ_y(ε̄p_{n+1}) Δε̄p (the Kirchhoff plastic power τ:d_p = σ_y ε̄̇p).
Units: SI (Pa; strains dimensionless; rates 1/s).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from arlequin.contract import StateError

from ..elastic import IsotropicElastic
from .hardening import Hardening, LinearHardening

__all__ = [
    "SQRT23",
    "InvertedElementError",
    "J2Material",
    "PlasticState",
    "hencky_j2_return",
    "hencky_strain",
    "j2_return_map",
    "j2_update",
]

SQRT23 = np.sqrt(2.0 / 3.0)


class InvertedElementError(StateError):
    """A cell's Jacobian det F became non-positive (or non-finite) at a quadrature point."""


@dataclass(frozen=True)
class J2Material:
    """Isotropic elastoplastic material: Hencky elasticity, von Mises yield, isotropic hardening.

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
    hardening : Hardening, optional
        Another hardening law (:mod:`arlequin.models.plasticity.hardening`); its σ_y(0) must equal
        ``yield_stress`` and ``hardening_modulus`` must be left at 0. See :meth:`with_law`.
    """

    young: float
    poisson: float
    density: float
    yield_stress: float
    hardening_modulus: float = 0.0
    hardening: Hardening | None = None

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
        if self.hardening is not None:
            if not isinstance(self.hardening, Hardening):
                raise ValueError(f"hardening must be a Hardening law, got {self.hardening!r}")
            s0 = self.hardening.initial_yield_stress
            if abs(s0 - self.yield_stress) > 1e-12 * s0 or self.hardening_modulus != 0.0:
                raise ValueError(
                    f"with a hardening law, yield_stress must be its σ_y(0) = {s0} Pa (got "
                    f"{self.yield_stress}) and hardening_modulus 0 (got "
                    f"{self.hardening_modulus}): use J2Material.with_law"
                )

    @classmethod
    def with_law(cls, young: float, poisson: float, density: float, hardening: Hardening):
        """A material with any hardening law (the initial yield stress taken from it)."""
        return cls(young, poisson, density, hardening.initial_yield_stress, 0.0, hardening)

    @property
    def law(self) -> Hardening:
        """The hardening law (linear from ``yield_stress`` and ``hardening_modulus`` by default)."""
        if self.hardening is not None:
            return self.hardening
        return LinearHardening(self.yield_stress, self.hardening_modulus)

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
        det F of the last evaluation (post-processing: σ = τ / J; bulk viscosity rates).
    plastic_work : ndarray, shape (n_elems, n_qp)
        Accumulated plastic work per unit reference volume (J/m³).
    viscous_work : ndarray, shape (n_elems, n_qp)
        Accumulated work of the artificial bulk viscosity per unit reference volume (J/m³).
    """

    cp_inv: np.ndarray
    eqps: np.ndarray
    kirchhoff: np.ndarray
    jacobian: np.ndarray
    plastic_work: np.ndarray | None = None
    viscous_work: np.ndarray | None = None

    @property
    def cauchy(self) -> np.ndarray:
        """Cauchy stress σ = τ / J (Pa), shape (3, 3, n_elems, n_qp)."""
        return self.kirchhoff / self.jacobian

    @property
    def von_mises(self) -> np.ndarray:
        """Von Mises equivalent Cauchy stress √(3/2) ‖dev σ‖ (Pa), shape (n_elems, n_qp)."""
        s = self.cauchy
        dev = s - np.einsum("kk...->...", s) / 3.0 * np.eye(3)[:, :, None, None]
        return np.sqrt(1.5 * np.einsum("ij...,ij...->...", dev, dev))


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


def j2_return_map(
    be_trial: np.ndarray,
    eqps: np.ndarray,
    material: J2Material,
    planar: bool = False,
    dt: float | None = None,
    tol: float = 1e-12,
    max_iter: int = 50,
    *,
    minus_identity: bool = False,
    log_volume: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
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
    dt : float, optional
        Time step (s) for rate-dependent laws (ε̄̇p = Δε̄p/Δt); None: rate 0.
    tol : float
        Relative tolerance of the Newton iterations on Δγ (nonlinear laws).
    max_iter : int
    minus_identity : bool
        ``be_trial`` holds b_e − 1 (accurate at small strains: the strains are then
        ½ log1p of its eigenvalues, see
        :meth:`~arlequin.models.plasticity.kinematics.Q1Kinematics.trial_elastic_stretch`).
    log_volume : ndarray (...), optional
        The volumetric Hencky strain tr ε_e (ln J̄ with F-bar) when ``be_trial`` is b_e up to an
        isotropic factor (F-bar: F C_p⁻¹ Fᵀ); default ½ ln det b_e.

    Returns
    -------
    tau : ndarray (3, 3, ...)
        Kirchhoff stress (Pa).
    be : ndarray (3, 3, ...)
        Updated elastic left Cauchy–Green tensor.
    eqps_new : ndarray (...)
    delta_gamma : ndarray (...)
        Plastic multiplier of the step (0 where elastic).
    plastic_work : ndarray (...)
        σ_y(ε̄p_{n+1}) Δε̄p, the plastic work of the step per unit reference volume (J/m³).

    Raises
    ------
    InvertedElementError
        If b_e is not positive definite; StateError if the Newton iterations fail.
    """
    dev, tr, vec = hencky_strain(be_trial, planar, minus_identity)  # principal, (3, ...)
    if log_volume is not None:
        tr = np.broadcast_to(log_volume, tr.shape)
    K, G = material.bulk_modulus, material.shear_modulus
    law = material.law
    s_trial = 2.0 * G * dev  # principal dev τ
    norm = np.sqrt(np.sum(s_trial**2, axis=0))
    eqps = np.asarray(eqps, dtype=float)
    f = norm - SQRT23 * law.flow_stress(eqps)  # at a vanishing rate: the smallest flow stress
    plastic = f > 0.0
    dgamma = np.zeros_like(norm)
    if np.any(plastic):
        dgamma[plastic] = _consistency(norm[plastic], eqps[plastic], law, G, dt, tol, max_iter)
    deqps = SQRT23 * dgamma
    eqps_new = eqps + deqps
    rate = 0.0 if (dt is None or not law.rate_dependent) else deqps / dt
    work = np.where(plastic, law.flow_stress(eqps_new, rate) * deqps, 0.0)
    # unit return direction; where elastic (or ‖dev τ‖ = 0) it is multiplied by dgamma = 0
    # radial return: the deviator shrinks by 1 − 2GΔγ/‖s_trial‖ (nothing where ‖s_trial‖ = 0)
    shrink = 1.0 - 2.0 * G * dgamma / np.where(norm > 0.0, norm, 1.0)
    dev_new = shrink * dev
    eps_new = tr / 3.0 + dev_new
    tau_principal = K * tr + 2.0 * G * dev_new
    tau = _from_principal(tau_principal, vec)
    be = _from_principal(np.exp(2.0 * eps_new), vec)
    return tau, be, eqps_new, dgamma, work


def hencky_strain(
    be: np.ndarray, planar: bool = False, minus_identity: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Principal Hencky strains of b_e (or of b_e − 1 with ``minus_identity``): their deviator
    (3, ...), their trace ½ ln det b_e (...) and the principal axes (3, 3, ...).

    The deviator comes from the two log-ratios ½ ln(λ_i²/λ_3²) = ½ log1p((μ_i − μ_3)/(1 + μ_3))
    (μ the eigenvalues of b_e − 1): two logarithms, and exact to round-off at small strains.
    Raises InvertedElementError unless b_e is SPD.
    """
    mu, vec = _sym_eig_planar(be) if planar else _sym_eig(be)
    if not minus_identity:
        mu = mu - 1.0
    if not np.all(mu > -1.0):
        raise InvertedElementError(
            f"trial elastic stretch tensor is not positive definite (min eigenvalue "
            f"{float(np.min(mu + 1.0)):.3e})"
        )
    dev, trace = _log_strains(mu)
    return dev, trace, vec


def _log_strains(mu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Deviatoric principal Hencky strains (3, ...) and their trace from the eigenvalues μ of
    b_e − 1 (the kernel's formulas)."""
    a = 0.5 * np.log1p((mu[0] - mu[2]) / (1.0 + mu[2]))
    b = 0.5 * np.log1p((mu[1] - mu[2]) / (1.0 + mu[2]))
    dev = np.stack([(2.0 * a - b) / 3.0, (2.0 * b - a) / 3.0, -(a + b) / 3.0])
    trace = 0.5 * (np.log1p(mu[0]) + np.log1p(mu[1]) + np.log1p(mu[2]))
    return dev, trace


def _consistency(norm, eqps, law, G, dt, tol, max_iter):
    """Δγ ≥ 0 solving r(Δγ) = ‖s_trial‖ − 2G Δγ − √(2/3) σ_y(ε̄p + √(2/3)Δγ, √(2/3)Δγ/Δt) = 0.

    r decreases strictly (σ_y non-decreasing in ε̄p and ε̄̇p), r(0) > 0 on the plastic points and
    r(‖s_trial‖/2G) < 0: Newton safeguarded by bisection on that bracket (Numerical Recipes'
    rtsafe: bisect when the Newton step leaves the bracket or does not halve the previous step).
    It converges through the kink of Johnson–Cook's rate term at ε̄̇p = ε̄̇0 and the infinite
    slope of ε̄p^n (n < 1) at ε̄p = 0, where plain Newton creeps.
    """
    rated = dt is not None and law.rate_dependent
    h0 = law.slope(eqps)
    dg = (norm - SQRT23 * law.flow_stress(eqps)) / (2.0 * G + 2.0 / 3.0 * h0)
    if law.kernel_code == 0:  # linear: the residual is linear in Δγ, the guess is exact
        return dg
    scale = SQRT23 * law.flow_stress(eqps)
    lo, hi = np.zeros_like(dg), norm / (2.0 * G)
    dg = np.clip(dg, 0.0, hi)
    step_old = hi - lo
    step = step_old.copy()
    for _ in range(max_iter):
        e = eqps + SQRT23 * dg
        rate = SQRT23 * dg / dt if rated else 0.0
        r = norm - 2.0 * G * dg - SQRT23 * law.flow_stress(e, rate)
        # a converged point keeps its Δγ (as in the kernel, which iterates point by point)
        done = (np.abs(r) <= tol * scale) | (hi - lo <= 1e-15 * hi)
        if np.all(done):
            return dg
        lo = np.where(r > 0.0, dg, lo)
        hi = np.where(r < 0.0, dg, hi)
        dr = -2.0 * G - 2.0 / 3.0 * law.slope(e, rate)
        if rated:
            dr = dr - (2.0 / 3.0) / dt * law.rate_slope(e, rate)
        newton = dg - r / dr
        bisect = ~((newton > lo) & (newton < hi)) | (np.abs(2.0 * r) > np.abs(step_old * dr))
        step_old = step
        step = np.where(bisect, 0.5 * (hi - lo), np.abs(r / dr))
        dg = np.where(done, dg, np.where(bisect, 0.5 * (lo + hi), newton))
    raise StateError(
        f"J2 return map: Newton on the plastic multiplier not converged in {max_iter} iterations "
        f"(residual {float(np.max(np.abs(r))):.3e} Pa)"
    )


def j2_update(
    F: np.ndarray,
    cp_inv: np.ndarray,
    eqps: np.ndarray,
    material: J2Material,
    *,
    dt: float | None = None,
    log_volume: np.ndarray | None = None,
    planar: bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The material point as a function of the deformation gradient and the state.

    Parameters
    ----------
    F : ndarray, shape (3, 3, ...)
        Deformation gradient (F̄ with F-bar, or F with ``log_volume`` = ln J̄).
    cp_inv, eqps : ndarray, shapes (3, 3, ...), (...)
        The state at the start of the step: C_p⁻¹ and ε̄p.
    material : J2Material
    dt : float, optional
        Step (s), for rate-dependent laws.
    log_volume : ndarray (...), optional
        Volumetric Hencky strain to use instead of ln det F (F-bar: ln J̄).
    planar : bool
        The third axis is principal.

    Returns
    -------
    tau : ndarray (3, 3, ...)
        Kirchhoff stress (Pa).
    cp_inv_new, eqps_new : ndarray
        The new state (C_p⁻¹ unchanged where the point stayed elastic).
    plastic_work : ndarray (...)
        The plastic work of the step per unit reference volume (J/m³).
    """
    F = np.asarray(F, dtype=float)
    eye = np.eye(3).reshape((3, 3) + (1,) * (F.ndim - 2))
    H = F - eye
    B = (
        H + np.swapaxes(H, 0, 1) + np.einsum("ik...,jk...->ij...", H, H)
        + np.einsum("ik...,kl...,jl...->ij...", F, cp_inv - eye, F)
    )  # fmt: skip
    tau, be, eqps_new, dgamma, work = j2_return_map(
        B, eqps, material, planar=planar, dt=dt, minus_identity=True, log_volume=log_volume
    )
    # b_e is that of F̄ = s F with ln s = (tr ε − ln J)/3: C_p⁻¹ = F̄⁻¹ b_e F̄⁻ᵀ
    Finv, J = _inv3(F)
    tr = np.broadcast_to(log_volume, J.shape) if log_volume is not None else np.log(J)
    s = np.exp((tr - np.log(J)) / 3.0)
    Fbar_inv = Finv / s
    cp_new = np.where(
        dgamma > 0.0, np.einsum("ik...,kl...,jl...->ij...", Fbar_inv, be, Fbar_inv), cp_inv
    )
    return tau, cp_new, eqps_new, work


def hencky_j2_return(
    be_trial: np.ndarray, eqps: np.ndarray, material: J2Material, planar: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`j2_return_map` without the plastic work and at a vanishing rate (kept for
    compatibility): returns (tau, be, eqps_new, delta_gamma)."""
    tau, be, eqps_new, dgamma, _ = j2_return_map(be_trial, eqps, material, planar)
    return tau, be, eqps_new, dgamma


def _det3(a: np.ndarray) -> np.ndarray:
    """Determinant of (3, 3, ...) tensors."""
    return (
        a[0, 0] * (a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1])
        + a[0, 1] * (a[1, 2] * a[2, 0] - a[1, 0] * a[2, 2])
        + a[0, 2] * (a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0])
    )


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
