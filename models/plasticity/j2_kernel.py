"""The compiled kernel of finite-strain J2 on planar Q1 cells (axisymmetric, plane strain).

One fused pass per cell, parallel over the cells (numba ``prange``; on the calling thread alone
below :data:`PARALLEL_MIN_CELLS`, see :func:`run_kernel`): deformation gradient at
the four Gauss points, the cell's mean dilatation (F-bar), the exponential-map return of
:mod:`arlequin.models.plasticity.j2` (closed-form principal axes in the (r, z) plane plus the hoop
or out-of-plane axis), the optional bulk viscosity, and the consistent internal force of
:mod:`arlequin.models.plasticity.kinematics`, written into preallocated per-cell buffers (no race:
the nodal forces are summed afterwards with ``np.bincount``). It is the numpy reference path
computed point by point, compared with it to 1e-13 (``tests/test_j2_kernel.py``).

Hardening laws by code (see :mod:`arlequin.models.plasticity.hardening`): 0 linear (σ_y0, H), 1 Voce
(σ_y0, Q, b, H), 2 Johnson–Cook (A, B, n, C, ε̄̇0, ε̄p floor).

numba compiles on first call (cached on disk, ``cache=True``); benchmarks count the first call
out of their figures.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

__all__ = [
    "PARALLEL_MIN_CELLS",
    "assemble_cell_forces",
    "assembly_dofs",
    "min_scaled_cell_size",
    "planar_j2_kernel",
    "run_kernel",
    "scratch",
    "thread_slots",
    "warm_up",
]

SQRT23 = math.sqrt(2.0 / 3.0)

#: Below this many cells a kernel runs on the calling thread alone. A planar cell costs about
#: 0.5 µs on one core (a hexahedron 3 µs); waking the sleeping worker threads
#: (``OMP_WAIT_POLICY=PASSIVE``) and joining them costs tens of µs: on the 2-core machine, loaded
#: by other work, two threads ran a 16-cell patch at 0.63 times the speed of one and a 64-cell
#: patch at 0.91. 256 cells (about 130 µs of work) leave the wake-up a small share.
PARALLEL_MIN_CELLS = 256


def run_kernel(kernel, n_cells: int, *args) -> None:
    """Call ``kernel(*args)``, on the calling thread alone when ``n_cells`` is below
    :data:`PARALLEL_MIN_CELLS` (numba's thread count is per calling thread and restored)."""
    if n_cells >= PARALLEL_MIN_CELLS:
        # no numba.get_num_threads() here: its launch check costs several µs a call (3% of an
        # Arlequin Taylor bar step under py-spy)
        kernel(*args)
        return
    n = nb.get_num_threads()
    if n == 1:
        kernel(*args)
        return
    nb.set_num_threads(1)
    try:
        kernel(*args)
    finally:
        nb.set_num_threads(n)


@nb.njit(cache=True)
def assemble_cell_forces(dofs, fe, flags, f):
    """Nodal forces from the cell forces, and the number of flagged cells.

    ``f[dofs[i, a, e]] += fe[i, a, e]`` summed in the order of ``np.bincount`` over the
    (component, node, cell)-ordered arrays (``f`` is zeroed first), so that the sums are the
    same bit for bit. Serial: the cells share nodes. The kernels' own pass, rather than
    ``np.bincount`` with a ravelled copy of the dofs and a separate ``np.any`` on the flags:
    those took 13% of the Arlequin Taylor bar's step. The dofs in the forces' own layout and
    unsigned (no wraparound test per index): 41 against 70 µs at 9,120 cells than with the
    kernels' cell-major int64 dofs.

    Parameters
    ----------
    dofs : ndarray of uint32 (or int64), shape (dim, nen, ne)
        The dof of component i of node a of cell e.
    fe : ndarray, shape (dim, nen, ne)
        Cell forces (N).
    flags : ndarray of int64, shape (ne,)
        The kernel's flags (0: a valid cell).
    f : ndarray, shape (n_dofs,)
        Output (overwritten), N.

    Returns
    -------
    int
        The number of cells with a non-zero flag.
    """
    dim, nen, ne = dofs.shape
    for k in range(f.size):
        f[k] = 0.0
    for i in range(dim):
        for a in range(nen):
            for e in range(ne):
                f[dofs[i, a, e]] += fe[i, a, e]
    bad = 0
    for e in range(ne):
        if flags[e] != 0:
            bad += 1
    return bad


def assembly_dofs(cell_dofs: np.ndarray) -> np.ndarray:
    """The dofs of :func:`assemble_cell_forces` from the kernels' (ne, nen, dim) ones: shape
    (dim, nen, ne), C-contiguous, uint32 (int64 beyond 2³² − 1 dofs)."""
    dtype = np.uint32 if cell_dofs.size == 0 or cell_dofs.max() < 2**32 - 1 else np.int64
    return np.ascontiguousarray(np.transpose(cell_dofs, (2, 1, 0)), dtype=dtype)


@nb.njit(cache=True, error_model="numpy")
def min_scaled_cell_size(p, cells, dofs, u, ratio):
    """min over the Q1 cells of ``ratio[e] · h_e`` (m), h_e the cell's area over its longest edge
    in the configuration x = p + u[dofs]: the numbers of
    :meth:`~arlequin.models.plasticity.kinematics.Q1Kinematics.cell_sizes` bit for bit,
    without its temporaries (the critical-step estimate every few steps).

    Parameters
    ----------
    p : ndarray, shape (2, n_nodes)
        Reference positions (m).
    cells : ndarray of int, shape (4, ne)
        The cells' nodes, counter-clockwise.
    dofs : ndarray of int, shape (2, n_nodes)
        Each node's dofs in ``u``.
    u : ndarray, shape (n_dofs,)
        Displacement (m).
    ratio : ndarray, shape (ne,)
        A factor per cell.
    """
    ne = cells.shape[1]
    best = np.inf
    x = np.empty((2, 4))
    for e in range(ne):
        for k in range(4):
            n = cells[k, e]
            x[0, k] = p[0, n] + u[dofs[0, n]]
            x[1, k] = p[1, n] + u[dofs[1, n]]
        longest2 = -np.inf
        for k in range(4):
            k1 = k + 1 if k < 3 else 0  # (k + 1) % 4 without Python's signed modulo
            d0 = x[0, k1] - x[0, k]
            d1 = x[1, k1] - x[1, k]
            s = d0 * d0 + d1 * d1
            if s > longest2:
                longest2 = s
        area = 0.5 * abs((x[0, 2] - x[0, 0]) * (x[1, 3] - x[1, 1])
                         - (x[0, 3] - x[0, 1]) * (x[1, 2] - x[1, 0]))  # fmt: skip
        h = ratio[e] * (area / math.sqrt(longest2))
        if h != h:  # NaN: a cell collapsed to a point (0/0), returned as np.min returns it
            return h
        if h < best:
            best = h
    return best


@nb.njit(cache=True, inline="always", error_model="numpy")
def _flow(code, prm, e, rate):
    if code == 0:
        return prm[0] + prm[1] * e
    if code == 1:
        return prm[0] + prm[1] * (1.0 - math.exp(-prm[2] * e)) + prm[3] * e
    ee = e if e > 0.0 else 0.0
    factor = 1.0
    if prm[3] > 0.0 and rate > prm[4]:
        factor = 1.0 + prm[3] * math.log(rate / prm[4])
    return (prm[0] + prm[1] * ee ** prm[2]) * factor


@nb.njit(cache=True, inline="always", error_model="numpy")
def _slope(code, prm, e, rate):
    if code == 0:
        return prm[1]
    if code == 1:
        return prm[1] * prm[2] * math.exp(-prm[2] * e) + prm[3]
    ee = e if e > prm[5] else prm[5]
    factor = 1.0
    if prm[3] > 0.0 and rate > prm[4]:
        factor = 1.0 + prm[3] * math.log(rate / prm[4])
    return prm[2] * prm[1] * ee ** (prm[2] - 1.0) * factor


@nb.njit(cache=True, inline="always", error_model="numpy")
def _rate_slope(code, prm, e, rate):
    if code != 2 or prm[3] == 0.0 or rate <= prm[4]:
        return 0.0
    ee = e if e > 0.0 else 0.0
    return (prm[0] + prm[1] * ee ** prm[2]) * prm[3] / rate


@nb.njit(cache=True, error_model="numpy")
def _plastic_multiplier(norm, eqps, code, prm, G, dt):
    """Δγ of the consistency equation: safeguarded Newton, as
    arlequin.models.plasticity.j2._consistency."""
    h0 = _slope(code, prm, eqps, 0.0)
    dg = (norm - SQRT23 * _flow(code, prm, eqps, 0.0)) / (2.0 * G + 2.0 / 3.0 * h0)
    if code == 0:
        return dg
    scale = SQRT23 * _flow(code, prm, eqps, 0.0)
    rated = dt > 0.0 and code == 2 and prm[3] > 0.0
    lo = 0.0
    hi = norm / (2.0 * G)
    dg = min(max(dg, 0.0), hi)
    step_old = hi - lo
    step = step_old
    for _ in range(50):
        e = eqps + SQRT23 * dg
        rate = SQRT23 * dg / dt if rated else 0.0
        r = norm - 2.0 * G * dg - SQRT23 * _flow(code, prm, e, rate)
        if abs(r) <= 1e-12 * scale or hi - lo <= 1e-15 * hi:
            return dg
        if r > 0.0:
            lo = dg
        elif r < 0.0:
            hi = dg
        dr = -2.0 * G - 2.0 / 3.0 * _slope(code, prm, e, rate)
        if rated:
            dr -= (2.0 / 3.0) / dt * _rate_slope(code, prm, e, rate)
        newton = dg - r / dr
        step_old_now = step
        if (newton > lo and newton < hi) and abs(2.0 * r) <= abs(step_old * dr):
            step = abs(r / dr)
            dg = newton
        else:
            step = 0.5 * (hi - lo)
            dg = 0.5 * (lo + hi)
        step_old = step_old_now
    return -1.0  # not converged: flagged by the caller


# fastmath: contraction into fused multiply-adds, and "arcp" (a division may become a product
# with a reciprocal, one reciprocal serving several divisions by the same value): outputs
# within 5e-16 of the kernel without it, 5% faster on one core at nr = 30 (same process)
@nb.njit(parallel=True, cache=True, error_model="numpy", fastmath={"contract", "arcp"})
def planar_j2_kernel(
    u, cell_dofs, grad, val, radius, dv0, alpha, axi, fbar, K, G, code, prm, dt,
    cp_inv, eqps, wp, wv, jac_old, visc, h0, scratch_h, scratch_g, scratch_u,
    fe, cp_new, eqps_new, tau_out, j_out, wp_new, wv_new, flags,
):  # fmt: skip
    """One evaluation on every cell (see the module docstring).

    Inputs: u (n_dofs,) displacement; cell_dofs (2, nen, ne); grad (nen, 2, ne, nq); val
    (nen, ne, nq); radius (ne, nq) (ones in plane strain); dv0, alpha (ne, nq); axi, fbar (bool);
    K, G (Pa); code, prm (6,) the hardening law; dt (s, ≤ 0: rates off); the committed state
    cp_inv (3, 3, ne, nq), eqps, wp, wv, jac_old (ne, nq); visc (4,) = (c_linear, c_quadratic,
    ρ₀, c_d) of the bulk viscosity (ρ₀ = 0: off), h0 (ne,) reference cell lengths:
    q = ρ (c_quad ℓ² ε̇_v² − c_lin ℓ c_d ε̇_v) on compression (ε̇_v < 0), ρ = ρ₀/J̄, ℓ = h0 √J̄.
    Scratch (overwritten, one slot per thread, no allocation per cell): scratch_h
    (n_threads, nq, 10), scratch_g (n_threads, nq, nen, 3), scratch_u (n_threads, 4, nen).
    Outputs (overwritten): fe (2, nen, ne) cell forces, cp_new, tau_out (3, 3, ne, nq),
    eqps_new, j_out, wp_new, wv_new (ne, nq), flags (ne,): 1 inverted cell, 2 return map not
    converged. The out-of-plane shear components of cp_new and tau_out ([0, 2], [2, 0], [1, 2],
    [2, 1]) are not written: they must hold zeros (the model's arrays come from a pool whose
    fresh arrays are zeros and which only this kernel writes; eight stores per point less).
    """
    ne = grad.shape[0]
    # Q1 cells with 2 × 2 Gauss points: fixed trip counts, so that the compiler unrolls the
    # node and point loops (about 10% of the kernel's time against run-time bounds)
    nq = 4
    nen = 4
    if grad.shape[1] != nq or grad.shape[2] != nen:
        raise ValueError("planar_j2_kernel: Q1 cells with 2 x 2 Gauss points only")
    if scratch_h.shape[1] < nq or scratch_h.shape[2] < 10:
        raise ValueError("planar_j2_kernel: scratch_h must hold (n_threads, 4, 10) (scratch())")
    third = 1.0 / 3.0
    for e in nb.prange(ne):
        flags[e] = 0
        tid = nb.get_thread_id()
        hs = scratch_h[tid]  # per qp: h00, h01, h10, h11, hθ = F − 1, J − 1, F⁻¹ (in-plane)
        gs = scratch_g[tid]  # per qp and node: ∇ₓN_a (2) and N_a / r
        us = scratch_u[tid]  # rows 0, 1: nodal u_r, u_z; rows 2, 3: J-weighted divergences
        # ---- one pass over the Gauss points: H = F − 1 (kept apart from 1 for small strains),
        # J, the volumes of J̄, the spatial gradients and their J-weighted sums (F-bar)
        vol0 = 0.0
        volj_m1 = 0.0
        volj_old = 0.0
        for a in range(nen):
            us[0, a] = u[cell_dofs[e, a, 0]]
            us[1, a] = u[cell_dofs[e, a, 1]]
            us[2, a] = 0.0
            us[3, a] = 0.0
        for q in range(nq):
            h00 = 0.0
            h01 = 0.0
            h10 = 0.0
            h11 = 0.0
            ur = 0.0
            for a in range(nen):
                ur_a = us[0, a]
                uz_a = us[1, a]
                g0 = grad[e, q, a, 0]
                g1 = grad[e, q, a, 1]
                h00 += ur_a * g0
                h01 += ur_a * g1
                h10 += uz_a * g0
                h11 += uz_a * g1
                ur += ur_a * val[e, q, a]
            hth = ur / radius[e, q] if axi else 0.0
            j2m1 = h00 + h11 + h00 * h11 - h01 * h10
            jm1 = j2m1 + hth + j2m1 * hth
            hs[q, 0] = h00
            hs[q, 1] = h01
            hs[q, 2] = h10
            hs[q, 3] = h11
            hs[q, 4] = hth
            hs[q, 5] = jm1
            if not (1.0 + jm1 > 0.0):
                flags[e] = 1
            dvq = dv0[e, q]
            vol0 += dvq
            volj_m1 += jm1 * dvq
            volj_old += jac_old[e, q] * dvq
            # spatial gradients ∇ₓN_a = F⁻ᵀ ∇_X N_a (in-plane block) and N_a / r
            f00 = 1.0 + h00
            f11 = 1.0 + h11
            idet = 1.0 / (f00 * f11 - h01 * h10)
            i00 = f11 * idet
            i01 = -h01 * idet
            i10 = -h10 * idet
            i11 = f00 * idet
            hs[q, 6] = i00  # F⁻¹'s in-plane block, again in the plastic update of C_p⁻¹
            hs[q, 7] = i01
            hs[q, 8] = i10
            hs[q, 9] = i11
            jw = (1.0 + jm1) * dvq
            rinv = 1.0 / (radius[e, q] * (1.0 + hth)) if axi else 0.0
            for a in range(nen):
                g0 = grad[e, q, a, 0]
                g1 = grad[e, q, a, 1]
                x0 = g0 * i00 + g1 * i10
                x1 = g0 * i01 + g1 * i11
                hp = val[e, q, a] * rinv
                gs[q, a, 0] = x0
                gs[q, a, 1] = x1
                gs[q, a, 2] = hp
                us[2, a] += (x0 + hp) * jw
                us[3, a] += x1 * jw
        if flags[e] != 0:
            for i in range(2):
                for a in range(nen):
                    fe[i, a, e] = 0.0
            continue
        jbar_m1 = volj_m1 / vol0
        jbar = 1.0 + jbar_m1
        lnjbar = math.log1p(jbar_m1)
        volj = jbar * vol0
        # ---- bulk viscosity: a pressure q on compression (Kirchhoff −J q 1)
        qv = 0.0
        jbar_old = volj_old / vol0
        if visc[2] > 0.0 and dt > 0.0:
            rate = (jbar - jbar_old) / (dt * jbar)  # volumetric strain rate (1/s)
            if rate < 0.0:  # compression only
                ell = h0[e] * math.sqrt(jbar)
                rho = visc[2] / jbar
                qv = rho * (visc[1] * ell * ell * rate * rate - visc[0] * ell * visc[3] * rate)
        ivolj = 1.0 / volj
        for a in range(nen):  # the cell averages of the divergences (F-bar)
            us[2, a] *= ivolj
            us[3, a] *= ivolj
        for i in range(2):
            for a in range(nen):
                fe[i, a, e] = 0.0
        # ---- return map and forces at each Gauss point
        for q in range(nq):
            h00 = hs[q, 0]
            h01 = hs[q, 1]
            h10 = hs[q, 2]
            h11 = hs[q, 3]
            hth = hs[q, 4]
            jm1 = hs[q, 5]
            jq = 1.0 + jm1
            # B = F C_p⁻¹ Fᵀ − 1 = H + Hᵀ + H Hᵀ + F D Fᵀ, D = C_p⁻¹ − 1 (in-plane block, third
            # axis); F-bar only rescales it: the volumetric strain is ln J̄ (ln J without)
            b00 = 1.0 + h00
            b11 = 1.0 + h11
            b22 = 1.0 + hth
            c00 = cp_inv[0, 0, e, q] - 1.0
            c01 = cp_inv[0, 1, e, q]
            c11 = cp_inv[1, 1, e, q] - 1.0
            c22 = cp_inv[2, 2, e, q] - 1.0
            t00 = b00 * c00 + h01 * c01
            t01 = b00 * c01 + h01 * c11
            t10 = h10 * c00 + b11 * c01
            t11 = h10 * c01 + b11 * c11
            e00 = 2.0 * h00 + h00 * h00 + h01 * h01 + t00 * b00 + t01 * h01
            e01 = h01 + h10 + h00 * h10 + h01 * h11 + t00 * h10 + t01 * b11
            e11 = 2.0 * h11 + h10 * h10 + h11 * h11 + t10 * h10 + t11 * b11
            e22 = 2.0 * hth + hth * hth + b22 * c22 * b22
            # in-plane eigenpairs: μ = mean ± rad, axes at angle θ with cos 2θ = (e00 − e11)/2rad
            mean = 0.5 * (e00 + e11)
            half = 0.5 * (e00 - e11)
            rad = math.sqrt(half * half + e01 * e01)
            if rad > 0.0:
                irad = 1.0 / rad
                c2t = half * irad
                s2t = e01 * irad
            else:
                c2t = 1.0
                s2t = 0.0
            cc = 0.5 * (1.0 + c2t)  # cos²θ
            ss = 0.5 * (1.0 - c2t)  # sin²θ
            cs = 0.5 * s2t  # cos θ sin θ
            l1 = mean + rad
            l2 = mean - rad
            if not (l2 > -1.0 and e22 > -1.0):
                flags[e] = 1
                continue
            # deviatoric Hencky strains from the log-ratios ½ ln(λ_i²/λ_3²)
            i3 = 1.0 / (1.0 + e22)
            ra = 0.5 * math.log1p((l1 - e22) * i3)
            rb = 0.5 * math.log1p((l2 - e22) * i3)
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
                # kernel on one core at nr = 30); H ≥ 0, so Δγ > 0
                dg = fy / (2.0 * G + 2.0 / 3.0 * prm[1])
            elif fy > 0.0:
                dg = _plastic_multiplier(norm, ep, code, prm, G, dt)
                if dg < 0.0:
                    flags[e] = 2
                    dg = 0.0
            # radial return: the deviator shrinks by 1 − 2GΔγ/‖s_trial‖
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
            # back to (r, z): principal directions (cos θ, sin θ) and (−sin θ, cos θ)
            tau00 = s1 * cc + s2 * ss
            tau11 = s1 * ss + s2 * cc
            tau01 = (s1 - s2) * cs
            tau22 = s3
            if dg > 0.0:
                # C_p⁻¹ = F̄⁻¹ b̄_e F̄⁻ᵀ = F⁻¹ (b̄_e / s²) F⁻ᵀ, b̄_e/s² of log-eigenvalues
                # 2(ε_i − ln s) = 2(ln J / 3 + shrink d_i)
                lj = math.log1p(jm1) * third
                x1 = math.exp(2.0 * (lj + shrink * d1))
                x2 = math.exp(2.0 * (lj + shrink * d2))
                be00 = x1 * cc + x2 * ss
                be11 = x1 * ss + x2 * cc
                be01 = (x1 - x2) * cs
                # d1 + d2 + d3 = 0: the three stretches multiply to J², so the third is a
                # quotient rather than a third exponential (5% of the kernel)
                be22 = jq * jq / (x1 * x2)
                # F⁻¹'s in-plane block from the first pass: the same expressions of the same
                # values, so the same floats, without a division and four products (3% of the
                # kernel on plastic points)
                n00 = hs[q, 6]
                n01 = hs[q, 7]
                n10 = hs[q, 8]
                n11 = hs[q, 9]
                u00 = n00 * be00 + n01 * be01
                u01 = n00 * be01 + n01 * be11
                u10 = n10 * be00 + n11 * be01
                u11 = n10 * be01 + n11 * be11
                cp_new[0, 0, e, q] = u00 * n00 + u01 * n01
                cp_new[0, 1, e, q] = u00 * n10 + u01 * n11
                cp_new[1, 0, e, q] = cp_new[0, 1, e, q]
                cp_new[1, 1, e, q] = u10 * n10 + u11 * n11
                cp_new[2, 2, e, q] = be22 / (b22 * b22)
            else:  # elastic: C_p⁻¹ kept bit for bit
                cp_new[0, 0, e, q] = cp_inv[0, 0, e, q]
                cp_new[0, 1, e, q] = cp_inv[0, 1, e, q]
                cp_new[1, 0, e, q] = cp_inv[1, 0, e, q]
                cp_new[1, 1, e, q] = cp_inv[1, 1, e, q]
                cp_new[2, 2, e, q] = cp_inv[2, 2, e, q]
            tau_out[0, 0, e, q] = tau00
            tau_out[1, 1, e, q] = tau11
            tau_out[0, 1, e, q] = tau01
            tau_out[1, 0, e, q] = tau01
            tau_out[2, 2, e, q] = tau22
            j_out[e, q] = jq
            wv_new[e, q] = wv[e, q] + qv * (jbar_old - jbar)
            # forces: material stress plus the viscous pressure
            w0 = alpha[e, q] * dv0[e, q]
            pv = jq * qv
            tau00 -= pv
            tau11 -= pv
            tau22 -= pv
            p = (tau00 + tau11 + tau22) * third
            for a in range(nen):
                ga0 = gs[q, a, 0]
                ga1 = gs[q, a, 1]
                hp = gs[q, a, 2]
                f0 = tau00 * ga0 + tau01 * ga1 + tau22 * hp
                f1 = tau01 * ga0 + tau11 * ga1
                if fbar:
                    f0 += p * (us[2, a] - ga0 - hp)
                    f1 += p * (us[3, a] - ga1)
                fe[0, a, e] += w0 * f0
                fe[1, a, e] += w0 * f1
    return 0


def thread_slots(shape: tuple[int, ...], align: int = 128) -> np.ndarray:
    """Per-thread scratch of float64, shape (n_threads, *shape'): ``shape`` with its first axis
    lengthened so that each thread's slot is a whole number of ``align``-byte blocks, from an
    ``align``-byte boundary. So no two threads write into the same cache line (or the pair of
    lines the adjacent-line prefetcher fetches together): on numpy's 16-byte aligned arrays
    the slots' boundary lines were shared, and the threads' writes to them (several per cell)
    invalidated each other's copy (false sharing): with both layouts alternated in one process,
    the planar kernel on two threads at nr = 30 ran 1.06–1.57 times faster on these slots (the
    old cost depended on where the arrays landed). The kernels index within the first
    ``shape[0]`` rows only."""
    n = nb.config.NUMBA_NUM_THREADS
    row = 8 * int(np.prod(shape[1:], dtype=np.int64))
    rows = int(shape[0])
    while (rows * row) % align:
        rows += 1
    size = n * rows * row // 8
    buf = np.empty(size + align // 8)
    start = (-buf.ctypes.data % align) // 8
    return buf[start : start + size].reshape((n, rows, *shape[1:]))


def scratch(n_qp: int = 4, nen: int = 4) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-thread scratch buffers of :func:`planar_j2_kernel` (small: they stay in cache; each
    thread's on its own cache lines, :func:`thread_slots`)."""
    return thread_slots((n_qp, 10)), thread_slots((n_qp, nen, 3)), thread_slots((4, nen))


def warm_up() -> None:
    """Compile (or load from the cache) the kernel on a one-cell problem."""
    nen, ne, nq = 4, 1, 4
    grad = np.zeros((ne, nq, nen, 2))
    grad[..., 0] = np.array([-1.0, 1.0, 1.0, -1.0])
    grad[..., 1] = np.array([-1.0, -1.0, 1.0, 1.0])
    ones = np.ones((ne, nq))
    zeros = np.zeros((ne, nq))
    cp = np.broadcast_to(np.eye(3)[:, :, None, None], (3, 3, ne, nq)).copy()
    dofs = np.arange(2 * nen).reshape(ne, nen, 2)
    out = [np.zeros((2, nen, ne)), np.zeros((3, 3, ne, nq)), np.zeros((ne, nq)),
           np.zeros((3, 3, ne, nq)), np.zeros((ne, nq)), np.zeros((ne, nq)), np.zeros((ne, nq)),
           np.zeros(ne, dtype=np.int64)]  # fmt: skip
    # the weight as FiniteStrainJ2 passes it, a read-only broadcast view: numba types it
    # apart from a writeable array, and a writeable one here left each process's first run
    # compiling (or loading) its own specialisation inside its clock
    weight = np.broadcast_to(ones, ones.shape)
    planar_j2_kernel(
        np.zeros(2 * nen), dofs, grad, np.full((ne, nq, nen), 0.25), ones, ones, weight,
        True, True, 1.0, 1.0, 0, np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0]), 0.0, cp, zeros,
        zeros, zeros, ones, np.zeros(4), np.ones(ne), *scratch(nq, nen), *out,
    )  # fmt: skip
    assemble_cell_forces(assembly_dofs(dofs), out[0], out[-1], np.zeros(2 * nen))
    square = np.array([[0.0, 1.0, 1.0, 0.0], [0.0, 0.0, 1.0, 1.0]])
    min_scaled_cell_size(square, np.arange(4).reshape(4, 1), np.arange(8).reshape(4, 2).T.copy(),
                         np.zeros(8), np.ones(1))  # fmt: skip
