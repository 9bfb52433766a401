"""Mediator space on the gluing zone and the L2 / H1 coupling matrices.

The coupling operator between a mediator field λ and a displacement u on the gluing zone S_g is

    L2:  c(λ, u) = ∫_Sg λ·u
    H1:  c(λ, u) = ∫_Sg λ·u + ℓ² ε(λ):ε(u)

(axisymmetric: measure 2π r dr dz, and ε is the meridional symmetric gradient in (r, z), so that a
constant λ has zero strain). Both matrices

    C_coarse[k, j] = c(ψ_k, φ_j^coarse),    C_fine[k, j] = c(ψ_k, φ_j^fine)

are computed from one Gram matrix G on the gluing cells of the integration mesh I (see
:mod:`arlequin.coupling.overlap`): C_model = Zᵀ G P_model, with P_model the (vector) transfer to I
and Z the mediator functions written on I. One shared quadrature makes the two transfers exact
adjoints. The mediator space is the coarse space restricted to S_g or the fine one (a patch's
``mediator="auto"`` chooses: :func:`arlequin.coupling.patches.resolve_mediator`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from skfem import Basis, BilinearForm, ElementVector
from skfem.helpers import dot, grad

from ..dofs import node_dofs, vector_operator
from ..geometry.reference import scalar_element_for
from .overlap import Overlap

__all__ = ["CouplingMatrices", "MediatorError", "coupling_matrices", "gram_matrix"]


class MediatorError(ValueError):
    """The mediator space or the gluing zone is empty or ill-defined."""


@dataclass(frozen=True)
class CouplingMatrices:
    """Coupling matrices of one patch.

    Attributes
    ----------
    coarse : scipy.sparse.csr_matrix, shape (n_multipliers, n_coarse_dofs)
    fine : scipy.sparse.csr_matrix, shape (n_multipliers, n_fine_dofs)
    mediator_dofs : ndarray of int, shape (n_multipliers,)
        Dofs of the mediator model (coarse or fine) that carry the mediator functions.
    mediator : {"coarse", "fine"}
    coupling : {"L2", "H1"}
    length : float
        H1 length ℓ (m); 0 for L2.
    """

    coarse: sp.csr_matrix
    fine: sp.csr_matrix
    mediator_dofs: np.ndarray
    mediator: str
    coupling: str
    length: float

    @property
    def n_multipliers(self) -> int:
        return int(self.coarse.shape[0])


def gram_matrix(
    overlap: Overlap,
    gluing_cells: np.ndarray,
    n_components: int,
    coupling: str = "H1",
    length: float = 0.0,
    axisymmetric: bool = False,
    intorder: int = 3,
    closed_form: bool = True,
) -> sp.csr_matrix:
    """Gram matrix of c(·,·) on the gluing cells of the integration mesh.

    Triangles and tetrahedra (not axisymmetric) take the closed form of P1 functions
    (``closed_form``, the default); other cells, or ``closed_form=False``, scikit-fem's
    quadrature of order ``intorder``.

    Returns
    -------
    scipy.sparse.csr_matrix, shape (n_components n_I_nodes,) * 2
    """
    if coupling not in ("L2", "H1"):
        raise ValueError(f"coupling must be 'L2' or 'H1', got {coupling!r}")
    if coupling == "H1" and not length > 0.0:
        raise ValueError(f"H1 coupling needs a positive length, got length={length}")
    mesh = overlap.integration_mesh
    gluing_cells = np.asarray(gluing_cells, dtype=np.int64)
    if gluing_cells.size == 0:
        raise MediatorError("the gluing zone is empty: no integration cell lies in it")
    ell2 = float(length) ** 2 if coupling == "H1" else 0.0
    if closed_form and _is_simplex(mesh) and not axisymmetric and mesh.dim() == n_components:
        return _simplex_gram(mesh, gluing_cells, ell2)
    element = ElementVector(scalar_element_for(mesh), dim=n_components)
    basis = Basis(mesh, element, elements=gluing_cells, intorder=intorder)

    def strain(u):
        g = grad(u)
        return 0.5 * (g + np.swapaxes(g, 0, 1))

    @BilinearForm
    def form(u, v, w):
        measure = 2.0 * np.pi * w.x[0] if axisymmetric else 1.0
        value = dot(u, v)
        if ell2:
            value = value + ell2 * np.einsum("ij...,ij...", strain(u), strain(v))
        return value * measure

    return form.assemble(basis).tocsr()


def _is_simplex(mesh) -> bool:
    return mesh.t.shape[0] == mesh.dim() + 1 and mesh.dim() >= 2


def _simplex_local(mesh, cells: np.ndarray, ell2: float) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form local Gram matrices of vector P1 functions on simplices.

    On a simplex T of measure |T| with barycentric gradients g_a (constant),
    ∫_T φ_a φ_b = |T| (1 + δ_ab) / ((d + 1)(d + 2)) and
    ε(φ_a e_i) : ε(φ_b e_j) = ½ (δ_ij g_a·g_b + g_a,j g_b,i): the same matrices as the
    quadrature of :func:`gram_matrix`'s form (tested to round-off), without the
    (functions² × quadrature points) arrays of a vector basis.

    Returns
    -------
    local : ndarray, shape (m, d + 1, d, d + 1, d)
        Entry (a, i, b, j): node a component i against node b component j.
    dofs : ndarray of int, shape (m, d + 1, d)
        The interleaved dofs d·node + i of the integration mesh.
    """
    d = mesh.dim()
    nv = d + 1
    mass_ref = (np.ones((nv, nv)) + np.eye(nv)) / ((d + 1) * (d + 2))
    eye = np.eye(d)
    x = np.transpose(mesh.p[:, mesh.t[:, cells]], (2, 1, 0))  # (m, nv, d)
    jac = np.transpose(x[:, 1:] - x[:, :1], (0, 2, 1))  # columns x_k − x_0
    vol = np.abs(np.linalg.det(jac)) / {2: 2.0, 3: 6.0}[d]
    inv = np.linalg.inv(jac)  # rows: gradients of λ_1..λ_d
    g = np.concatenate([-inv.sum(axis=1, keepdims=True), inv], axis=1)  # (m, nv, d)
    local = np.einsum("m,ab,ij->maibj", vol, mass_ref, eye)
    if ell2:
        gg = np.einsum("mak,mbk->mab", g, g)
        local += (
            0.5
            * ell2
            * vol[:, None, None, None, None]
            * (np.einsum("mab,ij->maibj", gg, eye) + np.einsum("maj,mbi->maibj", g, g))
        )
    dofs = d * mesh.t[:, cells].T[:, :, None] + np.arange(d)  # (m, nv, d)
    return local, dofs


def _local_csr(local: np.ndarray, dofs: np.ndarray, n: int) -> sp.csr_matrix:
    rows = np.broadcast_to(dofs[:, :, :, None, None], local.shape)
    cols = np.broadcast_to(dofs[:, None, None, :, :], local.shape)
    return sp.csr_matrix((local.ravel(), (rows.ravel(), cols.ravel())), shape=(n, n))


def _simplex_gram(mesh, cells: np.ndarray, ell2: float) -> sp.csr_matrix:
    """The L2/H1 Gram matrix of vector P1 functions on simplices, in closed form
    (:func:`_simplex_local`), chunk by chunk of cells."""
    n = mesh.dim() * mesh.nvertices
    out = sp.csr_matrix((n, n))
    for start in range(0, cells.size, _GRAM_CHUNK):
        local, dofs = _simplex_local(mesh, cells[start : start + _GRAM_CHUNK], ell2)
        out = out + _local_csr(local, dofs, n)
    return out


def _simplex_coupling(overlap: Overlap, cells: np.ndarray, ell2: float, mediator: str
                      ) -> tuple[sp.csr_matrix, sp.csr_matrix, np.ndarray]:  # fmt: skip
    """C_coarse, C_fine and the mediator dofs on simplices, chunk by chunk of gluing cells.

    Zᵀ G P of :func:`coupling_matrices` without the integration mesh's global Gram matrix
    nor its global vector transfers (at a million integration cells those are the build's
    largest objects): each chunk's Gram matrix on its own nodes, numbered locally, and the
    rows of the transfers at those nodes only.
    """
    mesh = overlap.integration_mesh
    d = mesh.dim()
    pc, pf = overlap.coarse_transfer.tocsr(), overlap.fine_transfer.tocsr()
    pm = pc if mediator == "coarse" else pf
    gluing_nodes = np.unique(mesh.t[:, cells])
    support = np.asarray(abs(pm[gluing_nodes]).max(axis=0).todense()).ravel() > 1e-12
    mediator_dofs = node_dofs(np.nonzero(support)[0], d).T.ravel()
    mediator_dofs.sort()
    if mediator_dofs.size == 0:
        raise MediatorError(f"the {mediator} mediator space has no support on the gluing zone")
    c_coarse = sp.csr_matrix((mediator_dofs.size, d * pc.shape[1]))
    c_fine = sp.csr_matrix((mediator_dofs.size, d * pf.shape[1]))
    for start in range(0, cells.size, _GRAM_CHUNK):
        local, dofs = _simplex_local(mesh, cells[start : start + _GRAM_CHUNK], ell2)
        nodes, renum = np.unique(dofs[:, :, 0] // d, return_inverse=True)
        local_dofs = d * renum.reshape(dofs.shape[:2])[:, :, None] + np.arange(d)
        gram = _local_csr(local, local_dofs, d * nodes.size)
        vc = vector_operator(pc[nodes], d)
        vf = vector_operator(pf[nodes], d)
        z = (vc if mediator == "coarse" else vf)[:, mediator_dofs]
        zt_g = (z.T @ gram).tocsr()
        c_coarse = c_coarse + zt_g @ vc
        c_fine = c_fine + zt_g @ vf
    return c_coarse.tocsr(), c_fine.tocsr(), mediator_dofs


#: Cells of one chunk of the closed-form Gram matrix (about 100 MB of temporaries in 3D).
_GRAM_CHUNK = 25_000


def coupling_matrices(
    overlap: Overlap,
    gluing_cells: np.ndarray,
    n_components: int,
    coupling: str = "H1",
    length: float | None = None,
    mediator: str = "coarse",
    axisymmetric: bool = False,
    intorder: int | None = None,
) -> CouplingMatrices:
    """Assemble C_coarse and C_fine on the gluing cells of an overlap.

    Parameters
    ----------
    overlap : Overlap
    gluing_cells : ndarray of int
        Cells of the integration mesh that form the gluing zone S_g.
    n_components : int
        Displacement components per node.
    coupling : {"L2", "H1"}
    length : float, optional
        H1 length ℓ (m), required for H1.
    mediator : {"coarse", "fine"}
        Which model's space, restricted to S_g, carries the multipliers.
    axisymmetric : bool
        Use the 2π r measure (meridional coordinates (r, z)).

    Raises
    ------
    MediatorError
        Empty gluing zone or a mediator space with no support on it.
    """
    if mediator not in ("coarse", "fine"):
        raise ValueError(f"mediator must be 'coarse' or 'fine', got {mediator!r}")
    if intorder is None:
        # products of two first-order functions (times r in axisymmetry) are integrated exactly
        intorder = 3 if axisymmetric else 2
    mesh = overlap.integration_mesh
    cells = np.asarray(gluing_cells, dtype=np.int64)
    if _is_simplex(mesh) and not axisymmetric and mesh.dim() == n_components and cells.size:
        if coupling not in ("L2", "H1"):
            raise ValueError(f"coupling must be 'L2' or 'H1', got {coupling!r}")
        if coupling == "H1" and not (length or 0.0) > 0.0:
            raise ValueError(f"H1 coupling needs a positive length, got length={length}")
        ell2 = float(length) ** 2 if coupling == "H1" else 0.0
        coarse, fine, mediator_dofs = _simplex_coupling(overlap, cells, ell2, mediator)
        return CouplingMatrices(coarse, fine, mediator_dofs, mediator, coupling,
                                float(length or 0.0) if coupling == "H1" else 0.0)  # fmt: skip
    gram = gram_matrix(
        overlap, gluing_cells, n_components, coupling, length or 0.0, axisymmetric, intorder
    )
    pc = overlap.vector_transfer("coarse", n_components)
    pf = overlap.vector_transfer("fine", n_components)
    pm = pc if mediator == "coarse" else pf
    # mediator functions = those of the chosen model whose support meets S_g with positive measure
    mesh = overlap.integration_mesh
    gluing_nodes = np.unique(mesh.t[:, np.asarray(gluing_cells)])
    rows = node_dofs(gluing_nodes, n_components).T.ravel()
    support = np.asarray(abs(pm[rows]).max(axis=0).todense()).ravel() > 1e-12
    mediator_dofs = np.nonzero(support)[0]
    if mediator_dofs.size == 0:
        raise MediatorError(f"the {mediator} mediator space has no support on the gluing zone")
    z = pm[:, mediator_dofs]
    zt_g = (z.T @ gram).tocsr()
    return CouplingMatrices(
        coarse=(zt_g @ pc).tocsr(),
        fine=(zt_g @ pf).tocsr(),
        mediator_dofs=mediator_dofs,
        mediator=mediator,
        coupling=coupling,
        length=float(length or 0.0) if coupling == "H1" else 0.0,
    )
