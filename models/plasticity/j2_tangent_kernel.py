"""The compiled consistent tangent of finite-strain J2 (planar and hexahedral Q1 cells).

The formulas of :mod:`arlequin.models.plasticity.j2_tangent` (its docstring derives them),
computed cell by cell, parallel over the cells (numba ``prange``), into per-cell dense blocks
(n_elems, nen·dim, nen·dim) that :class:`~arlequin.models.plasticity.j2_tangent.BlockAssembler`
sums into the sparse matrix. The spatial gradients are used in their sparse form: L^{bj} =
e_j ⊗ ∇ₓN_b (+ N_b/r on θθ for the radial dof in axisymmetry), so that

* L^{bj} : C : L^{ak} = Σ_n (C : L^{ak})_{jn} g_bn + δ_j0 h_b (C : L^{ak})_{θθ},
* τ : (L^{bj} L^{ak}) = (τ g_a)_j g_bk + δ_j0 δ_k0 τ_θθ h_a h_b,
* tr(L^{bj} L^{ak}) = g_bk g_aj + δ_j0 δ_k0 h_a h_b,

g_b = ∇ₓN_b, h_b = N_b/r (0 off axisymmetry). The principal axes come from the cyclic Jacobi
rotations of :mod:`arlequin.models.plasticity.j2_kernel_3d` (also on planar cells, whose third
axis they leave alone), the plastic multiplier from :mod:`arlequin.models.plasticity.j2_kernel`.
The numpy path is the reference (``tests/test_finite_strain_tangent.py``: 1e-12 relative).
numba compiles on first call (cached on disk).
"""

from __future__ import annotations

import math

import numba as nb

from .j2_kernel import SQRT23, _flow, _plastic_multiplier, _rate_slope, _slope, thread_slots
from .j2_kernel_3d import _jacobi3

__all__ = ["j2_tangent_kernel", "tangent_scratch"]


@nb.njit(cache=True, inline="always", error_model="numpy")
def _phi(t):
    """ln(1 + t)/t (1 at t = 0)."""
    if abs(t) < 1e-300:
        return 1.0
    return math.log1p(t) / t


@nb.njit(cache=True, error_model="numpy")
def _point_modulus(Bm, v, ep, lnv, K, G, code, prm, dt, C, tau):
    """At one point, from B = F C_p⁻¹ Fᵀ − 1 in ``Bm`` (destroyed: its eigenvalues on the
    diagonal), ε̄p and the volumetric strain ``lnv``: the Kirchhoff stress ``tau`` (3, 3) and
    the deviatoric spatial modulus ``C`` (3, 3, 3, 3). Returns 0, or 1 (B not SPD) or 2 (the
    return map did not converge)."""
    third = 1.0 / 3.0
    _jacobi3(Bm, v)
    mu = (Bm[0, 0], Bm[1, 1], Bm[2, 2])
    if not (mu[0] > -1.0 and mu[1] > -1.0 and mu[2] > -1.0):
        return 1
    i3 = 1.0 / (1.0 + mu[2])
    ra = 0.5 * math.log1p((mu[0] - mu[2]) * i3)
    rb = 0.5 * math.log1p((mu[1] - mu[2]) * i3)
    d = ((2.0 * ra - rb) * third, (2.0 * rb - ra) * third, -(ra + rb) * third)
    dnorm = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    norm = 2.0 * G * dnorm
    dg = 0.0
    if norm - SQRT23 * _flow(code, prm, ep, 0.0) > 0.0:
        dg = _plastic_multiplier(norm, ep, code, prm, G, dt)
        if dg < 0.0:
            return 2
    beta = 2.0 * G * dg / norm if dg > 0.0 else 0.0
    pl = 0.0
    if dg > 0.0:
        e_new = ep + SQRT23 * dg
        rated = dt > 0.0 and code == 2 and prm[3] > 0.0
        rate = SQRT23 * dg / dt if rated else 0.0
        h = _slope(code, prm, e_new, rate)
        if rated:
            h += _rate_slope(code, prm, e_new, rate) / dt
        pl = 2.0 * G * (1.0 / (1.0 + h / (3.0 * G)) - beta) / (dnorm * dnorm)
    g1 = 2.0 * G * (1.0 - beta)
    s = (K * lnv + g1 * d[0], K * lnv + g1 * d[1], K * lnv + g1 * d[2])
    for a in range(3):
        for b in range(3):
            tau[a, b] = (
                s[0] * v[a, 0] * v[b, 0] + s[1] * v[a, 1] * v[b, 1] + s[2] * v[a, 2] * v[b, 2]
            )
            for c in range(3):
                for e in range(3):
                    C[a, b, c, e] = 0.0
    for i in range(3):
        for k in range(3):
            dik = g1 * ((1.0 if i == k else 0.0) - third) - pl * d[i] * d[k]
            for a in range(3):
                for b in range(3):
                    nn = dik * v[a, i] * v[b, i]
                    for c in range(3):
                        for e in range(3):
                            C[a, b, c, e] += nn * v[c, k] * v[e, k]
    for i in range(3):
        for j in range(3):
            if i == j:
                continue
            xj = 1.0 + mu[j]
            cij = 0.5 * g1 * _phi((mu[i] - mu[j]) / xj) / xj
            cj = cij * xj
            ci = cij * (1.0 + mu[i])
            for a in range(3):
                for b in range(3):
                    nab = v[a, i] * v[b, j]
                    for c in range(3):
                        for e in range(3):
                            C[a, b, c, e] += nab * (cj * v[c, i] * v[e, j] + ci * v[c, j] * v[e, i])
    return 0


@nb.njit(cache=True, error_model="numpy")
def _kinematics(u, dofs_e, grad_e, val_e, rad_e, axi, dim, nen, nq, hs):
    """H (9), J − 1 and F⁻¹ (9) per point into ``hs`` (nq, 19); returns 0 or 1 (det F ≤ 0)."""
    for q in range(nq):
        for k in range(9):
            hs[q, k] = 0.0
        for a in range(nen):
            for i in range(dim):
                ui = u[dofs_e[a, i]]
                for j in range(dim):
                    hs[q, 3 * i + j] += ui * grad_e[q, a, j]
            if axi:
                hs[q, 8] += u[dofs_e[a, 0]] * val_e[q, a] / rad_e[q]
        h = hs[q]
        tr = h[0] + h[4] + h[8]
        tr2 = (
            h[0] * h[0]
            + h[4] * h[4]
            + h[8] * h[8]
            + 2.0 * (h[1] * h[3] + h[2] * h[6] + h[5] * h[7])
        )
        det = (h[0] * (h[4] * h[8] - h[5] * h[7]) - h[1] * (h[3] * h[8] - h[5] * h[6])
               + h[2] * (h[3] * h[7] - h[4] * h[6]))  # fmt: skip
        jm1 = tr + 0.5 * (tr * tr - tr2) + det
        hs[q, 9] = jm1
        if not (1.0 + jm1 > 0.0):
            return 1
        f00, f01, f02 = 1.0 + h[0], h[1], h[2]
        f10, f11, f12 = h[3], 1.0 + h[4], h[5]
        f20, f21, f22 = h[6], h[7], 1.0 + h[8]
        idet = 1.0 / (1.0 + jm1)
        hs[q, 10] = (f11 * f22 - f12 * f21) * idet
        hs[q, 11] = (f02 * f21 - f01 * f22) * idet
        hs[q, 12] = (f01 * f12 - f02 * f11) * idet
        hs[q, 13] = (f12 * f20 - f10 * f22) * idet
        hs[q, 14] = (f00 * f22 - f02 * f20) * idet
        hs[q, 15] = (f02 * f10 - f00 * f12) * idet
        hs[q, 16] = (f10 * f21 - f11 * f20) * idet
        hs[q, 17] = (f01 * f20 - f00 * f21) * idet
        hs[q, 18] = (f00 * f11 - f01 * f10) * idet
    return 0


@nb.njit(cache=True, error_model="numpy")
def _trial_b(hs_q, cp, e, q, Bm, T):
    """B = H + Hᵀ + H Hᵀ + F (C_p⁻¹ − 1) Fᵀ of one point into ``Bm`` (T: scratch)."""
    for i in range(3):
        for j in range(3):
            acc = 0.0
            for k in range(3):
                fik = hs_q[3 * i + k] + (1.0 if i == k else 0.0)
                acc += fik * (cp[k, j, e, q] - (1.0 if k == j else 0.0))
            T[i, j] = acc
    for i in range(3):
        for j in range(i, 3):
            acc = hs_q[3 * i + j] + hs_q[3 * j + i]
            for k in range(3):
                acc += hs_q[3 * i + k] * hs_q[3 * j + k]
                acc += T[i, k] * (hs_q[3 * j + k] + (1.0 if j == k else 0.0))
            Bm[i, j] = acc
            Bm[j, i] = acc


@nb.njit(parallel=True, cache=True, error_model="numpy", fastmath={"contract"})
def j2_tangent_kernel(
    u, cell_dofs, grad, val, radius, dv0, alpha, axi, fbar, K, G, code, prm, dt,
    cp_inv, eqps, s_h, s_g, s_m, s_c, s_cg, s_acc, ke, flags,
):  # fmt: skip
    """Per-cell tangents ``ke`` (ne, nen·dim, nen·dim), rows and columns (node, component).

    Inputs: u (n_dofs,); cell_dofs (ne, nen, dim); grad (ne, nq, nen, dim) ∇_X N_a; val
    (ne, nq, nen) N_a; radius (ne, nq) R (axisymmetric; ones otherwise); dv0, alpha (ne, nq);
    axi, fbar (bool); K, G (Pa); code, prm the hardening law (:mod:`.j2_kernel`); dt (s, ≤ 0:
    at a vanishing rate); the committed cp_inv (3, 3, ne, nq) and eqps (ne, nq). Scratch per
    thread (:func:`tangent_scratch`). flags (ne,): 1 inverted cell, 2 return map not converged.
    """
    ne = grad.shape[0]
    nq = grad.shape[1]
    nen = grad.shape[2]
    dim = grad.shape[3]
    n = nen * dim
    for e in nb.prange(ne):
        tid = nb.get_thread_id()
        hs, gs, m, C, CG, acc = s_h[tid], s_g[tid], s_m[tid], s_c[tid], s_cg[tid], s_acc[tid]
        flags[e] = _kinematics(u, cell_dofs[e], grad[e], val[e], radius[e], axi, dim, nen, nq,
                               hs)  # fmt: skip
        for r in range(n):
            for c in range(n):
                ke[e, r, c] = 0.0
                acc[r, c] = 0.0
        if flags[e] != 0:
            continue
        vol0 = 0.0
        volj = 0.0
        for q in range(nq):
            vol0 += dv0[e, q]
            volj += hs[q, 9] * dv0[e, q]
        lnjbar = math.log1p(volj / vol0)
        volj += vol0  # Σ J dV₀
        # spatial gradients g_a (3) and h_a = N_a/r per point; the J-weighted mean divergences
        for r in range(n):
            acc[n, r] = 0.0
        for q in range(nq):
            jw = (1.0 + hs[q, 9]) * dv0[e, q]
            for a in range(nen):
                for j in range(3):
                    x = 0.0
                    for k in range(dim):
                        x += grad[e, q, a, k] * hs[q, 10 + 3 * k + j]
                    gs[q, a, j] = x
                gs[q, a, 3] = val[e, q, a] / (radius[e, q] * (1.0 + hs[q, 8])) if axi else 0.0
                for j in range(dim):
                    acc[n, a * dim + j] += (gs[q, a, j] + (gs[q, a, 3] if j == 0 else 0.0)) * jw
        for r in range(n):
            acc[n, r] /= volj
        wsum = 0.0
        psum = 0.0
        for q in range(nq):
            _trial_b(hs[q], cp_inv, e, q, m[0], m[2])
            lnv = lnjbar if fbar else math.log1p(hs[q, 9])
            st = _point_modulus(m[0], m[1], eqps[e, q], lnv, K, G, code, prm, dt, C, m[3])
            if st != 0:
                flags[e] = st
                break
            w0 = alpha[e, q] * dv0[e, q]
            jw = (1.0 + hs[q, 9]) * dv0[e, q]
            p = (m[3, 0, 0] + m[3, 1, 1] + m[3, 2, 2]) / 3.0
            wsum += w0
            psum += w0 * p
            _point_blocks(gs[q], C, m[3], CG, w0, jw, p, K, fbar, nen, dim, ke[e], acc)
        if flags[e] != 0 or not fbar:
            continue
        for r in range(n):
            for c in range(n):
                dbar = acc[n, r] * acc[n, c]
                ke[e, r, c] += K * wsum * dbar + psum * (acc[r, c] / volj - dbar)
    return 0


@nb.njit(cache=True, error_model="numpy")
def _point_blocks(g, C, tau, CG, w0, jw, p, K, fbar, nen, dim, ke, acc):
    """Add one point's terms to the cell block ``ke`` and (F-bar) Σ Jw (div div − tr LL) to
    ``acc`` (see the module docstring; g (nen, 4): g_a and h_a)."""
    for a in range(nen):  # (C : L^{ak})_{jn}
        for k in range(dim):
            for j in range(3):
                for nn in range(3):
                    x = 0.0
                    for s in range(3):
                        x += C[j, nn, k, s] * g[a, s]
                    if k == 0:
                        x += C[j, nn, 2, 2] * g[a, 3]
                    CG[j, nn, a, k] = x
    for b in range(nen):
        for j in range(dim):
            r = b * dim + j
            hb = g[b, 3] if j == 0 else 0.0
            div_b = g[b, j] + hb
            for a in range(nen):
                tga = tau[j, 0] * g[a, 0] + tau[j, 1] * g[a, 1] + tau[j, 2] * g[a, 2]
                for k in range(dim):
                    c = a * dim + k
                    ha = g[a, 3] if k == 0 else 0.0
                    mat = g[b, 0] * CG[j, 0, a, k] + g[b, 1] * CG[j, 1, a, k]
                    mat += g[b, 2] * CG[j, 2, a, k] + hb * CG[2, 2, a, k]
                    hh = hb * ha
                    geo = tga * g[b, k] + tau[2, 2] * hh
                    trll = g[b, k] * g[a, j] + hh
                    if fbar:
                        ke[r, c] += w0 * (mat - geo + p * trll)
                        acc[r, c] += jw * (div_b * (g[a, k] + ha) - trll)
                    else:
                        ke[r, c] += w0 * (mat - geo + K * div_b * (g[a, k] + ha))


def tangent_scratch(n_qp: int, nen: int, dim: int):
    """Per-thread scratch of :func:`j2_tangent_kernel` (each thread's on its own cache lines,
    :func:`~arlequin.models.plasticity.j2_kernel.thread_slots`)."""
    n = nen * dim
    return (
        thread_slots((n_qp, 19)), thread_slots((n_qp, nen, 4)), thread_slots((4, 3, 3)),
        thread_slots((3, 3, 3, 3)), thread_slots((3, 3, nen, dim)), thread_slots((n + 1, n)),
    )  # fmt: skip
