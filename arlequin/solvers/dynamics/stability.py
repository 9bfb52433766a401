"""Critical time step of the explicit (central-difference, lumped-mass) coupled system.

Central differences are stable for Δt ≤ 2/ω_max, with ω_max² the largest eigenvalue of
K x = ω² M_L x (M_L the row-sum lumped α-weighted mass). Three estimates, all computed (never
guessed):

``"blocks"``
    Each model alone: ω_max,b² = λ_max(M_L,b^{-1/2} K_b M_L,b^{-1/2}) (Lanczos, ARPACK), with the
    weighted operators of the block, so the effect of lumping a weight that varies inside an
    element (which raises that element's frequency, by up to √1.5 in 1D) is included. The
    coupled system is never less stable than its models taken alone (adding constraints cannot
    raise the largest constrained eigenvalue, Courant–Fischer), so min_b 2/ω_max,b is a safe
    bound.
``"coupled"`` (default)
    The constrained system itself: λ_max of Q A Q with A = M_L^{-1/2} K M_L^{-1/2} and Q the
    orthogonal projector on the null space of B M_L^{-1/2} (all equality rows: mediator and
    Dirichlet rows), by Lanczos iterations (each one a solve with the factorised B M_L⁻¹ Bᵀ).
    Sharper (larger) than the block bound.
``"gershgorin"``
    A guaranteed upper bound of each block's ω_max² (row sums of |A|): a cheap, safe but
    pessimistic bound.

Lanczos values are converged to a relative tolerance of 1e-10; the solvers apply their own safety
factor on top of the critical step (see :class:`arlequin.solvers.CentralDifference`).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...contract import is_unilateral
from ...linalg.factor import factor_checked
from ...problem.system import CoupledSystem
from ..system.operators import SystemOperators
from ..system.rows import EqualityRows

__all__ = [
    "DEFAULT_SAFETY",
    "StableStep",
    "check_time_step",
    "largest_eigenvalue",
    "stable_time_step",
]

#: Default ratio of the time step to the computed critical step of the coupled system.
DEFAULT_SAFETY = 0.9

logger = logging.getLogger(__name__)

_DENSE_LIMIT = 200


@dataclass(frozen=True)
class StableStep:
    """Critical time steps (s) of a coupled explicit system.

    Attributes
    ----------
    critical : float
        2/ω_max of the estimate ``method`` (s).
    block_bound : float
        min over the blocks of their own critical step (s): a safe bound of the coupled one.
    per_block : dict
        Block name -> critical step of the block alone (s).
    omega_max : float
        ω_max (rad/s) of the estimate ``method``.
    method : str
    """

    critical: float
    block_bound: float
    per_block: dict[str, float]
    omega_max: float
    method: str


def largest_eigenvalue(op, n: int, tol: float = 1e-10, dense=None) -> float:
    """Largest eigenvalue of a symmetric positive semi-definite operator.

    Parameters
    ----------
    op : sparse matrix or LinearOperator, shape (n, n)
    n : int
    tol : float
        Relative tolerance of the Lanczos iterations.
    dense : callable, optional
        Returns the dense matrix (used instead of Lanczos for n <= 200).
    """
    if n == 0:
        return 0.0
    if n <= _DENSE_LIMIT:
        mat = (
            dense() if dense is not None else (op.toarray() if sp.issparse(op) else op @ np.eye(n))
        )
        mat = 0.5 * (mat + mat.T)
        return float(sla.eigvalsh(mat, subset_by_index=[n - 1, n - 1])[0])
    rng = np.random.default_rng(12345)
    v0 = rng.standard_normal(n)
    vals = spla.eigsh(
        op,
        k=1,
        which="LA",
        tol=tol,
        v0=v0,
        ncv=min(n, 40),
        maxiter=50 * n,
        return_eigenvectors=False,
    )
    return float(vals[0])


def _scaled(k: sp.spmatrix, m: np.ndarray) -> sp.csr_matrix:
    d = sp.diags(1.0 / np.sqrt(m))
    return (d @ k @ d).tocsr()


def _gershgorin(a: sp.csr_matrix) -> float:
    return float(np.max(np.asarray(abs(a).sum(axis=1)).ravel())) if a.shape[0] else 0.0


def _dt(lam: float) -> float:
    return 2.0 / math.sqrt(lam) if lam > 0.0 else math.inf


def stable_time_step(
    system: CoupledSystem,
    method: str = "coupled",
    constraints=(),
    tol: float = 1e-10,
    _ops: SystemOperators | None = None,
    _rows: EqualityRows | None = None,
    _s_lu=None,
) -> StableStep:
    """Critical time step (s) of the central-difference scheme with lumped weighted masses.

    Parameters
    ----------
    system : CoupledSystem
    method : {"coupled", "blocks", "gershgorin"}
        See the module docstring.
    constraints : sequence of LinearConstraint
        Extra equality rows (besides ``system.constraints``) for the coupled estimate.
    tol : float
        Relative tolerance of the Lanczos iterations.

    Returns
    -------
    StableStep
    """
    if method not in ("coupled", "blocks", "gershgorin"):
        raise ValueError(f"method must be 'coupled', 'blocks' or 'gershgorin', got {method!r}")
    ops = _ops if _ops is not None else SystemOperators(system, lumped=True)
    m = np.asarray(ops.mass, dtype=float)
    # the initial (small-strain) stiffness: the tangent of linear models, the initial tangent of
    # nonlinear ones (the current configuration is followed by CentralDifference.critical_time_step)
    a = _scaled(ops.initial_stiffness(), m)
    per_block: dict[str, float] = {}
    lam_blocks = []
    memo = getattr(system, "block_memo", None)
    for b in ops.blocks:

        def block_lam(b=b) -> float:
            ab = a[b.dofs][:, b.dofs].tocsr()
            if method == "gershgorin":
                return _gershgorin(ab)
            return largest_eigenvalue(ab, b.n_dofs, tol)

        # a block's own estimate depends on its terms only (its stiffness and lumped mass):
        # computed once for the systems that share it (a body kept when another body grows)
        lam_b = block_lam() if memo is None else memo(b, f"lam:{method}:{tol!r}", block_lam)
        lam_blocks.append(lam_b)
        per_block[b.name] = _dt(lam_b)
    block_bound = min(per_block.values()) if per_block else math.inf
    lam = max(lam_blocks) if lam_blocks else 0.0
    if method == "coupled":
        if _rows is None:
            eq = [c for c in list(system.constraints) + list(constraints) if not is_unilateral(c)]
            _rows = EqualityRows(eq, ops)
        if _rows.m:
            bt = (_rows.matrix @ sp.diags(1.0 / np.sqrt(m))).tocsr()
            if ops.n <= _DENSE_LIMIT:
                z = sla.null_space(bt.toarray())
                lam = largest_eigenvalue(None, z.shape[1], tol, dense=lambda: z.T @ (a @ z))
            else:
                s_lu = _s_lu
                if s_lu is None:
                    s = (_rows.matrix @ sp.diags(1.0 / m) @ _rows.matrix.T).tocsc()
                    s_lu = factor_checked(s, "B M⁻¹ Bᵀ", spd=True)
                btt = bt.T.tocsr()

                def project(y: np.ndarray) -> np.ndarray:
                    return y - btt @ s_lu.solve(bt @ y)

                op = spla.LinearOperator(
                    (ops.n, ops.n), matvec=lambda y: project(a @ project(np.ravel(y))), dtype=float
                )
                lam = largest_eigenvalue(op, ops.n, tol)
        lam = min(lam, max(lam_blocks)) if lam_blocks else lam
    crit = _dt(lam)
    logger.info(
        "critical time step (%s): %.6e s (per-model bound %.6e s)", method, crit, block_bound
    )
    return StableStep(
        critical=crit,
        block_bound=block_bound,
        per_block=per_block,
        omega_max=math.sqrt(max(lam, 0.0)),
        method=method,
    )


def check_time_step(dt: float, stable: StableStep) -> None:
    """Refuse a step above the critical one with a ``ValueError`` giving both numbers.

    Parameters
    ----------
    dt : float
        The step (s).
    stable : StableStep
        The critical-step estimate (s) it is checked against.
    """
    if dt > stable.critical * (1.0 + 1e-12):
        raise ValueError(
            f"time step dt={dt:.6e} s exceeds the critical step of the coupled explicit "
            f"system, {stable.critical:.6e} s ({stable.method} estimate; per-model bound "
            f"{stable.block_bound:.6e} s): use dt <= {stable.critical:.6e} s"
        )
