"""The base class of the time integrators (scipy ``OdeSolver`` style).

An integrator sees a :class:`arlequin.problem.system.CoupledSystem` (mass, internal force, tangent,
external force at time t, constraint rows with multipliers), never meshes. :meth:`Integrator.step`
owns the time ``t``, the step sizes and the ``status``; it calls the scheme's ``_step_impl``.
The size of each step comes from a step controller (:mod:`arlequin.solvers.dynamics.controllers`) or
from the caller (``step(dt)``), shortened to land exactly on the requested stop times.

State is committed, never mutated: model states at quadrature points and unilateral constraint
states are immutable records returned as trial values and committed once a step is accepted, so
that :meth:`Integrator.snapshot` / :meth:`Integrator.restore` redo a step or restart a run.
"""

from __future__ import annotations

import bisect
import copy
import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from ...contract import (
    ContractError,
    SimulationError,
    StateError,
    UnilateralConstraint,
    is_unilateral,
)
from ...linalg.timing import SWITCH
from ...linalg.vector_updates import sum_of_squares
from ...problem.system import CoupledSystem, LinearConstraint
from ..system.operators import SystemOperators, as_system, as_vector
from ..system.rows import EqualityRows, consistent_initial_state, scatter_active, stack_active
from .controllers import StepController, as_controller, check_step

__all__ = ["STATUSES", "Integrator", "IntegratorSnapshot"]

logger = logging.getLogger(__name__)

#: Values of :attr:`Integrator.status`.
STATUSES = ("running", "finished", "failed")

#: Relative tolerance (of the step) within which a time counts as a stop time.
_LANDING = 1e-9


class _ActiveLevels(NamedTuple):
    """The levels of stacked active rows, kept for their counts per constraint."""

    counts: tuple[int, ...]
    displacement: np.ndarray  # (m_A,) bool, read-only: a displacement-level row
    any_displacement: bool


@dataclass(frozen=True)
class IntegratorSnapshot:
    """Everything an integrator needs to continue from a time (see :meth:`Integrator.snapshot`).

    Attributes
    ----------
    t : float
        Time (s).
    step_count : int
    fields : dict
        The integrator's state variables (copies of arrays; model and constraint states are
        immutable and shared).
    """

    t: float
    step_count: int
    fields: dict[str, Any]
    scheme: str = ""
    n_dofs: int = 0


class Integrator:
    """Base class of the time integrators.

    Parameters
    ----------
    system : CoupledSystem or ArlequinProblem
        Blocks, equality constraints (``system.constraints``) and loads.
    dt : float, optional
        Time step (s) of a :class:`~arlequin.solvers.FixedStep` controller. Default: the
        scheme's default controller (the explicit scheme: 0.9 × the critical step of the coupled
        system; the implicit schemes: the same step).
    t0 : float
        Initial time (s).
    u0, v0 : ndarray (n,) or dict {block: array}, optional
        Initial displacement (m) and velocity (m/s) of each model; missing blocks are zero.
    constraints : sequence, optional
        Extra constraints: :class:`~arlequin.problem.system.LinearConstraint` rows or
        :class:`~arlequin.contract.UnilateralConstraint` objects (unilateral objects found in
        ``system.constraints`` are used as well).
    step_controller : StepController, float or callable, optional
        Chooses each step (see :mod:`arlequin.solvers.dynamics.controllers`); overrides ``dt``.
    consistent_initial : bool
        Project u0 and v0 (mass metric) onto the equality rows (coupling-consistent initial
        conditions); the correction's size is logged.
    check_finite : bool
        Raise :class:`~arlequin.contract.SimulationError` as soon as a displacement or velocity
        is NaN or overflows.
    lumped : bool, optional
        Row-sum lumped mass (default: the scheme's).
    max_status_iterations : int, optional
        Cap on the status iterations of the unilateral constraints per step (default: the
        largest ``max_iterations`` of the constraints).

    Attributes
    ----------
    t : float
        Current time (s).
    dt : float
        Size (s) of the next step.
    step_size : float or None
        Size (s) of the last step taken (None before the first).
    status : {"running", "finished", "failed"}
        ``"finished"`` once the last stop time (:meth:`set_stops`) is reached.
    u, v, a : ndarray, shape (n,)
        Displacement (m), velocity (m/s), acceleration (m/s²) at ``t``.
    states : dict
        Block name -> committed state per block term.
    constraint_states : dict
        Unilateral constraint name -> its committed state.
    step_count : int
    multipliers : dict
        Constraint name -> multipliers (N) at ``t`` (a step quantity for the θ-scheme).
    """

    name = "base"
    lumped_default = False
    #: Whether the scheme applies the trials' prescribed multipliers (``applied``, slip friction).
    applies_multipliers = False
    #: BLAS threads during :func:`~arlequin.solvers.solve`'s loop (None: as they are).
    blas_threads: int | None = None

    def __init__(
        self,
        system: CoupledSystem,
        dt: float | None = None,
        *,
        t0: float = 0.0,
        u0: Any = None,
        v0: Any = None,
        constraints: Sequence[Any] = (),
        step_controller: Any = None,
        consistent_initial: bool = True,
        check_finite: bool = True,
        lumped: bool | None = None,
        max_status_iterations: int | None = None,
        tangent: str = "consistent",
    ) -> None:
        system = as_system(system)
        self.system = system
        self.ops = SystemOperators(
            system, self.lumped_default if lumped is None else lumped, tangent=tangent
        )
        all_constraints = list(system.constraints) + list(constraints)
        self.unilateral: list[UnilateralConstraint] = self._unilateral_of(all_constraints)
        self.rows = self._equality_rows([c for c in all_constraints if not is_unilateral(c)])
        names = [c.name for c in self.unilateral] + list(self.rows.slices)
        if len(set(names)) != len(names):
            raise ValueError(f"constraint names must be unique, got {names}")
        caps = [c.max_iterations for c in self.unilateral]
        self.max_status_iterations = int(max_status_iterations or (max(caps) if caps else 1))
        self.check_finite = bool(check_finite)
        self._init_clock(t0)
        self.controller: StepController = self._controller_of(dt, step_controller)
        self.dt = self._checked_step(self.controller.propose(self))
        u = as_vector(u0, system, "u0 (initial displacement)")
        v = as_vector(v0, system, "v0 (initial velocity)")
        if consistent_initial and self.rows.m:
            u, v = consistent_initial_state(self.rows, self.ops, self.t, self.dt, u, v)
        self.u = u
        self.v = v
        self.a = np.zeros_like(u)
        self.constraint_states = {c.name: c.initial_state(u, v) for c in self.unilateral}
        self._stack_cache: dict = {}  # stack_active's last stacked rows
        # whether the last active rows (_active) had a displacement-level row: their impulse
        # right-hand side needs G_A u then
        self._active_displacement_rows = False
        self._initialize()

    def _unilateral_of(self, all_constraints: list[Any]) -> list[UnilateralConstraint]:
        """The unilateral constraints of ``all_constraints``, each checked to be either
        :class:`LinearConstraint` rows or a unilateral constraint this scheme can run."""
        for k, c in enumerate(all_constraints):
            if not (isinstance(c, LinearConstraint) or is_unilateral(c)):
                raise ContractError(
                    f"constraint {k} is a {type(c).__name__}: give LinearConstraint rows or "
                    "objects of the UnilateralConstraint protocol (arlequin.contract)"
                )
        unilateral = [c for c in all_constraints if is_unilateral(c)]
        for c in unilateral:
            if getattr(c, "explicit_only", False) and not self.applies_multipliers:
                raise ValueError(
                    f"constraint {c.name!r} prescribes multipliers (slip friction): "
                    f"it runs with the explicit integrator, not {self.name!r}"
                )
        return unilateral

    def _init_clock(self, t0: float) -> None:
        """The initial time, the step counters and statuses, the states and the works."""
        self.t = float(t0)
        if not math.isfinite(self.t):
            raise ValueError(f"initial time must be finite, got t0={t0}")
        self.t0 = self.t
        self.step_count = 0
        self.status = "running"
        self.step_size: float | None = None
        self._t_err = 0.0
        self.t_stops = np.zeros(0)
        self.states = self.ops.initial_states()
        self.status_iterations = 0
        self.n_status_failures = 0
        self.critical_dt: float | None = None
        nb = len(self.ops.blocks)
        self._w_ext = np.zeros(nb)
        self._w_coupling = np.zeros(nb)
        self._w_constraint = np.zeros(nb)
        self._w_internal = np.zeros(nb)
        self._w_damping = np.zeros(nb)
        self.multipliers: dict[str, np.ndarray] = {}

    def _controller_of(self, dt: float | None, step_controller: Any) -> StepController:
        """The step controller: ``step_controller``, else a fixed ``dt``, else the scheme's."""
        controller = as_controller(step_controller)
        if controller is None:
            controller = as_controller(dt) if dt is not None else self._default_controller()
        return controller

    # ------------------------------------------------------------------ scheme hooks
    def _equality_rows(self, constraints: list[LinearConstraint]) -> EqualityRows:
        """The equality rows the scheme uses (the explicit one's in its impulse basis)."""
        return EqualityRows(constraints, self.ops)

    def _default_controller(self) -> StepController:
        raise NotImplementedError

    def _check_step_size(self, dt: float) -> float:
        """Scheme-specific check of a step size (the explicit scheme: the stability limit)."""
        return dt

    def _initialize(self) -> None:
        raise NotImplementedError

    def _step_impl(self) -> None:
        """Advance from t by self.dt; commit t, u, v, a, states; set the next self.dt."""
        raise NotImplementedError

    def _phase_advanced(self) -> None:
        """Called once a step is committed, before the next step size is chosen (a
        multi-time-step scheme counts its fine steps here)."""

    def _step_size_changed(self) -> None:
        """Called after :meth:`set_step_size` changed the next step (explicit: redo the
        impulse that depends on it)."""

    # ------------------------------------------------------------------ step sizes and stops
    def _checked_step(self, dt: float) -> float:
        return self._check_step_size(check_step(dt))

    def set_stops(self, times: Sequence[float]) -> None:
        """Times (s) that steps must land on exactly (output times and the end time).

        The step that would cross a stop is shortened to reach it (and a step that would leave
        a sliver before it is split in two equal steps). ``status`` becomes ``"finished"`` at the
        last stop. The next step is re-chosen.
        """
        stops = np.unique(np.asarray(times, dtype=float).ravel())
        if stops.size and not np.all(np.isfinite(stops)):
            raise ValueError(f"stop times must be finite, got {stops[~np.isfinite(stops)]}")
        self.t_stops = stops[stops > self.t + _LANDING * self.dt]
        if self.t_stops.size:
            self.status = "running"
        dt = self._clip(self.dt)
        if dt != self.dt:
            self.set_step_size(dt)

    @property
    def t_stops(self) -> np.ndarray:
        """The stop times ahead (s), sorted, shape (k,) (:meth:`set_stops`)."""
        return self._t_stops

    @t_stops.setter
    def t_stops(self, stops: np.ndarray) -> None:
        self._t_stops = stops
        # the same times as a list of floats: the step looks its next stop up by bisection
        # (the array comparisons and masks took 5% of a Taylor bar's step)
        self._stop_list = [float(s) for s in stops]

    def _next_stop(self) -> float | None:
        stops = self._stop_list
        if not stops or stops[-1] <= self.t:
            return None
        # the first stop after t + tolerance, as the mask t_stops > t + tolerance finds it
        i = bisect.bisect_right(stops, self.t + _LANDING * max(self.dt, 1e-300))
        return stops[i] if i < len(stops) else None

    def _on_stop(self) -> bool:
        """Whether t is one of the stop times exactly."""
        stops = self._stop_list
        i = bisect.bisect_left(stops, self.t)
        return i < len(stops) and stops[i] == self.t

    def _clip(self, dt: float) -> float:
        stop = self._next_stop()
        if stop is None:
            return dt
        remaining = stop - self.t
        if abs(remaining - dt) <= _LANDING * dt:
            return dt  # lands on the stop (t is snapped there)
        if remaining <= dt * (1.0 + 1e-6):
            return remaining  # shortened, or a round-off longer: lands on the stop
        if remaining < 2.0 * dt:
            return 0.5 * remaining  # two equal steps rather than a sliver
        return dt

    def _next_step_size(self) -> float:
        """The controller's proposal for the step from the current t, clipped to the stops."""
        return self._check_step_size(self._clip(check_step(self.controller.propose(self))))

    def _end_time(self) -> float:
        """Time reached by a step of size self.dt from t, snapped onto a stop within tolerance."""
        # compensated (Kahan) sum of the steps: t does not drift over millions of steps
        t_new = self.t + (self.dt - self._t_err)
        stop = self._next_stop()
        if stop is not None and abs(t_new - stop) <= _LANDING * self.dt:
            return stop
        return t_new

    def set_step_size(self, dt: float) -> None:
        """Impose the size (s) of the next step (the controller proposes the ones after it)."""
        dt = self._checked_step(dt)
        if dt != self.dt:
            self.dt = dt
            self._step_size_changed()

    def reset_dt(self, dt: float) -> None:
        """Alias of :meth:`set_step_size` (kept from earlier versions; now allowed at any time)."""
        self.set_step_size(dt)

    # ------------------------------------------------------------------ stepping
    def step(self, dt: float | None = None) -> None:
        """Advance one time step (of size ``dt`` if given, else the controller's).

        Raises
        ------
        SimulationError
            If the new displacement or velocity is not finite (NaN or overflow), or a model
            reports an invalid state (:class:`~arlequin.contract.StateError`, e.g. an inverted
            cell). The integrator keeps its last committed state, so the step can be retried
            (``step(dt)`` with another size) or the run restored from a snapshot.
        """
        if self.status == "failed":
            raise RuntimeError(f"{self.name}: cannot step a failed integrator (restore a snapshot)")
        if self.status == "finished":
            raise RuntimeError(
                f"{self.name}: finished at t = {self.t:.6e} s, the last stop time "
                "(set_stops with later times to go on)"
            )
        # the clock first: a new step size redoes the impulse at t (explicit), timed parts
        # counted in the step they belong to
        timer = SWITCH.timer
        tic = timer.clock() if timer is not None else 0.0
        if dt is not None:
            self.set_step_size(dt)
        t_next = self.t + self.dt
        t_old, dt_step, err = self.t, self.dt, self._t_err
        try:
            self._step_impl()
        except StateError as err:
            raise SimulationError(
                f"{self.name}: {err} at step {self.step_count + 1}, t = {t_next:.6e} s "
                f"(dt = {self.dt:.6e} s)",
                self.step_count + 1,
                t_next,
            ) from err
        landed = self._on_stop()
        self._t_err = 0.0 if landed else (self.t - t_old) - (dt_step - err)
        if self._stop_list and self.t >= self._stop_list[-1]:
            self.status = "finished"
        if timer is not None:
            timer.end_step(timer.clock() - tic)

    def _check_finite(self, t_new: float, *arrays: np.ndarray, step: int | None = None) -> None:
        """Raise SimulationError if any array has a NaN or would overflow its energy (``step``:
        the step's number, default the next one)."""
        if not self.check_finite:
            return
        step = self.step_count + 1 if step is None else int(step)
        # Σx²: NaN, ±inf and values whose energy would overflow all make it non-finite
        if not math.isfinite(sum_of_squares(*arrays)):
            raise SimulationError(
                f"{self.name}: non-finite displacement or velocity (NaN or overflow) at step "
                f"{step}, t = {t_new:.6e} s (dt = {self.dt:.6e} s)",
                step,
                t_new,
            )

    # ------------------------------------------------------------------ snapshots
    _SNAPSHOT_FIELDS: tuple[str, ...] = (
        "t", "_t_err", "dt", "step_size", "status", "u", "v", "a", "states", "constraint_states",
        "multipliers", "status_iterations", "n_status_failures", "_w_ext", "_w_coupling",
        "_w_constraint", "_w_internal", "_w_damping",
    )  # fmt: skip

    def _scheme_fields(self) -> tuple[str, ...]:
        """Names of the scheme's own state variables (besides the common ones)."""
        return ()

    def snapshot(self) -> IntegratorSnapshot:
        """A copy of the integrator's state at ``t`` (restore it with :meth:`restore`)."""
        fields = {}
        for name in (*self._SNAPSHOT_FIELDS, *self._scheme_fields()):
            val = getattr(self, name)
            fields[name] = val.copy() if isinstance(val, np.ndarray) else copy.copy(val)
        fields["controller"] = copy.deepcopy(self.controller)
        return IntegratorSnapshot(
            self.t, self.step_count, fields, type(self).__name__, int(self.ops.n)
        )

    def restore(self, snap: IntegratorSnapshot) -> None:
        """Return to a snapshot's state (the run then continues from its time).

        Raises
        ------
        ValueError
            If the snapshot was taken from another scheme or a system of another size.
        """
        if snap.scheme != type(self).__name__ or snap.n_dofs != self.ops.n:
            raise ValueError(
                f"snapshot of a {snap.scheme} on {snap.n_dofs} dofs cannot be restored into a "
                f"{type(self).__name__} on {self.ops.n} dofs"
            )
        for name, val in snap.fields.items():
            setattr(self, name, val.copy() if isinstance(val, np.ndarray) else copy.copy(val))
        self.step_count = snap.step_count
        self.t = snap.t
        if self.status == "failed":
            self.status = "running"

    # ------------------------------------------------------------------ unilateral rows
    def _begin_unilateral(self, t: float, dt: float, u: np.ndarray, v: np.ndarray) -> list[Any]:
        """Trials of every unilateral constraint for a step from t of size dt."""
        return [c.begin_step(self.constraint_states[c.name], t, dt, u, v) for c in self.unilateral]

    def _active(self, trials: Sequence[Any]):
        """(G_A, rhs_A, active index lists, row levels is-displacement) of the trials."""
        cache = self._stack_cache
        g_a, rhs_a, idx = stack_active(trials, self.ops.n, cache)
        if not idx:
            self._active_displacement_rows = False
            return g_a, rhs_a, idx, np.zeros(0, dtype=bool)
        # the rows' levels for the same numbers of active rows per constraint kept, read-only,
        # with whether any is a displacement-level row (``_active_displacement_rows``)
        counts = tuple(a.size for a in idx)
        levels = cache.get("levels")
        if levels is None or levels.counts != counts:
            disp = np.concatenate(
                [np.full(a.size, c.level == "displacement") for c, a in zip(self.unilateral, idx)]
            )
            disp.flags.writeable = False
            levels = cache["levels"] = _ActiveLevels(counts, disp, bool(disp.any()))
        self._active_displacement_rows = levels.any_displacement
        return g_a, rhs_a, idx, levels.displacement

    def _full_multipliers(self, lam_a: np.ndarray, idx: Sequence[np.ndarray]) -> list[np.ndarray]:
        return scatter_active(lam_a, idx, [c.n_rows for c in self.unilateral])

    def _update_statuses(self, trials: list[Any], u: np.ndarray, v: np.ndarray,
                         lams: Sequence[np.ndarray]) -> tuple[list[Any], bool]:  # fmt: skip
        new = [c.update_status(tr, u, v, lam) for c, tr, lam in zip(self.unilateral, trials, lams)]
        return new, any(tr.changed for tr in new)

    def _status_cap_reached(self, t_new: float) -> None:
        self.n_status_failures += 1
        logger.warning(
            "%s: unilateral statuses still changing after %d iterations at step %d, t = %.6e s",
            self.name, self.max_status_iterations, self.step_count + 1, t_new,
        )  # fmt: skip

    def _commit_unilateral(
        self,
        trials: Sequence[Any],
        t: float,
        u: np.ndarray,
        v_before: np.ndarray,
        v_after: np.ndarray,
        lams: Sequence[np.ndarray],
        impulses: Sequence[np.ndarray],
        states: dict[str, Any] | None = None,
    ) -> dict[str, Any]:
        """The constraints' committed states after an accepted step (a new dict).

        ``lams``: the step's reported multipliers per constraint; ``impulses``: their time
        integrals over the step (N·s per unit of the rows), from which the work is computed.
        """
        base = self.constraint_states if states is None else states
        out = dict(base)
        for c, tr, lam, imp in zip(self.unilateral, trials, lams, impulses):
            try:
                out[c.name] = c.commit(
                    base[c.name], tr, t=t, u=u, v_before=v_before, v_after=v_after,
                    multipliers=lam, impulse=imp,
                )  # fmt: skip
            except SimulationError as err:
                # the explicit scheme commits its impulse at the time the step has reached
                in_step = t != self.t or self.step_count == 0
                err.step = self.step_count + 1 if in_step else self.step_count
                raise
        return out

    # ------------------------------------------------------------------ energies
    def energies(self) -> dict[str, dict[str, float]]:
        """Current energies and accumulated works per block (J).

        Returns
        -------
        dict
            ``{"kinetic", "kinetic_full_step", "strain", "stored", "dissipation",
            "external_work", "coupling_work", "constraint_work", "damping_work"}``, block name
            -> float. ``kinetic`` is the scheme's energy form (central differences:
            ½ ṽ^{n−½}·M v^{n+½}, whose balance closes to round-off for linear systems),
            ``kinetic_full_step`` ½ vᵀM v of v at t. ``strain``: ½ uᵀK u of linear blocks, the
            accumulated work of the internal forces of nonlinear ones; ``stored`` and
            ``dissipation``: the models' own stored energy and plastic dissipation of their
            committed states where they offer them (optional members ``stored_energy_of_state``
            and ``plastic_dissipation``, see :meth:`SystemOperators.stored_and_dissipated`),
            else ``strain`` and 0.
        """
        names = self.ops.names
        kin = self._kinetic()
        full = self.ops.kinetic(self.v)
        strain = self.ops.strain_linear(self.u)
        lin = np.asarray(self.ops.block_linear)
        stored, dissipated = self.ops.stored_and_dissipated(self.states, self._w_internal)
        stored = np.where(lin, strain, stored)
        strain = np.where(lin, strain, self._w_internal)
        w_ext, w_coupling, w_constraint = self._works()
        return {
            "kinetic": dict(zip(names, kin.tolist())),
            "kinetic_full_step": dict(zip(names, full.tolist())),
            "strain": dict(zip(names, strain.tolist())),
            "stored": dict(zip(names, stored.tolist())),
            "dissipation": dict(zip(names, dissipated.tolist())),
            "external_work": dict(zip(names, w_ext.tolist())),
            "coupling_work": dict(zip(names, w_coupling.tolist())),
            "constraint_work": dict(zip(names, w_constraint.tolist())),
            "damping_work": dict(zip(names, self._damping_work().tolist())),
        }

    def _kinetic(self) -> np.ndarray:
        """The scheme's kinetic energy per block (J); default ½ vᵀM v of the velocity at t."""
        return self.ops.kinetic(self.v)

    def _works(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Accumulated external, coupling and other-constraint works per block up to t (J)."""
        return self._w_ext, self._w_coupling, self._w_constraint

    def _damping_work(self) -> np.ndarray:  # (J) per block, ≤ 0; RayleighDamping's
        return self._w_damping

    def total_energy(self) -> float:
        """Σ_b T_b + U_b (J)."""
        e = self.energies()
        return float(sum(e["kinetic"].values()) + sum(e["strain"].values()))
