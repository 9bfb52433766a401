"""Multi-time-step central differences: the forces of slow blocks applied once every m steps.

The blocks of a coupled system are split into *slow* ones (the coarse linear-elastic model of
an Arlequin problem) and *fast* ones (the refined patches). Every fine step h kicks every dof
with the external forces, the fast blocks' internal forces and the constraint impulses (the
coupling rows and the contact act at every fine step, on both models, with their true masses);
the internal force of the slow blocks, ``K_s u_s``, is evaluated once per macro step H = m h
and applied as one impulse of size H̄ = ½(H_{n−1} + H_n) at the macro times. This is the
impulse form of multiple time stepping (Verlet-I / r-RESPA, Grubmüller et al. 1991, Tuckerman,
Berne and Martyna 1992), the velocity-Verlet splitting of the slow potential from the rest:

1. at a macro time T_n: ``v* = v^{n−½} + h̄ M⁻¹(f_ext − f_fast) − H̄ M⁻¹ f_slow(u^n)``;
2. at the other fine times: ``v* = v^{n−½} + h̄ M⁻¹(f_ext − f_fast)``;
3. then, at every fine time, the impulses of the one-step scheme
   (:mod:`arlequin.solvers.dynamics.explicit`) and the drift ``u += h v``.

With m = 1 it is :class:`~arlequin.solvers.CentralDifference` exactly. The macro map is
symplectic on the constraint subspace (the kicks and the projections of RATTLE preserve the
symplectic form), so a stable run has a bounded energy error and no drift. The error shows at
the interface: the constraint impulse of a macro time acts on the velocity after the slow kick,
so the impulse H̄ f_slow of the coarse dofs in the gluing zone passes into the patch once per
macro step (the per-step multipliers alternate at the macro period; their macro-step means are
the smooth coupling force).

Stability. The fine step obeys the coupled system's critical step. Each macro step uses the
ratio ``m_n = min(M, ⌊safety Δt_crit,slow / h_n⌋, ⌊safety π / (ω_f h_n)⌋)`` (at least 1):
the slow force's own Verlet limit (Δt_crit,slow, the critical step of the slow blocks alone),
and the resonance of impulse multiple time stepping, which grows the energy once the macro
step nears half the period of the fastest fast mode (H ω_f ≈ π; measured on a 1D Arlequin bar,
instability from H ω_f ≈ 2.9). ω_f is the largest frequency of the fast blocks (their
critical steps and the coupled ω_max, scaled by the current configuration). The second bound
means that subcycling pays only when the fine step is well below the fast partition's critical
step, e.g. when a few distorted cells set it; ``resonance_bound=False`` drops it and leaves the
energy check (``energy_tolerance``) to stop a resonating run with a clear error. Slow blocks
must be linear. Output and stop times land on macro times (a macro step is shortened to land,
its fine steps equal).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from ...contract import SimulationError
from ...linalg.vector_updates import scaled_plus
from .base import Integrator
from .controllers import check_step
from .explicit import CentralDifference
from .registry import register
from .stability import DEFAULT_SAFETY

__all__ = ["SubcycledCentralDifference"]

logger = logging.getLogger(__name__)


@register("explicit-mts", "subcycling", "multi-time-step")
class SubcycledCentralDifference(CentralDifference):
    """Explicit central differences with the slow blocks' forces every m fine steps.

    See the module docstring for the scheme.

    Parameters
    ----------
    system : CoupledSystem or ArlequinProblem
    dt : float, optional
        The fine step (s) (default: ``safety`` × the critical step of the coupled system).
    slow_blocks : sequence of str
        Names of the (linear) blocks whose internal force is evaluated once per macro step
        (default ``("coarse",)``, the coarse model of an :class:`~arlequin.ArlequinProblem`).
        At least one block must stay fast.
    step_ratio : int
        Largest ratio M of the macro step to the fine step (default 2; 1 is the one-step
        scheme). Each macro step uses the largest ratio ≤ M that keeps the slow blocks stable.
    resonance_bound : bool
        Also keep H ω_f ≤ 0.9 π (default True), ω_f the fast partition's largest frequency
        (:meth:`fast_frequency`): the impulse scheme is unstable near H ω_f = π (the module
        docstring). False leaves the energy check alone to stop a resonating run (for fast
        modes that the slow force does not reach, e.g. localised far from the gluing zone).
    energy_tolerance : float
        Largest relative energy balance error (abs(balance) / the largest energy or external work
        so far) accepted; checked every ``check_every`` macro steps. Beyond it the run stops
        with a :class:`~arlequin.contract.SimulationError`: a macro step resonating with the
        fast partition's frequencies makes the impulse scheme unstable (the module docstring),
        and the error names the ratio to lower. Default 0.05.
    check_every : int
        Macro steps between two energy checks (default 64).
    safety, stable_method, check_dt, **kwargs
        As :class:`~arlequin.solvers.CentralDifference`.

    Attributes
    ----------
    macro_steps : int
        Number of macro steps completed (slow force evaluations after the initial one).
    ratios : list of int
        The ratio m_n of each macro step started so far.
    """

    name = "explicit-mts"

    def __init__(
        self,
        system,
        dt: float | None = None,
        *,
        slow_blocks: Sequence[str] = ("coarse",),
        step_ratio: int = 2,
        resonance_bound: bool = True,
        energy_tolerance: float = 0.05,
        check_every: int = 64,
        safety: float = DEFAULT_SAFETY,
        stable_method: str = "coupled",
        check_dt: bool = True,
        **kwargs: Any,
    ) -> None:
        if kwargs.get("damping") is not None:
            raise ValueError("damping is not supported by the multi-time-step integrator "
                             "(its slow blocks' damping force would be applied per macro step): "
                             "use the explicit integrator")  # fmt: skip
        if isinstance(step_ratio, bool) or int(step_ratio) != step_ratio or step_ratio < 1:
            raise ValueError(
                f"step_ratio must be a positive integer, got step_ratio={step_ratio!r}"
            )
        if isinstance(slow_blocks, str):
            slow_blocks = (slow_blocks,)
        if not (isinstance(energy_tolerance, (int, float)) and energy_tolerance > 0.0):
            raise ValueError(
                f"energy_tolerance must be a positive number, got {energy_tolerance!r}"
            )
        if isinstance(check_every, bool) or int(check_every) != check_every or check_every < 1:
            raise ValueError(f"check_every must be a positive integer, got {check_every!r}")
        self.step_ratio = int(step_ratio)
        self.resonance_bound = bool(resonance_bound)
        self.energy_tolerance = float(energy_tolerance)
        self.check_every = int(check_every)
        self.slow_names = tuple(slow_blocks)
        self.macro_steps = 0
        self.ratios: list[int] = []
        super().__init__(
            system, dt, safety=safety, stable_method=stable_method, check_dt=check_dt, **kwargs
        )

    # ------------------------------------------------------------------ partition
    def _setup_partition(self) -> None:
        names = self.ops.names
        unknown = [n for n in self.slow_names if n not in names]
        if unknown:
            raise ValueError(
                f"slow_blocks {unknown} are not blocks of the system (blocks: {names})"
            )
        if not self.slow_names:
            raise ValueError("slow_blocks is empty: give the blocks advanced with the macro step")
        if set(self.slow_names) == set(names):
            raise ValueError(
                f"slow_blocks={list(self.slow_names)} are all the blocks: at least one block "
                "must advance with the fine step"
            )
        self._slow_b = [names.index(n) for n in self.slow_names]
        nonlinear = [names[b] for b in self._slow_b if not self.ops.block_linear[b]]
        if nonlinear:
            raise ValueError(
                f"slow_blocks {nonlinear} are nonlinear: only linear blocks (the coarse models) "
                "can have their forces applied once per macro step"
            )
        self._fast_b = tuple(b for b in range(len(names)) if b not in self._slow_b)
        off = self.ops.offsets
        slow = np.zeros(self.ops.n, dtype=bool)
        for b in self._slow_b:
            slow[off[b] : off[b + 1]] = True
        self._slow = slow
        # the slow dofs as ranges (a block's dofs are contiguous; adjacent blocks merged): the
        # slow force and its kick on those dofs alone, not masks over every dof (two n-vector
        # passes a macro step and one a kick: 4% of a multi-time-step ball impact's step)
        ranges: list[list[int]] = []
        for b in sorted(self._slow_b):
            if ranges and ranges[-1][1] == off[b]:
                ranges[-1][1] = int(off[b + 1])
            else:
                ranges.append([int(off[b]), int(off[b + 1])])
        self._slow_ranges = [slice(a, b) for a, b in ranges]

    # ------------------------------------------------------------------ step sizes
    def slow_critical_time_step(self) -> float:
        """Critical step (s) of the slow blocks alone (their lumped weighted mass and
        stiffness; the slow blocks being linear, it does not change during a run)."""
        per = self._stable().per_block
        return min(per[n] for n in self.slow_names)

    def fast_frequency(self) -> float:
        """ω_f (rad/s): the largest frequency of the fast partition, the larger of the coupled
        system's ω_max and 2/Δt_crit of the fast blocks alone (initial configuration), scaled
        by the current-configuration estimate of the nonlinear blocks."""
        stable = self._stable()
        per = stable.per_block
        fast = min(per[self.ops.names[b]] for b in self._fast_b)
        omega = max(stable.omega_max, 2.0 / fast)
        now = self._critical_now if self._critical_now is not None else stable.critical
        return omega * stable.critical / now

    def _ratio_for(self, h: float) -> int:
        if self.step_ratio == 1:
            return 1
        m = math.floor(self.safety * self.slow_critical_time_step() / h * (1.0 + 1e-12))
        if self.resonance_bound:
            # the impulse scheme resonates once H ω_f nears π (H = T_f / 2): keep H ω_f ≤ 0.9π
            m = min(m, math.floor(self.safety * math.pi / (self.fast_frequency() * h)))
        return max(1, min(self.step_ratio, m))

    def _plan(self, h: float) -> float:
        """Choose the ratio of the macro step starting at t for the fine step h; return the
        fine step once the macro step is landed on the next stop time."""
        m = self._ratio_for(h)
        big = Integrator._clip(self, m * h)
        if big != m * h:  # shortened to land: as few fine steps as the remainder needs
            m = max(1, min(m, math.ceil(big / h * (1.0 - 1e-9))))
        self._m_n = m
        self._plan_h = h if big == m * h else big / m
        return self._plan_h

    def _clip(self, dt: float) -> float:
        if self._j:
            stop = self._next_stop()
            end = self.t + (self._m_n - self._j) * self.dt
            if stop is not None and stop < end * (1.0 - 1e-12):
                raise RuntimeError(
                    f"{self.name}: stop time {stop:.6e} s falls inside the current macro step "
                    f"(ending at {end:.6e} s); set stops at the start of a macro step"
                )
            return self.dt  # inside a macro step the fine step is fixed
        m_before = self._m_n
        h = self._plan(dt)
        if h == self.dt and self._m_n != m_before:
            super()._step_size_changed()  # same fine step, another ratio: redo the kick at t
        return h

    def set_step_size(self, dt: float) -> None:
        """Impose the size (s) of the next step; only at the start of a macro step.

        Raises
        ------
        RuntimeError
            Inside a macro step (its fine steps are equal); the step size is left unchanged.
        """
        if self._j and dt != self.dt:
            raise RuntimeError(
                f"{self.name}: the step size can change only at the start of a macro step "
                f"(fine step {self._j} of {self._m_n} at t = {self.t:.6e} s)"
            )
        super().set_step_size(dt)

    def _next_step_size(self) -> float:
        if self._j:
            return self.dt
        return self._check_step_size(self._plan(check_step(self.controller.propose(self))))

    def _step_size_changed(self) -> None:
        if self.dt != self._plan_h:  # imposed by the caller: the largest ratio that lands
            m = self._ratio_for(self.dt)
            stop = self._next_stop()
            if stop is not None:
                m = max(1, min(m, math.floor((stop - self.t) / self.dt * (1.0 + 1e-9))))
            self._m_n = m
            self._plan_h = self.dt
        super()._step_size_changed()

    # ------------------------------------------------------------------ the scheme
    def _initialize(self) -> None:
        self._setup_partition()
        self._j = 0
        self._m_n = self._ratio_for(self.dt)
        self._plan_h = self.dt
        self._big_prev = 0.0
        self._big_cur = 0.0
        # M⁻¹ f_slow (m/s²) on the slow dofs in the order of _slow_ranges, made from the macro
        # time's internal force (_f_int at the start of a macro step) when a kick needs it
        self._minv_f_slow: np.ndarray | None = None
        self._starting = True  # the forces at t0 are those of a macro time
        super()._initialize()
        self._starting = False
        self._check_due = False
        self._energy0 = self.total_energy()
        self._energy_scale = abs(self._energy0)

    def _scheme_fields(self) -> tuple[str, ...]:
        return (*super()._scheme_fields(), "_j", "_m_n", "_plan_h", "_big_prev", "_big_cur",
                "_minv_f_slow", "macro_steps", "ratios", "_energy_scale")  # fmt: skip

    def _kinetic(self) -> np.ndarray:
        """½ ṽ⁻·M v⁺ per block; at a macro time the slow dofs' ṽ⁻ uses the macro steps."""
        ratio = np.full(self.ops.n, self.dt / self._dt_bar)
        if self._j == 0 and self.step_count:
            big = self._m_n * self.dt
            ratio[self._slow] = big / (0.5 * (self._big_prev + big))
        back = self._v_next - ratio * (self._v_next - self._v_minus)
        return 0.5 * self.ops.block_dots(back, self.ops.mass * self._v_next)

    def energy_balance_error(self) -> float:
        """``|E − E(0) − W_ext − W_c − W_r| / max(E, |W_ext|)`` so far (dimensionless)."""
        e = self.energies()
        total = sum(e["kinetic"].values()) + sum(e["strain"].values())
        works = sum(sum(e[k].values()) for k in ("external_work", "coupling_work",
                                                   "constraint_work"))  # fmt: skip
        w_ext = sum(e["external_work"].values())
        self._energy_scale = max(self._energy_scale, abs(total), abs(w_ext))
        bal = total - self._energy0 - works
        return abs(bal) / self._energy_scale if self._energy_scale > 0 else 0.0

    def _check_energy(self) -> None:
        err = self.energy_balance_error()
        if err > self.energy_tolerance:
            self.status = "failed"
            raise SimulationError(
                f"{self.name}: energy balance error {err:.3g} exceeds energy_tolerance="
                f"{self.energy_tolerance} at step {self.step_count}, t = {self.t:.6e} s, with "
                f"macro steps of {self._m_n} fine steps: the macro step resonates with the fast "
                f"blocks; lower step_ratio (now {self.step_ratio})",
                self.step_count,
                self.t,
            )

    def _forces(self, u: np.ndarray, t: float, dt: float | None = None):
        """Forces at u: the slow blocks' internal force only at a macro time (M⁻¹ f_slow kept
        in ``_minv_f_slow``; the returned internal force is zero on the slow dofs otherwise)."""
        macro_time = self._starting or self._j + 1 == self._m_n
        if macro_time:
            self._minv_f_slow = None  # of the force made here, which becomes _f_int
            return super()._forces(u, t, dt)
        return super()._forces(u, t, dt, blocks=self._fast_b)

    def _kick(self, v_minus: np.ndarray, dt_bar: float) -> np.ndarray:
        v_star = scaled_plus(dt_bar, self.a, v_minus)  # v⁻ + Δt̄ a, one compiled pass
        if self._j == 0:
            # the slow internal force acts as one impulse H̄ f_slow instead of h̄ f_slow
            big_bar = 0.5 * (self._big_prev + self._m_n * self.dt)
            scale = big_bar - dt_bar
            if scale != 0.0:  # zero while the macro steps are single fine steps (m = 1)
                if self._minv_f_slow is None:  # _f_int is the macro time's force (j = 0)
                    minv, f = self.ops.inv_mass, self._f_int
                    parts = [minv[sl] * f[sl] for sl in self._slow_ranges]
                    self._minv_f_slow = parts[0] if len(parts) == 1 else np.concatenate(parts)
                start = 0
                for sl in self._slow_ranges:  # the slow dofs only (zero force elsewhere)
                    stop = start + sl.stop - sl.start
                    v_star[sl] -= scale * self._minv_f_slow[start:stop]
                    start = stop
        return v_star

    def _step_impl(self) -> None:
        super()._step_impl()
        if self._check_due:  # at a macro time, once the kick at t is known
            self._check_due = False
            self._check_energy()

    def _phase_advanced(self) -> None:
        if self._j == 0:
            self._big_cur = self._m_n * self.step_size
            self.ratios.append(self._m_n)
        if self._j + 1 == self._m_n:
            self._big_prev = self._big_cur
            self._j = 0
            self.macro_steps += 1
            self._check_due = self.step_ratio > 1 and self.macro_steps % self.check_every == 0
        else:
            self._j += 1
