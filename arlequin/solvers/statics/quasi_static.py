"""Quasi-static analysis: load stepping with full Newton on the coupled saddle point.

A load factor λ (a pseudo-time) is raised from ``t0`` to ``load`` in steps; each step solves

    [K_T(u)  Bᵀ] [Δu]     [f_int(u) + Bᵀμ − f_ext(λ)]
    [B       0 ] [Δμ] = − [B u − g(λ)                ]

by Newton's method with the consistent tangent of every model (capability ``"tangent"`` of
:mod:`arlequin.contract`), weighted by the partition weights like every other term; B holds
every equality row but the Dirichlet rows, whose dofs are eliminated (their values prescribed,
their reactions computed). ``proportional=True`` (the default) scales the loads and prescribed
values of the system at λ = 1: f_ext(λ) = λ f_ext(1), g(λ) = λ g(1); with ``proportional=False``
they are the system's own functions of time evaluated at t = λ (a non-proportional path, such
as loading then unloading, given by the loads' amplitudes).

A step is committed only when Newton converges: the relative residual (the equilibrium
residual's norm over that of the external forces and the reactions, and the constraint
residual over its own scale) below ``tol``. A backtracking line search on the residual norm
guards each Newton update. When Newton does not converge in ``max_iterations`` or a model
raises :class:`~arlequin.contract.StateError` (an inverted cell), the step is cut (halved) and
computed again from the committed state; after ``easy_iterations`` or fewer iterations the
next step grows back (× ``growth``, never beyond the nominal step). When the step cannot be cut
further (``min_step``), the run stops and says why: a limit load (the structure's load-carrying
capacity: the incremental stiffness had dropped, or the tangent became singular), a
``StateError``, or a Newton failure. Linear blocks (the coarse elastic models) are condensed
once for the whole run (:mod:`arlequin.solvers.statics.condensation`): each Newton iteration factors
only the nonlinear blocks and the multipliers. The factorisations use a sparse direct solver
(``linear_solver``: SuperLU, or PARDISO where pypardiso is installed, which keeps its symbolic
analysis from one iteration of a load step to the next: :mod:`arlequin.linalg.direct`).

Timings (failed attempts included) in :attr:`QuasiStaticSolver.timings`. The coarse stress
outside the patches and the gluing bands are watched (``CoarseYieldWarning``,
``BandYieldWarning``). Units: SI.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ...contract import StateError
from ...linalg.direct import resolve_linear_solver
from ..system.constraints import is_unilateral
from ..system.operators import SystemOperators, as_system, as_vector
from ..system.yield_watch import UNWATCHED, BandYieldWatch
from .adaptive import AdaptableSolver, run_adaptive
from .condensation import SaddleSolver
from .quasi_static_result import (
    STATUSES,
    CoarseYieldWatch,
    IterationTracker,
    NewtonError,
    NewtonIteration,
    QuasiStaticResult,
    QuasiStaticStep,
)

__all__ = [
    "STATUSES",
    "NewtonError",
    "NewtonIteration",
    "QuasiStaticResult",
    "QuasiStaticSolver",
    "QuasiStaticStep",
    "solve_quasi_static",
]

logger = logging.getLogger(__name__)

#: Below this ratio of the current incremental stiffness to the first step's, a load that
#: cannot increase is reported as a limit load (Bergan's current stiffness parameter).
LIMIT_STIFFNESS_RATIO = 0.05


class _StepFailed(Exception):
    """A load step did not converge (internal: the step is cut)."""

    def __init__(self, reason: str, kind: str) -> None:
        super().__init__(reason)
        self.kind = kind  # "newton", "state", "singular"


class QuasiStaticSolver(AdaptableSolver):
    """Load stepping with Newton on a coupled system (see the module docstring).

    Parameters
    ----------
    system : CoupledSystem, ArlequinProblem or model
    load : float
        The target load factor λ_end (> t0).
    steps : int
        Number of equal load steps from t0 to ``load`` (≥ 1): the nominal step.
    proportional : bool
        Scale the loads and prescribed values at λ = 1 (True), or evaluate the system's own
        functions of time at t = λ (False).
    tol : float
        Relative residual at which Newton stops.
    max_iterations : int
        Newton iterations before the step is cut.
    min_step : float, optional
        Smallest Δλ before the run stops (default the nominal step / 2¹⁰).
    growth : float
        Factor of the next step after an easy one (≤ ``easy_iterations`` iterations).
    easy_iterations : int
    line_search : bool
        Backtracking on the residual norm (at most ``max_backtracks`` halvings).
    condense : bool
        Condense the linear blocks once (True) or factor the whole saddle point at every
        iteration (False, the reference).
    linear_solver : {"auto", "superlu", "pardiso"}
        The sparse direct solver of the Newton systems (:mod:`arlequin.linalg.direct`):
        ``"auto"`` is PARDISO where the optional pypardiso is installed, else SuperLU.
    reference_time : float
        With ``proportional``, the time (s) at which the system's loads and prescribed values
        are taken as those of λ = 1 (default 1).
    t0, u0, states :
        Start (default λ = 0, zero displacement, the models' initial states).
    restore : dict, optional
        A :meth:`checkpoint` of an interrupted run of the same problem and options: the solver
        continues from its last converged step, with the same steps and values as the
        uninterrupted run.

    Attributes
    ----------
    timings : dict
        Seconds (wall time) spent in :meth:`step` so far: ``"constitutive_and_tangent_s"``
        (internal forces, return maps, tangent assembly), ``"factorisation_s"``, ``"solve_s"``
        and ``"other_s"`` (the rest); see the module docstring.
    """

    def __init__(
        self,
        system: Any,
        load: float = 1.0,
        steps: int = 10,
        proportional: bool = True,
        tol: float = 1e-10,
        max_iterations: int = 25,
        min_step: float | None = None,
        growth: float = 1.5,
        easy_iterations: int = 4,
        line_search: bool = True,
        max_backtracks: int = 6,
        condense: bool = True,
        linear_solver: str = "auto",
        reference_time: float = 1.0,
        t0: float = 0.0,
        u0: Any = None,
        states: dict[str, list[Any]] | None = None,
        restore: dict[str, Any] | None = None,
    ) -> None:
        self.system = as_system(system)
        _check_inputs(load, steps, tol, max_iterations, growth, t0)
        unilateral = [c for c in self.system.constraints if is_unilateral(c)]
        if unilateral:
            raise ValueError(
                f"the quasi-static solver takes equality constraints only, got the unilateral "
                f"constraint {type(unilateral[0]).__name__}: contact needs a dynamic integrator"
            )
        resolve_linear_solver(linear_solver)  # a bad name before any work
        self.load, self.t0 = float(load), float(t0)
        self.nominal = (self.load - self.t0) / int(steps)
        self.min_step = float(min_step) if min_step is not None else self.nominal / 2**10
        if not (self.min_step > 0.0 and self.min_step <= self.nominal):
            raise ValueError(f"min_step must lie in (0, {self.nominal}], got {min_step}")
        self.proportional, self.tol = bool(proportional), float(tol)
        self.reference_time = float(reference_time)
        self.max_iterations, self.growth = int(max_iterations), float(growth)
        self.easy_iterations, self.line_search = int(easy_iterations), bool(line_search)
        self.max_backtracks = int(max_backtracks)
        self.ops = SystemOperators(self.system, lumped=False, with_mass=False)
        self.ops.check_tangents("the quasi-static solver")
        self.condense = bool(condense)
        self.linear_solver = linear_solver
        self.saddle = SaddleSolver(self.system, self.ops, condense=condense,
                                   linear_solver=linear_solver)  # fmt: skip
        self._timers = {"constitutive_and_tangent_s": 0.0, "step_s": 0.0}
        self.t = self.t0
        self.u = as_vector(u0, self.system, "u0")
        self.states = states if states is not None else self.ops.initial_states()
        self.mu = np.zeros(self.saddle.n_multipliers)
        self.dt = self.nominal
        self.history: list[QuasiStaticStep] = []
        self._previous: tuple[np.ndarray, np.ndarray, float] | None = None
        self._first_stiffness: float | None = None
        self._last_stiffness: float | None = None
        self.status = "running"
        self.band_watch = BandYieldWatch(lambda: self.system)  # the drivers call it
        if restore is not None:
            self._restore(restore)

    # -- loads -------------------------------------------------------------------------------
    def external_force(self, lam: float) -> np.ndarray:
        """f_ext(λ) (N), shape (n,)."""
        if self.proportional:
            return lam * self.system.external_force(self.reference_time)
        return self.system.external_force(lam)

    def prescribed(self, lam: float) -> tuple[np.ndarray, np.ndarray]:
        """The Dirichlet values and the other rows' right-hand sides at λ."""
        t = self.reference_time if self.proportional else lam
        scale = lam if self.proportional else 1.0
        fixed, g = self.saddle.rhs_at(t)
        return scale * fixed, scale * g

    # -- residuals ---------------------------------------------------------------------------
    def _residual_of(self, f_int, u, mu, lam):
        f_ext = self.external_force(lam)
        _, g = self.prescribed(lam)
        sad = self.saddle
        bt_mu = sad.b.T @ mu if sad.n_multipliers else np.zeros_like(u)
        r = f_int + bt_mu - f_ext
        r_free = r[sad.free]
        reactions = np.linalg.norm(r[sad.fixed]) if sad.fixed.size else 0.0
        scale = max(np.linalg.norm(f_ext), reactions, np.linalg.norm(bt_mu), 1e-300)
        rel = float(np.linalg.norm(r_free) / scale)
        rc = sad.b @ u - g if sad.n_multipliers else np.zeros(0)
        rel_c = 0.0
        if rc.size:
            cscale = max(np.linalg.norm(abs(sad.b) @ np.abs(u)), np.linalg.norm(g), 1e-300)
            rel_c = float(np.linalg.norm(rc) / cscale)
        # the parts (equilibrium, constraints) for the iterations' records; their max is tested
        return r_free, rc, max(rel, rel_c), (rel, rel_c)

    # -- one load step -----------------------------------------------------------------------
    def _newton(self, lam: float):
        """Newton at load factor ``lam`` from the committed state; returns the converged
        (u, μ, trial states, residual history, :class:`NewtonIteration` records) or raises
        :class:`_StepFailed`."""
        fixed_values, _ = self.prescribed(lam)
        # PARDISO's pivoting from this step's first tangent (a resumed run factorises alike)
        self.saddle.direct.renew_analysis()
        u, mu = self._predictor(lam)
        u[self.saddle.fixed] = fixed_values
        history: list[float] = []
        try:
            f_int, trial, kt = self._internal_force(u, tangent=True)
        except StateError as exc:
            raise _StepFailed(str(exc), "state") from exc
        r_free, rc, rel, _ = self._residual_of(f_int, u, mu, lam)
        track = IterationTracker(self.system, self.states, trial)
        for _ in range(self.max_iterations):
            history.append(rel)
            if not math.isfinite(rel):
                raise _StepFailed("non-finite residual", "newton")
            if rel <= self.tol:
                return u, mu, trial, history, track.records
            if _stagnates(history):
                raise _StepFailed(
                    f"Newton stagnates (relative residual {rel:.3e} after {len(history) - 1} "
                    "iterations, less than a decade in the last four)",
                    "newton",
                )
            try:
                du, dmu = self.saddle.solve(kt, -r_free, -rc)
            except np.linalg.LinAlgError as exc:
                raise _StepFailed(f"singular tangent: {exc}", "singular") from exc
            u, mu, f_int, trial, kt, s = self._update(u, mu, du, dmu, rel, lam)
            r_free, rc, rel, parts = self._residual_of(f_int, u, mu, lam)
            track.add(trial, rel, parts, s)
        history.append(rel)
        if rel <= self.tol:
            return u, mu, trial, history, track.records
        raise _StepFailed(
            f"Newton did not converge in {self.max_iterations} iterations (relative residual "
            f"{rel:.3e} > {self.tol:.1e})",
            "newton",
        )

    def _predictor(self, lam: float) -> tuple[np.ndarray, np.ndarray]:
        """The start of Newton: the last step's increment extrapolated to ``lam`` (the load
        path is smooth; from the committed state with no increment, the first iteration would
        see the elastic tangent of every point that was yielding), the committed state at the
        first step."""
        if self._previous is None:
            return self.u.copy(), self.mu.copy()
        u_prev, mu_prev, t_prev = self._previous
        ratio = (lam - self.t) / (self.t - t_prev)
        return self.u + ratio * (self.u - u_prev), self.mu + ratio * (self.mu - mu_prev)

    def _evaluate(self, u, lam, tangent: bool):
        """(f_int, trial states, tangent or None), or None where a model refuses u."""
        try:
            return self._internal_force(u, tangent)
        except StateError:
            return None

    def _internal_force(self, u, tangent: bool):
        """The models' internal forces (and tangent) at u from the committed states, timed."""
        t0 = time.perf_counter()
        try:
            return self.ops.internal_force(u, self.states, tangent=tangent)
        finally:
            self._timers["constitutive_and_tangent_s"] += time.perf_counter() - t0

    @property
    def timings(self) -> dict[str, float]:
        """Seconds spent in :meth:`step` so far, split (see the class docstring)."""
        split = {
            "constitutive_and_tangent_s": self._timers["constitutive_and_tangent_s"],
            "factorisation_s": self.saddle.direct.timings["factorisation_s"],
            "solve_s": self.saddle.direct.timings["solve_s"],
        }
        split["other_s"] = max(self._timers["step_s"] - sum(split.values()), 0.0)
        return split

    def _update(self, u, mu, du, dmu, rel, lam):
        """The Newton update u + s Δu, μ + s Δμ: s = 1, or with the line search the largest of
        1, 1/2, 1/4... that lowers the residual; returns it with f_int, the trial states and
        the tangent there, and s."""
        free = self.saddle.free
        s = 1.0
        for k in range(self.max_backtracks + 1):
            u_try = u.copy()
            u_try[free] += s * du
            mu_try = mu + s * dmu
            # the full step with its tangent (usually accepted); backtracking steps without
            evaluated = self._evaluate(u_try, lam, tangent=k == 0)
            if evaluated is None:
                if k == self.max_backtracks:
                    raise _StepFailed("every line-search step inverts a cell", "state")
                s *= 0.5
                continue
            f_int, trial, kt = evaluated
            if not self.line_search:
                break
            rel_try = self._residual_of(f_int, u_try, mu_try, lam)[2]
            if rel_try < rel or rel_try <= self.tol or k == self.max_backtracks:
                break
            s *= 0.5
        if kt is None:
            f_int, trial, kt = self._internal_force(u_try, tangent=True)
        return u_try, mu_try, f_int, trial, kt, s

    def step(self) -> QuasiStaticStep:
        """Advance by one load step (cut until it converges); commit it and return it.

        Raises
        ------
        NewtonError
            The step could not be cut further (a StateError or a Newton failure there, not a
            limit load: that sets ``status`` to ``"limit_load"`` and returns None).
        """
        t0 = time.perf_counter()
        try:
            return self._step()
        finally:
            self._timers["step_s"] += time.perf_counter() - t0

    def _step(self) -> QuasiStaticStep:
        cuts = 0
        while True:
            dt = min(self.dt, self.load - self.t)
            lam = self.t + dt
            if self.load - lam < 1e-12 * abs(self.load):
                lam = self.load
            try:
                u, mu, trial, history, records = self._newton(lam)
                break
            except _StepFailed as fail:
                if dt / 2.0 < self.min_step * (1.0 - 1e-12):
                    return self._stop(fail, dt)
                logger.info("load step to %.6g failed (%s): cut to %.3g", lam, fail, dt / 2)
                self.dt = dt / 2.0
                cuts += 1
        self._commit(u, mu, trial, lam)
        rec = QuasiStaticStep(lam, dt, len(history) - 1, tuple(history), cuts, tuple(records))
        self.history.append(rec)
        if rec.iterations <= self.easy_iterations and cuts == 0:
            self.dt = min(self.nominal, dt * self.growth)
        if self.t >= self.load:
            self.status = "completed"
        return rec

    def _commit(self, u, mu, trial, lam) -> None:
        du = np.linalg.norm(u - self.u)
        dlam = lam - self.t
        if du > 0.0:
            stiffness = abs(dlam) / du
            if self._first_stiffness is None:
                self._first_stiffness = stiffness
            self._last_stiffness = stiffness
        self._previous = (self.u, self.mu, self.t)
        self.u, self.mu, self.states, self.t = u, mu, trial, lam

    def _stop(self, fail: _StepFailed, dt: float):
        """The step cannot be cut further: a limit load, or a failure (raised)."""
        ratio = None
        if self._first_stiffness and self._last_stiffness is not None:
            ratio = self._last_stiffness / self._first_stiffness
        soft = ratio is not None and ratio < LIMIT_STIFFNESS_RATIO
        if fail.kind == "singular" or (fail.kind == "newton" and soft):
            self.status = "limit_load"
            self.message = (
                f"limit load: the load factor cannot increase beyond {self.t:.6g} (the step "
                f"{dt:.3g} failed: {fail}; incremental stiffness {ratio:.3g} of the first "
                f"step's)"
                if ratio is not None
                else f"limit load at {self.t:.6g}: {fail}"
            )
            return None
        kind = "a model's state was invalid" if fail.kind == "state" else "Newton failed"
        raise NewtonError(
            f"{kind} at the smallest load step ({dt:.3g}) after λ = {self.t:.6g}: {fail}",
            step=len(self.history) + 1,
            time=self.t + dt,
        )

    # -- checkpoints -------------------------------------------------------------------------
    _CHECKPOINT = ("t", "u", "mu", "states", "dt", "history", "status", "_previous",
                   "_first_stiffness", "_last_stiffness")  # fmt: skip

    def checkpoint(self) -> dict[str, Any]:
        """The committed state of the run with its whole history (picklable: arrays and
        immutable states), from which ``QuasiStaticSolver(..., restore=checkpoint)`` continues
        bit for bit (:meth:`snapshot` is the lighter undo point of an adaptive run)."""
        return {**{name: getattr(self, name) for name in self._CHECKPOINT},
                "band_watch": self.band_watch.state}  # fmt: skip

    def _restore(self, snap: dict[str, Any]) -> None:
        missing = [name for name in self._CHECKPOINT if name not in snap]
        if missing:
            raise ValueError(f"restore: the snapshot lacks {missing}")
        if np.shape(snap["u"]) != self.u.shape or np.shape(snap["mu"]) != self.mu.shape:
            raise ValueError(
                f"restore: the snapshot is of another problem ({np.size(snap['u'])} dofs and "
                f"{np.size(snap['mu'])} multipliers, this one {self.u.size} and {self.mu.size})"
            )
        for name in self._CHECKPOINT:
            setattr(self, name, snap[name])
        self.history, self.band_watch.state = list(self.history), snap.get("band_watch", UNWATCHED)

    # -- adaptation (arlequin.problem.adapt, driven by arlequin.solvers.statics.adaptive) ---------
    def replace_system(self, system: Any, u: np.ndarray, states: dict[str, list[Any]]) -> None:
        """Go on with another system (a grown patch) from the fields ``u`` and ``states`` moved
        onto it at the same load factor (blocks missing from ``states``: initial states); the
        multipliers are zero until :meth:`resolve`."""
        self.system = as_system(system)
        self.ops = SystemOperators(self.system, lumped=False, with_mass=False)
        self.ops.check_tangents("the quasi-static solver")
        timings = self.saddle.direct.timings
        self.saddle = SaddleSolver(self.system, self.ops, condense=self.condense,
                                   linear_solver=self.linear_solver)  # fmt: skip
        self.saddle.direct.timings = timings  # the run's, across the growths
        self.u = as_vector(u, self.system, "u")
        self.states = {**self.ops.initial_states(), **states}
        self.mu = np.zeros(self.saddle.n_multipliers)
        self._previous = None

    def resolve(self, previous: tuple[np.ndarray, float] | None = None) -> int:
        """Newton at the committed load factor from the committed fields (after
        :meth:`replace_system`): commits u, μ and the states; returns the iterations.
        ``previous``: the displacement of the step before (moved onto the new system) and its
        load factor, for the next step's predictor (without it the next step starts from the
        committed fields, as the first step)."""
        self.mu = self._least_squares_multipliers()
        t0 = time.perf_counter()
        try:
            u, mu, trial, history, _ = self._newton(self.t)
        except _StepFailed as fail:
            raise NewtonError(f"re-solving the grown patch at λ = {self.t:.6g} failed: {fail}",
                              step=len(self.history), time=self.t) from fail  # fmt: skip
        finally:
            self._timers["step_s"] += time.perf_counter() - t0  # counted with the steps
        self.u, self.mu, self.states = u, mu, trial
        if previous is not None:  # the multipliers' increment is not known: none
            self._previous = (np.asarray(previous[0], dtype=float), mu, float(previous[1]))
        return len(history) - 1

    # -- results -----------------------------------------------------------------------------
    def reactions(self) -> np.ndarray:
        """Reaction forces (N) at the Dirichlet dofs, zero elsewhere."""
        f_int, _, _ = self.ops.internal_force(self.u, self.states)
        bt_mu = self.saddle.b.T @ self.mu if self.saddle.n_multipliers else 0.0
        r = np.zeros_like(self.u)
        fixed = self.saddle.fixed
        r[fixed] = (f_int + bt_mu - self.external_force(self.t))[fixed]
        return r

    def result(self, message: str | None = None) -> QuasiStaticResult:
        """The run so far as a :class:`QuasiStaticResult`."""
        status = self.status if self.status in STATUSES else "stopped"
        msg = message or getattr(self, "message", None) or f"reached λ = {self.t:.6g}"
        return QuasiStaticResult(
            status=status,
            message=msg,
            load_factors=[self.t0] + [s.load_factor for s in self.history],
            steps=list(self.history),
            u=self.u.copy(),
            displacements=self.system.split(self.u),
            multipliers=self.saddle.split_multipliers(self.mu),
            reactions=self.reactions(),
            states=self.states,
            limit_load=self.t if status == "limit_load" else None,
            system=self.system,
            linear_solver=self.saddle.direct.name,
            timings=self.timings,
        )


#: Newton is given up early when, after this many iterations, the last four have not gained a
#: decade: far from the quadratic rate, the step is better cut than iterated (near a limit load
#: the pressure-driven cylinder spent 447 s in 25-iteration failures).
STAGNATION_ITERATIONS = 8


def _stagnates(history: list[float]) -> bool:
    k = len(history) - 1
    return k >= STAGNATION_ITERATIONS and history[-1] > 0.1 * history[-5]


def _check_inputs(load, steps, tol, max_iterations, growth, t0) -> None:
    if isinstance(steps, bool) or int(steps) != steps or steps < 1:
        raise ValueError(f"steps (the number of load steps) must be an integer >= 1, got {steps}")
    if not (math.isfinite(load) and math.isfinite(t0) and load > t0):
        raise ValueError(f"load (the target load factor) must exceed t0={t0}, got load={load}")
    if not (0.0 < tol < 1.0):
        raise ValueError(f"tol must lie in (0, 1), got tol={tol}")
    if int(max_iterations) != max_iterations or max_iterations < 1:
        raise ValueError(f"max_iterations must be an integer >= 1, got {max_iterations}")
    if not growth >= 1.0:
        raise ValueError(f"growth must be >= 1, got growth={growth}")


def solve_quasi_static(
    problem: Any,
    load: float = 1.0,
    steps: int = 10,
    on_step: Sequence[Callable[[QuasiStaticSolver], Any]] = (),
    callback: Callable[[QuasiStaticSolver], bool] | None = None,
    adapt: Any = None,
    **options: Any,
) -> QuasiStaticResult:
    """Solve a quasi-static problem by load stepping and Newton (see the module docstring).

    Parameters
    ----------
    problem : ArlequinProblem, MultiBodyProblem, CoupledSystem or model
    load : float
        The target load factor (the loads and prescribed values at λ = 1 are the problem's).
    steps : int
        Equal load steps to reach it (cut and grown back automatically where needed).
    on_step : sequence of callables
        Each called with the solver after every converged step (``solver.t``, ``solver.u``,
        ``solver.states``, ``solver.history[-1]``): to write results as the run goes.
    callback : callable, optional
        Called likewise; returning True stops the run (status ``"stopped"``).
    adapt : AdaptivePatch, optional
        A patch that grows where the material yields (:mod:`arlequin.problem.adapt`, driven by
        :func:`arlequin.solvers.statics.adaptive.run_adaptive`); listeners with an
        ``on_adapt(solver, adapt)`` member are told of each growth.
    **options
        Passed to :class:`QuasiStaticSolver` (``proportional``, ``tol``, ``max_iterations``,
        ``min_step``, ``growth``, ``line_search``, ``condense``, ``linear_solver``,
        ``reference_time``, ``t0``, ``u0``, ``states``, ``restore``).

    Returns
    -------
    QuasiStaticResult
        ``status`` "completed" (the target load reached), "limit_load" (the load could not
        increase: ``limit_load`` the last converged λ) or "stopped" (by the callback).

    Raises
    ------
    NewtonError
        A ``StateError`` or a Newton failure at the smallest step (``err.result`` holds the
        converged steps).
    ValueError
        Bad input (named), before any work.
    """
    if adapt is not None:
        if not callable(getattr(adapt, "bind", None)):
            raise ValueError(f"adapt must be an AdaptivePatch, got {type(adapt).__name__}")
        problem = adapt.bind(problem)
    solver = QuasiStaticSolver(problem, load=load, steps=steps, **options)
    if adapt is not None:
        return run_adaptive(solver, adapt, on_step, callback)
    watch, band = CoarseYieldWatch(problem), solver.band_watch
    message = None
    while solver.status == "running":
        try:
            rec = solver.step()
        except NewtonError as err:
            err.result = band.finish(solver.result(str(err)))
            raise
        if rec is None:  # a limit load
            break
        watch(solver)
        band(solver)
        for listener in on_step:
            listener(solver)
        if callback is not None and callback(solver):
            solver.status = "stopped"
            message = f"stopped by the callback at λ = {solver.t:.6g}"
    return band.finish(watch.finish(solver.result(message)))
