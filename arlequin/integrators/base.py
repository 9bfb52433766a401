"""Common machinery of the dynamic integrators: base class, registry, ``solve``, energy accounting.

An integrator sees a :class:`arlequin.system.CoupledSystem` (mass, internal force, tangent,
external force at time t, constraint rows with multipliers), never meshes. Like scipy's
``OdeSolver``: a base class whose :meth:`Integrator.step` calls ``_step_impl``, a registry
accepting a name or a class (:func:`get_integrator`), and :func:`solve` returning a
:class:`DynamicResult`, with a callback for recording.

Energy accounting (every integrator, every step): per block (model) b,

* kinetic energy ``T_b = ½ v_bᵀ M_b v_b`` with the α-weighted mass of the integrator (lumped for
  the explicit scheme), strain energy ``U_b = ½ u_bᵀ K_b u_b`` (α-weighted; nonlinear blocks: the
  accumulated work of the internal forces);
* work of the external forces ``W_ext,b``, of the coupling (mediator) forces ``W_c,b`` and of the
  other constraint forces (Dirichlet reactions, contact) ``W_r,b``, accumulated from the forces
  and the displacement increments / velocities of the step (never as a balance residual).

The coupling forces on the two models are opposite (−C_cᵀλ and +C_fᵀλ): their works on the coarse
and on the fine block cancel when the coupled velocities satisfy C_c v_c = C_f v_f. The balance
``E − E(0) − W_ext − W_c − W_r`` (E = Σ T_b + U_b) measures the numerical energy error.
Units: J for energies and works, N for multipliers (the force on the system is −Bᵀλ).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..system import CoupledSystem, LinearConstraint, StateError
from .constraints import UnilateralConstraint, is_unilateral

__all__ = [
    "REGISTRY",
    "ConstraintError",
    "DynamicResult",
    "EqualityRows",
    "Integrator",
    "SimulationError",
    "SystemOperators",
    "get_integrator",
    "register",
    "solve",
]

logger = logging.getLogger(__name__)


# ---------------------------------------------------------------------------------------------
# errors
# ---------------------------------------------------------------------------------------------
class SimulationError(ValueError):
    """A run failed (non-finite values, Newton failure...).

    Attributes
    ----------
    step : int
        Index of the failed step (1 for the first step).
    time : float
        Time (s) reached by the failed step.
    result : DynamicResult or None
        What was recorded until then (set by :func:`solve`).
    """

    def __init__(self, message: str, step: int, time: float) -> None:
        super().__init__(message)
        self.step = int(step)
        self.time = float(time)
        self.result: DynamicResult | None = None


class ConstraintError(ValueError):
    """The constraint rows cannot be enforced (linearly dependent rows, zero masses...)."""


# ---------------------------------------------------------------------------------------------
# the system seen by an integrator
# ---------------------------------------------------------------------------------------------
def _is_linear(model: Any) -> bool:
    """A model is linear if it says so (``is_linear``) or has no ``tangent`` method."""
    flag = getattr(model, "is_linear", None)
    if flag is not None:
        return bool(flag)
    return not callable(getattr(model, "tangent", None))


class SystemOperators:
    """Mass, internal force and tangent of a :class:`CoupledSystem` for the integrators.

    Linear blocks use the assembled weighted stiffness (computed once: a step is a sparse
    mat-vec); nonlinear block terms call their model's ``internal_force(u, state, weight) ->
    (f, trial_state)`` and ``tangent(u, state, weight) -> sparse`` (or
    ``internal_force_and_tangent(u, state, weight) -> (f, K_t, trial_state)``) and keep one state
    per term; ``initial_state(weight)``, if the model has it, gives the initial state.

    Parameters
    ----------
    system : CoupledSystem
    lumped : bool
        Row-sum lumped weighted mass (explicit scheme) or consistent weighted mass.
    """

    def __init__(self, system: CoupledSystem, lumped: bool) -> None:
        self.system = system
        self.blocks = list(system.blocks)
        self.n = int(system.n_dofs)
        self.lumped = bool(lumped)
        self.block_linear = [all(_is_linear(t.model) for t in b.terms) for b in self.blocks]
        self.linear = all(self.block_linear)
        self.offsets = np.array([b.offset for b in self.blocks] + [self.n], dtype=np.int64)
        self.block_of_dof = np.repeat(np.arange(len(self.blocks)), np.diff(self.offsets))
        self.names = [b.name for b in self.blocks]
        mass = system.mass(lumped=self.lumped)
        self.mass = mass
        if self.lumped:
            mass = np.asarray(mass, dtype=float)
            bad = np.nonzero(~(mass > 0.0))[0]
            if bad.size:
                j = int(bad[0])
                b = self.blocks[int(self.block_of_dof[j])]
                raise ConstraintError(
                    f"lumped weighted mass must be positive, got {mass[j]:.3e} kg at dof "
                    f"{j - b.offset} of block {b.name!r} ({bad.size} such dofs): check the "
                    "partition weights (epsilon > 0) and the density"
                )
            self.inv_mass = 1.0 / mass
        else:
            self.inv_mass = None
        # linear part of the stiffness: the whole block for linear blocks
        kb = []
        for b, lin in zip(self.blocks, self.block_linear):
            if lin:
                kb.append(system.block_stiffness(b))
            else:
                kb.append(sp.csr_matrix((b.n_dofs, b.n_dofs)))
        self.stiffness = sp.block_diag(kb, format="csr")
        self._nonlinear_terms = [
            (bi, ti, t)
            for bi, (b, lin) in enumerate(zip(self.blocks, self.block_linear))
            if not lin
            for ti, t in enumerate(b.terms)
        ]

    # ------------------------------------------------------------------ states
    def initial_states(self) -> dict[str, list[Any]]:
        """One state per block term (None for models without state)."""
        out: dict[str, list[Any]] = {}
        for b in self.blocks:
            states = []
            for t in b.terms:
                init = getattr(t.model, "initial_state", None)
                states.append(
                    init(t.weight) if callable(init) and not _is_linear(t.model) else None
                )
            out[b.name] = states
        return out

    # ------------------------------------------------------------------ forces
    def _term_u(self, b, t, u: np.ndarray) -> np.ndarray:
        ub = u[b.dofs]
        return ub if t.transfer is None else t.transfer @ ub

    def internal_force(
        self, u: np.ndarray, states: Mapping[str, list[Any]], tangent: bool = False
    ) -> tuple[np.ndarray, dict[str, list[Any]], sp.csr_matrix | None]:
        """Internal force (N) at ``u`` from the committed ``states``.

        Returns
        -------
        f : ndarray, shape (n,)
        trial_states : dict
            Block name -> list of trial states (to commit once the step is accepted).
        tangent : sparse (n, n) or None
            Consistent tangent (N/m) when ``tangent`` is True.
        """
        f = self.stiffness @ u
        trial = {name: list(s) for name, s in states.items()}
        if not self._nonlinear_terms:
            return f, trial, (self.stiffness if tangent else None)
        kt_blocks: dict[int, sp.csr_matrix] = {}
        for bi, ti, term in self._nonlinear_terms:
            b = self.blocks[bi]
            ut = self._term_u(b, term, u)
            state = states[b.name][ti]
            kt = None
            both = getattr(term.model, "internal_force_and_tangent", None)
            if tangent and callable(both):
                ft, kt, new_state = both(ut, state, term.weight)
            else:
                ft, new_state = term.model.internal_force(ut, state, term.weight)
                if tangent:
                    tfun = getattr(term.model, "tangent", None)
                    kt = (
                        tfun(ut, state, term.weight)
                        if callable(tfun)
                        else term.model.stiffness(term.weight)
                    )
            trial[b.name][ti] = new_state
            p = term.transfer
            fb = ft if p is None else p.T @ ft
            f[b.dofs] += term.sign * fb
            if tangent:
                kt = sp.csr_matrix(kt)
                kb = term.sign * (kt if p is None else (p.T @ kt @ p))
                kt_blocks[bi] = kb if bi not in kt_blocks else kt_blocks[bi] + kb
        kt_full = None
        if tangent:
            blocks = []
            for bi, b in enumerate(self.blocks):
                blocks.append(kt_blocks.get(bi, sp.csr_matrix((b.n_dofs, b.n_dofs))))
            kt_full = (self.stiffness + sp.block_diag(blocks, format="csr")).tocsr()
        return f, trial, kt_full

    # ------------------------------------------------------------------ per-block reductions
    def block_dots(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Per-block dot products Σ_{j∈b} x_j y_j, shape (n_blocks,)."""
        prod = x * y
        return np.add.reduceat(prod, self.offsets[:-1]) if self.n else np.zeros(len(self.blocks))

    def kinetic(self, v: np.ndarray) -> np.ndarray:
        """α-weighted kinetic energy per block (J) with the integrator's mass."""
        mv = self.mass * v if self.lumped else self.mass @ v
        return 0.5 * self.block_dots(v, mv)

    def strain_linear(self, u: np.ndarray) -> np.ndarray:
        """½ uᵀ K u per block (J) for the linear blocks (0 for the others)."""
        return 0.5 * self.block_dots(u, self.stiffness @ u)


def _as_vector(x: Any, system: CoupledSystem, what: str) -> np.ndarray:
    """Global vector from None, an array (n,) or a dict {block name: block vector}."""
    n = system.n_dofs
    if x is None:
        return np.zeros(n)
    if isinstance(x, Mapping):
        out = np.zeros(n)
        for name, val in x.items():
            b = system.block(name)
            val = np.asarray(val, dtype=float).ravel()
            if val.size != b.n_dofs:
                raise ValueError(
                    f"{what} for block {name!r} has {val.size} values, expected {b.n_dofs}"
                )
            out[b.dofs] = val
        return out
    out = np.asarray(x, dtype=float).ravel().copy()
    if out.size != n:
        raise ValueError(f"{what} has {out.size} values, expected {n} (the system's dofs)")
    return out


def _rate(c: LinearConstraint, t: float, h: float, order: int = 1) -> np.ndarray:
    """d^order g / dt^order by centred differences with step h (zero for constant data)."""
    if not callable(c.rhs):
        return np.zeros(c.n_rows)
    if order == 1:
        return (c.g(t + h) - c.g(t - h)) / (2.0 * h)
    return (c.g(t + h) - 2.0 * c.g(t) + c.g(t - h)) / (h * h)


class EqualityRows:
    """The equality constraints of a system stacked: ``B`` (m×n), levels, kinds, right-hand sides.

    Attributes
    ----------
    constraints : list of LinearConstraint
    matrix : csr_matrix, shape (m, n)
    slices : dict
        Constraint name -> rows.
    displacement : ndarray of bool, shape (m,)
        Rows at displacement level (the others are at velocity level).
    coupling : ndarray of bool, shape (m,)
        Rows of kind ``"coupling"``.
    cols : ndarray of int
        Global dofs touched by the rows; ``matrix_cols = matrix[:, cols]``.
    """

    def __init__(self, constraints: Sequence[LinearConstraint], ops: SystemOperators) -> None:
        self.constraints = list(constraints)
        n = ops.n
        self.n = n
        names = [c.name for c in self.constraints]
        if len(set(names)) != len(names):
            raise ValueError(f"constraint names must be unique, got {names}")
        mats = [sp.csr_matrix(c.matrix) for c in self.constraints]
        for c, mat in zip(self.constraints, mats):
            if mat.shape[1] != n:
                raise ValueError(f"constraint {c.name!r} has {mat.shape[1]} columns, expected {n}")
        self.matrix = sp.vstack(mats, format="csr") if mats else sp.csr_matrix((0, n))
        self.matrix.sum_duplicates()
        self.m = int(self.matrix.shape[0])
        self.slices: dict[str, slice] = {}
        start = 0
        disp, coup = [], []
        for c in self.constraints:
            self.slices[c.name] = slice(start, start + c.n_rows)
            start += c.n_rows
            disp.append(np.full(c.n_rows, c.level == "displacement"))
            coup.append(np.full(c.n_rows, c.kind == "coupling"))
        self.displacement = np.concatenate(disp) if disp else np.zeros(0, dtype=bool)
        self.coupling = np.concatenate(coup) if coup else np.zeros(0, dtype=bool)
        self.cols = np.unique(self.matrix.indices) if self.m else np.zeros(0, dtype=np.int64)
        self.matrix_cols = self.matrix[:, self.cols].tocsr() if self.m else sp.csr_matrix((0, 0))
        self.matrix_cols_t = self.matrix_cols.T.tocsr()
        self.block_of_col = ops.block_of_dof[self.cols]
        self.n_blocks = len(ops.blocks)
        # per-block row products in one mat-vec: row (b m + i) holds row i of B on block b's dofs
        if self.m:
            coo = self.matrix_cols.tocoo()
            self._stacked = sp.csr_matrix(
                (coo.data, (self.block_of_col[coo.col] * self.m + coo.row, coo.col)),
                shape=(self.n_blocks * self.m, self.cols.size),
            )
        self._coupling_f = self.coupling.astype(float)
        self._constant = all(not callable(c.rhs) for c in self.constraints)
        self._g0 = self._g(0.0) if self._constant else None

    def _g(self, t: float) -> np.ndarray:
        parts = [c.g(t) for c in self.constraints]
        return np.concatenate(parts) if parts else np.zeros(0)

    def g(self, t: float) -> np.ndarray:
        """Stacked right-hand sides at time t (s), shape (m,)."""
        return self._g0 if self._g0 is not None else self._g(t)

    @property
    def time_dependent(self) -> bool:
        return not self._constant

    def rate(self, t: float, h: float, order: int = 1) -> np.ndarray:
        """Stacked d^order g/dt^order at t (centred differences, step h)."""
        if self._constant:
            return np.zeros(self.m)
        parts = [_rate(c, t, h, order) for c in self.constraints]
        return np.concatenate(parts) if parts else np.zeros(0)

    def split(self, lam: np.ndarray) -> dict[str, np.ndarray]:
        """Stacked multipliers -> {constraint name: multipliers}."""
        return {name: lam[s].copy() for name, s in self.slices.items()}

    def block_powers(self, lam: np.ndarray, x_cols: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per-block −λ·(B_b x_b) for the coupling rows and for the other rows.

        Parameters
        ----------
        lam : ndarray, shape (m,)
            Multipliers (N).
        x_cols : ndarray, shape (len(cols),)
            A velocity (m/s) or displacement increment (m) on :attr:`cols`.

        Returns
        -------
        coupling, other : ndarray, shape (n_blocks,)
            Power (W) or work (J) of the constraint forces −Bᵀλ on each block.
        """
        nb = self.n_blocks
        if self.m == 0:
            return np.zeros(nb), np.zeros(nb)
        rb = (self._stacked @ x_cols).reshape(nb, self.m) * lam
        pc = -(rb * self._coupling_f).sum(axis=1)
        po = -rb.sum(axis=1) - pc
        return pc, po


def unilateral_block_power(
    ops: SystemOperators, g: sp.csr_matrix, lam: np.ndarray, x: np.ndarray
) -> np.ndarray:
    """Per-block −λ·(G_b x_b) of unilateral rows G (m, n) with multipliers λ (m,)."""
    if g.shape[0] == 0:
        return np.zeros(len(ops.blocks))
    return -ops.block_dots(g.T @ lam, x)


class ScaledLU:
    """Sparse LU (SuperLU) of a symmetric matrix after symmetric diagonal scaling ``D A D``.

    ``D_ii = |A_ii|^{-1/2}``; rows with a zero diagonal (multiplier rows of a saddle point) get
    the inverse norm of their scaled row, so that stiffness, mass and constraint rows of very
    different units become commensurate. A pivot below ``1e-14`` of the largest one (after
    scaling) means linearly dependent rows: :class:`ConstraintError`.

    Parameters
    ----------
    mat : sparse, shape (N, N)
    what : str
        Name of the matrix for the error message.
    names : callable, optional
        Row index -> description, for the error message.
    spd : bool
        Symmetric positive definite: symmetric ordering, diagonal pivots.
    """

    def __init__(
        self,
        mat: sp.spmatrix,
        what: str,
        names: Callable[[int], str] | None = None,
        spd: bool = False,
    ) -> None:
        mat = sp.csr_matrix(mat)
        n = mat.shape[0]
        diag = np.abs(mat.diagonal())
        d = np.zeros(n)
        nz = diag > 0.0
        d[nz] = 1.0 / np.sqrt(diag[nz])
        if not np.all(nz):
            scaled_cols = sp.csr_matrix(mat[~nz] @ sp.diags(d))
            norms = np.sqrt(np.asarray(scaled_cols.multiply(scaled_cols).sum(axis=1)).ravel())
            bad = np.nonzero(norms == 0.0)[0]
            if bad.size:
                i = int(np.nonzero(~nz)[0][bad[0]])
                where = f" ({names(i)})" if names is not None else ""
                raise ConstraintError(f"{what} has an empty row {i}{where}")
            d[~nz] = 1.0 / norms
        self.d = d
        scaled = sp.csc_matrix(sp.diags(d) @ mat @ sp.diags(d))
        try:
            if spd:
                self.lu = spla.splu(scaled, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0)
            else:
                self.lu = spla.splu(scaled)
        except RuntimeError as exc:
            raise ConstraintError(
                f"{what} is singular ({exc}): the constraint rows are linearly dependent"
            ) from exc
        piv = np.abs(self.lu.U.diagonal())
        tiny = np.nonzero(~(piv > 1e-14 * piv.max()))[0] if piv.size else np.zeros(0, int)
        if tiny.size:
            where = ""
            if names is not None:
                where = f" (near {names(int(self.lu.perm_c[tiny[0]]) if spd else int(tiny[0]))})"
            raise ConstraintError(
                f"{what} is numerically singular: {tiny.size} pivot(s) below 1e-14 of the "
                f"largest after scaling{where}; the constraint rows are linearly dependent (e.g. "
                "a Dirichlet condition on dofs that the mediator rows already tie, or duplicate "
                "rows)"
            )
        self.shape = mat.shape

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve A x = rhs; rhs of shape (N,) or (N, k)."""
        d = self.d if rhs.ndim == 1 else self.d[:, None]
        return d * self.lu.solve(np.ascontiguousarray(d * rhs))


def _factor_checked(
    mat: sp.spmatrix, what: str, names: Callable[[int], str] | None = None, spd: bool = False
) -> ScaledLU | None:
    """:class:`ScaledLU` of a square sparse matrix (None if it is empty)."""
    if mat.shape[0] == 0:
        return None
    return ScaledLU(mat, what, names, spd)


# ---------------------------------------------------------------------------------------------
# result
# ---------------------------------------------------------------------------------------------
@dataclass
class DynamicResult:
    """Histories of a dynamic run (recorded steps) and its final state.

    Attributes
    ----------
    times : ndarray, shape (n_rec,)
        Recorded times (s), starting with the initial time.
    kinetic, strain : dict
        Block name -> α-weighted kinetic / strain energy (J), shape (n_rec,).
    external_work, coupling_work, constraint_work : dict
        Block name -> accumulated work (J) of the external forces, of the coupling (mediator)
        forces and of the other constraint forces (Dirichlet reactions, contact), shape (n_rec,).
    multipliers : dict
        Constraint name -> multipliers as forces (N), shape (n_rec, m).
    status_iterations : ndarray of int, shape (n_rec,)
        Status iterations of the unilateral constraints in the step ending at each record.
    u, v : ndarray, shape (n,)
        Final displacement (m) and velocity (m/s).
    fields : dict or None
        ``{"u": (n_rec, n), "v": (n_rec, n)}`` when recorded (``save_fields=True``).
    n_steps : int
    dt : float
        Time step (s).
    critical_dt : float or None
        Critical (stable-limit) step of the explicit coupled system (s), when computed.
    status : int
        0: reached t_end; 1: stopped by the callback; −1: failed (see ``message``).
    message : str
    n_status_failures : int
        Steps whose status iterations reached the cap.
    integrator : str
    """

    times: np.ndarray
    kinetic: dict[str, np.ndarray]
    strain: dict[str, np.ndarray]
    external_work: dict[str, np.ndarray]
    coupling_work: dict[str, np.ndarray]
    constraint_work: dict[str, np.ndarray]
    multipliers: dict[str, np.ndarray]
    status_iterations: np.ndarray
    u: np.ndarray
    v: np.ndarray
    n_steps: int
    dt: float
    status: int = 0
    message: str = ""
    critical_dt: float | None = None
    n_status_failures: int = 0
    integrator: str = ""
    fields: dict[str, np.ndarray] | None = None
    states: Any = field(default=None, repr=False)

    @property
    def success(self) -> bool:
        return self.status >= 0

    @staticmethod
    def _sum(d: dict[str, np.ndarray], n: int) -> np.ndarray:
        return np.sum(list(d.values()), axis=0) if d else np.zeros(n)

    @property
    def total_kinetic(self) -> np.ndarray:
        """Σ_b T_b (J), shape (n_rec,)."""
        return self._sum(self.kinetic, self.times.size)

    @property
    def total_strain(self) -> np.ndarray:
        """Σ_b U_b (J), shape (n_rec,)."""
        return self._sum(self.strain, self.times.size)

    @property
    def total_energy(self) -> np.ndarray:
        """E = Σ_b T_b + U_b (J), shape (n_rec,)."""
        return self.total_kinetic + self.total_strain

    @property
    def total_external_work(self) -> np.ndarray:
        return self._sum(self.external_work, self.times.size)

    @property
    def total_coupling_work(self) -> np.ndarray:
        return self._sum(self.coupling_work, self.times.size)

    @property
    def total_constraint_work(self) -> np.ndarray:
        return self._sum(self.constraint_work, self.times.size)

    @property
    def balance(self) -> np.ndarray:
        """E − E(0) − W_ext − W_c − W_r (J): the numerical energy error, shape (n_rec,)."""
        e = self.total_energy
        return (
            e
            - e[0]
            - self.total_external_work
            - self.total_coupling_work
            - self.total_constraint_work
        )

    def block_balance(self, block: str) -> np.ndarray:
        """Energy balance of one block (its coupling work included), shape (n_rec,)."""
        e = self.kinetic[block] + self.strain[block]
        return (
            e
            - e[0]
            - self.external_work[block]
            - self.coupling_work[block]
            - self.constraint_work[block]
        )

    def energy_drift(self) -> float:
        """max_t |E(t) − E(0)| / E(0) (dimensionless); E(0) must be positive."""
        e = self.total_energy
        if not e[0] > 0.0:
            raise ValueError(f"energy drift needs a positive initial energy, got E(0) = {e[0]}")
        return float(np.max(np.abs(e - e[0])) / e[0])

    def relative_balance(self) -> float:
        """max_t |balance| / max_t(E(t), |W_ext|) (dimensionless)."""
        scale = max(
            float(np.max(np.abs(self.total_energy))),
            float(np.max(np.abs(self.total_external_work))),
        )
        return float(np.max(np.abs(self.balance)) / scale) if scale > 0 else 0.0


# ---------------------------------------------------------------------------------------------
# base class
# ---------------------------------------------------------------------------------------------
class Integrator:
    """Base class of the time integrators (scipy ``OdeSolver`` style).

    Parameters
    ----------
    system : CoupledSystem
        Blocks, equality constraints (``system.constraints``) and loads.
    dt : float, optional
        Time step (s). Default: the solver's default (the explicit scheme: a safety factor times
        the critical step of the coupled system; the implicit schemes: the same explicit step).
    t0 : float
        Initial time (s).
    u0, v0 : ndarray (n,) or dict {block: array}, optional
        Initial displacement (m) and velocity (m/s) of each model; missing blocks are zero.
    constraints : sequence, optional
        Extra constraints: :class:`LinearConstraint` rows or :class:`UnilateralConstraint` objects
        (unilateral objects found in ``system.constraints`` are used as well).
    consistent_initial : bool
        Project u0 and v0 (mass metric) onto the equality rows (coupling-consistent initial
        conditions); the correction's size is logged.
    check_finite : bool
        Raise :class:`SimulationError` as soon as a displacement or velocity is NaN or overflows.
    max_status_iterations : int, optional
        Cap on the status iterations of the unilateral constraints per step (default: the
        largest ``max_iterations`` of the constraints).

    Attributes
    ----------
    t : float
        Current time (s).
    u, v, a : ndarray, shape (n,)
        Displacement (m), velocity (m/s), acceleration (m/s²) at ``t``.
    states : dict
        Block name -> committed state per block term.
    step_count : int
    multipliers : dict
        Constraint name -> multipliers (N) at ``t`` (a step quantity for the θ-scheme).
    """

    name = "base"
    lumped_default = False

    def __init__(
        self,
        system: CoupledSystem,
        dt: float | None = None,
        *,
        t0: float = 0.0,
        u0: Any = None,
        v0: Any = None,
        constraints: Sequence[Any] = (),
        consistent_initial: bool = True,
        check_finite: bool = True,
        lumped: bool | None = None,
        max_status_iterations: int | None = None,
    ) -> None:
        if not isinstance(system, CoupledSystem):
            problem_system = getattr(system, "system", None)
            if callable(problem_system):
                system = problem_system()
            else:
                raise TypeError(f"expected a CoupledSystem, got {type(system).__name__}")
        self.system = system
        self.ops = SystemOperators(system, self.lumped_default if lumped is None else lumped)
        all_constraints = list(system.constraints) + list(constraints)
        self.unilateral: list[UnilateralConstraint] = [
            c for c in all_constraints if is_unilateral(c)
        ]
        equality = [c for c in all_constraints if not is_unilateral(c)]
        self.rows = EqualityRows(equality, self.ops)
        for c in self.unilateral:
            if c.matrix().shape[1] != self.ops.n:
                raise ValueError(
                    f"unilateral constraint {c.name!r} has {c.matrix().shape[1]} columns, "
                    f"expected {self.ops.n}"
                )
        caps = [c.max_iterations for c in self.unilateral]
        self.max_status_iterations = int(max_status_iterations or (max(caps) if caps else 1))
        self.check_finite = bool(check_finite)
        self.t = float(t0)
        self.t0 = float(t0)
        self.step_count = 0
        self.states = self.ops.initial_states()
        self.status_iterations = 0
        self.n_status_failures = 0
        self.critical_dt: float | None = None
        nb = len(self.ops.blocks)
        self._w_ext = np.zeros(nb)
        self._w_coupling = np.zeros(nb)
        self._w_constraint = np.zeros(nb)
        self._w_internal = np.zeros(nb)
        self.dt = self._choose_dt(dt)
        if not (self.dt > 0.0 and math.isfinite(self.dt)):
            raise ValueError(f"time step must be positive and finite, got dt={self.dt}")
        u = _as_vector(u0, system, "u0")
        v = _as_vector(v0, system, "v0")
        if consistent_initial and self.rows.m:
            u, v = self._consistent(u, v)
        self.u = u
        self.v = v
        self.a = np.zeros_like(u)
        self.multipliers: dict[str, np.ndarray] = {}
        self._initialize()

    # ------------------------------------------------------------------ hooks
    def _choose_dt(self, dt: float | None) -> float:
        raise NotImplementedError

    def _initialize(self) -> None:
        raise NotImplementedError

    def _step_impl(self) -> None:
        raise NotImplementedError

    def reset_dt(self, dt: float) -> None:
        """Change the time step before the first step (re-initialises the integrator)."""
        if self.step_count:
            raise RuntimeError("reset_dt is only allowed before the first step")
        self.dt = self._choose_dt(float(dt))
        self._initialize()

    # ------------------------------------------------------------------ initial conditions
    def _project(self, x: np.ndarray, rows: np.ndarray, target: np.ndarray) -> np.ndarray:
        """Mass-metric projection of x onto {y: B[rows] y = target}."""
        b = self.rows.matrix[np.nonzero(rows)[0]]
        if b.shape[0] == 0:
            return x
        r = target - b @ x
        if not np.any(r):
            return x
        if self.ops.lumped:
            s = (b @ sp.diags(self.ops.inv_mass) @ b.T).tocsc()
            lu = _factor_checked(s, "the initial-condition projection matrix B M⁻¹ Bᵀ", spd=True)
            return x + self.ops.inv_mass * (b.T @ lu.solve(r))
        mat = sp.bmat([[self.ops.mass, b.T], [b, None]], format="csc")
        lu = _factor_checked(mat, "the initial-condition projection saddle point")
        sol = lu.solve(np.concatenate([np.zeros(x.size), r]))
        return x + sol[: x.size]

    def _consistent(self, u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rows = self.rows
        h = self.dt
        u_new = self._project(u, rows.displacement, rows.g(self.t))
        vt = np.where(rows.displacement, rows.rate(self.t, h), rows.g(self.t))
        v_new = self._project(v, np.ones(rows.m, dtype=bool), vt)
        for what, old, new in (("displacement", u, u_new), ("velocity", v, v_new)):
            change = float(np.linalg.norm(new - old))
            if change > 1e-12 * max(float(np.linalg.norm(old)), 1e-300):
                logger.info(
                    "initial %s projected onto the constraints (change %.3e, relative %.3e)",
                    what,
                    change,
                    change / max(float(np.linalg.norm(old)), 1e-300),
                )
        return u_new, v_new

    # ------------------------------------------------------------------ stepping
    def step(self) -> None:
        """Advance one time step (updates t, u, v, a, states, multipliers, works).

        Raises
        ------
        SimulationError
            If the new displacement or velocity is not finite (NaN or overflow), or a model
            reports an invalid state (:class:`~arlequin.system.StateError`, e.g. an inverted
            cell).
        """
        t_start = self.t
        try:
            self._step_impl()
        except StateError as err:
            t_next = t_start + self.dt
            raise SimulationError(
                f"{self.name}: {err} at step {self.step_count + 1}, t = {t_next:.6e} s "
                f"(dt = {self.dt:.6e} s)",
                self.step_count + 1,
                t_next,
            ) from err
        self.step_count += 1
        if self.check_finite:
            # Σu² + Σv² (einsum's own loop, no multithreaded BLAS call): NaN, ±inf and values
            # whose energy would overflow all make it non-finite
            with np.errstate(over="ignore", invalid="ignore"):
                check = float(np.einsum("i,i->", self.u, self.u)) + float(
                    np.einsum("i,i->", self.v, self.v)
                )
            if not math.isfinite(check):
                raise SimulationError(
                    f"{self.name}: non-finite displacement or velocity (NaN or overflow) at step "
                    f"{self.step_count}, t = {self.t:.6e} s (dt = {self.dt:.6e} s)",
                    self.step_count,
                    self.t,
                )

    # ------------------------------------------------------------------ unilateral rows
    def _active_rows(self) -> tuple[sp.csr_matrix, list[np.ndarray]]:
        """Stacked active unilateral rows (m_A, n) and the active index per constraint."""
        mats, idx = [], []
        for c in self.unilateral:
            act = np.nonzero(c.active)[0]
            idx.append(act)
            mats.append(c.matrix()[act])
        if not mats:
            return sp.csr_matrix((0, self.ops.n)), idx
        return sp.vstack(mats, format="csr"), idx

    def _unilateral_full(self, lam_a: np.ndarray, idx: list[np.ndarray]) -> list[np.ndarray]:
        out, start = [], 0
        for c, act in zip(self.unilateral, idx):
            full = np.zeros(c.n_rows)
            full[act] = lam_a[start : start + act.size]
            start += act.size
            out.append(full)
        return out

    def _update_statuses(self, u: np.ndarray, v: np.ndarray, lams: list[np.ndarray]) -> bool:
        changed = False
        for c, lam in zip(self.unilateral, lams):
            changed = c.update_status(u, v, lam) or changed  # every constraint is updated
        return changed

    def _status_cap_reached(self) -> None:
        self.n_status_failures += 1
        logger.warning(
            "%s: unilateral statuses still changing after %d iterations at step %d, t = %.6e s",
            self.name,
            self.max_status_iterations,
            self.step_count + 1,
            self.t,
        )

    # ------------------------------------------------------------------ energies
    def energies(self) -> dict[str, dict[str, float]]:
        """Current energies and accumulated works per block (J).

        Returns
        -------
        dict
            ``{"kinetic", "strain", "external_work", "coupling_work", "constraint_work"}``, each
            a dict block name -> float.
        """
        names = self.ops.names
        kin = self.ops.kinetic(self.v)
        strain = self.ops.strain_linear(self.u)
        lin = np.asarray(self.ops.block_linear)
        strain = np.where(lin, strain, self._w_internal)
        return {
            "kinetic": dict(zip(names, kin.tolist())),
            "strain": dict(zip(names, strain.tolist())),
            "external_work": dict(zip(names, self._w_ext.tolist())),
            "coupling_work": dict(zip(names, self._w_coupling.tolist())),
            "constraint_work": dict(zip(names, self._w_constraint.tolist())),
        }

    def total_energy(self) -> float:
        """Σ_b T_b + U_b (J)."""
        e = self.energies()
        return float(sum(e["kinetic"].values()) + sum(e["strain"].values()))


# ---------------------------------------------------------------------------------------------
# registry and solve
# ---------------------------------------------------------------------------------------------
REGISTRY: dict[str, type[Integrator]] = {}


def register(*names: str) -> Callable[[type[Integrator]], type[Integrator]]:
    """Class decorator adding an integrator to :data:`REGISTRY` under ``names``."""

    def deco(cls: type[Integrator]) -> type[Integrator]:
        for n in names:
            REGISTRY[n] = cls
        return cls

    return deco


def get_integrator(name_or_class: str | type[Integrator]) -> type[Integrator]:
    """An integrator class from a registry name (``"explicit"``, ``"newmark"``...) or a class."""
    from . import explicit, implicit  # noqa: F401  (registration)

    if isinstance(name_or_class, type) and issubclass(name_or_class, Integrator):
        return name_or_class
    if isinstance(name_or_class, str) and name_or_class in REGISTRY:
        return REGISTRY[name_or_class]
    raise ValueError(
        f"unknown integrator {name_or_class!r}; registered names are {sorted(REGISTRY)} "
        "(or pass an Integrator subclass)"
    )


class _Recorder:
    def __init__(self, integ: Integrator, save_fields: bool) -> None:
        self.integ = integ
        self.times: list[float] = []
        self.rows: list[dict[str, dict[str, float]]] = []
        self.mult: dict[str, list[np.ndarray]] = {}
        self.iters: list[int] = []
        self.save_fields = save_fields
        self.us: list[np.ndarray] = []
        self.vs: list[np.ndarray] = []

    def record(self) -> None:
        it = self.integ
        self.times.append(it.t)
        self.rows.append(it.energies())
        for name, lam in it.multipliers.items():
            self.mult.setdefault(name, []).append(np.array(lam, dtype=float))
        self.iters.append(it.status_iterations)
        if self.save_fields:
            self.us.append(it.u.copy())
            self.vs.append(it.v.copy())

    def result(self, status: int, message: str) -> DynamicResult:
        it = self.integ
        names = it.ops.names

        def hist(key: str) -> dict[str, np.ndarray]:
            return {n: np.array([r[key][n] for r in self.rows]) for n in names}

        fields = None
        if self.save_fields:
            fields = {"u": np.array(self.us), "v": np.array(self.vs)}
        return DynamicResult(
            times=np.array(self.times),
            kinetic=hist("kinetic"),
            strain=hist("strain"),
            external_work=hist("external_work"),
            coupling_work=hist("coupling_work"),
            constraint_work=hist("constraint_work"),
            multipliers={k: np.array(v) for k, v in self.mult.items()},
            status_iterations=np.array(self.iters, dtype=np.int64),
            u=it.u.copy(),
            v=it.v.copy(),
            n_steps=it.step_count,
            dt=it.dt,
            status=status,
            message=message,
            critical_dt=it.critical_dt,
            n_status_failures=it.n_status_failures,
            integrator=it.name,
            fields=fields,
            states=it.states,
        )


def solve(
    system: Any,
    integrator: str | type[Integrator] = "explicit",
    t_end: float | None = None,
    dt: float | None = None,
    *,
    n_steps: int | None = None,
    t0: float = 0.0,
    u0: Any = None,
    v0: Any = None,
    callback: Callable[[Integrator], bool | None] | None = None,
    record_every: int = 1,
    save_fields: bool = False,
    **options: Any,
) -> DynamicResult:
    """Integrate a coupled system in time.

    Parameters
    ----------
    system : CoupledSystem or ArlequinProblem
        The system (a problem is turned into its system).
    integrator : str or Integrator subclass
        ``"explicit"`` (central difference), ``"newmark"``, ``"hht"``, ``"theta"``... or a class.
    t_end : float, optional
        End time (s). The step is reduced (never increased) so that an integer number of steps
        reaches ``t_end`` exactly.
    dt : float, optional
        Time step (s); default: the integrator's default (see :class:`Integrator`).
    n_steps : int, optional
        Number of steps instead of ``t_end``.
    t0 : float
        Initial time (s).
    u0, v0 : ndarray or dict, optional
        Initial displacement (m) and velocity (m/s) (see :class:`Integrator`).
    callback : callable, optional
        ``callback(integrator)`` at every recorded step (after the initial state and after every
        ``record_every`` steps); returning True stops the run (``status = 1``).
    record_every : int
        Record energies and multipliers every ``record_every`` steps (and at the last step).
    save_fields : bool
        Also record u and v (memory: n_rec × n each).
    **options
        Passed to the integrator class (``beta``, ``gamma``, ``alpha``, ``theta``, ``safety``,
        ``constraints``, ``consistent_initial``...).

    Returns
    -------
    DynamicResult

    Raises
    ------
    SimulationError
        On NaN/overflow or a failed step; ``err.result`` holds what was recorded until then.
    """
    cls = get_integrator(integrator)
    if (t_end is None) == (n_steps is None):
        raise ValueError("give exactly one of t_end (s) or n_steps")
    if record_every < 1:
        raise ValueError(f"record_every must be >= 1, got {record_every}")
    if t_end is not None:
        if not t_end > t0:
            raise ValueError(f"t_end must exceed t0, got t_end={t_end}, t0={t0}")
        integ = cls(system, dt, t0=t0, u0=u0, v0=v0, **options)
        steps = max(1, math.ceil((t_end - t0) / integ.dt * (1.0 - 1e-12)))
        dt_run = (t_end - t0) / steps
        if abs(dt_run - integ.dt) > 1e-14 * integ.dt:
            integ.reset_dt(dt_run)
    else:
        steps = int(n_steps)
        if steps < 1:
            raise ValueError(f"n_steps must be >= 1, got {n_steps}")
        integ = cls(system, dt, t0=t0, u0=u0, v0=v0, **options)
    rec = _Recorder(integ, save_fields)
    rec.record()
    if callback is not None and callback(integ):
        return rec.result(1, "stopped by the callback at the initial state")
    for k in range(1, steps + 1):
        try:
            integ.step()
        except SimulationError as err:
            err.result = rec.result(-1, str(err))
            raise
        if k % record_every == 0 or k == steps:
            rec.record()
            if callback is not None and callback(integ):
                return rec.result(1, f"stopped by the callback at step {k}, t = {integ.t:.6e} s")
    return rec.result(0, f"reached t = {integ.t:.6e} s in {steps} steps")
