"""Explicit central differences with lumped weighted masses and velocity-level constraint impulses.

Variable steps (Δt_n from t_n to t_{n+1}, Δt̄_n = ½(Δt_{n−1} + Δt_n), Δt_{−1} = 0), lumped
α-weighted mass M (diagonal):

1. free prediction ``v* = v^{n−1/2} + Δt̄_n M⁻¹ (f_ext(t_n) − f_int(u^n))`` (v^{−1/2} = v^0:
   the first step is the usual half step);
2. impulses Λ (N·s) that make the corrected velocity ``v^{n+1/2} = v* − M⁻¹ Bᵀ Λ`` satisfy every
   equality row at velocity level:

   * displacement rows ``B u = g``: ``B v^{n+1/2} = (g(t_{n+1}) − B u^n)/Δt_n`` (the end-of-step
     displacement satisfies the row exactly: no drift);
   * velocity rows ``B v = g``: ``B v^{n+1/2} = g(t_{n+1/2})``;

   i.e. ``(B M⁻¹ Bᵀ) Λ = B v* − w``. For the Arlequin rows ``[C_c, −C_f]`` the matrix is
   ``C_c M_c⁻¹ C_cᵀ + C_f M_f⁻¹ C_fᵀ``; the masses being constant (total Lagrangian), it is
   factorised once. Active unilateral rows (contact) are added by a Schur complement on that
   factorisation, and the step's solve is repeated until their statuses settle;
3. ``u^{n+1} = u^n + Δt_n v^{n+1/2}``.

This is velocity Verlet with the steps Δt_n, second order for any step sequence. Multipliers are
reported as forces λ^n = Λ^n/Δt̄_n at t_n (force on the system −Bᵀλ). The full-step velocity
splits the kick at t_n in proportion to the two half steps,
``v^n = v^{n−1/2} + Δt_{n−1}/(Δt_{n−1} + Δt_n) (v^{n+1/2} − v^{n−1/2})`` (the mean of the two
mid-step velocities for a constant step; for time-independent rows it is projected on the rows),
so the impulse at t_n is computed at the end of step n−1 with the step Δt_n chosen then, and
everything at t_n (u, v, a, λ, energies) is known after each call of
:meth:`CentralDifference.step`; imposing another Δt_n (``step(dt)``, ``set_step_size``) redoes
that impulse. Works are accumulated by the trapezoidal rule on the powers at t_n and t_{n+1}:
external ``f·v``, constraint ``−λ·B v``.

With linear models a step is one sparse mat-vec with the assembled stiffness, a few vector
operations, two small sparse products with the rows restricted to the dofs they touch, and one
triangular solve pair.
"""

from __future__ import annotations

import logging
import time
from typing import Any

import numpy as np
import scipy.sparse as sp

from ...contract import SimulationError, capabilities
from ...linalg.impulses import ImpulseSolver
from ...linalg.timing import SWITCH, energy_products_done, timer_start, vector_updates_done
from ...linalg.vector_updates import interpolated, scaled_plus, work_products
from ..system.rows import EqualityRows, rows_times, subtract_transposed, unilateral_block_powers
from .base import Integrator
from .controllers import FixedStep, StepController
from .damping import RayleighDamping
from .registry import register
from .row_basis import ImpulseBasis
from .stability import DEFAULT_SAFETY, StableStep, check_time_step, stable_time_step

__all__ = ["DEFAULT_SAFETY", "CentralDifference"]

logger = logging.getLogger(__name__)


@register("explicit", "central_difference", "central-difference")
class CentralDifference(Integrator):
    """Explicit central differences, lumped α-weighted masses, velocity-level constraint impulses.

    Parameters
    ----------
    system : CoupledSystem
    dt : float, optional
        Time step (s). Default: ``safety`` × the critical step of the coupled system. A step above
        the computed critical step is refused with a ``ValueError`` giving both numbers.
    safety : float
        Ratio of the default step to the critical step (default 0.9).
    stable_method : {"coupled", "blocks", "gershgorin"}
        Estimate of the critical step (see :mod:`arlequin.solvers.dynamics.stability`).
    check_dt : bool
        Refuse a step above the critical one (default True).
    damping : RayleighDamping, optional
        Rayleigh damping C = α M + β K₀ (:mod:`arlequin.solvers.dynamics.damping`): the force
        −C v^{n−1/2} at t_n, the critical step reduced accordingly, the dissipated energy in
        ``energies()["damping_work"]``. Default none.
    **kwargs
        See :class:`arlequin.solvers.dynamics.base.Integrator` (``step_controller`` among them: e.g.
        :class:`~arlequin.solvers.CriticalFraction` to follow a changing configuration).

    Attributes
    ----------
    stable_step : StableStep
        The critical-step estimates at the initial configuration.
    constraint_time : float
        Wall time (s) spent in the constraint impulses (transfers B v, Bᵀ Λ and the solves).
    """

    name = "explicit"
    lumped_default = True
    applies_multipliers = True
    # its dense products are a few contact rows: a BLAS pool would spin on the kernels' cores
    blas_threads = 1

    def __init__(
        self,
        system,
        dt: float | None = None,
        *,
        safety: float = DEFAULT_SAFETY,
        stable_method: str = "coupled",
        check_dt: bool = True,
        damping: RayleighDamping | None = None,
        **kwargs: Any,
    ) -> None:
        if damping is not None and not isinstance(damping, RayleighDamping):
            raise TypeError(f"damping must be a RayleighDamping or None, got "
                            f"{type(damping).__name__}")  # fmt: skip
        self.damping = damping if damping is not None and damping.active else None
        self._c_matrix: sp.csr_matrix | None = None
        self._f_damp: np.ndarray | None = None
        if not 0.0 < safety <= 1.0:
            raise ValueError(f"safety factor must lie in (0, 1], got safety={safety}")
        if kwargs.get("lumped") is False:
            raise ValueError("the explicit scheme needs lumped masses (lumped=True)")
        self.safety = float(safety)
        self.stable_method = stable_method
        self.check_dt = bool(check_dt)
        self.stable_step: StableStep | None = None
        self._solver: ImpulseSolver | None = None
        self._critical_found: list[tuple[Any, int, Any, float]] | None = None
        self._columns_scratch: np.ndarray | None = None  # zeros (n,): subtract_transposed's
        self._critical_now: float | None = None
        self._critical_at: int | None = None
        self._impulse_failed = False
        self._f_applied: np.ndarray | None = None
        self.constraint_time = 0.0
        self._work_buffer: np.ndarray | None = None  # the internal work's products
        self._neg_inv_mass: tuple[np.ndarray, np.ndarray] | None = None
        super().__init__(system, dt, **kwargs)

    def _equality_rows(self, constraints) -> EqualityRows:
        # constraints with pivot dofs in their identity basis: the same corrected velocities,
        # a diagonal-plus-low-rank impulse matrix (row_basis); multipliers reported as given
        self.row_basis = ImpulseBasis(constraints, self.ops)
        return self.row_basis.rows

    # ------------------------------------------------------------------ stable step
    def _impulse_solver(self) -> ImpulseSolver:
        if self._solver is None:
            self._solver = ImpulseSolver(self.rows, self.ops.inv_mass)
            self._minv_cols = self.ops.inv_mass[self.rows.cols]
            self._no_rows, self._no_lam = sp.csr_matrix((0, self.ops.n)), np.zeros(0)
        return self._solver

    def _stable(self) -> StableStep:
        if self.stable_step is None:
            solver = self._impulse_solver()
            self.stable_step = stable_time_step(
                self.system, self.stable_method, _ops=self.ops, _rows=self.rows, _s_lu=solver.lu
            )
            if self.damping is not None:
                self.stable_step = self.damping.stable_step(self.stable_step)
            self.critical_dt = self.stable_step.critical
        return self.stable_step

    def critical_time_step(self, max_age: int = 0) -> float:
        """Critical step (s) of the coupled system in the current configuration.

        The computed critical step of the initial configuration (:attr:`stable_step`), scaled by
        ``min_m Δt_m(u)/Δt_m(0)`` over the nonlinear models that declare the
        ``"critical_time_step"`` capability (their own element estimates in the current and the
        initial configuration); linear systems keep the initial value.

        Parameters
        ----------
        max_age : int
            Return the last estimate if it was made at most this many steps ago (0: estimate
            now).
        """
        # the kept estimate first: most steps of a CriticalFraction controller end here
        if (
            max_age > 0
            and self._critical_at is not None
            and self._critical_now is not None
            and self.step_count - self._critical_at < max_age
        ):
            return self._critical_now
        crit = self._stable().critical
        u = getattr(self, "u", None)
        if u is None:
            self._critical_now = crit
            return crit
        self._critical_at = self.step_count
        ratio = 1.0
        for b, ti, term, step0 in self._critical_terms():
            now = float(term.model.critical_time_step(self.ops._term_u(b, term, u),
                                                      self.states[b.name][ti]))  # fmt: skip
            ratio = min(ratio, now / step0)
        self._critical_now = crit * ratio
        return self._critical_now

    def _critical_terms(self) -> list[tuple[Any, int, Any, float]]:
        """(block, term index, term, its critical step at u = 0 (s)) of the nonlinear models
        with the ``"critical_time_step"`` capability, found once: the capability test (protocol
        checks, ~12 µs a model) is not repeated at every estimate."""
        if self._critical_found is None:
            found = []
            for bi, b in enumerate(self.ops.blocks):
                if self.ops.block_linear[bi]:
                    continue
                for ti, term in enumerate(b.terms):
                    if "critical_time_step" not in capabilities(term.model):
                        continue
                    u0 = self.ops._term_u(b, term, np.zeros(self.u.shape))
                    found.append((b, ti, term, float(term.model.critical_time_step(u0, None))))
            self._critical_found = found
        return self._critical_found

    def _default_controller(self) -> StepController:
        return FixedStep(self.safety * self._stable().critical)

    def _check_step_size(self, dt: float) -> float:
        if self.check_dt:
            stable = self._stable()
            # the latest estimate (a CriticalFraction controller refreshes it)
            now = self._critical_now if self._critical_now is not None else stable.critical
            if dt <= now * (1.0 + 1e-12):
                return dt  # check_time_step's test, without building a StableStep each step
            if now != stable.critical:
                stable = StableStep(
                    now, stable.block_bound, stable.per_block, 2.0 / now, "current-configuration"
                )
            check_time_step(dt, stable)
        return dt

    # ------------------------------------------------------------------ impulses
    def _rhs_equality(self, v_star: np.ndarray, u: np.ndarray, t_next: float) -> np.ndarray:
        """B v* − w for the equality rows, w the velocity targets of the mid-step velocity
        ending at t_next: (g(t_next) − B u)/Δt (displacement rows), g(t_next − Δt/2) (velocity
        rows)."""
        rows = self.rows
        dt = self.dt
        cols = rows.cols
        if rows.all_displacement:
            # B v* − (g − B u)/Δt = B (v* + u/Δt) − g/Δt: one product on the touched dofs,
            # v* + u/Δt formed inside it (the same floats as the gathers' and the sum's)
            if rows.cols_u32 is not None:
                bw = rows.times.times_gathered(rows.cols_u32, v_star, u, dt)
            else:
                bw = rows.times(v_star[cols] + u[cols] / dt)
            return bw - rows.g(t_next) / dt
        disp = rows.displacement
        bv = rows.times(v_star[cols])
        bu = rows.times(u[cols])
        g_end = rows.g(t_next)
        g_mid = rows.g(t_next - 0.5 * dt) if rows.time_dependent else g_end
        return bv - np.where(disp, (g_end - bu) / dt, g_mid)

    def _impulse(self, v_star: np.ndarray, dt_bar: float):
        """Impulses making ``v_star − M⁻¹BᵀΛ`` satisfy the rows for the step from t.

        ``v_star`` is overwritten. Returns (Λ_E, Λ_A, full unilateral multipliers per constraint
        as forces, G_A, v_new, trials).
        """
        rows = self.rows
        solver = self._impulse_solver()
        t_next = self._end_time()
        timer = SWITCH.timer
        tic = timer.clock() if timer is not None else 0.0
        r_e = self._rhs_equality(v_star, self.u, t_next) if rows.m else np.zeros(0)
        if not self.unilateral:
            lam_e = solver.solve_equality(r_e)
            v_new = v_star
            if rows.m:
                rows.subtract_impulse(v_new, self._minv_cols, lam_e)
            self.status_iterations = 0
            if timer is not None:
                timer.linear_algebra += timer.clock() - tic
            return lam_e, self._no_lam, [], self._no_rows, v_new, []
        if timer is not None:
            timer.linear_algebra += timer.clock() - tic
        return self._status_loop(solver, v_star, r_e, dt_bar, t_next)

    def _status_loop(
        self, solver: ImpulseSolver, v_free: np.ndarray, r_e0: np.ndarray, dt_bar: float,
        t_next: float,
    ):  # fmt: skip
        """The impulse with unilateral constraints: their statuses iterated from their trials
        at t (``v_free`` the free prediction, ``r_e0`` the equality rows' right-hand side for
        it); returns what :meth:`_impulse` does."""
        rows = self.rows
        dt = self.dt
        u, t = self.u, self.t
        minv = self.ops.inv_mass
        trials = self._begin_unilateral(t, dt, u, v_free)
        converged = False
        it = 0
        while it < self.max_status_iterations:
            it += 1
            g_a, rhs_a, idx, disp = self._active(trials)
            # prescribed multipliers of inactive rows (slip friction): a force during the step
            applied = [getattr(tr, "applied", None) for tr in trials]
            f_app = self._applied_force(trials, applied)
            v_star, r_e = v_free, r_e0
            if f_app is not None:
                v_star = v_free + dt_bar * minv * f_app
                r_e = self._rhs_equality(v_star, u, t_next) if rows.m else r_e0
            lam_e, lam_a, v_new = self._solve_impulses(solver, v_star, r_e, g_a, rhs_a, disp)
            fulls = self._full_multipliers(lam_a / dt_bar, idx)
            if f_app is not None:
                fulls = [f if a is None else f + a for f, a in zip(fulls, applied)]
            self._f_applied = f_app
            u_end = scaled_plus(dt, v_new, u)  # u + Δt v, one compiled pass
            trials, changed = self._update_statuses(trials, u_end, v_new, fulls)
            if not changed:
                converged = True
                break
        self.status_iterations = it
        self._impulse_failed = not converged
        if not converged:
            # the step keeps the last solve; each constraint commits what it used in it
            self._status_cap_reached(t_next)
        return lam_e, lam_a, fulls, g_a, v_new, trials

    def _solve_impulses(
        self, solver: ImpulseSolver, v_star: np.ndarray, r_e: np.ndarray, g_a, rhs_a: np.ndarray,
        disp: np.ndarray,
    ):  # fmt: skip
        """One status iteration's solve: (Λ_E, Λ_A) of the equality rows (right-hand side
        ``r_e``) and the active rows ``g_a`` (targets ``rhs_a``, displacement-level where
        ``disp``), and the velocity ``v_star − M⁻¹BᵀΛ`` (a new array)."""
        rows = self.rows
        dt = self.dt
        u = self.u
        minv = self.ops.inv_mass
        timer = SWITCH.timer
        # velocity-level rows (contact) target rhs_a itself: no product with u for them
        tic = timer.clock() if timer is not None else 0.0
        w_a = np.where(disp, (rhs_a - g_a @ u) / dt, rhs_a) \
            if self._active_displacement_rows else rhs_a  # fmt: skip
        r_a = rows_times(g_a, v_star) - w_a
        lam_e, lam_a = solver.solve(r_e, g_a, r_a)
        v_new = v_star.copy()
        if rows.m:
            rows.subtract_impulse(v_new, self._minv_cols, lam_e)
        if g_a.shape[0]:
            # M⁻¹ Gᵀλ subtracted on G_A's columns alone (no n-vector for a few rows)
            scratch = self._columns_scratch
            if scratch is None or scratch.shape != minv.shape:
                scratch = self._columns_scratch = np.zeros(minv.shape)
            subtract_transposed(g_a, lam_a, minv, v_new, scratch)
        if timer is not None:
            timer.linear_algebra += timer.clock() - tic
        return lam_e, lam_a, v_new

    def _applied_force(self, trials, applied) -> np.ndarray | None:
        """−Σ Bᵀ λ_applied (N) of the trials' prescribed multipliers, or None without any."""
        f = None
        for tr, app in zip(trials, applied):
            if app is not None and np.any(app):
                part = -(tr.matrix.T @ app)
                f = part if f is None else f + part
        return f

    def _impulse_at_t(self) -> None:
        """Impulse at the current time t for the step self.dt: sets v^{n+1/2}, v^n, λ^n, the
        constraint states after it and the powers at t."""
        dt_prev, dt = self._dt_prev, self.dt
        dt_bar = 0.5 * (dt_prev + dt)
        v_minus = self._v_minus
        v_star = self._kick(v_minus, dt_bar)
        tic = time.perf_counter()
        lam_e, lam_a, fulls, g_a, v_next, trials = self._impulse(v_star, dt_bar)
        self.constraint_time += time.perf_counter() - tic
        if trials:
            self.constraint_states = self._commit_unilateral(
                trials, self.t, self.u, v_minus, v_next, fulls, [dt_bar * f for f in fulls],
                states=self._pre_impulse_states,
            )  # fmt: skip
        self._v_next = v_next
        share = dt_prev / (dt_prev + dt)
        if share:
            # v⁻ + share (v⁺ − v⁻) in one compiled pass
            self.v = interpolated(v_minus, v_next, share)
        else:
            self.v = v_minus.copy()
        self._lam_e = lam_e
        self._lam_a = lam_a
        self._g_a = g_a
        self._dt_bar = dt_bar
        mult = self.row_basis.multipliers(lam_e / dt_bar) if self.rows.m else {}
        for c, lam in zip(self.unilateral, fulls):
            mult[c.name] = lam
        self.multipliers = mult
        # works of the step that ended at t: the trapezoidal rule on the forces at both ends
        # times the step's own (mid-step) velocity v^{n-1/2}, the discrete work that closes the
        # balance of the scheme's energy exactly for linear systems. Pending until the next
        # step starts, since a new step size at t changes the forces at t.
        half = 0.5 * dt_prev
        # the powers of these forces with v^{n+1/2} too, which the next step needs (_step_impl):
        # the constraint forces computed once for both, kept with v^{n+1/2} itself (never
        # modified in place; a restored run recomputes them, to the same numbers)
        p_now, p_next = self._powers(v_minus, v_next)
        self._p_next = (v_next, p_next)
        # (4, n_blocks): external, coupling, other constraints, damping
        self._w_pending = half * (self._p_prev + p_now)

    def _kick(self, v_minus: np.ndarray, dt_bar: float) -> np.ndarray:
        """The free prediction v* = v^{n−½} + Δt̄_n a^n (a new array)."""
        return scaled_plus(dt_bar, self.a, v_minus)  # one compiled pass

    def _kinetic(self) -> np.ndarray:
        """The scheme's kinetic energy per block (J): ½ ṽ^{n−½}·M v^{n+½}, with ṽ^{n−½} the
        mid-step velocity the step Δt_n would have before t_n (v^{n−½} for a constant step)."""
        back = self._v_next - (self.dt / self._dt_bar) * (self._v_next - self._v_minus)
        return 0.5 * self.ops.block_dots(back, self.ops.mass * self._v_next)

    def _powers(self, v: np.ndarray, v2: np.ndarray | None = None) -> np.ndarray:
        """External, coupling, other-constraint and damping powers per block (W) of the forces
        at the current time with the velocity v (m/s): an array (4, n_blocks), rows in that
        order; with a second velocity v2, an array (2, 4, n_blocks), one such array for each
        velocity (the constraint forces computed once)."""
        vs = (v,) if v2 is None else (v, v2)
        nb = len(self.ops.blocks)
        out = np.zeros((len(vs), 4, nb))
        if self.rows.m:  # rows 1 and 2: the coupling rows' and the others'
            self.rows.add_block_powers(self._lam_e / self._dt_bar, vs, out[:, 1:3])
        if self._g_a.shape[0]:
            lam = self._lam_a / self._dt_bar
            out[:, 2] += unilateral_block_powers(self.ops, self._g_a, lam, vs)
        tic = timer_start()
        for i, x in enumerate(vs):
            if self._f_ext is not None:
                out[i, 0] = self.ops.block_dots(self._f_ext, x)
            if self._f_applied is not None:  # slip friction
                out[i, 2] += self.ops.block_dots(self._f_applied, x)
            if self._f_damp is not None:
                out[i, 3] = -self.ops.block_dots(self._f_damp, x)
        energy_products_done(tic)
        return out[0] if v2 is None else out

    def _damping_force(self, v: np.ndarray) -> np.ndarray | None:
        """C v (N) with the mid-step velocity v that precedes the force's time, or None."""
        if self.damping is None:
            return None
        if self._c_matrix is None:
            self._c_matrix = self.damping.matrix(self.ops.mass, self.ops.initial_stiffness())
        return self._c_matrix @ v

    def _forces(
        self, u: np.ndarray, t: float, dt: float | None = None, blocks=None
    ) -> tuple[np.ndarray, np.ndarray | None, dict]:
        # blocks: the block indices whose internal force is evaluated (None: all)
        f_int, trial, _ = self.ops.internal_force(u, self.states, dt=dt, blocks=blocks)
        f_ext = self.system.external_force(t) if self.system.load is not None else None
        if f_ext is not None and not f_ext.any():
            f_ext = None  # unloaded at t: skip the force and its power
        return f_int, f_ext, trial

    def _acceleration(self, f_int: np.ndarray, f_ext: np.ndarray | None) -> np.ndarray:
        minv = self.ops.inv_mass
        if f_ext is None:
            # (−M⁻¹) f_int with −M⁻¹ kept (negation is exact): one array a step fewer
            cached = self._neg_inv_mass
            if cached is None or cached[0] is not minv:
                cached = self._neg_inv_mass = (minv, -minv)
            return cached[1] * f_int
        a = f_ext - f_int
        a *= minv
        return a

    # ------------------------------------------------------------------ initial state
    def _initialize(self) -> None:
        f_int, f_ext, trial = self._forces(self.u, self.t)
        self.states = trial
        self._f_int = f_int
        self._f_ext = f_ext
        self._v_minus = self.v.copy()  # v^{-1/2} = v^0: the first kick is a half step
        self._f_damp = self._damping_force(self._v_minus)
        f_all = f_int if self._f_damp is None else f_int + self._f_damp
        self.a = self._acceleration(f_all, f_ext)
        self._dt_prev = 0.0
        self._pre_impulse_states = self.constraint_states
        nb = len(self.ops.blocks)
        self._p_prev = np.zeros((4, nb))
        self._impulse_at_t()

    def _step_size_changed(self) -> None:
        # the impulse at t and everything reported at t depend on the step that follows it
        if self._impulse_failed:
            self.n_status_failures -= 1  # that impulse is replaced
        self.constraint_states = self._pre_impulse_states
        self._impulse_at_t()

    def _works(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        pe, pc, po, _ = self._w_pending
        return self._w_ext + pe, self._w_coupling + pc, self._w_constraint + po

    def _damping_work(self) -> np.ndarray:
        return self._w_damping + self._w_pending[3]

    def _scheme_fields(self) -> tuple[str, ...]:
        return (
            "_v_next", "_v_minus", "_dt_prev", "_dt_bar", "_f_int", "_f_ext", "_lam_e", "_lam_a",
            "_g_a", "_p_prev", "_w_pending", "_pre_impulse_states", "_critical_now",
            "_critical_at", "_impulse_failed", "_f_applied", "_f_damp",
        )  # fmt: skip

    # ------------------------------------------------------------------ step
    def _step_impl(self) -> None:
        dt = self.dt
        t_new = self._end_time()
        v_half = self._v_next
        u_new = scaled_plus(dt, v_half, self.u)  # u + Δt v^{n+½}, one compiled pass
        f_int, f_ext, trial = self._forces(u_new, t_new, dt)
        f_damp = self._damping_force(v_half)  # −C v^{n+1/2}: the damping force at t_{n+1}
        tic = timer_start()  # M⁻¹ f, a diagonal solve: timed as a vector update
        a_new = self._acceleration(f_int if f_damp is None else f_int + f_damp, f_ext)
        vector_updates_done(tic)
        # the step size at t is final now: commit the works of the step that ended at t
        self._w_ext, self._w_coupling, self._w_constraint = self._works()
        self._w_damping = self._damping_work()
        # the forces at t with this step's velocity (computed with the impulse at t)
        cached = getattr(self, "_p_next", None)
        self._p_prev = cached[1] if cached is not None and cached[0] is v_half else \
            self._powers(v_half)  # fmt: skip
        # commit the step's kinematics and model states
        if not self.ops.linear:
            # Δu ⊙ ½(f_old + f_new) in one compiled pass into a kept buffer, summed per block
            buf = self._work_buffer
            if buf is None or buf.shape != u_new.shape:
                buf = self._work_buffer = np.empty(u_new.shape)
            tic = timer_start()
            products = work_products(u_new, self.u, self._f_int, f_int, buf)
            self._w_internal += self.ops.block_sums(products)
            energy_products_done(tic)
        self.u = u_new
        self.a = a_new
        self.states = trial
        self.t = t_new
        self._f_int = f_int
        self._f_ext = f_ext
        self._f_damp = f_damp
        self._dt_prev = dt
        self._v_minus = v_half
        self.step_size = dt
        self.step_count += 1
        self._phase_advanced()
        # the next step and the impulse at t_{n+1} that depends on it
        try:
            self.dt = self._next_step_size()
            self._pre_impulse_states = self.constraint_states
            self._impulse_at_t()
            # a non-finite u or a (NaN, overflow) shows in u or v here
            self._check_finite(t_new, self.u, self.v, step=self.step_count)
        except SimulationError:
            self.status = "failed"
            raise

    # ------------------------------------------------------------------ info
    @property
    def mid_step_velocity(self) -> np.ndarray:
        """v^{n+1/2} (m/s): the velocity of the next step, already constrained."""
        return self._v_next
