"""Static solution of a coupled system: the Arlequin saddle point.

    [K_c   0    C_cᵀ] [u_c]   [f_c]
    [0     K_f −C_fᵀ] [u_f] = [f_f]
    [C_c  −C_f   0  ] [ λ ]   [ 0 ]

Dirichlet rows are eliminated (their dofs are removed and moved to the right-hand side); all other
equality rows (mediator equations, user constraints) keep their Lagrange multipliers. The sparse
system is solved by SuperLU (scipy) or, with ``linear_solver="amg"`` (and ``"auto"`` on large 3D
systems), by GMRES with an augmented-Lagrangian smoothed-aggregation multigrid preconditioner
(:mod:`arlequin.linalg.saddle_amg`). Units: displacements m, multipliers in the units of the
constraint rows' dual (N for Dirichlet reactions).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...contract import is_linear
from ...linalg.saddle_amg import KrylovInfo, solve_saddle_amg
from ...problem.system import CoupledSystem

logger = logging.getLogger(__name__)

__all__ = [
    "AMG_MIN_UNKNOWNS",
    "AMG_MIN_UNKNOWNS_COUPLED",
    "STATIC_LINEAR_SOLVERS",
    "SaddlePoint",
    "SingularSystemError",
    "StaticResult",
    "assemble_saddle_point",
    "check_supports",
    "rigid_modes",
    "solve_static",
]


#: The ``linear_solver`` values of :func:`solve_static`.
STATIC_LINEAR_SOLVERS = ("auto", "superlu", "amg")
#: Unknowns (free dofs) of a 3D system without multiplier rows (a single model) from which
#: ``"auto"`` picks the iterative solver (measured by ``benchmarks/scaling.py``, see
#: docs/scaling.md: the two cost the same at 15-20k); 1D, 2D and axisymmetric systems stay on
#: SuperLU.
AMG_MIN_UNKNOWNS = 30_000
#: The same with multiplier rows (mediators, user rows): their augmentation γ Bᵀ W⁻¹ B holds
#: 1.7 to 7 times the stiffness's entries, and the two solvers cost the same at about 120k to
#: 150k unknowns on the 3D plate with a refined ring patch.
AMG_MIN_UNKNOWNS_COUPLED = 150_000


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
        """The displacement on every dof (m) from the free dofs' values ``u_free``."""
        u = np.zeros(self.free.size + self.fixed.size)
        u[self.free] = u_free
        u[self.fixed] = self.fixed_values
        return u

    def residual(self, u: np.ndarray, multipliers: np.ndarray) -> float:
        """Relative residual of (u, λ) in the discrete equations, u the full vector.

        The larger of ‖[K u + Bᵀλ − f]_free‖ / max(‖K u‖, ‖f‖, ‖Bᵀλ‖) (equilibrium rows) and
        ‖B u − g‖ / ‖abs(B) abs(u)‖ (constraint rows, measured against their own scale: the two
        kinds of rows have different units and magnitudes).
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

    def best_multipliers(self, u: np.ndarray, initial: np.ndarray | None = None) -> np.ndarray:
        """Multipliers minimising ‖[K u + Bᵀλ − f]_free‖ for a given full displacement u.

        Solved through the normal equations (B_f B_fᵀ) λ = B_f r with a sparse LU (symmetric
        ordering) and one step of iterative refinement; where that factorisation does not fit
        in memory (fine mediators on large patches), by LSQR started from ``initial`` (e.g.
        the multipliers of the solve).
        """
        bt = self.constraints.T.tocsr()[self.free]
        r = (self.load - self.stiffness @ u)[self.free]
        normal = (bt.T @ bt).tocsc()
        if normal.shape[0] <= 10_000:
            lu = spla.splu(normal, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0)
            lam = lu.solve(bt.T @ r)
            lam += lu.solve(bt.T @ (r - bt @ lam))
            return lam
        x0 = None if initial is None else np.asarray(initial, dtype=float)
        return spla.lsqr(bt, r, atol=1e-15, btol=1e-15, iter_lim=20 * bt.shape[1], x0=x0)[0]


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
    linear_solver : str
        The solver used: ``"superlu"`` or ``"amg"``.
    krylov : KrylovInfo or None
        Iterations, true residual and times (multigrid set-up, Krylov) of the iterative solve.
    """

    displacements: dict[str, np.ndarray]
    multipliers: dict[str, np.ndarray]
    strain_energy: dict[str, float]
    residual: float
    u: np.ndarray
    system: CoupledSystem = field(repr=False)
    saddle_point: SaddlePoint | None = field(repr=False)
    linear_solver: str = "superlu"
    krylov: KrylovInfo | None = None


def rigid_modes(system: CoupledSystem) -> tuple[np.ndarray, list[str]] | None:
    """The rigid-body motions of a system's bodies as global vectors, and their names.

    Returns ``(R, names)`` with R of shape (n, n_modes) — the same rigid motion of space
    evaluated at the nodes of every block (mediator rows leave such a motion free) — or None
    when a block's model has no mesh or kinematics to build them from.
    """
    kinds = {getattr(b.model, "kind", None) for b in system.blocks}
    if (
        None in kinds
        or len(kinds) != 1
        or any(getattr(b.model, "mesh", None) is None for b in system.blocks)
    ):
        return None
    kind = kinds.pop()
    if kind == "1d":
        names = ["translation x"]
    elif kind == "axisymmetric":
        names = ["translation z"]
    elif kind in ("plane_strain", "plane_stress"):
        names = ["translation x", "translation y", "rotation about z"]
    else:
        names = ["translation x", "translation y", "translation z", "rotation about x",
                 "rotation about y", "rotation about z"]  # fmt: skip
    cols = []
    for b in system.blocks:
        x = np.asarray(b.model.mesh.p, dtype=float)
        d, nn = x.shape
        modes = np.zeros((len(names), d, nn))
        if kind == "axisymmetric":
            modes[0, 1] = 1.0
        else:
            for i in range(d):
                modes[i, i] = 1.0
            if d == 2:
                modes[2, 0], modes[2, 1] = -x[1], x[0]
            elif d == 3:
                modes[3, 1], modes[3, 2] = -x[2], x[1]
                modes[4, 0], modes[4, 2] = x[2], -x[0]
                modes[5, 0], modes[5, 1] = -x[1], x[0]
        cols.append(np.transpose(modes, (2, 1, 0)).reshape(d * nn, len(names)))
    return np.vstack(cols), names


def check_supports(system: CoupledSystem, t: float = 0.0) -> None:
    """Raise :class:`SingularSystemError` if the displacement-level rows (supports, mediator
    rows, user rows) leave a rigid-body motion of the structure free (a static problem then
    has no unique solution)."""
    rm = rigid_modes(system)
    if rm is None:
        return
    r, names = rm
    rows = [c.matrix for c in system.constraints if c.level == "displacement"]
    if rows:
        br = sp.vstack(rows, format="csr") @ r
        scale = np.linalg.norm(r, axis=0)
        br = br / np.where(scale > 0, scale, 1.0)
        # the modes' Gram matrix (n_modes², tiny) rather than an SVD of the m rows
        gram = br.T @ br
        ev, vec = np.linalg.eigh(0.5 * (gram + gram.T))
        free = vec[:, ev <= 1e-20 * max(ev.max(initial=0.0), 1.0)].T
    else:
        free = np.eye(len(names))
    if free.shape[0]:
        described = [names[int(np.argmax(np.abs(v)))] for v in free]
        raise SingularSystemError(
            f"the supports leave {free.shape[0]} rigid-body mode(s) free "
            f"({', '.join(described)}): add Dirichlet conditions (add_dirichlet) that fix them "
            "before a static solve"
        )


def _solve_saddle(mat: sp.csc_matrix, rhs: np.ndarray) -> np.ndarray:
    """SuperLU, one step of iterative refinement; scipy's default solve if that fails or leaves
    a residual above 1e-10.

    With few multiplier rows (zero diagonal) threshold pivoting (``diag_pivot_thresh=0.01``)
    keeps the stiffness pivots: 27 s -> 1 s on a 60k-dof strip patch test (40 multipliers);
    with many (a fine mediator: 20k of 41k rows) partial pivoting is faster (8.5 s against
    19 s), so it is kept there."""
    zero_diag = np.count_nonzero(mat.diagonal() == 0.0)
    threshold = 0.01 if zero_diag < 0.1 * mat.shape[0] else 1.0
    try:
        lu = spla.splu(mat, permc_spec="COLAMD", diag_pivot_thresh=threshold)
        x = lu.solve(rhs)
        x = x + lu.solve(rhs - mat @ x)
        if np.linalg.norm(mat @ x - rhs) <= 1e-10 * max(np.linalg.norm(rhs), 1e-300):
            return x
    except RuntimeError:
        pass
    return spla.spsolve(mat, rhs)


def solve_static(
    problem,
    t: float = 0.0,
    *,
    linear_solver: str = "auto",
    linear_solver_options: dict | None = None,
) -> StaticResult:
    """Solve the static coupled problem (an ``ArlequinProblem`` or a ``CoupledSystem``).

    A problem whose models are all linear is one sparse solve of the saddle point. A problem
    with a nonlinear model (an elastoplastic patch) is never given its linear answer: it is
    solved by Newton with the consistent tangents, as one load step of
    :func:`~arlequin.solvers.statics.quasi_static.solve_quasi_static` (cut automatically where
    Newton needs it) from the unloaded state to the loads at ``t``; a path-dependent material then
    follows a proportional path (call ``solve_quasi_static`` for another path, for the history
    of the steps, or to resume). The strain energies of its nonlinear blocks are not given.

    Parameters
    ----------
    problem : ArlequinProblem or CoupledSystem
    t : float
        Time (s) of the loads and prescribed values.
    linear_solver : {"auto", "superlu", "amg"}
        ``"superlu"``: the sparse LU of the scaled saddle point (the reference); ``"amg"``: GMRES
        preconditioned by an augmented Lagrangian and smoothed-aggregation multigrid
        (:func:`arlequin.linalg.saddle_amg.solve_saddle_amg`); ``"auto"``: ``"amg"`` for 3D
        systems of at least ``AMG_MIN_UNKNOWNS`` unknowns (``AMG_MIN_UNKNOWNS_COUPLED`` with
        multiplier rows), SuperLU otherwise. Linear problems
        only (a nonlinear one is solved by the quasi-static solver's direct solvers).
    linear_solver_options : dict, optional
        For ``"amg"``: ``rtol`` (true relative residual, default 1e-10), ``maxiter`` (GMRES
        iterations, default 1000), ``gamma`` (the augmentation, default the mean of the
        stiffness's diagonal).

    Raises
    ------
    SingularSystemError
        If the supports leave a rigid-body motion free (checked before solving), or the
        system is singular for another reason (dependent constraint rows).
    LinearSolverError
        If the iterative solve's true residual stays above its tolerance.
    ValueError
        If a load is not finite, or ``linear_solver`` is not one of ``STATIC_LINEAR_SOLVERS``.
    """
    if linear_solver not in STATIC_LINEAR_SOLVERS:
        raise ValueError(
            f"linear_solver must be one of {STATIC_LINEAR_SOLVERS}, got {linear_solver!r}"
        )
    options = dict(linear_solver_options or {})
    unknown = set(options) - {"rtol", "maxiter", "gamma"}
    if unknown:
        raise ValueError(
            f"linear_solver_options: unknown option(s) {sorted(unknown)}; "
            "known: 'rtol', 'maxiter', 'gamma'"
        )
    system = problem if isinstance(problem, CoupledSystem) else problem.system()
    check_supports(system, t)
    if not all(is_linear(term.model) for b in system.blocks for term in b.terms):
        if linear_solver == "amg":
            raise ValueError(
                "linear_solver='amg' is not available for nonlinear static problems yet: use "
                "'auto' or 'superlu'"
            )
        return _solve_nonlinear(system, t)
    sp_sys = assemble_saddle_point(system, t)
    bad = np.nonzero(~np.isfinite(sp_sys.load))[0]
    if bad.size:
        raise ValueError(
            f"the load vector has {bad.size} non-finite value(s) (first at global dof "
            f"{int(bad[0])}): check the body forces and tractions"
        )
    name = _choose_solver(linear_solver, system, sp_sys)
    krylov = None
    if name == "amg":
        x, krylov = _solve_amg(system, sp_sys, options)
        return _result(system, sp_sys, x, name, krylov)
    try:
        x = _solve_saddle(sp_sys.matrix, sp_sys.rhs)
    except RuntimeError as exc:  # SuperLU: "Factor is exactly singular"
        raise SingularSystemError(f"the coupled static system is singular: {exc}") from exc
    if not np.all(np.isfinite(x)):
        raise SingularSystemError(
            "the coupled static system is singular (non-finite solution): check that the coarse "
            "model's rigid motions are removed and that the mediator rows are independent"
        )
    return _result(system, sp_sys, x, name, krylov)


def _result(system, sp_sys: SaddlePoint, x, name: str, krylov) -> StaticResult:
    """The static result of the saddle point's solution x (scaled multipliers)."""
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
        linear_solver=name,
        krylov=krylov,
    )


def _choose_solver(name: str, system: CoupledSystem, sp_sys: SaddlePoint) -> str:
    """``"auto"`` resolved: the iterative solver on 3D systems of at least ``AMG_MIN_UNKNOWNS``
    unknowns (``AMG_MIN_UNKNOWNS_COUPLED`` with multiplier rows), SuperLU otherwise."""
    if name != "auto":
        return name
    kinds = {getattr(b.model, "kind", None) for b in system.blocks}
    coupled = sp_sys.matrix.shape[0] > sp_sys.n_free
    big = sp_sys.matrix.shape[0] >= (AMG_MIN_UNKNOWNS_COUPLED if coupled else AMG_MIN_UNKNOWNS)
    return "amg" if big and kinds == {"3d"} else "superlu"


def _solve_amg(system: CoupledSystem, sp_sys: SaddlePoint, options: dict):
    """The saddle point by GMRES + augmented-Lagrangian multigrid, the rigid-body modes of each
    block (zero on the other blocks) as near-null space, multigrid on the full numbering."""
    n = sp_sys.free.size + sp_sys.fixed.size
    modes = rigid_modes(system)
    near_null, blocksize = None, 1
    if modes is not None:
        r = modes[0]
        k = r.shape[1]
        near_null = np.zeros((n, k * len(system.blocks)))
        for i, b in enumerate(system.blocks):
            near_null[b.dofs, i * k : (i + 1) * k] = r[b.dofs]
        dims = {int(np.asarray(b.model.mesh.p).shape[0]) for b in system.blocks}
        d = dims.pop() if len(dims) == 1 else 1
        if all(b.offset % d == 0 and b.n_dofs % d == 0 for b in system.blocks):
            blocksize = d
    nf = sp_sys.n_free
    return solve_saddle_amg(
        sp_sys.matrix[:nf, :nf],
        sp_sys.matrix[nf:, :nf],
        sp_sys.rhs,
        near_null_space=near_null,
        free=sp_sys.free,
        n_full=n,
        blocksize=blocksize,
        **options,
    )


def _solve_nonlinear(system: CoupledSystem, t: float) -> StaticResult:
    """A nonlinear static problem as one load step of the quasi-static solver."""
    from .quasi_static import solve_quasi_static

    logger.info("solve_static: nonlinear models, solved by Newton (one quasi-static load step)")
    qs = solve_quasi_static(system, load=1.0, steps=1, reference_time=t)
    if qs.status != "completed":
        raise SingularSystemError(
            f"the nonlinear static problem has no solution at the given loads: {qs.message} "
            "(use solve_quasi_static to follow the load up to there)"
        )
    energies = {
        b.name: 0.5 * float(qs.u[b.dofs] @ (system.block_stiffness(b) @ qs.u[b.dofs]))
        for b in system.blocks
        if all(is_linear(term.model) for term in b.terms)
    }
    return StaticResult(
        displacements=qs.displacements,
        multipliers=qs.multipliers,
        strain_energy=energies,
        residual=qs.steps[-1].residuals[-1],
        u=qs.u,
        system=system,
        saddle_point=None,
    )
