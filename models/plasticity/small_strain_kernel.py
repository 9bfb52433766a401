"""The compiled consistent tangent of small-strain J2, fused with its assembly.

Σ_qp w Bᵀ D B with D = K 1⊗1 + 2G(1 − a) I_dev + c n⊗n (Mandel, the moduli of
:func:`~arlequin.models.plasticity.small_strain_j2.consistent_tangent`), computed cell by cell
from the scalar gradients g_a = ∇N_a and added straight into the CSR data array through the
scatter map of :class:`~arlequin.models.assembly.CellPattern` (the cells of one colour in
parallel, numba ``prange``: no two share a node, so no race). With the weights folded in
(g2 = 2G(1 − a) w, t = K w − g2/3, c w), the entry of dofs (a, i), (b, j) at a point is

    g2 · ½(δ_ij g_a·g_b + g_aj g_bi) + t · tr_ai tr_bj + c w · (n g_a)_i (n g_b)_j,

tr_ai = g_ai (the divergence of N_a e_i), plus in axisymmetry the hoop strain h_a = N_a / r in
the (a0, b0) entry (g2 h_a h_b), in tr_a0 and in (n g_a)_0 (n_θθ h_a). With the mean dilatation
(B-bar), B̄ = B + ⅓ 1 ⊗ (div̄ − div) and D 1 = 3Kw 1, n · 1 = 0 give B̄ᵀ D B̄ = Bᵀ D B +
Kw (div̄ ⊗ div̄ − div ⊗ div): the point term's t becomes −g2/3 and each cell adds
(K Σ_qp w) div̄ ⊗ div̄ once. The numpy path of
:func:`numpy_tangent_blocks` (the former assembly's local matrices) is the
reference (``tests/test_assembly.py``: 1e-12 relative). numba compiles on first call (cached
on disk).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = ["bmatrix", "numpy_tangent_blocks", "small_strain_tangent_kernel"]

_R2 = math.sqrt(2.0)
_IR2 = 1.0 / _R2


@nb.njit(cache=True, inline="always")
def _normal_tensor(normal, e, q, dim, nt):
    """The in-plane (dim × dim) part of the Mandel normal at (e, q) into nt; its θθ (zz)
    component."""
    if dim == 3:
        nt[0, 0], nt[1, 1], nt[2, 2] = normal[0, e, q], normal[1, e, q], normal[2, e, q]
        nt[1, 2] = nt[2, 1] = normal[3, e, q] * _IR2
        nt[0, 2] = nt[2, 0] = normal[4, e, q] * _IR2
        nt[0, 1] = nt[1, 0] = normal[5, e, q] * _IR2
        return 0.0
    nt[0, 0], nt[1, 1] = normal[0, e, q], normal[1, e, q]
    nt[0, 1] = nt[1, 0] = normal[3, e, q] * _IR2
    return normal[2, e, q]


@nb.njit(parallel=True, cache=True, fastmath={"contract", "reassoc"})
def small_strain_tangent_kernel(
    data, cells, base, row_stride, order, colour_ptr, grad, val, rinv, axi, g2, tt, cw, normal,
    bbar, dv, kv,
):  # fmt: skip
    """Add Σ_qp w B̄ᵀ D B̄ of every cell into ``data`` (nnz,) (the module's formulas).

    grad (nen, dim, n_cells, n_qp), val (nen, n_cells, n_qp), rinv (n_cells, n_qp) (read with
    ``axi``), g2, tt, cw, dv (n_cells, n_qp), normal (ns, n_cells, n_qp), kv (n_cells,) (read
    with ``bbar``: K Σ_qp w); cells, base, row_stride, order, colour_ptr those of a
    :class:`~arlequin.models.assembly.CellPattern`.
    """
    nen, dim, _, nq = grad.shape
    nd = nen * dim
    for col in range(colour_ptr.size - 1):
        for k in nb.prange(colour_ptr[col], colour_ptr[col + 1]):
            e = order[k]
            loc = np.zeros((nd, nd))
            g = np.empty((nen, dim))
            h = np.zeros(nen)
            tr = np.empty((nen, dim))
            ng = np.empty((nen, dim))
            nt = np.empty((dim, dim))
            dbar = np.zeros(nd)
            vol = 0.0
            for q in range(nq):
                nzz = _normal_tensor(normal, e, q, dim, nt)
                for a in range(nen):
                    if axi:
                        h[a] = val[a, e, q] * rinv[e, q]
                    for i in range(dim):
                        g[a, i] = grad[a, i, e, q]
                    for i in range(dim):
                        s = 0.0
                        for m in range(dim):
                            s += nt[i, m] * g[a, m]
                        ng[a, i] = s
                        tr[a, i] = g[a, i]
                    tr[a, 0] += h[a]
                    ng[a, 0] += nzz * h[a]
                if bbar:
                    vol += dv[e, q]
                    for a in range(nen):
                        for i in range(dim):
                            dbar[dim * a + i] += tr[a, i] * dv[e, q]
                half = 0.5 * g2[e, q]
                t = tt[e, q]
                c = cw[e, q]
                for a in range(nen):
                    for b in range(a, nen):
                        s = 0.0
                        for m in range(dim):
                            s += g[a, m] * g[b, m]
                        if axi:  # the hoop strains' product in the (a0, b0) entry
                            hh = 2.0 * half * h[a] * h[b]
                            loc[dim * a, dim * b] += hh
                            if b != a:
                                loc[dim * b, dim * a] += hh
                        for i in range(dim):
                            for j in range(dim):
                                v = (half * g[a, j] * g[b, i] + t * tr[a, i] * tr[b, j]
                                     + c * ng[a, i] * ng[b, j])  # fmt: skip
                                if i == j:
                                    v += half * s
                                loc[dim * a + i, dim * b + j] += v
                                if b != a:
                                    loc[dim * b + j, dim * a + i] += v
            if bbar:
                for m in range(nd):
                    dbar[m] /= vol
                for m in range(nd):
                    for n in range(nd):
                        loc[m, n] += kv[e] * dbar[m] * dbar[n]
            for a in range(nen):
                stride = row_stride[cells[e, a]]
                for b in range(nen):
                    p = base[e, a, b]
                    for i in range(dim):
                        for j in range(dim):
                            data[p + i * stride + j] += loc[dim * a + i, dim * b + j]
    return data


# ------------------------------------------------------------------ numpy reference
def bmatrix(model, cells: slice) -> np.ndarray:
    """B matrices of a SmallStrainJ2 ``model`` (Mandel strain of each cell dof), shape
    (n_cells, n_qp, ns, dim · nen), the numpy reference's."""
    g = np.moveaxis(model._grad[:, :, cells], (0, 1), (2, 3))  # (ne, nq, nen, dim)
    ne, nq, nen, d = g.shape
    b = np.zeros((ne, nq, model.ns, nen, d))
    for i in range(d):
        b[:, :, i, :, i] = g[..., i]
    if d == 3:
        for k, (i, j) in enumerate(((1, 2), (0, 2), (0, 1))):
            b[:, :, 3 + k, :, i] = g[..., j] / _R2
            b[:, :, 3 + k, :, j] = g[..., i] / _R2
    else:
        b[:, :, 3, :, 0], b[:, :, 3, :, 1] = g[..., 1] / _R2, g[..., 0] / _R2
        if model._rinv is not None:
            val = np.moveaxis(model._val[:, cells], 0, -1)  # (ne, nq, nen)
            b[:, :, 2, :, 0] = val * model._rinv[cells, :, None]
    b = b.reshape(ne, nq, model.ns, nen * d)
    if model.bbar:
        div = b[:, :, 0] + b[:, :, 1] + b[:, :, 2]  # (ne, nq, nd)
        dv = model._dv[cells]
        mean = np.einsum("eqm,eq->em", div, dv) / dv.sum(axis=1)[:, None]
        b[:, :, :3] += ((mean[:, None] - div) / 3.0)[:, :, None]
    return b


def numpy_tangent_blocks(model, ret, w: np.ndarray) -> np.ndarray:
    """The cells' Σ_qp w Bᵀ D B, D = K 1⊗1 + 2G(1 − a) I_dev + c n⊗n, (n_elems, nd, nd) by
    numpy (blocks of cells): the reference of the compiled :func:`small_strain_tangent_kernel`."""
    K, G = model.material.bulk_modulus, model.material.shear_modulus
    ne, nq = model.shape
    nd = model._cell_dofs.shape[1]
    g2 = 2.0 * G * (1.0 - ret.reduction) * w  # (ne, nq)
    vol = K * w - g2 / 3.0
    cw = ret.normal_coefficient * w
    normal = np.moveaxis(ret.normal, 0, -1)  # (ne, nq, ns)
    data = np.empty((ne, nd, nd))
    block = max(1, int(4e6 // (nq * model.ns * nd)))
    for start in range(0, ne, block):
        c = slice(start, min(ne, start + block))
        b = bmatrix(model, c)
        tr = b[:, :, 0] + b[:, :, 1] + b[:, :, 2]  # (n, nq, nd)
        nb = np.einsum("eqs,eqsm->eqm", normal[c], b)
        bw = (b * g2[c, :, None, None]).reshape(b.shape[0], -1, nd)
        k = np.matmul(np.swapaxes(bw, 1, 2), b.reshape(b.shape[0], -1, nd))
        k += np.matmul(np.swapaxes(tr * vol[c, :, None], 1, 2), tr)
        k += np.matmul(np.swapaxes(nb * cw[c, :, None], 1, 2), nb)
        data[c] = k
    return data
