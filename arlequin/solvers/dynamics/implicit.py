"""Implicit integrators on the monolithic saddle point: Newmark (β, γ), HHT-α, θ-scheme.

All three solve, each step, for one unknown vector x (n) and the multipliers μ of the equality
rows and of the active unilateral rows, with the end-of-step quantities affine in x:

    u = u_p + c_u x,   v = v_p + c_v x,   "a" = a_p + c_a x

and the residual (N)

    R(x, μ) = M (a_p + c_a x) + w₁ f_int(u) + w₀ f_int(u^n) + w₀ᶜ Bᵀλ^n − f̄ + Bᵀ μ = 0,
    f̄ = w₁ f_ext(t_{n+1}) + w₀ f_ext(t_n),

with the rows written on x: displacement rows ``B u = g(t_{n+1})`` as ``B x = (g − B u_p)/c_u``,
velocity rows ``B v = g(t_{n+1})`` as ``B x = (g − B v_p)/c_v``:

=============  ===========  ==========================  ===========  ==========  ==========
scheme         x            u_p, c_u                    c_v          (w₁, w₀)    μ
=============  ===========  ==========================  ===========  ==========  ==========
Newmark        a^{n+1}      ũ, βΔt²                     γΔt          (1, 0)      λ^{n+1}
HHT-α          a^{n+1}      ũ, βΔt²                     γΔt          (1+α, −α)   (1+α)λ^{n+1}
θ-scheme       v^{n+1}      u^n+(1−θ)Δt v^n, θΔt         1            (θ, 1−θ)    λ (step)
=============  ===========  ==========================  ===========  ==========  ==========

(ũ = u^n + Δt v^n + (½−β)Δt² a^n; HHT: α ∈ [−1/3, 0], β = (1−α)²/4, γ = ½ − α; θ-scheme:
u^{n+1} = u^n + Δt((1−θ)v^n + θ v^{n+1}),
M(v^{n+1} − v^n)/Δt = f̄ − w₁f_int^{n+1} − w₀f_int^n − Bᵀλ).

Linear models: the matrix [[c_a M + w₁ c_u K, Bᵀ], [B, 0]] is factorised once (SuperLU) and each
step is one solve; nonlinear models: Newton iterations on R with the consistent tangent. The
trapezoidal rule (Newmark β = ¼, γ = ½, or θ = ½) conserves the energy of a linear system exactly.

Works per step: Newmark/HHT ``Δu·(F^n + F^{n+1})/2`` (end-point forces), θ-scheme ``Δu·F̄`` (step
forces), with Δu = u^{n+1} − u^n = Δt × the step's mean velocity.
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
import scipy.sparse as sp

from ...contract import SimulationError
from ...linalg.factor import factor_checked
from ..system.rows import rows_key, unilateral_block_power
from .base import Integrator
from .controllers import FixedStep, StepController
from .registry import register
from .stability import DEFAULT_SAFETY, stable_time_step

__all__ = ["HHTAlpha", "ImplicitIntegrator", "Newmark", "ThetaScheme"]

logger = logging.getLogger(__name__)


class ImplicitIntegrator(Integrator):
    """Common saddle-point machinery of :class:`Newmark`, :class:`HHTAlpha`, :class:`ThetaScheme`.

    Parameters
    ----------
    system : CoupledSystem
    dt : float, optional
        Time step (s); default: the default step of the explicit scheme on the same system
        (0.9 × the critical step of the coupled lumped-mass system).
    lumped : bool
        Lumped (row-sum) weighted mass instead of the consistent one (default False).
    newton_rtol, newton_atol : float
        Newton convergence: ‖R‖ ≤ rtol·scale + atol (N), scale = max of the norms of the terms
        of R (nonlinear models only).
    max_newton : int
        Newton iteration cap (a step that does not converge raises :class:`SimulationError`).
    newton : {"consistent", "initial"}
        Tangent of the Newton iterations on nonlinear models: their consistent tangent (the
        ``"tangent"`` capability, required: a model without it is refused with a
        :class:`~arlequin.contract.CapabilityError`), or their initial stiffness (modified
        Newton: linear convergence, for models without a tangent).
    **kwargs
        See :class:`arlequin.solvers.Integrator`.
    """

    name = "implicit"
    # subclasses set these from their parameters
    w1 = 1.0
    w0 = 0.0
    w0c = 0.0
    endpoint_multipliers = True

    def __init__(
        self,
        system,
        dt: float | None = None,
        *,
        newton_rtol: float = 1e-10,
        newton_atol: float = 0.0,
        max_newton: int = 25,
        newton: str = "consistent",
        **kwargs: Any,
    ) -> None:
        self.newton_rtol = float(newton_rtol)
        self.newton_atol = float(newton_atol)
        self.max_newton = int(max_newton)
        self._lu_cache: dict[Any, Any] = {}
        self.newton_iterations = 0
        if newton not in ("consistent", "initial"):
            raise ValueError(f"newton must be 'consistent' or 'initial', got {newton!r}")
        super().__init__(system, dt, tangent=newton, **kwargs)

    # ------------------------------------------------------------------ scheme hooks
    def _affine(self) -> tuple[np.ndarray, float, np.ndarray, float, np.ndarray, float]:
        """(u_p, c_u, v_p, c_v, a_p, c_a) of the current step."""
        raise NotImplementedError

    def _x_from_state(self) -> np.ndarray:
        """Initial guess of x (the predictor)."""
        raise NotImplementedError

    def _finish(self, x: np.ndarray) -> None:
        """Set self.a from the converged x (u and v are set by the caller)."""
        raise NotImplementedError

    # ------------------------------------------------------------------ dt, initial state
    def _default_controller(self) -> StepController:
        # the explicit scheme's step: lumped operators of their own (this scheme's mass may be
        # consistent)
        step = stable_time_step(self.system, "coupled")
        self.critical_dt = step.critical
        logger.info("implicit scheme: default dt = %.3g x critical explicit step", DEFAULT_SAFETY)
        return FixedStep(DEFAULT_SAFETY * step.critical)

    def _initialize(self) -> None:
        self.ops.check_tangents(f"the {self.name} scheme")
        self._lu_cache = {}
        self._empty_rows = sp.csr_matrix((0, self.ops.n))
        f_int, trial, _kt = self.ops.internal_force(self.u, self.states)
        self.states = trial
        self._f_int = f_int
        self._f_ext = self._external(self.t)
        self._fc_old = np.zeros(self.ops.n)  # Bᵀλ^n of all rows (end-point multipliers)
        self.multipliers = self.rows.split(np.zeros(self.rows.m))
        for c in self.unilateral:
            self.multipliers[c.name] = np.zeros(c.n_rows)
        self._initial_acceleration()

    def _scheme_fields(self) -> tuple[str, ...]:
        return ("_f_int", "_f_ext", "_fc_old", "_lam", "_lam_e_old", "_uni_old")

    def _external(self, t: float) -> np.ndarray:
        if self.system.load is None:
            return np.zeros(self.ops.n)
        return self.system.external_force(t)

    def _initial_acceleration(self) -> None:
        """Constrained a^0 and λ^0 from M a + f_int + Bᵀλ = f_ext, B a = d²g/dt² (or dg/dt)."""
        rows = self.rows
        r = self._f_ext - self._f_int
        m = self.ops.mass
        mmat = sp.diags(m) if self.ops.lumped else m
        if rows.m:
            h = self.dt
            target = np.where(rows.displacement, rows.rate(self.t, h, 2), rows.rate(self.t, h, 1))
            mat = sp.bmat([[mmat, rows.matrix.T], [rows.matrix, None]], format="csc")
            lu = factor_checked(mat, "the initial-acceleration saddle point [[M, Bᵀ], [B, 0]]")
            sol = lu.solve(np.concatenate([r, target]))
            a, lam = sol[: self.ops.n], sol[self.ops.n :]
        else:
            a = (
                r / m
                if self.ops.lumped
                else factor_checked(sp.csc_matrix(m), "the mass", spd=True).solve(r)
            )
            lam = np.zeros(0)
        self.a = a
        self._lam = lam
        self.multipliers = rows.split(lam)
        for c in self.unilateral:
            self.multipliers[c.name] = np.zeros(c.n_rows)
        self._fc_old = rows.matrix.T @ lam if rows.m else np.zeros(self.ops.n)
        self._lam_e_old = lam
        self._uni_old = [np.zeros(c.n_rows) for c in self.unilateral]

    # ------------------------------------------------------------------ linear algebra
    def _mass_times(self, x: np.ndarray) -> np.ndarray:
        return self.ops.mass * x if self.ops.lumped else self.ops.mass @ x

    def _system_matrix(self, kt: sp.spmatrix, c_a: float, c_u: float, b: sp.csr_matrix):
        mmat = sp.diags(self.ops.mass) if self.ops.lumped else self.ops.mass
        a = (c_a * mmat + (self.w1 * c_u) * kt).tocsr()
        return sp.bmat([[a, b.T], [b, None]], format="csc")

    def _rows_on_x(
        self,
        u_p: np.ndarray,
        c_u: float,
        v_p: np.ndarray,
        c_v: float,
        t_new: float,
        trials: list[Any],
    ) -> tuple[sp.csr_matrix, np.ndarray, list[np.ndarray], Any]:
        """Equality + active unilateral rows written on x: (B, r, active index lists, key)."""
        rows = self.rows
        if not self.unilateral:
            if not rows.m:
                return self._empty_rows, np.zeros(0), [], (self.dt,)
            g = rows.g(t_new)
            rhs_e = np.where(
                rows.displacement, (g - rows.matrix @ u_p) / c_u, (g - rows.matrix @ v_p) / c_v
            )
            return rows.matrix, rhs_e, [], (self.dt,)
        mats, rhs = [], []
        if rows.m:
            g = rows.g(t_new)
            bu = rows.matrix @ u_p
            bv = rows.matrix @ v_p
            rhs.append(np.where(rows.displacement, (g - bu) / c_u, (g - bv) / c_v))
            mats.append(rows.matrix)
        g_a, rhs_a, idx, disp = self._active(trials)
        if g_a.shape[0]:
            rhs.append(np.where(disp, (rhs_a - g_a @ u_p) / c_u, (rhs_a - g_a @ v_p) / c_v))
            mats.append(g_a)
        n = self.ops.n
        b = sp.vstack(mats, format="csr") if mats else sp.csr_matrix((0, n))
        r = np.concatenate(rhs) if rhs else np.zeros(0)
        return b, r, idx, (self.dt, rows_key(g_a))

    def _solve_constrained(self, t_new: float, trials: list[Any]):
        """One constrained solve (linear or Newton) with the trials' statuses."""
        u_p, c_u, v_p, c_v, a_p, c_a = self._affine()
        b, r_rows, idx, key = self._rows_on_x(u_p, c_u, v_p, c_v, t_new, trials)
        n = self.ops.n
        f_bar = self.w1 * self._f_ext_new + self.w0 * self._f_ext
        known = f_bar - self._mass_times(a_p) - self.w0 * self._f_int - self.w0c * self._fc_old
        if self.ops.linear:
            lu = self._lu_cache.get(key)
            if lu is None:
                mat = self._system_matrix(self.ops.stiffness, c_a, c_u, b)
                lu = factor_checked(
                    mat, f"the {self.name} saddle point [[c_a M + c_u K, Bᵀ], [B, 0]]"
                )
                if len(self._lu_cache) >= 8:
                    self._lu_cache.clear()
                self._lu_cache[key] = lu
            rhs = np.concatenate([known - self.w1 * (self.ops.stiffness @ u_p), r_rows])
            sol = lu.solve(rhs)
            x, mu = sol[:n], sol[n:]
            u = u_p + c_u * x
            f_int, trial, _ = self.ops.internal_force(u, self.states, dt=self.dt)
            self.newton_iterations = 1
            return x, mu, b, idx, f_int, trial
        # Newton: one internal-force + tangent evaluation per iteration
        x = self._x_from_state()
        mu = np.zeros(b.shape[0])
        scale0 = max(float(np.linalg.norm(known)), 1e-300)
        force = self.ops.internal_force
        f_int, trial, kt = force(u_p + c_u * x, self.states, tangent=True, dt=self.dt)
        res = np.full(n, np.inf)
        for it in range(1, self.max_newton + 1):
            res0 = self._mass_times(c_a * x) + self.w1 * f_int - known
            mat = self._system_matrix(kt, c_a, c_u, b)
            lu = factor_checked(mat, f"the {self.name} Newton saddle point")
            sol = lu.solve(np.concatenate([-res0, r_rows - b @ x]))
            dx, mu = sol[:n], sol[n:]
            x = x + dx
            f_int, trial, kt = force(u_p + c_u * x, self.states, tangent=True, dt=self.dt)
            bmu = b.T @ mu if b.shape[0] else 0.0
            res = self._mass_times(c_a * x) + self.w1 * f_int - known + bmu
            scale = max(scale0, float(np.linalg.norm(self.w1 * f_int)), float(np.linalg.norm(bmu)))
            if np.linalg.norm(res) <= self.newton_rtol * scale + self.newton_atol:
                self.newton_iterations = it
                return x, mu, b, idx, f_int, trial
            if not np.all(np.isfinite(res)):
                break
        raise SimulationError(
            f"{self.name}: Newton did not converge in {self.max_newton} iterations at step "
            f"{self.step_count + 1}, t = {t_new:.6e} s (residual {np.linalg.norm(res):.3e} N)",
            self.step_count + 1,
            t_new,
        )

    # ------------------------------------------------------------------ step
    def _step_impl(self) -> None:
        dt = self.dt
        t_new = self._end_time()
        self._f_ext_new = self._external(t_new)
        trials = self._begin_unilateral(self.t, dt, self.u, self.v)
        converged = False
        it = 0
        while it < self.max_status_iterations:
            it += 1
            x, mu, b, idx, f_int, trial = self._solve_constrained(t_new, trials)
            u_p, c_u, v_p, c_v, _, _ = self._affine()
            u_new = u_p + c_u * x
            v_new = v_p + c_v * x
            m_e = self.rows.m
            lam_all = self._multipliers_from(mu)
            fulls = self._full_multipliers(lam_all[m_e:], idx)
            if not self.unilateral:
                converged = True
                break
            trials, changed = self._update_statuses(trials, u_new, v_new, fulls)
            if not changed:
                converged = True
                break
        self._check_finite(t_new, u_new, v_new)
        status_iterations = it if self.unilateral else 0
        if not converged:
            self._status_cap_reached(t_new)
        if self.endpoint_multipliers:  # the step's force: the mean of the end-point values
            impulses = [0.5 * dt * (o + n) for o, n in zip(self._uni_old, fulls)]
        else:
            impulses = [dt * f for f in fulls]
        constraint_states = (
            self._commit_unilateral(trials, t_new, u_new, self.v, v_new, fulls, impulses)
            if trials
            else self.constraint_states
        )
        # works with the forces of the step: −Δu·Bᵀλ̄ per block (λ̄: mean of the end-point
        # multipliers, or the step multipliers of the θ-scheme)
        du = u_new - self.u
        nb = len(self.ops.blocks)
        rows = self.rows
        m_e = rows.m
        lam_e_new = lam_all[:m_e]
        if self.endpoint_multipliers:
            f_ext_w = 0.5 * (self._f_ext + self._f_ext_new)
            lam_e_w = 0.5 * (self._lam_e_old + lam_e_new)
            uni_w = [0.5 * (o + n) for o, n in zip(self._uni_old, fulls)]
        else:
            f_ext_w = self.w1 * self._f_ext_new + self.w0 * self._f_ext
            lam_e_w = lam_e_new
            uni_w = fulls
        if m_e:
            w_c, w_o = rows.block_powers(lam_e_w, du[rows.cols])
        else:
            w_c, w_o = np.zeros(nb), np.zeros(nb)
        for tr, lam in zip(trials, uni_w):
            w_o = w_o + unilateral_block_power(self.ops, tr.matrix, lam, du)
        if self.system.load is not None:
            self._w_ext += self.ops.block_dots(du, f_ext_w)
        self._w_coupling += w_c
        self._w_constraint += w_o
        if not self.ops.linear:
            self._w_internal += self.ops.block_dots(du, 0.5 * (self._f_int + f_int))
        # commit
        self.status_iterations = status_iterations
        self.constraint_states = constraint_states
        self.u = u_new
        self.v = v_new
        self._finish(x)
        self.t = t_new
        self.states = trial
        self._f_int = f_int
        self._f_ext = self._f_ext_new
        if self.w0c:
            self._fc_old = b.T @ lam_all if b.shape[0] else np.zeros(self.ops.n)
        self._lam_e_old = lam_e_new
        self._uni_old = fulls
        mult = rows.split(lam_e_new) if m_e else {}
        for c, lam in zip(self.unilateral, fulls):
            mult[c.name] = lam
        self.multipliers = mult
        self.step_size = dt
        self.step_count += 1
        self.dt = self._next_step_size()

    def _multipliers_from(self, mu: np.ndarray) -> np.ndarray:
        """Reported multipliers (N) from the unknown μ."""
        return mu / self.w1 if self.endpoint_multipliers else mu


@register("newmark")
class Newmark(ImplicitIntegrator):
    """Newmark (β, γ) on the monolithic saddle point (default: trapezoidal rule β = ¼, γ = ½).

    Parameters
    ----------
    beta, gamma : float
        Newmark parameters; unconditionally stable for 2β ≥ γ ≥ ½; second order iff γ = ½.
    **kwargs
        See :class:`ImplicitIntegrator`.
    """

    name = "newmark"

    def __init__(
        self,
        system,
        dt: float | None = None,
        *,
        beta: float = 0.25,
        gamma: float = 0.5,
        **kwargs: Any,
    ) -> None:
        if not beta > 0.0:
            raise ValueError(f"Newmark beta must be positive (implicit), got beta={beta}")
        if not gamma >= 0.5:
            raise ValueError(f"Newmark gamma must be >= 1/2, got gamma={gamma}")
        self.beta = float(beta)
        self.gamma = float(gamma)
        super().__init__(system, dt, **kwargs)

    def _affine(self):
        dt, beta, gamma = self.dt, self.beta, self.gamma
        u_pred = self.u + dt * self.v + (0.5 - beta) * dt * dt * self.a
        v_pred = self.v + (1.0 - gamma) * dt * self.a
        return u_pred, beta * dt * dt, v_pred, gamma * dt, np.zeros_like(self.u), 1.0

    def _x_from_state(self) -> np.ndarray:
        return self.a.copy()

    def _finish(self, x: np.ndarray) -> None:
        self.a = x


@register("hht", "hht-alpha", "hht_alpha")
class HHTAlpha(Newmark):
    """Hilber–Hughes–Taylor α-method: Newmark with α-weighted forces, numerical damping.

    Parameters
    ----------
    alpha : float
        In [−1/3, 0]; 0 is the trapezoidal rule, −1/3 the strongest damping of high frequencies.
        β = (1 − α)²/4 and γ = ½ − α unless given.
    """

    name = "hht"

    def __init__(
        self,
        system,
        dt: float | None = None,
        *,
        alpha: float = -0.1,
        beta: float | None = None,
        gamma: float | None = None,
        **kwargs: Any,
    ) -> None:
        if not -1.0 / 3.0 - 1e-12 <= alpha <= 0.0:
            raise ValueError(f"HHT alpha must lie in [-1/3, 0], got alpha={alpha}")
        self.alpha = float(alpha)
        self.w1 = 1.0 + alpha
        self.w0 = -alpha
        self.w0c = -alpha
        beta = (1.0 - alpha) ** 2 / 4.0 if beta is None else beta
        gamma = 0.5 - alpha if gamma is None else gamma
        super().__init__(system, dt, beta=beta, gamma=gamma, **kwargs)


@register("theta", "theta-scheme", "theta_scheme")
class ThetaScheme(ImplicitIntegrator):
    """θ-scheme on (u, v): u^{n+1} = u^n + Δt((1−θ)v^n + θv^{n+1}) (the seed's scheme).

    M (v^{n+1} − v^n)/Δt = θ(f^{n+1} − f_int^{n+1}) + (1−θ)(f^n − f_int^n) − Bᵀλ, with λ the
    step's multipliers (reported as forces). θ = ½: trapezoidal rule (energy conserving, second
    order); θ > ½: first order, dissipative. Velocity-level rows act on v^{n+1}.

    Parameters
    ----------
    theta : float
        In [½, 1].
    """

    name = "theta"
    endpoint_multipliers = False

    def __init__(
        self, system, dt: float | None = None, *, theta: float = 0.5, **kwargs: Any
    ) -> None:
        if not 0.5 <= theta <= 1.0:
            raise ValueError(f"theta must lie in [1/2, 1], got theta={theta}")
        self.theta = float(theta)
        self.w1 = self.theta
        self.w0 = 1.0 - self.theta
        self.w0c = 0.0
        super().__init__(system, dt, **kwargs)

    def _affine(self):
        dt, th = self.dt, self.theta
        u_p = self.u + (1.0 - th) * dt * self.v
        return u_p, th * dt, np.zeros_like(self.u), 1.0, -self.v / dt, 1.0 / dt

    def _x_from_state(self) -> np.ndarray:
        return self.v.copy()

    def _finish(self, x: np.ndarray) -> None:
        # mean acceleration of the step (m/s²); u and v are already the end-of-step values
        self.a = (x - self._v_start) / self._dt_step

    def _step_impl(self) -> None:
        self._v_start = self.v.copy()
        self._dt_step = self.dt
        super()._step_impl()

    def _initial_acceleration(self) -> None:
        # the θ-scheme needs no initial acceleration; multipliers are step quantities
        self.a = np.zeros(self.ops.n)
        self._lam = np.zeros(self.rows.m)
        self._lam_e_old = self._lam
        self._uni_old = [np.zeros(c.n_rows) for c in self.unilateral]
