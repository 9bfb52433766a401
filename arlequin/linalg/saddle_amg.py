"""The iterative solve of a saddle point [K Bᵀ; B 0] [u; λ] = [f; g] by algebraic multigrid.

The augmented Lagrangian K_γ = K + γ Bᵀ W⁻¹ B (W = diag of the rows' squared norms, γ scaled to
the stiffness's diagonal) has the same solution in the system [K_γ Bᵀ; B 0] [u; λ] =
[f + γ Bᵀ W⁻¹ g; g] and is definite even where K alone is singular (a patch held only by its
mediator rows). GMRES runs on that system with the block upper-triangular preconditioner
[K_γ Bᵀ; 0 −W/γ] (Benzi and Olshanskii, 2006): the multiplier Schur complement −B K_γ⁻¹ Bᵀ is
close to −W/γ, and K_γ⁻¹ is one V-cycle of pyamg's smoothed aggregation with the rigid-body
modes of every block as near-null space (what FEniCSx's GAMG does for elasticity). The true
residual of the original system is checked at the end: a solve above the tolerance raises
:class:`~arlequin.contract.LinearSolverError`, never returns.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..contract import LinearSolverError
from .threads import blas_threads

__all__ = ["KrylovInfo", "solve_saddle_amg"]

#: GMRES restart length (inner iterations between restarts).
RESTART = 150


@dataclass(frozen=True)
class KrylovInfo:
    """What one iterative saddle-point solve did.

    Attributes
    ----------
    iterations : int
        GMRES iterations (inner, over all restarts).
    residual : float
        ‖A x − b‖ / ‖b‖ of the original (non-augmented) saddle point.
    setup_seconds, krylov_seconds : float
        Multigrid set-up (s) and Krylov iterations (s).
    gamma : float
        The augmentation γ used (units of K).
    levels : int
        Levels of the multigrid hierarchy.
    """

    iterations: int
    residual: float
    setup_seconds: float
    krylov_seconds: float
    gamma: float
    levels: int


def _multigrid_matrix(k_gamma, free, n_full, blocksize):
    """K_γ embedded in the full numbering (identity-like rows at the eliminated dofs), as BSR
    of the nodal block size when the numbering allows it, so that aggregation is nodal."""
    if free is None:
        return k_gamma.tocsr(), None
    n_free = free.size
    p = sp.csr_matrix((np.ones(n_free), (free, np.arange(n_free))), shape=(n_full, n_free))
    fixed = np.setdiff1d(np.arange(n_full), free)
    diag = float(np.mean(np.abs(k_gamma.diagonal()))) if n_free else 1.0
    d = sp.csr_matrix((np.full(fixed.size, diag), (fixed, fixed)), shape=(n_full, n_full))
    full = (p @ k_gamma @ p.T + d).tocsr()
    if blocksize > 1 and n_full % blocksize == 0:
        full = full.tobsr(blocksize=(blocksize, blocksize))
    return full, p


def _near_null(near_null_space, free, n):
    """The near-null space restricted to nothing (full numbering: zero at the eliminated dofs)
    or None (pyamg's constant vector)."""
    if near_null_space is None:
        return None
    b = np.array(near_null_space, dtype=float, copy=True).reshape(n, -1)
    if free is not None:
        mask = np.ones(n, dtype=bool)
        mask[free] = False
        b[mask] = 0.0
    keep = np.linalg.norm(b, axis=0) > 0
    return b[:, keep] if keep.any() else None


def solve_saddle_amg(
    stiffness: sp.spmatrix,
    rows: sp.spmatrix,
    rhs: np.ndarray,
    *,
    near_null_space: np.ndarray | None = None,
    free: np.ndarray | None = None,
    n_full: int | None = None,
    blocksize: int = 1,
    rtol: float = 1e-10,
    maxiter: int = 1000,
    gamma: float | None = None,
) -> tuple[np.ndarray, KrylovInfo]:
    """Solve [K Bᵀ; B 0] x = rhs by GMRES with an augmented-Lagrangian multigrid preconditioner.

    Parameters
    ----------
    stiffness : sparse matrix, shape (n, n)
        K, symmetric positive semi-definite (singular blocks allowed where B holds them).
    rows : sparse matrix, shape (m, n)
        B, the constraint rows (independent).
    rhs : ndarray, shape (n + m,)
        [f; g].
    near_null_space : ndarray, shape (n_full, k), optional
        Near-null modes of K (rigid-body modes of each block, one set of columns a block), in
        the numbering of ``free`` if given, else of K.
    free : ndarray of int, optional
        Where K's dofs sit in a full numbering of ``n_full`` dofs (the others eliminated): the
        multigrid then works on that numbering, blocked by ``blocksize`` (nodal aggregation).
    n_full : int, optional
        Size of the full numbering (with ``free``).
    blocksize : int
        Dofs a node in the full numbering (2 in 2D, 3 in 3D).
    rtol : float
        Tolerance on ‖A x − b‖ / ‖b‖ (true residual).
    maxiter : int
        Largest number of GMRES iterations (over all restarts).
    gamma : float, optional
        Augmentation; by default the mean of K's diagonal (units of K).

    Returns
    -------
    x : ndarray, shape (n + m,)
    info : KrylovInfo

    Raises
    ------
    LinearSolverError
        If the true residual is above ``rtol`` after ``maxiter`` iterations.
    """
    import pyamg

    t0 = time.perf_counter()
    k = sp.csr_matrix(stiffness)
    b = sp.csr_matrix(rows)
    n, m = k.shape[0], b.shape[0]
    rhs = np.asarray(rhs, dtype=float)
    a = sp.bmat([[k, b.T], [b, None]], format="csr") if m else k
    w = np.asarray(b.multiply(b).sum(axis=1)).ravel()
    w = np.maximum(w, 1e-300 + 1e-14 * (w.max() if m else 0.0))
    if gamma is None:
        gamma = float(np.mean(np.abs(k.diagonal()))) if n else 1.0
    k_gamma = (k + gamma * (b.T @ sp.diags(1.0 / w) @ b)).tocsr() if m else k
    f_aug = rhs[:n] + (gamma * (b.T @ (rhs[n:] / w)) if m else 0.0)
    aug_rhs = np.concatenate([f_aug, rhs[n:]])
    a_aug = sp.bmat([[k_gamma, b.T], [b, None]], format="csr") if m else k
    nf = n if free is None else int(n_full)
    mg_mat, p = _multigrid_matrix(k_gamma, free, nf, blocksize)
    ml = pyamg.smoothed_aggregation_solver(mg_mat, B=_near_null(near_null_space, free, nf))
    cycle = ml.aspreconditioner(cycle="V")
    bt = b.T.tocsr()

    def apply(r):
        r = np.asarray(r).ravel()
        lam = -gamma * r[n:] / w
        ru = r[:n] - bt @ lam
        zu = cycle @ ru if p is None else p.T @ (cycle @ (p @ ru))
        return np.concatenate([zu, lam])

    prec = spla.LinearOperator(a_aug.shape, matvec=apply, dtype=float)
    t1 = time.perf_counter()
    with blas_threads(1):  # vector operations: memory-bound, threads only spin (1.3 ms -> 5 µs)
        x, its, res = _gmres(a, a_aug, aug_rhs, rhs, prec, rtol, maxiter)
    info = KrylovInfo(its, res, t1 - t0, time.perf_counter() - t1, gamma, len(ml.levels))
    if not res <= rtol:
        raise LinearSolverError(
            f"the iterative saddle-point solve (GMRES + smoothed-aggregation multigrid) did not "
            f"converge: relative residual {res:.3e} after {its} iteration(s), tolerance "
            f"{rtol:.1e} (raise maxiter, or use linear_solver='superlu')"
        )
    return x, info


def _gmres(a, a_aug, aug_rhs, rhs, prec, rtol, maxiter):
    """GMRES on the augmented system, restarted from its iterate until the TRUE residual of the
    original system is below ``rtol`` or ``maxiter`` iterations are spent."""
    norm = np.linalg.norm(rhs)
    x = np.zeros(a.shape[0])
    if norm == 0.0:
        return x, 0, 0.0
    its = 0
    res = 1.0
    counter = [0]

    def count(_):
        counter[0] += 1

    while its < maxiter:
        restart = min(RESTART, maxiter - its)
        counter[0] = 0
        x, _ = spla.gmres(a_aug, aug_rhs, x0=x, rtol=0.1 * rtol, atol=0.0, restart=restart,
                          maxiter=max(1, (maxiter - its) // restart), M=prec, callback=count,
                          callback_type="pr_norm")  # fmt: skip
        its += max(counter[0], 1)
        res = float(np.linalg.norm(a @ x - rhs) / norm)
        if res <= rtol or not np.isfinite(res):
            break
    return x, its, res
