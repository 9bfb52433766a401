"""The result of a dynamic run: recorded histories, the final state, energy accounting.

Energy accounting (every integrator): per block (model) b,

* kinetic energy ``T_b = ½ v_bᵀ M_b v_b`` with the α-weighted mass of the integrator (lumped for
  the explicit scheme), strain energy ``U_b = ½ u_bᵀ K_b u_b`` (α-weighted; nonlinear blocks: the
  accumulated work of the internal forces);
* stored energy ``S_b`` and plastic dissipation ``D_b``: the models' own, from their committed
  states, for nonlinear blocks whose models offer the optional members
  ``stored_energy_of_state(state, weight)`` and ``plastic_dissipation(state, weight)``
  (:class:`arlequin.contract.DynamicModel`); else ``S_b = U_b`` and ``D_b = 0``;
* work of the external forces ``W_ext,b``, of the coupling (mediator) forces ``W_c,b`` and of the
  other constraint forces (Dirichlet reactions, contact) ``W_r,b``, accumulated from the forces
  and the displacement increments / velocities of the steps (never as a balance residual).

The coupling forces on the two models are opposite (−C_cᵀλ and +C_fᵀλ): their works on the coarse
and on the fine block cancel when the coupled velocities satisfy C_c v_c = C_f v_f. The balance
``E − E(0) − W_ext − W_c − W_r`` (E = Σ T_b + U_b) measures the numerical energy error. With
nonlinear blocks U_b is the internal work, so that balance is the scheme's own; the *material*
balance ``material_balance`` writes it with the models' stored energy and dissipation instead,
``T + S + D − (T + S + D)(0) − W``: it also measures how far the scheme's internal work is from
the constitutive update's (the trapezoidal rule on the forces against the return map's
backward-Euler dissipation).
Units: J for energies and works. Multipliers λ are such that the force on the system is −Bᵀλ
(N): their unit is N over the unit of their rows (Dirichlet rows: N; mediator rows, of
∫ψ·φ: N/m³, N/m for 1D bars; contact rows −W G: Pa).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["DynamicResult"]


@dataclass
class DynamicResult:
    """Histories of a dynamic run (recorded steps) and its final state.

    Attributes
    ----------
    times : ndarray, shape (n_rec,)
        Recorded times (s), starting with the initial time.
    kinetic, strain : dict
        Block name -> α-weighted kinetic / strain energy (J), shape (n_rec,). ``kinetic`` is the
        integrator's energy form (central differences: ½ ṽ^{n−½}·M v^{n+½}; see
        docs/dynamics.md), the one the balance is written with.
    external_work, coupling_work, constraint_work : dict
        Block name -> accumulated work (J) of the external forces, of the coupling (mediator)
        forces and of the other constraint forces (Dirichlet reactions, contact), shape (n_rec,).
    multipliers : dict
        Constraint name -> multipliers, shape (n_rec, m): the force on the system is −Bᵀλ (N);
        N for Dirichlet rows, N/m³ for mediator rows (N/m for 1D bars), Pa for contact rows.
    status_iterations : ndarray of int, shape (n_rec,)
        Status iterations of the unilateral constraints in the step ending at each record.
    u, v : ndarray, shape (n,)
        Final displacement (m) and velocity (m/s).
    fields : dict or None
        ``{"u": (n_rec, n), "v": (n_rec, n)}`` when recorded (``save_fields=True``).
    n_steps : int
    dt : float
        Size of the last step (s): the time step of a constant-step run.
    step_sizes : ndarray, shape (n_rec,)
        Size (s) of the step ending at each record (0 at the initial record).
    critical_dt : float or None
        Critical (stable-limit) step of the explicit coupled system (s), when computed.
    status : int
        0: reached t_end; 1: stopped by the callback; −1: failed (see ``message``).
    message : str
    n_status_failures : int
        Steps whose status iterations reached the cap.
    integrator : str
    states : dict
        Final committed model states (block name -> one state per block term).
    constraint_states : dict
        Final committed state of each unilateral constraint (name -> its state record, with
        ``work`` the accumulated work of its forces, J).
    constraint_records : dict
        Unilateral constraint name -> the per-step records of the recorded steps (one per record
        after the initial one, i.e. aligned with ``times[1:]``); see :meth:`history`.
    kinetic_full_step : dict
        Block name -> ½ vᵀM v of the full-step velocity (J), shape (n_rec,): a diagnostic (for
        the explicit scheme it differs from ``kinetic`` by O((ωΔt)²) of the excited modes).
    damping_work : dict
        Block name -> work of the damping forces since the start (J, ≤ 0), shape (n_rec,):
        zeros without :class:`~arlequin.solvers.RayleighDamping`.
    band_plastic_fraction : float or None
        The largest share of a J2 patch's gluing band that was plastic at a recorded sample
        (None: no J2 patch; :class:`~arlequin.solvers.system.yield_watch.BandYieldWatch`).
    stored, dissipation : dict
        Block name -> stored energy and accumulated plastic dissipation (J), shape (n_rec,),
        of the models that offer them (``stored_energy_of_state``, ``plastic_dissipation``);
        else ``strain`` and zeros (linear blocks: ½ uᵀK u and zeros).
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
    step_sizes: np.ndarray | None = None
    constraint_states: dict[str, Any] = field(default_factory=dict, repr=False)
    constraint_records: dict[str, list[Any]] = field(default_factory=dict, repr=False)
    kinetic_full_step: dict[str, np.ndarray] = field(default_factory=dict)
    damping_work: dict[str, np.ndarray] = field(default_factory=dict)
    stored: dict[str, np.ndarray] = field(default_factory=dict)
    dissipation: dict[str, np.ndarray] = field(default_factory=dict)
    band_plastic_fraction: float | None = None

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
    def total_damping_work(self) -> np.ndarray:
        return self._sum(self.damping_work, self.times.size)

    @property
    def balance(self) -> np.ndarray:
        """E − E(0) − W_ext − W_c − W_r − W_d (J): the numerical energy error, shape (n_rec,)."""
        e = self.total_energy
        return (
            e
            - e[0]
            - self.total_external_work
            - self.total_coupling_work
            - self.total_constraint_work
            - self.total_damping_work
        )

    @property
    def total_stored(self) -> np.ndarray:
        """Σ_b S_b (J), shape (n_rec,) (``strain`` where no block reports its stored energy)."""
        return self._sum(self.stored, self.times.size) if self.stored else self.total_strain

    @property
    def total_dissipation(self) -> np.ndarray:
        """Σ_b D_b, the plastic dissipation of the models that report it (J), shape (n_rec,)."""
        return self._sum(self.dissipation, self.times.size)

    @property
    def material_balance(self) -> np.ndarray:
        """T + S + D − (T + S + D)(0) − W_ext − W_c − W_r − W_d (J), shape (n_rec,): the
        balance with the models' stored energy and plastic dissipation (see the module
        docstring); equal to :attr:`balance` for linear systems."""
        e = self.total_kinetic + self.total_stored + self.total_dissipation
        return (
            e
            - e[0]
            - self.total_external_work
            - self.total_coupling_work
            - self.total_constraint_work
            - self.total_damping_work
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
            - self.damping_work.get(block, 0.0)
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

    def history(self, name: str) -> list[Any]:
        """The recorded per-step records of unilateral constraint ``name`` (aligned with
        ``times[1:]``); a contact constraint stacks them into arrays with its own
        ``history(result)`` method."""
        if name not in self.constraint_records:
            known = sorted(self.constraint_records)
            raise KeyError(f"no unilateral constraint named {name!r}; recorded: {known}")
        return self.constraint_records[name]

    def summary(self) -> str:
        """One line: integrator, steps, end time, energy balance."""
        return (
            f"{self.integrator}: {self.n_steps} steps to t = {self.times[-1]:.6e} s "
            f"(last dt {self.dt:.4e} s), status {self.status}, energy balance "
            f"{self.relative_balance():.3e} of the energy scale"
        )
