"""Static solution of a coupled system: the Arlequin saddle point.

    [K_c   0    C_cᵀ] [u_c]   [f_c]
    [0     K_f −C_fᵀ] [u_f] = [f_f]
    [C_c  −C_f   0  ] [ λ ]   [ 0 ]

Dirichlet rows are eliminated (their dofs are removed and moved to the right-hand side); all other
equality rows (mediator equations, user constraints) keep their Lagrange multipliers. The sparse
system is solved by SuperLU (scipy). Units: displacements m, multipliers in the units of the
constraint rows' dual (N for Dirichlet reactions).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..system import CoupledSystem

__all__ = [
    "SaddlePoint",
    "SingularSystemError",
    "StaticResult",
    "assemble_saddle_point",
    "solve_static",
]


class SingularSystemError(ValueError):
    """The coupled static system is singular (missing supports, dependent constraints...)."""


@dataclass
class SaddlePoint:
    """The reduced saddle-point system of a :class:`CoupledSystem`.

    Attributes
    ----------
    matrix : scipy.sparse.csc_matrix, shape (n_free + m, n_free + m)
        Constraint rows are multiplied by ``constraint_scale`` (multipliers divided by it).
    rhs : ndarray, shape (n_free + m,)
    free, fixed : ndarray of int
        Global dofs left free / fixed by Dirichlet rows.
    fixed_values : ndarray
        Prescribed values of the fixed dofs (m).
    multiplier_slices : dict
        Constraint name -> slice into the multiplier vector.
    """

    matrix: sp.csc_matrix
    rhs: np.ndarray
    free: np.ndarray
    fixed: np.ndarray
    fixed_values: np.ndarray
    multiplier_slices: dict[str, slice]
    stiffness: sp.csr_matrix
    load: np.ndarray
    constraints: sp.csr_matrix
    constraint_rhs: np.ndarray
    constraint_scale: float = 1.0

    @property
    def n_free(self) -> int:
        return int(self.free.size)

    def full_displacement(self, u_free: np.ndarray) -> np.ndarray:
        u = np.zeros(self.free.size + self.fixed.size)
        u[self.free] = u_free
        u[self.fixed] = self.fixed_values
        return u

    def residual(self, u: np.ndarray, multipliers: np.ndarray) -> float:
        """Relative residual of (u, λ) in the discrete equations, u the full vector.

        The larger of ‖[K u + Bᵀλ − f]_free‖ / max(‖K u‖, ‖f‖, ‖Bᵀλ‖) (equilibrium rows) and
        ‖B u − g‖ / ‖|B| |u|‖ (constraint rows, measured against their own scale: the two kinds
        of rows have different units and magnitudes).
        """
        b = self.constraints
        r1 = (self.stiffness @ u + b.T @ multipliers - self.load)[self.free]
        scale1 = max(
            np.linalg.norm((self.stiffness @ u)[self.free]),
            np.linalg.norm(self.load[self.free]),
            np.linalg.norm((b.T @ multipliers)[self.free]),
            1e-300,
        )
        out = float(np.linalg.norm(r1) / scale1)
        if b.shape[0]:
            r2 = b @ u - self.constraint_rhs
            scale2 = max(
                np.linalg.norm(abs(b) @ np.abs(u)), np.linalg.norm(self.constraint_rhs), 1e-300
            )
            out = max(out, float(np.linalg.norm(r2) / scale2))
        return out

    def best_multipliers(self, u: np.ndarray) -> np.ndarray:
        """Multipliers minimising ‖[K u + Bᵀλ − f]_free‖ for a given full displacement u.

        Solved through the normal equations (B_f B_fᵀ) λ = B_f r with a sparse LU, then one step
        of iterative refinement on the least-squares residual.
        """
        bt = self.constraints.T.tocsr()[self.free]
        r = (self.load - self.stiffness @ u)[self.free]
        normal = (bt.T @ bt).tocsc()
        lu = spla.splu(normal)
        lam = lu.solve(bt.T @ r)
        lam += lu.solve(bt.T @ (r - bt @ lam))
        return lam


def assemble_saddle_point(system: CoupledSystem, t: float = 0.0) -> SaddlePoint:
    """Assemble the reduced saddle point at time ``t`` (s) (loads and prescribed values at t)."""
    n = system.n_dofs
    k = system.stiffness()
    f = system.external_force(t)
    fixed_list, value_list = [], []
    others = []
    for c in system.constraints:
        if c.kind == "dirichlet" and c.level == "displacement":
            m = c.matrix.tocoo()
            fixed_list.append(m.col[np.argsort(m.row)])
            value_list.append(c.g(t))
        elif c.level == "displacement":
            others.append(c)
    fixed = np.concatenate(fixed_list) if fixed_list else np.zeros(0, dtype=np.int64)
    values = np.concatenate(value_list) if value_list else np.zeros(0)
    fixed, first = np.unique(fixed, return_index=True)
    values = values[first]
    free = np.setdiff1d(np.arange(n), fixed)
    u_fixed = np.zeros(n)
    u_fixed[fixed] = values
    b = sp.vstack([c.matrix for c in others], format="csr") if others else sp.csr_matrix((0, n))
    g = np.concatenate([c.g(t) for c in others]) if others else np.zeros(0)
    slices, start = {}, 0
    for c in others:
        slices[c.name] = slice(start, start + c.n_rows)
        start += c.n_rows
    kff = k[free][:, free]
    # Scale the constraint rows to the stiffness: their entries (m² for L2 coupling) can be
    # 1e13 times smaller than stiffness entries (N/m), and unscaled rows are then satisfied only
    # to the solver's tolerance relative to the stiffness, i.e. not at all.
    scale = 1.0
    if b.nnz:
        scale = float(abs(kff).max() / abs(b).max()) if kff.nnz else 1.0
    bf = scale * b[:, free]
    mat = sp.bmat([[kff, bf.T], [bf, None]], format="csc")
    rhs = np.concatenate([(f - k @ u_fixed)[free], scale * (g - b @ u_fixed)])
    return SaddlePoint(mat, rhs, free, fixed, values, slices, k, f, b, g, scale)


@dataclass
class StaticResult:
    """Result of :func:`solve_static`.

    Attributes
    ----------
    displacements : dict
        Block name -> nodal displacements (m), node-interleaved.
    multipliers : dict
        Constraint name -> Lagrange multipliers.
    strain_energy : dict
        Block name -> α-weighted strain energy (J).
    residual : float
        Relative residual of the solution in the discrete equations.
    u : ndarray
        Global displacement vector (m).
    """

    displacements: dict[str, np.ndarray]
    multipliers: dict[str, np.ndarray]
    strain_energy: dict[str, float]
    residual: float
    u: np.ndarray
    system: CoupledSystem = field(repr=False)
    saddle_point: SaddlePoint = field(repr=False)


def solve_static(problem, t: float = 0.0) -> StaticResult:
    """Solve the static coupled problem (an ``ArlequinProblem`` or a ``CoupledSystem``)."""
    system = problem if isinstance(problem, CoupledSystem) else problem.system()
    sp_sys = assemble_saddle_point(system, t)
    try:
        x = spla.spsolve(sp_sys.matrix, sp_sys.rhs)
    except RuntimeError as exc:  # SuperLU: "Factor is exactly singular"
        raise SingularSystemError(f"the coupled static system is singular: {exc}") from exc
    if not np.all(np.isfinite(x)):
        raise SingularSystemError(
            "the coupled static system is singular (non-finite solution): check that the coarse "
            "model's rigid motions are removed and that the mediator rows are independent"
        )
    u = sp_sys.full_displacement(x[: sp_sys.n_free])
    lam = x[sp_sys.n_free :] * sp_sys.constraint_scale
    residual = sp_sys.residual(u, lam)
    return StaticResult(
        displacements=system.split(u),
        multipliers={name: lam[s] for name, s in sp_sys.multiplier_slices.items()},
        strain_energy=system.strain_energies(u),
        residual=residual,
        u=u,
        system=system,
        saddle_point=sp_sys,
    )
