"""Constraint protocol of the dynamic integrators.

Two families of constraint rows enter every integrator through Lagrange multipliers:

*Equality rows* (:class:`arlequin.system.LinearConstraint`): ``B u = g(t)`` at displacement level
or ``B v = g(t)`` at velocity level. Arlequin mediator equations (``kind="coupling"``), Dirichlet
conditions (``kind="dirichlet"``) and prescribed velocities are of this kind. Their rows are fixed
for the whole run, so the integrators factorise what depends on them once.

*Unilateral rows* (:class:`UnilateralConstraint`): a set of candidate rows ``G`` (m×n) of which
only the currently *active* ones are enforced as equalities (at the constraint's ``level``); the
multipliers of the inactive rows are zero. The active set is decided inside each time step by the
constraint object itself: the integrator solves the step's constrained problem with the current
statuses, passes the predicted end-of-step displacement, velocity and multipliers to
:meth:`UnilateralConstraint.update_status`, and repeats the constrained solve until no status
changes or a cap on the iterations is reached (the count is recorded; reaching the cap is logged
and counted, not fatal). This is the primal–dual active-set / indicator fixed point of the
level-set (Signorini–Moreau) contact model of ``docs/dynamics.md``.

Sign convention (all constraints)
---------------------------------
The force a constraint exerts on the system is ``−Bᵀλ`` (N), with ``λ`` the multiplier reported by
the integrators, as in the static saddle point ``K u + Bᵀλ = f``. For an inequality ``G u ≤ h``
the admissible multipliers are ``λ ≥ 0``. A contact model that wants the pressure to be negative
(``λ ≤ 0``, ``docs/DESIGN`` §3) passes the rows ``−G`` instead.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp

__all__ = ["LinearInequality", "UnilateralConstraint", "is_unilateral"]

logger = logging.getLogger(__name__)


def is_unilateral(constraint: object) -> bool:
    """Whether a constraint object follows the unilateral protocol (has ``update_status``)."""
    return callable(getattr(constraint, "update_status", None))


class UnilateralConstraint:
    """Base class of constraints whose active rows are decided inside each time step.

    Subclasses implement :meth:`matrix`, :meth:`rhs` and :meth:`update_status`; they may override
    :meth:`begin_step` (update the geometry, guess the statuses) and :meth:`end_step` (commit).

    Parameters
    ----------
    name : str
        Name used in reports and in the multiplier histories.
    level : {"velocity", "displacement"}
        Whether an active row enforces ``G v = rhs(t)`` on the end-of-step velocity or
        ``G u = rhs(t)`` on the end-of-step displacement.
    max_iterations : int
        Cap on the status iterations of one step (the integrator uses the largest cap of its
        unilateral constraints).
    kind : str
        Reporting group of the constraint work (default ``"contact"``).

    Attributes
    ----------
    active : ndarray of bool, shape (m,)
        Current statuses (True: the row is enforced as an equality).
    iterations : int
        Status iterations used by the last step.
    """

    def __init__(
        self,
        name: str = "unilateral",
        level: str = "velocity",
        max_iterations: int = 25,
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
        self.iterations = 0
        self._active: np.ndarray | None = None

    # ------------------------------------------------------------------ rows
    @property
    def n_rows(self) -> int:
        """Number of candidate rows m."""
        return int(self.matrix().shape[0])

    def matrix(self) -> sp.csr_matrix:
        """Candidate rows G, shape (m, n), in the current configuration."""
        raise NotImplementedError

    def rhs(self, t: float) -> np.ndarray:
        """Right-hand side of the active rows at time ``t`` (s), shape (m,) (m or m/s)."""
        return np.zeros(self.n_rows)

    @property
    def active(self) -> np.ndarray:
        if self._active is None:
            self._active = np.zeros(self.n_rows, dtype=bool)
        return self._active

    @active.setter
    def active(self, value: np.ndarray) -> None:
        self._active = np.asarray(value, dtype=bool).copy()

    # ------------------------------------------------------------------ step protocol
    def begin_step(self, t: float, dt: float, u: np.ndarray, v: np.ndarray) -> None:
        """Called once per step before the first constrained solve.

        Parameters
        ----------
        t : float
            Time at the start of the step (s).
        dt : float
            Time step (s).
        u, v : ndarray, shape (n,)
            Displacement (m) and velocity (m/s) at the start of the step.
        """

    def update_status(self, u: np.ndarray, v: np.ndarray, multipliers: np.ndarray) -> bool:
        """Update :attr:`active` from the predicted end-of-step quantities.

        Parameters
        ----------
        u, v : ndarray, shape (n,)
            Predicted end-of-step displacement (m) and velocity (m/s) obtained with the current
            statuses.
        multipliers : ndarray, shape (m,)
            Multipliers (N) of all candidate rows, zero on the inactive ones.

        Returns
        -------
        bool
            True if any status changed (the integrator then repeats the constrained solve).
        """
        raise NotImplementedError

    def end_step(self, t: float, u: np.ndarray, v: np.ndarray, multipliers: np.ndarray) -> None:
        """Called once the step is accepted (t is the end-of-step time, s)."""


class LinearInequality(UnilateralConstraint):
    """Unilateral rows ``G u ≤ h(t)`` with multipliers ``λ ≥ 0`` (force on the system −Gᵀλ).

    A minimal, complete implementation of the protocol (rigid obstacles, gaps between nodes).

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
    level, name, max_iterations : see :class:`UnilateralConstraint`
    gap_tol : float
        Gap tolerance (m).
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
        super().__init__(name=name, level=level, max_iterations=max_iterations, kind=kind)
        self._g = sp.csr_matrix(matrix)
        self._bound = bound
        self.gap_tol = float(gap_tol)

    def matrix(self) -> sp.csr_matrix:
        return self._g

    def bound(self, t: float) -> np.ndarray:
        """h(t), shape (m,) (m)."""
        b = self._bound(t) if callable(self._bound) else self._bound
        return np.broadcast_to(np.asarray(b, dtype=float), (self._g.shape[0],)).copy()

    def rhs(self, t: float) -> np.ndarray:
        if self.level == "displacement":
            return self.bound(t)
        return np.zeros(self._g.shape[0])

    def update_status(self, u: np.ndarray, v: np.ndarray, multipliers: np.ndarray) -> bool:
        old = self.active.copy()
        lam = np.asarray(multipliers, dtype=float)
        if self.level == "displacement":
            gap = self._g @ u - self._pending_bound
            new = np.where(old, lam >= 0.0, gap > self.gap_tol)
        else:
            approach = self._g @ v > 0.0
            new = self._closed & np.where(old, lam >= 0.0, approach)
        self.active = new
        return bool(np.any(new != old))

    def begin_step(self, t: float, dt: float, u: np.ndarray, v: np.ndarray) -> None:
        # the bound at the end of the step, used by update_status
        self._pending_bound = self.bound(t + dt)
        if self.level == "velocity":
            # S_d: the gap predicted with the step's free velocity, fixed during the iterations
            self._closed = self._g @ (u + dt * v) - self._pending_bound >= -self.gap_tol
            self.active = self.active & self._closed
