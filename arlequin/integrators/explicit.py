"""Explicit central differences with lumped weighted masses and velocity-level constraint impulses.

Each step (Δt constant, lumped α-weighted mass M, diagonal):

1. free prediction of the mid-step velocity ``v* = v^{n−1/2} + Δt M⁻¹ (f_ext(t_n) − f_int(u^n))``;
2. impulses Λ (N·s) that make the corrected velocity ``v^{n+1/2} = v* − M⁻¹ Bᵀ Λ`` satisfy every
   equality row at velocity level:

   * displacement rows ``B u = g``: ``B v^{n+1/2} = (g(t_{n+1}) − B u^n)/Δt`` (the end-of-step
     displacement satisfies the row exactly: no drift);
   * velocity rows ``B v = g``: ``B v^{n+1/2} = g(t_{n+1/2})``;

   i.e. ``(B M⁻¹ Bᵀ) Λ = B v* − w``. For the Arlequin rows ``[C_c, −C_f]`` the matrix is
   ``C_c M_c⁻¹ C_cᵀ + C_f M_f⁻¹ C_fᵀ``; the masses being constant (total Lagrangian), it is
   factorised once. Active unilateral rows (contact) are added by a Schur complement on that
   factorisation, and the step's solve is repeated until their statuses settle;
3. ``u^{n+1} = u^n + Δt v^{n+1/2}``.

Multipliers are reported as forces λ = Λ/Δt at t_n (force on the system −Bᵀλ). The full-step
velocity is the average of the two mid-step velocities, ``v^n = (v^{n−1/2} + v^{n+1/2})/2``
(for time-independent rows it equals the RATTLE full-step velocity, projected on the rows), so
the impulse of step n is computed at the end of step n−1 and everything at t_n (u, v, a, λ,
energies) is known after each call of :meth:`CentralDifference.step`. Works are accumulated by the
trapezoidal rule on the powers at t_n and t_{n+1}: external ``f·v``, constraint ``−λ·B v``.

With linear models a step is one sparse mat-vec with the assembled stiffness, a few vector
operations, two small sparse products with the rows restricted to the dofs they touch, and one
triangular solve pair.
"""

from __future__ import annotations

import logging
import time
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from .base import ConstraintError, Integrator, _factor_checked, register, unilateral_block_power
from .stability import StableStep, stable_time_step

__all__ = ["DEFAULT_SAFETY", "CentralDifference"]

logger = logging.getLogger(__name__)

#: Default ratio of the time step to the computed critical step of the coupled system.
DEFAULT_SAFETY = 0.9


class _ImpulseSolver:
    """Solves (B M⁻¹ Bᵀ) Λ = r for the equality rows E plus the active unilateral rows A.

    The equality block S_EE is factorised once; active rows enter by a Schur complement
    (dense, cached per active pattern), or by a sparse factorisation of the whole matrix when
    there are many of them.
    """

    _DENSE_SCHUR = 300

    def __init__(self, rows, inv_mass: np.ndarray) -> None:
        self.rows = rows
        self.inv_mass = inv_mass
        self.m_e = rows.m
        if self.m_e:
            bj = rows.matrix_cols
            s = (bj @ sp.diags(inv_mass[rows.cols]) @ bj.T).tocsc()
            self.s_ee = s

            def row_name(i: int) -> str:
                for name, sl in rows.slices.items():
                    if sl.start <= i < sl.stop:
                        return f"row {i - sl.start} of constraint {name!r}"
                return f"row {i}"

            self.lu = _factor_checked(
                s, "the impulse matrix B M⁻¹ Bᵀ of the equality rows", row_name, spd=True
            )
        else:
            self.s_ee = None
            self.lu = None
        self._cache: dict[Any, Any] = {}

    def solve_equality(self, r: np.ndarray) -> np.ndarray:
        return self.lu.solve(r) if self.m_e else np.zeros(0)

    def solve(self, r_e: np.ndarray, g_a: sp.csr_matrix, r_a: np.ndarray, key: Any):
        """Return (Λ_E, Λ_A) for right-hand sides r_e (m_E,), r_a (m_A,) and active rows g_a."""
        m_a = g_a.shape[0]
        if m_a == 0:
            return self.solve_equality(r_e), np.zeros(0)
        minv = self.inv_mass
        s_aa = (g_a @ sp.diags(minv) @ g_a.T).tocsr()
        if self.m_e == 0:
            fac = self._cache.get(key)
            if fac is None:
                fac = (
                    "lu",
                    _factor_checked(s_aa, "the impulse matrix of the active rows", spd=True),
                )
                self._cache = {key: fac}
            return np.zeros(0), fac[1].solve(r_a)
        s_ae = (g_a @ sp.diags(minv) @ self.rows.matrix.T).tocsr()
        if m_a <= self._DENSE_SCHUR:
            fac = self._cache.get(key)
            if fac is None:
                x = self.lu.solve(s_ae.T.toarray()) if s_ae.nnz else np.zeros((self.m_e, m_a))
                schur = s_aa.toarray() - s_ae @ x
                try:
                    cho = sla.cho_factor(schur)
                except np.linalg.LinAlgError as exc:
                    raise ConstraintError(
                        "active unilateral rows are dependent on each other or on the equality "
                        f"rows ({m_a} active rows)"
                    ) from exc
                fac = ("schur", x, cho)
                self._cache = {key: fac}
            _, x, cho = fac
            y = self.lu.solve(r_e)
            lam_a = sla.cho_solve(cho, r_a - s_ae @ y)
            return y - x @ lam_a, lam_a
        fac = self._cache.get(key)
        if fac is None:
            full = sp.bmat([[self.s_ee, s_ae.T], [s_ae, s_aa]], format="csc")
            fac = (
                "full",
                _factor_checked(full, "the impulse matrix with the active rows", spd=True),
            )
            self._cache = {key: fac}
        sol = fac[1].solve(np.concatenate([r_e, r_a]))
        return sol[: self.m_e], sol[self.m_e :]


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
        Estimate of the critical step (see :mod:`arlequin.integrators.stability`).
    check_dt : bool
        Refuse a step above the critical one (default True).
    **kwargs
        See :class:`arlequin.integrators.Integrator`.

    Attributes
    ----------
    stable_step : StableStep
        The critical-step estimates.
    """

    name = "explicit"
    lumped_default = True

    def __init__(
        self,
        system,
        dt: float | None = None,
        *,
        safety: float = DEFAULT_SAFETY,
        stable_method: str = "coupled",
        check_dt: bool = True,
        **kwargs: Any,
    ) -> None:
        if not 0.0 < safety <= 1.0:
            raise ValueError(f"safety factor must lie in (0, 1], got safety={safety}")
        if kwargs.get("lumped") is False:
            raise ValueError("the explicit scheme needs lumped masses (lumped=True)")
        self.safety = float(safety)
        self.stable_method = stable_method
        self.check_dt = bool(check_dt)
        self.stable_step: StableStep | None = None
        self._solver: _ImpulseSolver | None = None
        #: wall time (s) spent in the constraint impulses (transfers B v, Bᵀ Λ and the solve)
        self.constraint_time = 0.0
        super().__init__(system, dt, **kwargs)

    # ------------------------------------------------------------------ set-up
    def _impulse_solver(self) -> _ImpulseSolver:
        if self._solver is None:
            self._solver = _ImpulseSolver(self.rows, self.ops.inv_mass)
            self._minv_cols = self.ops.inv_mass[self.rows.cols]
            self._no_rows = sp.csr_matrix((0, self.ops.n))
            self._no_lam = np.zeros(0)
        return self._solver

    def _choose_dt(self, dt: float | None) -> float:
        solver = self._impulse_solver()
        if self.stable_step is None and (dt is None or self.check_dt):
            self.stable_step = stable_time_step(
                self.system, self.stable_method, _ops=self.ops, _rows=self.rows, _s_lu=solver.lu
            )
            self.critical_dt = self.stable_step.critical
        if dt is None:
            return self.safety * self.stable_step.critical
        dt = float(dt)
        if self.check_dt and dt > self.stable_step.critical * (1.0 + 1e-12):
            s = self.stable_step
            raise ValueError(
                f"time step dt={dt:.6e} s exceeds the critical step of the coupled explicit "
                f"system, {s.critical:.6e} s ({s.method} estimate; per-model bound "
                f"{s.block_bound:.6e} s): use dt <= {s.critical:.6e} s"
            )
        return dt

    # ------------------------------------------------------------------ helpers
    def _rhs_equality(self, v_star: np.ndarray, u: np.ndarray, t_next: float) -> np.ndarray:
        """B v* − w for the equality rows, w the velocity targets of the mid-step velocity
        ending at t_next: (g(t_next) − B u)/Δt (displacement rows), g(t_next − Δt/2) (velocity
        rows)."""
        rows = self.rows
        dt = self.dt
        cols = rows.cols
        if rows.displacement.all():
            # B v* − (g − B u)/Δt = B (v* + u/Δt) − g/Δt: one product on the touched dofs
            return rows.matrix_cols @ (v_star[cols] + u[cols] / dt) - rows.g(t_next) / dt
        disp = rows.displacement
        bv = rows.matrix_cols @ v_star[cols]
        bu = rows.matrix_cols @ u[cols]
        g_end = rows.g(t_next)
        g_mid = rows.g(t_next - 0.5 * dt) if rows.time_dependent else g_end
        return bv - np.where(disp, (g_end - bu) / dt, g_mid)

    def _impulse(
        self, v_star: np.ndarray, u: np.ndarray, t: float, scale: float
    ) -> tuple[np.ndarray, np.ndarray, list[np.ndarray], sp.csr_matrix, np.ndarray]:
        """Impulses making ``v_star − scale·M⁻¹BᵀΛ`` satisfy the rows for the step from t.

        ``scale`` is 1 for a full step and 1/2 for the initial half step. ``v_star`` is
        overwritten. Returns (Λ_E, Λ_A, [full unilateral multipliers per constraint, as
        forces], G_A, v_new).
        """
        rows = self.rows
        dt = self.dt
        solver = self._impulse_solver()
        t_next = t + dt
        r_e = self._rhs_equality(v_star, u, t_next) / scale if rows.m else np.zeros(0)
        minv = self.ops.inv_mass
        if not self.unilateral:
            lam_e = solver.solve_equality(r_e)
            v_new = v_star
            if rows.m:
                v_new[rows.cols] -= (scale * self._minv_cols) * (rows.matrix_cols_t @ lam_e)
            self.status_iterations = 0
            return lam_e, self._no_lam, [], self._no_rows, v_new
        for c in self.unilateral:
            c.begin_step(t, dt, u, v_star)
        converged = False
        it = 0
        while it < self.max_status_iterations:
            it += 1
            g_a, idx = self._active_rows()
            v_trial = v_star.copy()
            rhs_a = (
                np.concatenate([c.rhs(t_next)[a] for c, a in zip(self.unilateral, idx)])
                if idx
                else np.zeros(0)
            )
            lev_disp = (
                np.concatenate(
                    [
                        np.full(a.size, c.level == "displacement")
                        for c, a in zip(self.unilateral, idx)
                    ]
                )
                if idx
                else np.zeros(0, dtype=bool)
            )
            w_a = np.where(lev_disp, (rhs_a - g_a @ u) / dt, rhs_a)
            r_a = (g_a @ v_trial - w_a) / scale
            key = tuple(a.tobytes() for a in idx) + tuple(id(c.matrix()) for c in self.unilateral)
            lam_e, lam_a = solver.solve(r_e, g_a, r_a, key)
            v_new = v_trial
            if rows.m:
                v_new[rows.cols] -= scale * minv[rows.cols] * (rows.matrix_cols_t @ lam_e)
            if g_a.shape[0]:
                v_new -= scale * minv * (g_a.T @ lam_a)
            fulls = self._unilateral_full(lam_a / dt, idx)
            u_pred = u + dt * v_new
            if not self._update_statuses(u_pred, v_new, fulls):
                converged = True
                break
        self.status_iterations = it
        if not converged:
            # the step keeps the last solve; the statuses were updated after it and are the
            # next step's starting guess
            self._status_cap_reached()
        return lam_e, lam_a, fulls, g_a, v_new

    def _forces(self, u: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray, dict]:
        f_int, trial, _ = self.ops.internal_force(u, self.states)
        f_ext = self.system.external_force(t) if self.system.load is not None else None
        if f_ext is not None and not f_ext.any():
            f_ext = None  # unloaded at t: skip the force and its power
        return f_int, f_ext, trial

    def _record_impulse(self, lam_e, fulls, g_a, lam_a) -> None:
        self._lam_e = lam_e
        self._lam_a = lam_a
        self._g_a = g_a
        mult = self.rows.split(lam_e / self.dt) if self.rows.m else {}
        for c, lam in zip(self.unilateral, fulls):
            mult[c.name] = lam
        self.multipliers = mult

    def _powers(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """External, coupling and other-constraint powers per block at the current time (W)."""
        nb = len(self.ops.blocks)
        v = self.v
        p_ext = self.ops.block_dots(self._f_ext, v) if self._f_ext is not None else np.zeros(nb)
        if self.rows.m:
            lam = self._lam_e / self.dt
            pc, po = self.rows.block_powers(lam, v[self.rows.cols])
        else:
            pc, po = np.zeros(nb), np.zeros(nb)
        if self._g_a.shape[0]:
            po = po + unilateral_block_power(self.ops, self._g_a, self._lam_a / self.dt, v)
        return p_ext, pc, po

    # ------------------------------------------------------------------ initial state
    def _initialize(self) -> None:
        dt = self.dt
        u, v = self.u, self.v
        f_int, f_ext, trial = self._forces(u, self.t)
        self.states = trial
        self._f_int = f_int
        self._f_ext = f_ext
        minv = self.ops.inv_mass
        a = -minv * f_int if f_ext is None else minv * (f_ext - f_int)
        self.a = a
        # half step: v^{1/2} = v^0 + Δt/2 a^0 − ½ M⁻¹ Bᵀ Λ^0 with B v^{1/2} = w^0
        lam_e, lam_a, fulls, g_a, v_half = self._impulse(v + 0.5 * dt * a, u, self.t, 0.5)
        self._v_next = v_half  # v^{1/2}
        self._record_impulse(lam_e, fulls, g_a, lam_a)
        self._p_prev = self._powers()

    # ------------------------------------------------------------------ step
    def _step_impl(self) -> None:
        dt = self.dt
        u_old = self.u
        v_half = self._v_next
        u = u_old + dt * v_half
        self.t = self.t0 + (self.step_count + 1) * dt
        f_int, f_ext, trial = self._forces(u, self.t)
        minv = self.ops.inv_mass
        a = -minv * f_int if f_ext is None else minv * (f_ext - f_int)
        # impulse at t_{n+1} for the next mid-step velocity
        v_star = v_half + dt * a
        tic = time.perf_counter()
        lam_e, lam_a, fulls, g_a, v_next = self._impulse(v_star, u, self.t, 1.0)
        self.constraint_time += time.perf_counter() - tic
        self.states = trial
        self.u = u
        self.a = a
        self.v = 0.5 * (v_half + v_next)
        self._v_next = v_next
        self._f_ext = f_ext
        self._record_impulse(lam_e, fulls, g_a, lam_a)
        for c, lam in zip(self.unilateral, fulls):
            c.end_step(self.t, u, self.v, lam)
        p_new = self._powers()
        p_old = self._p_prev
        half = 0.5 * dt
        self._w_ext += half * (p_old[0] + p_new[0])
        self._w_coupling += half * (p_old[1] + p_new[1])
        self._w_constraint += half * (p_old[2] + p_new[2])
        if not self.ops.linear:
            du = u - u_old
            self._w_internal += self.ops.block_dots(du, 0.5 * (self._f_int + f_int))
        self._f_int = f_int
        self._p_prev = p_new

    # ------------------------------------------------------------------ info
    @property
    def mid_step_velocity(self) -> np.ndarray:
        """v^{n+1/2} (m/s): the velocity of the next step, already constrained."""
        return self._v_next
