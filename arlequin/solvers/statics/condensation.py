"""The Newton systems of the quasi-static solver, with the linear blocks condensed once.

Each Newton iteration solves the saddle point of the free dofs (Dirichlet dofs eliminated)

    [K_LL   0     B_Lᵀ] [x_L]   [r_L]
    [0      K_NN  B_Nᵀ] [x_N] = [r_N]
    [B_L    B_N   0   ] [ y ]   [r_c]

where L are the dofs of the linear blocks (the coarse elastic models: K_LL never changes) and N
those of the nonlinear ones (the patches: K_NN is their consistent tangent, new at every
iteration); the stiffness is block diagonal, the blocks meeting only through the equality rows
B (mediators, user rows). With K_LL factorised once, x_L = K_LL⁻¹ (r_L − B_Lᵀ y) leaves

    [K_NN   B_Nᵀ] [x_N]   [r_N                ]
    [B_N    −S  ] [ y ] = [r_c − B_L K_LL⁻¹ r_L]      S = B_L K_LL⁻¹ B_Lᵀ (dense, once)

so an iteration factors only the patches and the multipliers. S has one row per constraint row
that touches a linear block (the coarse mediator's band): it is kept dense. Where condensing
does not apply or would not pay (no linear block, no nonlinear one, linear dofs fewer than
:data:`MIN_LINEAR_SHARE` of the nonlinear ones, K_LL singular: a linear block held only by the
mediator rows, or S too large), every iteration factors the whole saddle point (the reference
path, ``condense=False``).

Constraint rows are scaled to the stiffness (as in :mod:`arlequin.solvers.statics.static`): their
entries (m² for L2 coupling) can be 1e13 times smaller than the stiffness's (N/m).

The systems of the iterations are factorised by a
:class:`~arlequin.linalg.direct.SparseDirectSolver` (``linear_solver``: SuperLU, or PARDISO which
keeps its symbolic analysis from one iteration to the next); K_LL, factorised once, stays with
SuperLU.
"""

from __future__ import annotations

import logging
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...linalg.direct import SparseDirectSolver
from ...problem.system import CoupledSystem
from ..system.operators import SystemOperators

__all__ = ["MAX_CONDENSED_ENTRIES", "MIN_LINEAR_SHARE", "SaddleSolver"]

logger = logging.getLogger(__name__)

#: Largest n_L × m_L of the dense K_LL⁻¹ B_Lᵀ kept by the condensation (8 bytes each: 400 MB).
MAX_CONDENSED_ENTRIES = 50_000_000

#: Smallest ratio of linear to nonlinear free dofs for which the condensation is used.
MIN_LINEAR_SHARE = 0.25


class SaddleSolver:
    """Dirichlet elimination and the Newton solves of a coupled system.

    Parameters
    ----------
    system : CoupledSystem
    ops : SystemOperators
        Its operators (which blocks are linear, their assembled stiffness).
    condense : bool
        Condense the linear blocks (see the module docstring).
    linear_solver : {"auto", "superlu", "pardiso"}
        The backend of the iterations' factorisations (:mod:`arlequin.linalg.direct`).

    Attributes
    ----------
    free, fixed : ndarray of int
        Global dofs left free / prescribed by the Dirichlet rows.
    b : scipy.sparse.csr_matrix, shape (m, n)
        The other displacement-level equality rows, stacked.
    n_multipliers : int
    condensed : bool
        Whether the linear blocks are condensed.
    direct : SparseDirectSolver
        The iterations' factorisations; ``direct.name`` the backend, ``direct.timings`` the
        seconds spent factorising and solving (with K_LL's solves).
    """

    def __init__(
        self,
        system: CoupledSystem,
        ops: SystemOperators,
        condense: bool = True,
        linear_solver: str = "auto",
    ):
        self.direct = SparseDirectSolver(linear_solver)
        self.system, self.ops = system, ops
        n = system.n_dofs
        dirichlet = [
            c for c in system.constraints if c.kind == "dirichlet" and c.level == "displacement"
        ]
        self._others = [
            c for c in system.constraints
            if c.level == "displacement" and not (c.kind == "dirichlet")
        ]  # fmt: skip
        self._dirichlet = dirichlet
        fixed = [c.matrix.tocoo() for c in dirichlet]
        cols = np.concatenate([m.col[np.argsort(m.row)] for m in fixed]) if fixed else []
        self.fixed, self._first = np.unique(np.asarray(cols, dtype=np.int64), return_index=True)
        self.free = np.setdiff1d(np.arange(n), self.fixed)
        self.b = (
            sp.vstack([c.matrix for c in self._others], format="csr")
            if self._others
            else sp.csr_matrix((0, n))
        )
        self.n_multipliers = int(self.b.shape[0])
        k0 = ops.initial_stiffness()[self.free][:, self.free]
        self.scale = 1.0
        if self.b.nnz and k0.nnz:
            self.scale = float(abs(k0).max() / abs(self.b).max())
        self._bf = (self.scale * self.b[:, self.free]).tocsr()
        self.condensed = False
        if condense:
            self._condense()

    # -- right-hand sides --------------------------------------------------------------------
    def rhs_at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """The Dirichlet values (on :attr:`fixed`) and the other rows' g at time ``t``."""
        values = (
            np.concatenate([c.g(t) for c in self._dirichlet])[self._first]
            if self._dirichlet
            else np.zeros(0)
        )
        g = np.concatenate([c.g(t) for c in self._others]) if self._others else np.zeros(0)
        return values, g

    def split_multipliers(self, mu: np.ndarray) -> dict[str, np.ndarray]:
        """Constraint name -> its multipliers."""
        out, start = {}, 0
        for c in self._others:
            out[c.name] = mu[start : start + c.n_rows]
            start += c.n_rows
        return out

    # -- condensation ------------------------------------------------------------------------
    def _condense(self) -> None:
        """Factor K_LL and form S = B_L K_LL⁻¹ B_Lᵀ once (or leave the reference path)."""
        linear_dof = np.zeros(self.system.n_dofs, dtype=bool)
        for b, lin in zip(self.ops.blocks, self.ops.block_linear):
            linear_dof[b.dofs] = lin
        is_lin = linear_dof[self.free]
        self._L, self._N = np.nonzero(is_lin)[0], np.nonzero(~is_lin)[0]
        if not self._L.size or not self._N.size:
            return
        if self._L.size < MIN_LINEAR_SHARE * self._N.size:
            # a small linear block saves less than its extra solves cost (the sphere, coarse
            # dofs 4% of the patch's: 5.7 s full, 7.1 s condensed)
            logger.info("condensation skipped: %d linear dofs for %d nonlinear ones",
                        self._L.size, self._N.size)  # fmt: skip
            return
        k = self.ops.stiffness[self.free][:, self.free].tocsc()
        kll = k[self._L][:, self._L].tocsc()
        bl = self._bf[:, self._L].tocsc()
        rows = np.unique(bl.tocoo().row)
        if self._L.size * max(rows.size, 1) > MAX_CONDENSED_ENTRIES:
            logger.info("condensation skipped: K_LL^-1 B_L^T would hold %d entries",
                        self._L.size * rows.size)  # fmt: skip
            return
        try:
            self._kll = spla.splu(kll, permc_spec="COLAMD")
        except RuntimeError as exc:  # singular: a linear block held by the mediator only
            logger.info("condensation skipped: K_LL is singular (%s)", exc)
            return
        bl_rows = bl[rows].toarray()  # (m_L, n_L)
        y = self._kll.solve(np.asfortranarray(bl_rows.T))  # K_LL⁻¹ B_Lᵀ, (n_L, m_L)
        if not np.all(np.isfinite(y)):
            return
        s = np.zeros((self.n_multipliers, self.n_multipliers))
        s[np.ix_(rows, rows)] = bl_rows @ y
        self._s = sp.csr_matrix(s)
        self._bl = bl.tocsr()
        self._bn = self._bf[:, self._N].tocsr()
        self.condensed = True

    # -- solves ------------------------------------------------------------------------------
    def solve(
        self, kt: sp.csr_matrix, r_free: np.ndarray, r_c: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Solve the Newton system for (Δu on the free dofs, Δμ) given the tangent ``kt``
        (n, n) and the right-hand sides ``r_free`` (equilibrium, free dofs) and ``r_c``
        (constraint rows, unscaled).

        Raises
        ------
        numpy.linalg.LinAlgError
            The system is singular (a mechanism: the limit load of a perfectly plastic body).
        """
        rc = self.scale * r_c
        if self.condensed:
            x, y = self._solve_condensed(kt, r_free, rc)
        else:
            x, y = self._solve_full(kt, r_free, rc)
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
            raise np.linalg.LinAlgError("non-finite Newton update")
        return x, self.scale * y

    def _solve_full(self, kt, r_free, rc):
        kff = kt[self.free][:, self.free]
        m = self.n_multipliers
        mat = sp.bmat([[kff, self._bf.T], [self._bf, None]], format="csc") if m else kff.tocsc()
        rhs = np.concatenate([r_free, rc])
        sol = self.direct.factor(mat).solve(rhs)
        return sol[: self.free.size], sol[self.free.size :]

    def _solve_condensed(self, kt, r_free, rc):
        kf = kt[self.free][:, self.free]
        knn = kf[self._N][:, self._N]
        r_l, r_n = r_free[self._L], r_free[self._N]
        kinv_rl = self._kll_solve(r_l)
        mat = sp.bmat([[knn, self._bn.T], [self._bn, -self._s]], format="csc")
        rhs = np.concatenate([r_n, rc - self._bl @ kinv_rl])
        sol = self.direct.factor(mat).solve(rhs)
        x_n, y = sol[: self._N.size], sol[self._N.size :]
        x = np.empty(self.free.size)
        x[self._N] = x_n
        x[self._L] = kinv_rl - self._kll_solve(self._bl.T @ y)
        return x, y

    def _kll_solve(self, rhs: np.ndarray) -> np.ndarray:
        t0 = time.perf_counter()
        x = self._kll.solve(rhs)
        self.direct.timings["solve_s"] += time.perf_counter() - t0
        return x
