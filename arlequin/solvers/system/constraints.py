"""Unilateral rows ``G u ≤ h(t)``: a minimal, complete implementation of the constraint protocol.

Two families of constraint rows enter every integrator through Lagrange multipliers:

*Equality rows* (:class:`arlequin.problem.system.LinearConstraint`): ``B u = g(t)`` at displacement
level or ``B v = g(t)`` at velocity level. Arlequin mediator equations (``kind="coupling"``),
Dirichlet conditions (``kind="dirichlet"``) and prescribed velocities are of this kind. Their rows
are fixed for the whole run, so the integrators factorise what depends on them once.

*Unilateral rows* (:class:`arlequin.contract.UnilateralConstraint`): candidate rows of which only
the currently *active* ones are enforced as equalities; the active set is decided inside each
time step by the constraint (a primal–dual active-set / indicator fixed point, the level-set
contact model's). The constraint object holds its configuration only: the integrator passes its
immutable state in and commits the new one (see the protocol).

This module gives :class:`LinearInequality`, rows fixed in time (rigid obstacles, gaps between
nodes). Sign convention: the force on the system is ``−Gᵀλ`` with ``λ ≥ 0`` admissible; a model
whose pressure is negative (``λ ≤ 0``, the contact models) passes the rows ``−G`` instead.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import scipy.sparse as sp

from ...contract import UnilateralConstraint, is_unilateral

__all__ = [
    "InequalityState",
    "InequalityTrial",
    "LinearInequality",
    "UnilateralConstraint",
    "is_unilateral",
]


@dataclass(frozen=True)
class InequalityState:
    """Committed state of a :class:`LinearInequality` (immutable).

    Attributes
    ----------
    active : ndarray of bool, shape (m,)
        Statuses after the last step (the next step's first guess).
    work : float
        Accumulated work of the constraint forces (J), −Σ Λ·G (v⁻ + v⁺)/2 over the steps'
        impulses Λ = ∫ λ dt.
    record : None
        No per-step record.
    """

    active: np.ndarray
    work: float = 0.0
    record: Any = None


@dataclass(frozen=True)
class InequalityTrial:
    """A :class:`LinearInequality` during one step (immutable); see
    :class:`arlequin.contract.ConstraintTrial`.

    Attributes
    ----------
    bound : ndarray, shape (m,)
        h at the end of the step (m).
    closed : ndarray of bool, shape (m,) or None
        Velocity level: rows whose gap predicted with the step's free velocity is closed (S_d).
    """

    active: np.ndarray
    matrix: sp.csr_matrix
    rhs: np.ndarray
    bound: np.ndarray
    closed: np.ndarray | None
    changed: bool = False
    iterations: int = 0


class LinearInequality:
    """Unilateral rows ``G u ≤ h(t)`` with multipliers ``λ ≥ 0`` (force on the system −Gᵀλ).

    ``level="displacement"`` (Signorini, primal–dual active set)
        An inactive row becomes active when the predicted end-of-step ``G u − h`` exceeds
        ``gap_tol``; an active row is released when its multiplier is negative (tensile).
    ``level="velocity"`` (Moreau)
        A row is a candidate when its end-of-step gap predicted with the step's free velocity
        (passed to :meth:`begin_step`) is closed (``G (u + Δt v) − h ≥ −gap_tol``); a
        candidate is active when it would approach (``G v > 0``, inactive rows) or when its
        multiplier is not negative (active rows); active rows enforce ``G v = 0`` (persistent
        contact), so the penetration is at most of the order of Δt times the approach velocity
        at activation and does not drift afterwards.

    Parameters
    ----------
    matrix : sparse or ndarray, shape (m, n)
        Rows G on the global dof vector.
    bound : ndarray (m,), float or callable
        h(t) (m); the velocity-level rows enforce G v = dh/dt = 0 (fixed obstacles).
    level : {"displacement", "velocity"}
    name : str
    max_iterations : int
        Cap on the status iterations of one step.
    gap_tol : float
        Gap tolerance (m).
    kind : str
        Reporting group of the constraint work.
    """

    def __init__(
        self,
        matrix,
        bound: float | np.ndarray | Callable[[float], np.ndarray] = 0.0,
        level: str = "displacement",
        name: str = "inequality",
        max_iterations: int = 25,
        gap_tol: float = 0.0,
        kind: str = "contact",
    ) -> None:
        if level not in ("velocity", "displacement"):
            raise ValueError(
                f"constraint level must be 'velocity' or 'displacement', got {level!r}"
            )
        if max_iterations < 1:
            raise ValueError(f"max_iterations must be >= 1, got {max_iterations}")
        self.name = name
        self.level = level
        self.max_iterations = int(max_iterations)
        self.kind = kind
        self._g = sp.csr_matrix(matrix)
        self._bound = bound
        self.gap_tol = float(gap_tol)

    @property
    def n_rows(self) -> int:
        return int(self._g.shape[0])

    def matrix(self) -> sp.csr_matrix:
        """Rows G, shape (m, n)."""
        return self._g

    def bound(self, t: float) -> np.ndarray:
        """h(t), shape (m,) (m)."""
        b = self._bound(t) if callable(self._bound) else self._bound
        return np.broadcast_to(np.asarray(b, dtype=float), (self.n_rows,)).copy()

    # ------------------------------------------------------------------ protocol
    def initial_state(self, u: np.ndarray, v: np.ndarray) -> InequalityState:
        """The state at the start of a run (all rows inactive)."""
        return InequalityState(np.zeros(self.n_rows, dtype=bool))

    def begin_step(
        self, state: InequalityState, t: float, dt: float, u: np.ndarray, v: np.ndarray
    ) -> InequalityTrial:
        """The trial of a step of size ``dt`` (s) from ``t`` (see
        :class:`arlequin.contract.UnilateralConstraint`)."""
        bound = self.bound(t + dt)  # at the end of the step
        if self.level == "velocity":
            # S_d: the gap predicted with the step's free velocity, fixed during the iterations
            closed = self._g @ (u + dt * v) - bound >= -self.gap_tol
            return InequalityTrial(
                state.active & closed, self._g, np.zeros(self.n_rows), bound, closed
            )
        return InequalityTrial(state.active.copy(), self._g, bound, bound, None)

    def update_status(
        self, trial: InequalityTrial, u: np.ndarray, v: np.ndarray, multipliers: np.ndarray
    ) -> InequalityTrial:
        """New active statuses from the trial displacement, velocity and multipliers, and
        whether they changed."""
        old = trial.active
        lam = np.asarray(multipliers, dtype=float)
        if self.level == "displacement":
            new = np.where(old, lam >= 0.0, self._g @ u - trial.bound > self.gap_tol)
        else:
            new = trial.closed & np.where(old, lam >= 0.0, self._g @ v > 0.0)
        return replace(
            trial, active=new, changed=bool(np.any(new != old)), iterations=trial.iterations + 1
        )

    def commit(
        self,
        state: InequalityState,
        trial: InequalityTrial,
        *,
        t: float,
        u: np.ndarray,
        v_before: np.ndarray,
        v_after: np.ndarray,
        multipliers: np.ndarray,
        impulse: np.ndarray,
    ) -> InequalityState:
        """The state after an accepted step (see
        :class:`arlequin.contract.UnilateralConstraint`)."""
        work = -0.5 * float(impulse @ (self._g @ (v_before + v_after)))
        return InequalityState(trial.active.copy(), state.work + work)
