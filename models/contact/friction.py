"""Coulomb friction in the level-set contact model: a tangential indicator field S_t.

At each collocation point k of :class:`arlequin.models.LevelSetContact`, with the active normal
status S = S_d S_v, the tangential multiplier λ_t (Pa, a vector of the tangent plane) and the
tangential velocity jump [[v_t]] (m/s, the slave's velocity relative to the obstacle)::

    S_t = 1(|λ_t − κ_t [[v_t]]| ≤ μ |λ_v|)                                  (stick)
    λ_t = S [S_t (λ_t − η_t [[v_t]]) + (1 − S_t) μ |λ_v| q / |q|],  q = λ_t − κ_t [[v_t]]

(κ_t > 0, Pa·s/m, default the normal κ). With the nodal collocation the equation separates by
point like the normal one: a stick point (S S_t = 1) has the row ``[[v_t]] = 0`` (an active
velocity row, enforced by an impulse as the normal rows are); a slip point (S = 1, S_t = 0) has
the prescribed multiplier ``λ_t = μ|λ_v| q/|q|`` (a force during the step, passed to the
integrator as the trial's ``applied`` multipliers); a point out of contact has λ_t = 0. The
tangential term enters the weak form like the normal one, ``∫ S λ_t·[[w_t]] dΓ`` with the
vertex rule: the rows are ``B_t = −W G_t`` and the force on the bodies is ``−B_tᵀ λ_t``.

Sign conventions: the tangents t_j (j < dim − 1) are unit vectors orthogonal to the contact
normal n (2D and axisymmetric: t = (n_y, −n_x), the radial direction on a wall z = 0; 3D: an
orthonormal pair, t_1 ⟂ n and the coordinate axis least aligned with n, t_2 = n × t_1);
[[v_t]]_j = t_j·(v_s − v_m) (v_m = 0 against an obstacle); the force on the slave is w λ_t
along t (its reaction on the master), opposite to the slip (λ_t·[[v_t]] ≤ 0 when sliding, so
that the dissipation D_f = −∫ λ_t·[[v_t]] dΓ dt ≥ 0).

The fixed point of each step iterates on (S_d, S_v, S_t) and the slip tractions together: after
each solve, the normal statuses are updated as in the frictionless model; a point that stays in
contact sticks if ``|q| ≤ μ|λ_v|`` (q = λ_t for a stick point, whose [[v_t]] = 0) and slips
otherwise with ``λ_t = μ|λ_v| q/|q|`` (the projection of q on the Coulomb disc: in 3D the slip
direction is iterated through q); a point that enters contact starts as stick. An iteration is
one solve of the step's impulses; the loop ends when no status changes and no slip traction
moves by more than ``slip_tolerance × μ|λ_v|``.

Friction work is accumulated from the multipliers like the normal contact work (the impulse of
the tangential multipliers, stick and slip, times the mean of the velocities before and after
it), reported as ``friction_work`` (J, ≤ 0: minus the dissipation).

Supported: rigid obstacles (:class:`RigidContactPair`) and deformable pairs
(:class:`DeformableContactPair`: [[v_t]] is the slave's velocity relative to the master point it
is paired with, the tangents those of the master's normal), 2D, axisymmetric (the points on the
axis carry no friction row: their radial velocity is zero by symmetry) and 3D, with the
explicit integrator (slip tractions are applied forces; ``explicit_only``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from .geometry import ContactGeometry, ContactPair, RigidContactPair
from .level_set import LevelSetContact
from .records import ContactState, ContactTrial, evolve

__all__ = ["CoulombContact", "FrictionState", "FrictionTrial", "tangents"]


def tangents(normal: np.ndarray) -> np.ndarray:
    """Unit tangents orthogonal to unit normals, shape (dim − 1, dim, m) for normal (dim, m)."""
    n = np.asarray(normal, dtype=float)
    dim, m = n.shape
    if dim == 2:
        return np.stack([n[1], -n[0]])[None]
    if dim != 3:
        raise ValueError(f"friction needs a 2D or 3D contact surface, got dim={dim}")
    axis = np.zeros((3, m))
    axis[np.argmin(np.abs(n), axis=0), np.arange(m)] = 1.0
    t1 = np.cross(axis.T, n.T).T
    t1 /= np.linalg.norm(t1, axis=0)
    t2 = np.cross(n.T, t1.T).T
    return np.stack([t1, t2])


@dataclass(frozen=True)
class FrictionTrial:
    """A step of :class:`CoulombContact` inside its fixed point (the integrators' trial).

    Rows are ordered normal (m) then tangential (j m + k for tangent j, point k).
    """

    active: np.ndarray
    matrix: sp.csr_matrix
    rhs: np.ndarray
    changed: bool
    iterations: int
    applied: np.ndarray
    normal: ContactTrial
    rows_t: sp.csr_matrix
    stick: np.ndarray
    vt: np.ndarray


@dataclass(frozen=True)
class FrictionState:
    """Committed state: the normal model's :class:`ContactState` plus the friction part.

    ``work`` and ``impulse`` are the normal ones (as in the frictionless model);
    ``friction_work`` (J, ≤ 0) the work of the tangential multipliers; ``stick`` the stick
    statuses of the last step (m,); ``slip_iterations`` the fixed-point iterations of the last
    step.
    """

    normal: ContactState
    friction_work: float
    stick: np.ndarray
    tangential: np.ndarray

    @property
    def work(self) -> float:
        return self.normal.work

    @property
    def impulse(self) -> np.ndarray | None:
        return self.normal.impulse

    @property
    def active(self) -> np.ndarray:
        return self.normal.active

    @property
    def record(self) -> Any:
        return self.normal.record


class CoulombContact(LevelSetContact):
    """Level-set contact with isotropic Coulomb friction (module docstring).

    Parameters
    ----------
    pair : RigidContactPair or DeformableContactPair
    friction : float
        Coulomb coefficient μ > 0.
    kappa, eta : float, optional
        As :class:`LevelSetContact` (Pa·s/m).
    kappa_t : float, optional
        κ_t > 0 (Pa·s/m) of the stick indicator; default κ.
    slip_tolerance : float
        Relative change of the slip tractions (of ``μ|λ_v|``) below which the fixed point stops.
    **kwargs
        ``material``, ``name``, ``max_iterations``, ``on_failure``, ``update_geometry`` as
        :class:`LevelSetContact`.
    """

    explicit_only = True

    def __init__(
        self,
        pair: ContactPair,
        friction: float,
        kappa: float | None = None,
        eta: float | None = None,
        *,
        kappa_t: float | None = None,
        slip_tolerance: float = 1e-10,
        **kwargs: Any,
    ) -> None:
        if pair.slave.dim not in (2, 3):
            raise ValueError(f"friction needs a 2D or 3D surface, got dim={pair.slave.dim}")
        if not (np.isfinite(friction) and friction > 0.0):
            raise ValueError(f"friction coefficient must be positive and finite, got {friction}")
        super().__init__(pair, kappa, eta, **kwargs)
        self.friction = float(friction)
        self.kappa_t = self.kappa if kappa_t is None else float(kappa_t)
        if not (np.isfinite(self.kappa_t) and self.kappa_t > 0.0):
            raise ValueError(f"kappa_t must be positive (Pa·s/m), got kappa_t={kappa_t}")
        if not slip_tolerance > 0.0:
            raise ValueError(f"slip_tolerance must be positive, got {slip_tolerance}")
        self.slip_tolerance = float(slip_tolerance)
        self.n_tangents = pair.slave.dim - 1
        m = pair.n_points
        # points on the axis of an axisymmetric surface: no radial motion, no friction row
        self._frictional = np.ones(m, dtype=bool)
        if getattr(pair.slave, "axisymmetric", False):
            r = pair.slave.positions(np.zeros(pair.n_dofs))[0]
            self._frictional = r > 1e-12 * max(float(np.abs(r).max()), 1e-300)
        self._t_cache: tuple[np.ndarray, sp.csr_matrix] | None = None
        self._stack_cache: tuple[Any, Any, sp.csr_matrix] | None = None

    @property
    def n_rows(self) -> int:
        return self.pair.n_points * (1 + self.n_tangents)

    # ------------------------------------------------------------------ rows
    def tangential_rows(self, geo: ContactGeometry) -> sp.csr_matrix:
        """G_t: v ↦ [[v_t]] at the points, shape ((dim − 1) m, n), row j m + k."""
        cached = self._t_cache
        rigid = isinstance(self.pair, RigidContactPair)
        if (
            rigid
            and cached is not None
            and (cached[0] is geo.normal or np.array_equal(cached[0], geo.normal))
        ):
            return cached[1]  # a rigid pair's rows depend on its normals only
        if geo.jump is None:
            raise ValueError("the contact pair gives no velocity-jump rows (ContactGeometry.jump)")
        t = tangents(geo.normal) * self._frictional[None, None, :]  # (nt, dim, m)
        g = sp.vstack([geo.jump(t[j]) for j in range(t.shape[0])], format="csr")
        # read-only normals (a plane's, the same array every step) are kept as they are
        n = geo.normal
        self._t_cache = (n if not n.flags.writeable else n.copy(), g)
        return g

    def _stack(self, ntrial: ContactTrial, g_t: sp.csr_matrix) -> sp.csr_matrix:
        cached = self._stack_cache
        if cached is not None and cached[0] is ntrial.matrix and cached[1] is g_t:
            return cached[2]  # the same rows as last step: the integrator reuses its solve
        w = np.tile(self.pair.weights, self.n_tangents)
        stacked = sp.vstack([ntrial.matrix, sp.diags(-w) @ g_t], format="csr")
        self._stack_cache = (ntrial.matrix, g_t, stacked)
        return stacked

    def matrix(self) -> sp.csr_matrix:
        """Rows [B_n; B_t] in the reference configuration, shape ((1 + nt) m, n)."""
        base = super().matrix()
        w = np.tile(self.pair.weights, self.n_tangents)
        return sp.vstack([base, sp.diags(-w) @ self.tangential_rows(self._geo0)], format="csr")

    # ------------------------------------------------------------------ protocol
    def initial_state(self, u: np.ndarray, v: np.ndarray) -> FrictionState:
        """The frictionless model's initial state, no friction work, no point sticking."""
        m = self.pair.n_points
        return FrictionState(super().initial_state(u, v), 0.0, np.zeros(m, dtype=bool),
                             np.zeros(self.n_tangents * m))  # fmt: skip

    def begin_step(self, state: FrictionState, t: float, dt: float, u: np.ndarray,
                   v: np.ndarray) -> FrictionTrial:  # fmt: skip
        """The normal trial, the tangential rows; first guess: every point in contact sticks
        (a sliding point slips again after one solve, with the traction of this step's λ_v)."""
        ntrial = super().begin_step(state.normal, t, dt, u, v)
        g_t = self.tangential_rows(ntrial.geometry)
        m, nt = self.pair.n_points, self.n_tangents
        stick = ntrial.active & self._frictional
        return FrictionTrial(
            active=np.concatenate([ntrial.active, np.tile(stick, nt)]),
            matrix=self._stack(ntrial, g_t), rhs=np.zeros(m * (1 + nt)), changed=False,
            iterations=0, applied=np.zeros(m * (1 + nt)), normal=ntrial, rows_t=g_t,
            stick=stick, vt=np.zeros((nt, m)),
        )  # fmt: skip

    def update_status(self, trial: FrictionTrial, u: np.ndarray, v: np.ndarray,
                      multipliers: np.ndarray) -> FrictionTrial:  # fmt: skip
        """Normal statuses as the frictionless model; then stick or slip (module docstring)."""
        m, nt = self.pair.n_points, self.n_tangents
        lam = np.asarray(multipliers, dtype=float)
        ntrial = super().update_status(trial.normal, u, v, lam[:m])
        lam_t = lam[m:].reshape(nt, m)
        vt = (trial.rows_t @ v).reshape(nt, m)
        was_in = trial.normal.active  # the normal statuses of this solve
        now_in = ntrial.active & self._frictional
        cap = self.friction * np.abs(lam[:m])
        q = lam_t - self.kappa_t * vt * (~trial.stick)  # a stick point's [[v_t]] is zero
        qn = np.sqrt(np.sum(q * q, axis=0))
        stick = now_in & ((qn <= cap) | ~was_in)  # a point entering contact starts as stick
        slip = now_in & ~stick
        applied_t = np.where(slip, cap * q / np.where(qn > 0.0, qn, 1.0), 0.0)
        old_t = trial.applied[m:].reshape(nt, m)
        moved = np.abs(applied_t - old_t).max() if applied_t.size else 0.0
        scale = float(cap.max()) if cap.size else 0.0
        changed = (ntrial.changed or bool(np.any(stick != trial.stick))
                   or moved > self.slip_tolerance * max(scale, 1e-300))  # fmt: skip
        applied = np.concatenate([np.zeros(m), applied_t.ravel()])
        return evolve(
            trial, active=np.concatenate([ntrial.active, np.tile(stick, nt)]), changed=changed,
            iterations=trial.iterations + 1, applied=applied, normal=ntrial, stick=stick,
            vt=vt,
        )  # fmt: skip

    def commit(self, state: FrictionState, trial: FrictionTrial, *, t: float, u: np.ndarray,
               v_before: np.ndarray, v_after: np.ndarray, multipliers: np.ndarray,
               impulse: np.ndarray) -> FrictionState:  # fmt: skip
        """The normal state as the frictionless model; the friction work
        ``−Λ_t·B_t (v_before + v_after)/2`` (J) of the tangential impulses Λ_t."""
        m = self.pair.n_points
        lam = np.asarray(multipliers, dtype=float)
        imp = np.asarray(impulse, dtype=float)
        nstate = super().commit(state.normal, trial.normal, t=t, u=u, v_before=v_before,
                                v_after=v_after, multipliers=lam[:m], impulse=imp[:m])  # fmt: skip
        w = np.tile(self.pair.weights, self.n_tangents)
        bt_v = -w * (trial.rows_t @ (v_before + v_after))
        friction_work = state.friction_work - 0.5 * float(imp[m:] @ bt_v)
        return FrictionState(nstate, friction_work, trial.stick.copy(), lam[m:].copy())
