"""Finite-strain kinematics of Q1 cells, shared by every material: F, F-bar, internal forces.

Total Lagrangian: the reference gradients ∇_X N_a and values N_a of the Q1 shape functions at
the Gauss points (2×2, 2×2×2) are computed once. For a nodal displacement u,

* F = 1 + Σ_a u_a ⊗ ∇_X N_a (in-plane block); axisymmetric F_θθ = 1 + u_r/R (R the reference
  radius), plane strain F_zz = 1;
* F-bar with the cell's mean dilatation: F̄ = (J̄/J)^{1/3} F, J̄ = ∫ J dV₀ / ∫ dV₀ (volume-averaged:
  the centre value fails the axisymmetric and 3D patch tests on distorted cells);
* the consistent internal force of a Kirchhoff stress τ (weight w₀ = α dV₀, dV₀ with 2πR in
  axisymmetry):  f_a = Σ_qp w₀ [τ ∇ₓN_a + p (div̄N_a − div N_a) e],  p = tr τ/3, ∇ₓN_a = F⁻ᵀ∇_X N_a,
  div N_a e_i its i-th component (+ N_a/r for the radial one), div̄ its J-weighted cell average,
  plus the hoop term τ_θθ N_a/r on the radial component.

Quadrature-point arrays have shape (components…, n_elems, n_qp); units SI.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from skfem import Basis, Mesh, MeshHex, MeshQuad

from .j2 import InvertedElementError, _det3, _inv3

__all__ = ["KINDS", "Q1Kinematics", "TrialStretch", "det_minus_one"]

#: Kinematics of the finite-strain models.
KINDS = ("plane_strain", "axisymmetric", "3d")


@dataclass(frozen=True)
class TrialStretch:
    """What :meth:`Q1Kinematics.trial_elastic_stretch` returns (quadrature-point arrays).

    Attributes
    ----------
    F, Finv : ndarray (3, 3, n_elems, n_qp)
        Deformation gradient and its inverse.
    J : ndarray (n_elems, n_qp)
        det F.
    scale : ndarray (n_elems, n_qp) or float
        The F-bar factor (J̄/J)^{1/3} (1 without F-bar).
    B : ndarray (3, 3, n_elems, n_qp) or None
        F C_p⁻¹ Fᵀ − 1 (None without C_p⁻¹).
    log_volume : ndarray (n_elems, n_qp)
        ln J̄ (F-bar) or ln J: the volumetric Hencky strain.
    """

    F: np.ndarray
    Finv: np.ndarray
    J: np.ndarray
    scale: Any
    B: np.ndarray | None
    log_volume: np.ndarray


def det_minus_one(H: np.ndarray) -> np.ndarray:
    """det(1 + H) − 1 for (3, 3, ...) tensors, without the cancellation of det(1 + H) − 1:
    tr H + ½((tr H)² − tr H²) + det H."""
    tr = np.einsum("ii...->...", H)
    tr2 = np.einsum("ij...,ji...->...", H, H)
    return tr + 0.5 * (tr**2 - tr2) + _det3(H)


class Q1Kinematics:
    """Precomputed reference quantities of a Q1 mesh and the finite-strain operations on it.

    Parameters
    ----------
    mesh : skfem.MeshQuad or skfem.MeshHex
        Reference mesh (m); axisymmetric meshes use (r, z) = (x[0], x[1]).
    kind : {"axisymmetric", "plane_strain", "3d"}
    basis : skfem.Basis
        The scalar Q1 basis with the model's quadrature.
    dofs : ndarray of int, shape (dim, n_nodes)
        Dof of each component at each node.

    Attributes
    ----------
    grad : ndarray, shape (n_nodes_per_cell, dim, n_elems, n_qp)
        ∇_X N_a at the quadrature points.
    val : ndarray, shape (n_nodes_per_cell, n_elems, n_qp)
        N_a at the quadrature points.
    radius : ndarray (n_elems, n_qp) or None
        Reference radius R at the quadrature points (axisymmetric).
    dv0 : ndarray, shape (n_elems, n_qp)
        Reference volume per quadrature point (m³, or m² per m of thickness in plane strain).
    cell_dofs : ndarray of int, shape (dim, n_nodes_per_cell, n_elems)
    """

    def __init__(self, mesh: Mesh, kind: str, basis: Basis, dofs: np.ndarray) -> None:
        if not isinstance(mesh, MeshQuad | MeshHex):
            raise ValueError(
                f"finite-strain models need a MeshQuad (axisymmetric, plane strain) or a MeshHex "
                f"(3d) mesh, got {type(mesh).__name__}: linear simplices lock under plastic flow"
            )
        if kind not in KINDS or (kind == "3d") != (mesh.dim() == 3):
            raise ValueError(f"kind={kind!r} does not fit a {mesh.dim()}D mesh; use one of {KINDS}")
        self.mesh = mesh
        self.kind = kind
        self.dim = mesh.dim()
        t = np.asarray(mesh.t)
        nen = t.shape[0]
        self.grad = np.stack([basis.basis[a][0].grad for a in range(nen)])
        self.val = np.stack([np.asarray(basis.basis[a][0]) for a in range(nen)])
        x = np.asarray(basis.global_coordinates())
        self.radius = x[0] if kind == "axisymmetric" else None
        measure = 2.0 * np.pi * x[0] if kind == "axisymmetric" else 1.0
        self.dv0 = np.asarray(basis.dx) * measure
        self.dofs = np.asarray(dofs)
        self.cell_dofs = self.dofs[:, t]
        self.n_dofs = int(self.dofs.size)

    @property
    def shape(self) -> tuple[int, int]:
        """(n_elems, n_qp)."""
        return self.dv0.shape

    def cell_displacements(self, u: np.ndarray) -> np.ndarray:
        """Nodal displacements per cell, shape (dim, n_nodes_per_cell, n_elems)."""
        u = np.asarray(u, dtype=float)
        if u.shape != (self.n_dofs,):
            raise ValueError(f"displacement must have shape ({self.n_dofs},), got {u.shape}")
        return u[self.cell_dofs]

    def displacement_gradient(self, u: np.ndarray) -> np.ndarray:
        """H = F − 1 at the quadrature points, shape (3, 3, n_elems, n_qp).

        Kept apart from F so that small strains are not lost to round-off (1 + 1e-12 − 1)."""
        ue = self.cell_displacements(u)
        d = self.dim
        H = np.zeros((3, 3, *self.shape))
        H[:d, :d] = np.einsum("iae,ajeq->ijeq", ue, self.grad)
        if self.kind == "axisymmetric":
            H[2, 2] = np.einsum("ae,aeq->eq", ue[0], self.val) / self.radius
        return H

    def deformation_gradient(self, u: np.ndarray) -> np.ndarray:
        """F at the quadrature points, shape (3, 3, n_elems, n_qp)."""
        return self.displacement_gradient(u) + np.eye(3)[:, :, None, None]

    def mean_dilatation(self, J: np.ndarray) -> np.ndarray:
        """J̄ = v_e / V_e per cell (current over reference volume), shape (n_elems, 1)."""
        return (J * self.dv0).sum(axis=1, keepdims=True) / self.dv0.sum(axis=1, keepdims=True)

    def check_jacobian(self, J: np.ndarray) -> None:
        """Raise :class:`InvertedElementError` naming the first cell with det F ≤ 0 or NaN."""
        bad = ~(J > 0.0)
        if np.any(bad):
            cell = int(np.nonzero(bad.any(axis=1))[0][0])
            raise InvertedElementError(
                f"inverted or degenerate cell {cell}: det F = {float(np.min(J[cell])):.3e} "
                f"({int(bad.any(axis=1).sum())} such cells)"
            )

    def kinematics(self, u: np.ndarray, fbar: bool) -> tuple[np.ndarray, np.ndarray, Any, Any]:
        """F, F⁻¹, J = det F (checked > 0) and the F-bar factor (J̄/J)^{1/3} (1 without)."""
        t = self.trial_elastic_stretch(u, None, fbar)
        return t.F, t.Finv, t.J, t.scale

    def trial_elastic_stretch(
        self, u: np.ndarray, cp_inv: np.ndarray | None, fbar: bool
    ) -> TrialStretch:
        """The kinematics of a step at u and the trial elastic stretch from ``cp_inv``.

        B = F C_p⁻¹ Fᵀ − 1 is assembled from H = F − 1 (H + Hᵀ + HHᵀ + F(C_p⁻¹ − 1)Fᵀ) rather
        than by subtracting 1 from b_e, so that the Hencky strain keeps its relative accuracy
        down to the smallest strains. With F-bar, F̄ = (J̄/J)^{1/3} F only rescales b_e: its
        deviatoric Hencky strain is that of B, and its volumetric one is ln J̄ (plastic flow is
        isochoric, det C_p = 1); without, ln J. The kernel does the same, point by point.
        """
        H = self.displacement_gradient(u)
        eye = np.eye(3)[:, :, None, None]
        F = H + eye
        Finv, J = _inv3(F)
        self.check_jacobian(J)
        jm1 = det_minus_one(H)
        if fbar:
            jbar_m1 = self.mean_dilatation(jm1)
            x = (jbar_m1 - jm1) / J  # J̄/J − 1
            s = np.cbrt(1.0 + x)
            scale = 1.0 + x / (s * s + s + 1.0)  # ∛(1 + x) without cancellation in s − 1
            log_volume = np.broadcast_to(np.log1p(jbar_m1), J.shape)
        else:
            scale, log_volume = 1.0, np.log1p(jm1)
        B = None
        if cp_inv is not None:
            B = (
                H
                + np.swapaxes(H, 0, 1)
                + np.einsum("ikeq,jkeq->ijeq", H, H)
                + np.einsum("ikeq,kleq,jleq->ijeq", F, cp_inv - eye, F)
            )
        return TrialStretch(F, Finv, J, scale, B, log_volume)

    def internal_force(
        self, tau: np.ndarray, F: np.ndarray, Finv: np.ndarray, J: np.ndarray, w0: np.ndarray,
        fbar: bool,
    ) -> np.ndarray:  # fmt: skip
        """Nodal force (N), shape (n_dofs,), of the Kirchhoff stress τ (3, 3, n_elems, n_qp)
        with the weights w₀ = α dV₀ (n_elems, n_qp) (see the module docstring)."""
        d = self.dim
        gx = np.einsum("akeq,kjeq->ajeq", self.grad, Finv[:d, :d])
        fe = np.einsum("ijeq,ajeq,eq->iae", tau[:d, :d], gx, w0)
        hoop = None
        if self.kind == "axisymmetric":
            hoop = self.val / (self.radius * F[2, 2])  # N_a / r, (nen, ne, nq)
            fe[0] += np.einsum("eq,aeq,eq->ae", tau[2, 2], hoop, w0)
        if fbar:
            div = gx.copy()
            if hoop is not None:
                div[:, 0] += hoop
            jw = J * self.dv0
            div_mean = np.einsum("aieq,eq->aie", div, jw) / jw.sum(axis=1)
            p = np.einsum("iieq->eq", tau) / 3.0
            fe += np.einsum("eq,aieq,eq->iae", p, div_mean[..., None] - div, w0)
        return np.bincount(self.cell_dofs.ravel(), weights=fe.ravel(), minlength=self.n_dofs)

    def cell_sizes(self, x: np.ndarray) -> np.ndarray:
        """h = cell measure / longest edge for the node positions x (dim, n_nodes), (n_elems,)
        (m): the thickness of the cell, what limits its explicit stable step."""
        t = self.mesh.t
        p = x[:, t]  # (dim, nen, ne)
        if self.dim == 2:
            d = np.roll(p, -1, axis=1) - p  # the four edges (dim, 4, ne)
            longest = np.sqrt((d[0] * d[0] + d[1] * d[1]).max(axis=0))
            # the area from the diagonals: ½ |(x2 − x0) × (x3 − x1)|
            area = 0.5 * np.abs(
                (p[0, 2] - p[0, 0]) * (p[1, 3] - p[1, 1])
                - (p[0, 3] - p[0, 1]) * (p[1, 2] - p[1, 0])
            )
            return area / longest
        # hexahedra: volume / largest face area; the volume from the corner Jacobians
        from arlequin.geometry.meshcheck import corner_jacobians

        current = type(self.mesh)(x, t)
        vol = np.mean(np.abs(corner_jacobians(current)), axis=0)
        # the longest of the 28 vertex pairs (i < j; the 64 ordered pairs of the full distance
        # table, with their zeros and repeats, took half of this call at every estimate): the
        # same squares summed in the same order as np.linalg.norm, and max √s = √(max s)
        i, j = np.triu_indices(p.shape[1], 1)
        d = p[:, i] - p[:, j]  # (dim, n_pairs, ne)
        longest = np.sqrt(np.max(d[0] * d[0] + d[1] * d[1] + d[2] * d[2], axis=0))
        return vol / longest**2
