"""The compiled kernel of finite-strain J2 on 8-node hexahedra (3D), the planar kernel's twin.

One fused pass per cell, parallel over the cells (numba ``prange``), of exactly the formulas of
the numpy path (:mod:`arlequin.models.plasticity.kinematics`,
:func:`arlequin.models.plasticity.j2.j2_return_map`): H = F − 1 at the Gauss points, J − 1 without
cancellation, the cell's mean dilatation (F-bar), b_e − 1 = H + Hᵀ + H Hᵀ + F (C_p⁻¹ − 1) Fᵀ, its
eigen-decomposition (cyclic Jacobi rotations on the 3 × 3 matrix, to round-off: the principal axes
are no longer known as in the planar case), the exponential-map radial return, the optional bulk
viscosity and the consistent internal force with the F-bar pressure term. Compared with the numpy
path to 1e-13 (``tests/test_j2_kernel.py``).

The hardening laws and the plastic multiplier are those of
:mod:`arlequin.models.plasticity.j2_kernel`. numba compiles on first call (cached on disk);
benchmarks count the first call out.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from .j2_kernel import (
    SQRT23,
    _flow,
    _plastic_multiplier,
    assemble_cell_forces,
    assembly_dofs,
    thread_slots,
)

__all__ = ["solid_j2_kernel", "solid_scratch", "warm_up_solid"]


@nb.njit(cache=True, inline="always", error_model="numpy")
def _rotate(app, aqq, apq, arp, arq, v0p, v1p, v2p, v0q, v1q, v2q):
    """One Jacobi rotation J(p, q) that zeroes a_pq of a symmetric 3 × 3 (r: the third index):
    the new a_pp, a_qq, a_rp, a_rq and the columns p and q of V J."""
    if apq == 0.0:
        return app, aqq, arp, arq, v0p, v1p, v2p, v0q, v1q, v2q
    # t = tan φ = sgn θ / (|θ| + √(θ² + 1)), θ = (a_qq − a_pp) / 2a_pq, without forming θ:
    # one division less on the sweeps' critical path (6% of the 3D kernel)
    d = aqq - app
    t = 2.0 * abs(apq) / (abs(d) + math.sqrt(d * d + 4.0 * apq * apq))
    if d != 0.0 and (d < 0.0) != (apq < 0.0):
        t = -t
    c = 1.0 / math.sqrt(t * t + 1.0)
    s = t * c
    return (app - t * apq, aqq + t * apq, c * arp - s * arq, s * arp + c * arq,
            c * v0p - s * v0q, c * v1p - s * v1q, c * v2p - s * v2q,
            s * v0p + c * v0q, s * v1p + c * v1q, s * v2p + c * v2q)  # fmt: skip


@nb.njit(cache=True, inline="always", error_model="numpy")
def _jacobi3(a, v):
    """Eigen-decomposition of the symmetric 3 × 3 ``a`` (its upper triangle is read): on
    return its diagonal holds the eigenvalues and the columns of ``v`` the unit eigenvectors
    (cyclic Jacobi). The sweeps run on scalars (six entries of ``a``, nine of ``v``): on the
    arrays they took a third of the 3D kernel's time."""
    a00, a11, a22 = a[0, 0], a[1, 1], a[2, 2]
    a01, a02, a12 = a[0, 1], a[0, 2], a[1, 2]
    v00, v01, v02 = 1.0, 0.0, 0.0
    v10, v11, v12 = 0.0, 1.0, 0.0
    v20, v21, v22 = 0.0, 0.0, 1.0
    for _ in range(30):
        off = a01 * a01 + a02 * a02 + a12 * a12
        scale = a00 * a00 + a11 * a11 + a22 * a22 + 2.0 * off
        if off <= 1e-36 * scale:
            break
        # (p, q) = (0, 1), r = 2
        a00, a11, a02, a12, v00, v10, v20, v01, v11, v21 = _rotate(
            a00, a11, a01, a02, a12, v00, v10, v20, v01, v11, v21
        )
        a01 = 0.0
        # (p, q) = (0, 2), r = 1
        a00, a22, a01, a12, v00, v10, v20, v02, v12, v22 = _rotate(
            a00, a22, a02, a01, a12, v00, v10, v20, v02, v12, v22
        )
        a02 = 0.0
        # (p, q) = (1, 2), r = 0
        a11, a22, a01, a02, v01, v11, v21, v02, v12, v22 = _rotate(
            a11, a22, a12, a01, a02, v01, v11, v21, v02, v12, v22
        )
        a12 = 0.0
    a[0, 0], a[1, 1], a[2, 2] = a00, a11, a22
    a[0, 1], a[0, 2], a[1, 2] = a01, a02, a12
    a[1, 0], a[2, 0], a[2, 1] = a01, a02, a12
    v[0, 0], v[0, 1], v[0, 2] = v00, v01, v02
    v[1, 0], v[1, 1], v[1, 2] = v10, v11, v12
    v[2, 0], v[2, 1], v[2, 2] = v20, v21, v22


@nb.njit(parallel=True, cache=True, error_model="numpy", fastmath={"contract"})
def solid_j2_kernel(
    u, cell_dofs, grad, dv0, alpha, fbar, K, G, code, prm, dt,
    cp_inv, eqps, wp, wv, jac_old, visc, h0, scratch_h, scratch_g, scratch_m,
    fe, cp_new, eqps_new, tau_out, j_out, wp_new, wv_new, flags,
):  # fmt: skip
    """One evaluation on every cell (see the module docstring).

    Inputs: u (n_dofs,); cell_dofs (ne, nen, 3); grad (ne, nq, nen, 3) reference gradients;
    dv0, alpha (ne, nq); fbar (bool); K, G (Pa); code, prm (6,) the hardening law; dt (s, ≤ 0:
    rates off); the committed state cp_inv (3, 3, ne, nq), eqps, wp, wv, jac_old (ne, nq);
    visc (4,) and h0 (ne,) as :func:`arlequin.models.plasticity.j2_kernel.planar_j2_kernel`.
    Scratch, one slot per thread: scratch_h (n_threads, nq, 19) H, J − 1 and F⁻¹, scratch_g
    (n_threads, nq + 1, nen, 3) ∇ₓN_a per point and the cell's mean divergences, scratch_m
    (n_threads, 4, 3, 3). Outputs (overwritten): fe (3, nen, ne), cp_new, tau_out (3, 3, ne, nq),
    eqps_new, j_out, wp_new, wv_new (ne, nq), flags (ne,): 1 inverted cell, 2 return map not
    converged.
    """
    ne = grad.shape[0]
    nq = grad.shape[1]
    nen = grad.shape[2]
    third = 1.0 / 3.0
    for e in nb.prange(ne):
        flags[e] = 0
        tid = nb.get_thread_id()
        hs = scratch_h[tid]
        gs = scratch_g[tid]
        m = scratch_m[tid]  # m[0] E = b_e − 1, m[1] its axes, m[2] F⁻¹ v_k, m[3] T
        vol0 = 0.0
        volj_m1 = 0.0
        volj_old = 0.0
        for q in range(nq):
            for k in range(9):
                hs[q, k] = 0.0
            for a in range(nen):
                u0 = u[cell_dofs[e, a, 0]]
                u1 = u[cell_dofs[e, a, 1]]
                u2 = u[cell_dofs[e, a, 2]]
                for j in range(3):
                    g = grad[e, q, a, j]
                    hs[q, j] += u0 * g
                    hs[q, 3 + j] += u1 * g
                    hs[q, 6 + j] += u2 * g
            h00, h01, h02 = hs[q, 0], hs[q, 1], hs[q, 2]
            h10, h11, h12 = hs[q, 3], hs[q, 4], hs[q, 5]
            h20, h21, h22 = hs[q, 6], hs[q, 7], hs[q, 8]
            tr = h00 + h11 + h22
            tr2 = (h00 * h00 + h11 * h11 + h22 * h22
                   + 2.0 * (h01 * h10 + h02 * h20 + h12 * h21))  # fmt: skip
            det = (h00 * (h11 * h22 - h12 * h21) - h01 * (h10 * h22 - h12 * h20)
                   + h02 * (h10 * h21 - h11 * h20))  # fmt: skip
            jm1 = tr + 0.5 * (tr * tr - tr2) + det
            hs[q, 9] = jm1
            if not (1.0 + jm1 > 0.0):
                flags[e] = 1
            vol0 += dv0[e, q]
            volj_m1 += jm1 * dv0[e, q]
            volj_old += jac_old[e, q] * dv0[e, q]
        if flags[e] != 0:
            for i in range(3):
                for a in range(nen):
                    fe[i, a, e] = 0.0
            continue
        jbar_m1 = volj_m1 / vol0
        jbar = 1.0 + jbar_m1
        lnjbar = math.log1p(jbar_m1)
        volj = jbar * vol0
        qv = 0.0
        jbar_old = volj_old / vol0
        if visc[2] > 0.0 and dt > 0.0:
            rate = (jbar - jbar_old) / (dt * jbar)
            if rate < 0.0:
                ell = h0[e] * math.sqrt(jbar)
                rho = visc[2] / jbar
                qv = rho * (visc[1] * ell * ell * rate * rate - visc[0] * ell * visc[3] * rate)
        # ---- spatial gradients ∇ₓN_a = F⁻ᵀ ∇_X N_a and the J-weighted mean divergences
        for a in range(nen):
            for k in range(3):
                gs[nq, a, k] = 0.0
        for q in range(nq):
            f00, f01, f02 = 1.0 + hs[q, 0], hs[q, 1], hs[q, 2]
            f10, f11, f12 = hs[q, 3], 1.0 + hs[q, 4], hs[q, 5]
            f20, f21, f22 = hs[q, 6], hs[q, 7], 1.0 + hs[q, 8]
            jq = 1.0 + hs[q, 9]
            idet = 1.0 / jq
            i00 = (f11 * f22 - f12 * f21) * idet
            i01 = (f02 * f21 - f01 * f22) * idet
            i02 = (f01 * f12 - f02 * f11) * idet
            i10 = (f12 * f20 - f10 * f22) * idet
            i11 = (f00 * f22 - f02 * f20) * idet
            i12 = (f02 * f10 - f00 * f12) * idet
            i20 = (f10 * f21 - f11 * f20) * idet
            i21 = (f01 * f20 - f00 * f21) * idet
            i22 = (f00 * f11 - f01 * f10) * idet
            hs[q, 10], hs[q, 11], hs[q, 12] = i00, i01, i02  # F⁻¹, for C_p⁻¹ below
            hs[q, 13], hs[q, 14], hs[q, 15] = i10, i11, i12
            hs[q, 16], hs[q, 17], hs[q, 18] = i20, i21, i22
            jw = jq * dv0[e, q]
            for a in range(nen):
                g0 = grad[e, q, a, 0]
                g1 = grad[e, q, a, 1]
                g2 = grad[e, q, a, 2]
                x0 = g0 * i00 + g1 * i10 + g2 * i20
                x1 = g0 * i01 + g1 * i11 + g2 * i21
                x2 = g0 * i02 + g1 * i12 + g2 * i22
                gs[q, a, 0] = x0
                gs[q, a, 1] = x1
                gs[q, a, 2] = x2
                gs[nq, a, 0] += x0 * jw
                gs[nq, a, 1] += x1 * jw
                gs[nq, a, 2] += x2 * jw
        ivolj = 1.0 / volj
        for a in range(nen):
            for k in range(3):
                gs[nq, a, k] *= ivolj
                fe[k, a, e] = 0.0
        # ---- return map and forces at each Gauss point
        for q in range(nq):
            jm1 = hs[q, 9]
            jq = 1.0 + jm1
            # T = F D, D = C_p⁻¹ − 1; E = H + Hᵀ + H Hᵀ + T Fᵀ (symmetric)
            for i in range(3):
                for j in range(3):
                    acc = 0.0
                    for k in range(3):
                        fik = hs[q, 3 * i + k] + (1.0 if i == k else 0.0)
                        dkj = cp_inv[k, j, e, q] - (1.0 if k == j else 0.0)
                        acc += fik * dkj
                    m[3, i, j] = acc
            for i in range(3):
                for j in range(i, 3):
                    acc = hs[q, 3 * i + j] + hs[q, 3 * j + i]
                    for k in range(3):
                        acc += hs[q, 3 * i + k] * hs[q, 3 * j + k]
                        fjk = hs[q, 3 * j + k] + (1.0 if j == k else 0.0)
                        acc += m[3, i, k] * fjk
                    m[0, i, j] = acc
                    m[0, j, i] = acc
            _jacobi3(m[0], m[1])
            mu0 = m[0, 0, 0]
            mu1 = m[0, 1, 1]
            mu2 = m[0, 2, 2]
            if not (mu0 > -1.0 and mu1 > -1.0 and mu2 > -1.0):
                flags[e] = 1
                continue
            i3 = 1.0 / (1.0 + mu2)
            ra = 0.5 * math.log1p((mu0 - mu2) * i3)
            rb = 0.5 * math.log1p((mu1 - mu2) * i3)
            d1 = (2.0 * ra - rb) * third
            d2 = (2.0 * rb - ra) * third
            d3 = -(ra + rb) * third
            tr = lnjbar if fbar else math.log1p(jm1)
            norm = 2.0 * G * math.sqrt(d1 * d1 + d2 * d2 + d3 * d3)
            ep = eqps[e, q]
            fy = norm - SQRT23 * _flow(code, prm, ep, 0.0)
            dg = 0.0
            if fy > 0.0 and code == 0:
                # linear hardening: Δγ of _plastic_multiplier's first line (equal to rounding:
                # here the kernel's fastmath may fuse its products), here rather than through
                # its call (not inlined: the point's live values spilled around it, 7% of the
                # planar kernel on one core at nr = 30); H ≥ 0, so Δγ > 0
                dg = fy / (2.0 * G + 2.0 / 3.0 * prm[1])
            elif fy > 0.0:
                dg = _plastic_multiplier(norm, ep, code, prm, G, dt)
                if dg < 0.0:
                    flags[e] = 2
                    dg = 0.0
            shrink = 1.0 - 2.0 * G * dg / norm if (norm > 0.0 and dg > 0.0) else 1.0
            dep = SQRT23 * dg
            eqps_new[e, q] = ep + dep
            wrk = 0.0
            if dg > 0.0:
                rate = dep / dt if dt > 0.0 else 0.0
                wrk = _flow(code, prm, ep + dep, rate) * dep
            wp_new[e, q] = wp[e, q] + wrk
            s1 = K * tr + 2.0 * G * shrink * d1
            s2 = K * tr + 2.0 * G * shrink * d2
            s3 = K * tr + 2.0 * G * shrink * d3
            v = m[1]
            for i in range(3):
                for j in range(i, 3):
                    t_ij = s1 * v[i, 0] * v[j, 0] + s2 * v[i, 1] * v[j, 1] + s3 * v[i, 2] * v[j, 2]
                    tau_out[i, j, e, q] = t_ij
                    tau_out[j, i, e, q] = t_ij
            if dg > 0.0:
                # C_p⁻¹ = F⁻¹ (b̄_e / s²) F⁻ᵀ, log-eigenvalues 2(ln J / 3 + shrink d_i)
                lj = math.log1p(jm1) * third
                x1 = math.exp(2.0 * (lj + shrink * d1))
                x2 = math.exp(2.0 * (lj + shrink * d2))
                x3 = math.exp(2.0 * (lj + shrink * d3))
                # F⁻¹ v_k, the columns of m[2] (F⁻¹ kept from the gradients' pass)
                for i in range(3):
                    r0 = hs[q, 10 + 3 * i]
                    r1 = hs[q, 11 + 3 * i]
                    r2 = hs[q, 12 + 3 * i]
                    for k in range(3):
                        m[2, i, k] = r0 * v[0, k] + r1 * v[1, k] + r2 * v[2, k]
                w = m[2]
                for i in range(3):
                    for j in range(i, 3):
                        c_ij = x1 * w[i, 0] * w[j, 0] + x2 * w[i, 1] * w[j, 1] \
                            + x3 * w[i, 2] * w[j, 2]  # fmt: skip
                        cp_new[i, j, e, q] = c_ij
                        cp_new[j, i, e, q] = c_ij
            else:  # elastic: C_p⁻¹ kept bit for bit
                for i in range(3):
                    for j in range(3):
                        cp_new[i, j, e, q] = cp_inv[i, j, e, q]
            j_out[e, q] = jq
            wv_new[e, q] = wv[e, q] + qv * (jbar_old - jbar)
            w0 = alpha[e, q] * dv0[e, q]
            pv = jq * qv
            t00 = tau_out[0, 0, e, q] - pv
            t11 = tau_out[1, 1, e, q] - pv
            t22 = tau_out[2, 2, e, q] - pv
            t01 = tau_out[0, 1, e, q]
            t02 = tau_out[0, 2, e, q]
            t12 = tau_out[1, 2, e, q]
            p = (t00 + t11 + t22) * third
            for a in range(nen):
                x0 = gs[q, a, 0]
                x1 = gs[q, a, 1]
                x2 = gs[q, a, 2]
                f0 = t00 * x0 + t01 * x1 + t02 * x2
                f1 = t01 * x0 + t11 * x1 + t12 * x2
                f2 = t02 * x0 + t12 * x1 + t22 * x2
                if fbar:
                    f0 += p * (gs[nq, a, 0] - x0)
                    f1 += p * (gs[nq, a, 1] - x1)
                    f2 += p * (gs[nq, a, 2] - x2)
                fe[0, a, e] += w0 * f0
                fe[1, a, e] += w0 * f1
                fe[2, a, e] += w0 * f2
    return 0


def solid_scratch(n_qp: int = 8, nen: int = 8) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-thread scratch buffers of :func:`solid_j2_kernel` (each thread's on its own cache
    lines, :func:`~arlequin.models.plasticity.j2_kernel.thread_slots`)."""
    return thread_slots((n_qp, 19)), thread_slots((n_qp + 1, nen, 3)), thread_slots((4, 3, 3))


def warm_up_solid() -> None:
    """Compile (or load from the cache) the kernel on a one-cell problem."""
    nen, ne, nq = 8, 1, 8
    corners = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], float) - 0.5
    grad = np.broadcast_to(corners, (ne, nq, nen, 3)).copy()
    ones = np.ones((ne, nq))
    zeros = np.zeros((ne, nq))
    cp = np.broadcast_to(np.eye(3)[:, :, None, None], (3, 3, ne, nq)).copy()
    dofs = np.arange(3 * nen).reshape(ne, nen, 3)
    out = [np.zeros((3, nen, ne)), np.zeros((3, 3, ne, nq)), np.zeros((ne, nq)),
           np.zeros((3, 3, ne, nq)), np.zeros((ne, nq)), np.zeros((ne, nq)), np.zeros((ne, nq)),
           np.zeros(ne, dtype=np.int64)]  # fmt: skip
    # the weight as FiniteStrainJ2 passes it, a read-only broadcast view: numba types it
    # apart from a writeable array, and a writeable one here left each process's first run
    # compiling (or loading) its own specialisation inside its clock
    weight = np.broadcast_to(ones, ones.shape)
    solid_j2_kernel(
        np.zeros(3 * nen), dofs, grad, ones, weight, True, 1.0, 1.0, 0,
        np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0]), 0.0, cp, zeros, zeros, zeros, ones,
        np.zeros(4), np.ones(ne), *solid_scratch(nq, nen), *out,
    )  # fmt: skip
    assemble_cell_forces(assembly_dofs(dofs), out[0], out[-1], np.zeros(3 * nen))
