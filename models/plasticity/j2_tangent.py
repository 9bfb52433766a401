"""The consistent (algorithmic) tangent of :class:`~arlequin.models.FiniteStrainJ2` (numpy path).

The exact derivative ∂f/∂u of the force of
:meth:`~arlequin.models.plasticity.kinematics.Q1Kinematics.internal_force` with the stress of
:func:`~arlequin.models.plasticity.j2.j2_return_map`, at u from the committed state. Notation per
quadrature point: L^{bj} = δF F⁻¹ for the unit displacement of dof j of node b (e_j ⊗ ∇ₓN_b, plus
N_b/r on θθ for the radial dof in axisymmetry), div_bj = tr L^{bj}, div̄_bj its J-weighted cell
average (∂ ln J̄/∂u_bj), w₀ = α dV₀. The force is
f_bj = Σ w₀ [τ : L^{bj} + p (div̄_bj − div_bj)] (F-bar) or Σ w₀ τ : L^{bj} (without).

Material part. τ = K tr ε 1 + s with tr ε = ln J̄ (ln J without F-bar) and s = dev τ an isotropic
function of b = F C_p⁻¹ Fᵀ (principal values x_i = 1 + μ_i, axes n_i): s_i = 2G(1 − β) dev ε_i,
β = 2GΔγ/‖s^tr‖, ε_i = ½ ln x_i. For Δb = Δl b + b Δlᵀ (Δl = ΔF F⁻¹), in the principal frame

* ds_ii = Σ_j D_ij Δl_jj, D = 2G(1 − β)(I − ⅓ 1⊗1) − 2G(θ − β) n̂⊗n̂ (plastic points; n̂ the unit
  principal deviator, θ = 1/(1 + H/3G), H = ∂σ_y/∂ε̄p at the converged ε̄p (+ ∂σ_y/∂ε̄̇p / Δt for a
  rate-dependent law given the step)); elastic: β = 0 and no n̂⊗n̂ term;
* ds_ij = c_ij (x_j Δl_ij + x_i Δl_ji) (i ≠ j), c_ij = (s_i − s_j)/(x_i − x_j)
  = G(1 − β) φ(t)/x_j, φ(t) = ln(1 + t)/t, t = (μ_i − μ_j)/(1 + μ_j): exact, and smooth through
  repeated eigenvalues (φ(0) = 1 is the limit (D_ii − D_ij)/2x_i).

So Δτ = C : Δl + K Δ ln J̄ 1 (C from the above, rotated to Cartesian axes).

Tangent, per cell (F-bar):
K_{bj,ak} = Σ w₀ [L^{bj} : C : L^{ak} − τ : (L^{bj} L^{ak}) + p tr(L^{bj} L^{ak})]
+ K W div̄_bj div̄_ak + P Δdiv̄_{bj,ak},
W = Σ w₀, P = Σ w₀ p, Δdiv̄_{bj,ak} = Σ Jw [div_bj div_ak − tr(L^{bj} L^{ak})] / Σ Jw
− div̄_bj div̄_ak (Jw = J dV₀): the last term couples every node of the cell through J̄.
Without F-bar: Σ w₀ [L^{bj} : C : L^{ak} + K div_bj div_ak − τ : (L^{bj} L^{ak})].
With this F-bar force (the variation of F̄, unlike the force ∫ τ(F̄) : ∇ₓδu of de Souza Neto et
al. 1996, whose tangent is non-symmetric) and the exponential-map return (a closest-point
projection in log strains) the force is the gradient of an incremental potential Σ w₀ ψ̃(F̄):
the tangent is symmetric to round-off (``tests/test_finite_strain_tangent.py``); it is returned
as a general CSR matrix all the same.

Rate-dependent laws: with the step ``dt`` the slope of the consistency equation includes
∂σ_y/∂ε̄̇p / Δt (the derivative of ``internal_force(..., dt=dt)``); without it, the law at a
vanishing rate, as the force without ``dt``. The bulk viscosity is not differentiated.

Per-cell dense blocks (n_nodes·dim)², computed over chunks of cells (vectorised, bounded
memory), assembled into a CSR matrix whose pattern is built once (:class:`BlockAssembler`).
Units: N/m.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .j2 import J2Material, _log_strains, _sym_eig, _sym_eig_planar, j2_return_map

__all__ = ["BlockAssembler", "cell_tangents", "numpy_tangent", "spatial_modulus"]

#: floats of the per-chunk spatial gradients L (bounds the memory of a chunk)
_CHUNK_FLOATS = 4_000_000


def _phi(t: np.ndarray) -> np.ndarray:
    """ln(1 + t)/t, 1 at t = 0 (log1p keeps its relative accuracy for any t ≠ 0)."""
    small = np.abs(t) < 1e-300
    return np.where(small, 1.0, np.log1p(t) / np.where(small, 1.0, t))


def _hardening_slope(material: J2Material, eqps_new, dgamma, dt):
    """H = dσ_y/dε̄p along the return at the converged point (with the rate term if the step
    is given and the law is rate dependent): the slope of the consistency equation."""
    law = material.law
    if dt is None or not law.rate_dependent:
        return law.slope(eqps_new)
    rate = np.sqrt(2.0 / 3.0) * dgamma / dt
    return law.slope(eqps_new, rate) + law.rate_slope(eqps_new, rate) / dt


def spatial_modulus(B, eqps, material: J2Material, planar: bool, dt=None, log_volume=None):
    """The return at B = F C_p⁻¹ Fᵀ − 1 and its deviatoric spatial modulus.

    Returns
    -------
    tau : ndarray (3, 3, ...)
        Kirchhoff stress (Pa), as :func:`j2_return_map` gives it.
    C : ndarray (..., 3, 3, 3, 3)
        dτ_ij = C_ijkl Δl_kl + K Δ(tr ε) δ_ij for Δl = ΔF F⁻¹ (Pa).
    """
    tau, _, eqps_new, dgamma, _ = j2_return_map(
        B, eqps, material, planar=planar, dt=dt, minus_identity=True, log_volume=log_volume
    )
    mu, vec = _sym_eig_planar(B) if planar else _sym_eig(B)
    dev, _ = _log_strains(mu)
    G = material.shear_modulus
    norm = 2.0 * G * np.sqrt(np.sum(dev**2, axis=0))
    plastic = dgamma > 0.0
    safe = np.where(norm > 0.0, norm, 1.0)
    beta = np.where(plastic, 2.0 * G * dgamma / safe, 0.0)
    theta = 1.0 / (1.0 + _hardening_slope(material, eqps_new, dgamma, dt) / (3.0 * G))
    nhat = 2.0 * G * dev / safe  # (3, ...)
    shape = mu.shape[1:]
    Cp = np.zeros((*shape, 3, 3, 3, 3))
    dev_proj = np.eye(3) - 1.0 / 3.0
    D = 2.0 * G * (1.0 - beta)[..., None, None] * dev_proj
    D -= (2.0 * G * np.where(plastic, theta - beta, 0.0))[..., None, None] * np.einsum(
        "i...,j...->...ij", nhat, nhat
    )
    x = 1.0 + mu
    for i in range(3):
        for k in range(3):
            Cp[..., i, i, k, k] = D[..., i, k]
        for j in range(3):
            if i != j:
                c = G * (1.0 - beta) * _phi((mu[i] - mu[j]) / x[j]) / x[j]
                Cp[..., i, j, i, j] = c * x[j]
                Cp[..., i, j, j, i] = c * x[i]
    N = np.moveaxis(vec, (0, 1), (-2, -1))  # (..., 3, 3), columns the axes
    C = np.einsum("...ai,...bj,...ijkl,...ck,...dl->...abcd", N, N, Cp, N, N, optimize=True)
    return tau, C


def _gradients(kin, F, Finv, cells):
    """L^{bj} (E, Q, nen·dim, 3, 3) of a chunk of cells, row (b, j) = b·dim + j."""
    d = kin.dim
    grad = kin.grad[..., cells, :]  # (nen, d, E, Q)
    nen = grad.shape[0]
    gx = np.einsum("akeq,kjeq->eqaj", grad, Finv[:d, :d][:, :, cells])  # (E, Q, nen, d)
    E, Q = gx.shape[:2]
    L = np.zeros((E, Q, nen, d, 3, 3))
    for j in range(d):
        L[:, :, :, j, j, :d] = gx
    if kin.kind == "axisymmetric":
        hoop = kin.val[:, cells] / (kin.radius[cells] * F[2, 2][cells])  # (nen, E, Q)
        L[:, :, :, 0, 2, 2] = np.moveaxis(hoop, 0, -1)
    return L.reshape(E, Q, nen * d, 3, 3)


def cell_tangents(kin, C, tau, F, Finv, J, w0, K, fbar, cells):
    """Dense tangents (E, nen·dim, nen·dim) of the cells ``cells`` (see the module docstring).

    ``C`` (E, Q, 3, 3, 3, 3) and ``tau`` (3, 3, E, Q) of those cells, the kinematics (F, F⁻¹, J,
    w₀ = α dV₀) of the whole mesh; rows and columns ordered (node, component)."""
    L = _gradients(kin, F, Finv, cells)
    E, Q, n = L.shape[:3]
    Lf = L.reshape(E, Q, n, 9)
    t = np.moveaxis(tau, (0, 1), (-2, -1))  # (E, Q, 3, 3)
    w = w0[cells][..., None, None]
    mat = Lf @ C.reshape(E, Q, 9, 9) @ np.swapaxes(Lf, -1, -2)
    # τ : (L^{bj} L^{ak}) = Σ_mr L^{bj}_mr (L^{ak} τ)_rm
    geo = Lf @ np.swapaxes((L @ t[:, :, None]), -1, -2).reshape(E, Q, n, 9).swapaxes(-1, -2)
    # tr(L^{bj} L^{ak}) = Σ_mr L^{bj}_mr L^{ak}_rm
    trll = Lf @ np.swapaxes(L, -1, -2).reshape(E, Q, n, 9).swapaxes(-1, -2)
    div = np.einsum("eqnii->eqn", L)
    if not fbar:
        vol = K * div[..., :, None] * div[..., None, :]
        return np.sum(w * (mat - geo + vol), axis=1)
    p = np.einsum("eqii->eq", t) / 3.0
    jw = (J * kin.dv0)[cells]  # (E, Q)
    jw_sum = jw.sum(axis=1)
    div_bar = np.einsum("eqn,eq->en", div, jw) / jw_sum[:, None]
    outer_bar = div_bar[:, :, None] * div_bar[:, None, :]
    ddiv_bar = (
        np.einsum("eq,eqnm->enm", jw, div[..., :, None] * div[..., None, :] - trll)
        / jw_sum[:, None, None]
        - outer_bar
    )
    w2 = w0[cells]
    ke = np.sum(w * (mat - geo + p[..., None, None] * trll), axis=1)
    ke += (K * w2.sum(axis=1))[:, None, None] * outer_bar
    ke += (w2 * p).sum(axis=1)[:, None, None] * ddiv_bar
    return ke


def chunks(kin):
    """Slices of cells whose spatial gradients fit in :data:`_CHUNK_FLOATS` floats."""
    ne, nq = kin.shape
    nen = kin.grad.shape[0]
    size = max(1, _CHUNK_FLOATS // (nq * nen * kin.dim * 9 + 81 * nq))
    return [slice(s, min(s + size, ne)) for s in range(0, ne, size)]


def numpy_tangent(kin, material, fbar, u, state, alpha, dt, assembler):
    """The consistent tangent (sparse, N/m) at ``u`` from the committed ``state`` (a
    :class:`~arlequin.models.plasticity.j2.PlasticState`) with the weights ``alpha`` (n_elems,
    n_qp), chunk by chunk of cells; ``assembler`` a :class:`BlockAssembler` of the mesh."""
    trial = kin.trial_elastic_stretch(u, state.cp_inv, fbar)
    w0 = alpha * kin.dv0
    planar = kin.dim == 2
    n = kin.grad.shape[0] * kin.dim
    blocks = np.empty((kin.shape[0], n, n))
    logv = np.broadcast_to(trial.log_volume, trial.J.shape)
    for cells in chunks(kin):
        tau, C = spatial_modulus(
            trial.B[:, :, cells], state.eqps[cells], material, planar, dt, logv[cells]
        )
        blocks[cells] = cell_tangents(
            kin, C, tau, trial.F, trial.Finv, trial.J, w0, material.bulk_modulus, fbar, cells
        )
    return assembler.assemble(blocks)


class BlockAssembler:
    """CSR assembly of per-cell dense blocks: the pattern built once from the cell dofs.

    Parameters
    ----------
    cell_dofs : ndarray of int, shape (dim, n_nodes_per_cell, n_elems)
    n_dofs : int
    """

    def __init__(self, cell_dofs: np.ndarray, n_dofs: int) -> None:
        dofs = np.transpose(cell_dofs, (2, 1, 0)).reshape(cell_dofs.shape[2], -1)  # (E, n)
        rows = np.repeat(dofs[:, :, None], dofs.shape[1], axis=2).ravel()
        cols = np.repeat(dofs[:, None, :], dofs.shape[1], axis=1).ravel()
        key = rows.astype(np.int64) * n_dofs + cols
        unique, self._slot = np.unique(key, return_inverse=True)
        self._slot = self._slot.ravel()
        r, c = np.divmod(unique, n_dofs)
        self._indices = c.astype(np.int32 if n_dofs < 2**31 else np.int64)
        self._indptr = np.searchsorted(r, np.arange(n_dofs + 1)).astype(self._indices.dtype)
        self.n_dofs = n_dofs
        self.nnz = unique.size

    def assemble(self, blocks: np.ndarray) -> sp.csr_matrix:
        """Σ over cells of the blocks (E, n, n) as a CSR (n_dofs, n_dofs) matrix."""
        data = np.bincount(self._slot, weights=blocks.ravel(), minlength=self.nnz)
        return sp.csr_matrix(
            (data, self._indices.copy(), self._indptr.copy()), shape=(self.n_dofs, self.n_dofs)
        )
