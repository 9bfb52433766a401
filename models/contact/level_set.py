"""Frictionless dynamic contact: the level-set (Signorini–Moreau) model and a Signorini baseline.

Conventions (SI units; see ``docs/contact.md``)
-----------------------------------------------
``d_n``
    Signed normal distance (m) at a contact collocation point, **negative when the bodies are
    apart** (the paper's convention), positive when they overlap.
``[[v_n]]``
    Normal velocity jump ``ḋ_n`` (m/s), **positive when the bodies approach**.
``λ_v``
    Normal contact pressure (Pa), ``λ_v ≤ 0`` in contact; reports give
    ``contact_pressure = −λ_v ≥ 0``.
``κ`` (``kappa``, Pa·s/m)
    Parameter of the velocity indicator ``S_v = 1(λ_v − κ[[v_n]] ≤ 0)``, κ > 0; default the
    acoustic impedance ρc of the material, so that both terms have the same size.
``η`` (``eta``, Pa·s/m)
    Parameter of ``λ_v = S_d S_v (λ_v − η[[v_n]])``, η ≠ 0 (default κ).
``S_d = 1(d_n ≥ 0)``
    Gap indicator, evaluated on the predicted end-of-step gap.
Rigid obstacles
    A level-set function φ(x) (m), φ > 0 in free space, with its gradient; ``d_n = −φ`` (φ should
    be a signed distance near the surface for the reported gaps to be distances).

Discretisation
--------------
The contact collocation points are the nodes of the slave surface Γ_c: the quadrature on Γ_c is
the vertex (nodal) rule of its facets, weights ``w_k = Σ_F |F|/n_v`` (m² in 3D, m per unit
thickness in plane 2D, 2πr|F|/n_v in axisymmetry, the cross-section in 1D). λ_v lives in the
nodal (P1/Q1 trace) space of Γ_c, the trace of the displacement space (inf–sup compatible: one
multiplier per collocation point, no over-constraint). The paper's weak equation

    −(1/η) ∫_Γc [λ_v − S_d S_v (λ_v − η[[v_n]])] λ* dΓ = 0

integrated with that rule separates by node: ``w_k[(1 − S_k) λ_k + S_k η [[v_n]]_k] / η = 0``,
i.e. ``λ_k = 0`` where ``S_k = S_d S_v = 0`` and ``[[v_n]]_k = 0`` where ``S_k = 1``: active
velocity rows of the integrators' unilateral protocol. The force on the bodies is
``Σ_k w_k S_k λ_k [[w_n]]_k``, the same rule applied to ``∫_Γc S_d S_v λ_v [[w_n]] dΓ``.

Rows and signs: with ``G`` (m × n) the map ``v ↦ [[v_n]]`` at the collocation points and
``W = diag(w)``, the constraint rows are ``B = −W G`` and the multiplier of row k is ``λ_k``
itself, so that the integrators' force ``−Bᵀλ = Gᵀ W λ`` is the paper's contact force and
``λ ≤ 0`` is a pressure.

Per time step (:meth:`LevelSetContact.begin_step` … :meth:`LevelSetContact.commit`, the protocol
of :class:`arlequin.contract.UnilateralConstraint`) the statuses ``S = S_d S_v`` are found by a
fixed point driven by the integrator: freeze them, solve, update ``S_v`` from ``λ_v − κ[[v_n]]``
of the solution, repeat until no status changes. The constraint objects hold their configuration
only; statuses, work and records live in immutable :class:`ContactState` / trial records that the
integrator passes in and commits, so a step can be redone and a run restarted.
``S_d`` is evaluated once per step on the predicted end-of-step gap ``d_n + Δt [[v_n]]`` (free
flight from the start-of-step velocity; the explicit scheme passes its free mid-step velocity),
and stays 1 for a point that was active in the previous step: an active point has
``[[v_n]] = 0`` so its gap is frozen (no drift), and it is released only through ``S_v``
(tension). At activation a θ-scheme point penetrates by at most ``(1 − θ) Δt [[v_n]]``.

Contact work is accumulated from the multipliers, never as an energy-balance residual: an impulse
``Λ = Δt λ`` that takes the velocities from ``v⁻`` to ``v⁺`` does the work
``−Λ·B (v⁻ + v⁺)/2 = Λ·W G (v⁻ + v⁺)/2`` (J), exactly the kinetic-energy change it causes.

Pairs (:mod:`arlequin.models.contact.geometry`): :class:`RigidContactPair` (a deformable surface
against an :class:`Obstacle` of :mod:`arlequin.models.contact.obstacles`: plane, sphere, any φ with
its gradient) and :class:`DeformableContactPair` (slave nodes against master facets: node-to-node in
1D, point-to-segment in 2D, point-to-facet in 3D; closest-point projection in the current
configuration).

:class:`SignoriniContact` is the displacement-level baseline (Newmark + Signorini with a
Lagrange multiplier, primal–dual active set on ``d_n(u_{n+1}) ≤ 0``).

The per-step arithmetic (the rows' products, the statuses) runs in the compiled kernels of
:mod:`arlequin.models.contact.kernel` when the rows are CSR (always, from the pairs), the numpy
expressions beside each call being their reference (the same numbers bit for bit).

Size: the shared constraint machinery (geometry per step, records, work) and the two models on
it stay together (under 600 lines).
"""

from __future__ import annotations

import logging
from typing import Any

import numpy as np
import scipy.sparse as sp

from arlequin.contract import SimulationError, csr_pattern, same_pattern

from .geometry import (
    ContactGeometry,
    ContactPair,
    ContactSurface,
    DeformableContactPair,
    RigidContactPair,
    csr_with_data,
)
from .kernel import (
    equal_gathered,
    level_set_begin,
    level_set_status,
    rows_sum_dot,
    scaled_entries,
)
from .obstacles import LevelSetObstacle, Obstacle, PlaneObstacle, SphereObstacle
from .records import ContactHistory, ContactRecord, ContactState, ContactTrial, build, evolve

__all__ = [
    "ContactConvergenceError",
    "ContactGeometry",
    "ContactHistory",
    "ContactPair",
    "ContactRecord",
    "ContactState",
    "ContactSurface",
    "DeformableContactPair",
    "LevelSetContact",
    "LevelSetObstacle",
    "Obstacle",
    "PlaneObstacle",
    "RigidContactPair",
    "SignoriniContact",
    "SphereObstacle",
    "acoustic_impedance",
]

logger = logging.getLogger(__name__)


class ContactConvergenceError(SimulationError):
    """The status fixed point of a contact constraint did not converge (``on_failure="raise"``)."""


def acoustic_impedance(young: float, density: float, poisson: float | None = None) -> float:
    """Acoustic impedance ρ c (Pa·s/m), the default κ of :class:`LevelSetContact`.

    Parameters
    ----------
    young : float
        Young's modulus E (Pa).
    density : float
        Density ρ (kg/m³).
    poisson : float, optional
        Poisson's ratio: c is then the dilatational speed √((λ + 2μ)/ρ); without it the bar
        speed √(E/ρ).
    """
    if not (young > 0.0 and density > 0.0):
        raise ValueError(
            f"acoustic impedance needs young > 0 and density > 0, got {young}, {density}"
        )
    modulus = young
    if poisson is not None:
        modulus = young * (1.0 - poisson) / ((1.0 + poisson) * (1.0 - 2.0 * poisson))
    return float(np.sqrt(modulus * density))


def _compiled(g: Any, x: np.ndarray, last: list) -> bool:
    """Whether the compiled kernels apply to rows g and a vector x: CSR rows of floats and a
    float vector of their width (else the numpy reference, the same numbers). ``last`` keeps
    the last rows found CSR of floats and their width (a plane's rows: the same every step)."""
    if last[0] is not g:
        if not (getattr(g, "format", None) == "csr" and g.data.dtype == np.float64):
            return False
        last[0], last[1] = g, (g.shape[1],)
    return x.dtype == np.float64 and x.shape == last[1]


class _ContactConstraint:
    """Shared machinery: the geometry per step, the records, the contact work."""

    kind = "contact"

    def __init__(
        self,
        pair: ContactPair,
        *,
        name: str,
        level: str,
        max_iterations: int,
        on_failure: str,
        update_geometry: bool,
    ) -> None:
        if level not in ("velocity", "displacement"):
            raise ValueError(
                f"constraint level must be 'velocity' or 'displacement', got {level!r}"
            )
        if max_iterations < 1:
            raise ValueError(f"max_iterations must be >= 1, got {max_iterations}")
        if on_failure not in ("warn", "raise"):
            raise ValueError(f"on_failure must be 'warn' or 'raise', got {on_failure!r}")
        self.name = name
        self.level = level
        self.max_iterations = int(max_iterations)
        self.pair = pair
        self.on_failure = on_failure
        self.update_geometry = bool(update_geometry)
        self._u0 = np.zeros(pair.n_dofs)
        self._b_cache: tuple[sp.csr_matrix, sp.csr_matrix] | None = None
        self._b_pattern: tuple | None = None  # a G, its rows' −w, its zeros, B's template
        self._geo0 = pair.geometry(self._u0)
        dofs = getattr(pair, "geometry_dofs", None)
        if dofs is not None:
            dofs = np.asarray(dofs, dtype=np.int64)
            if dofs.size and not (0 <= dofs.min() and dofs.max() < pair.n_dofs):
                raise ValueError(f"contact pair's geometry_dofs must lie in [0, {pair.n_dofs}), "
                                 f"got [{dofs.min()}, {dofs.max()}]")  # fmt: skip
        self._gdofs = dofs
        self._csr_rows: list = [None, None]  # see _compiled: the geometry's rows
        self._csr_b: list = [None, None]  # and B's
        # a trial's fields that start at zero, shared by every trial (read-only: states and
        # trials are never modified in place; new arrays replace them)
        m = pair.n_points
        self._zeros = (np.zeros(m), np.zeros(m, dtype=bool))
        for a in self._zeros:
            a.flags.writeable = False

    # rows
    @property
    def n_rows(self) -> int:
        return self.pair.n_points

    def _make_b(self, g: sp.csr_matrix) -> sp.csr_matrix:
        cached = self._b_cache
        if cached is not None and cached[0] is g:  # the pair reuses unchanged rows
            return cached[1]
        # −W G: each row's entries scaled (a sparse product per step cost a tenth of a step),
        # the zeros (a flat master's tangential components) dropped as eliminate_zeros does,
        # from the arrays: with scipy's copy and eliminate_zeros it cost 21 µs a step, 15 then
        gc = g if getattr(g, "format", None) == "csr" else sp.csr_matrix(g)
        # the pattern of B for G's pattern (its index arrays, shared while the points keep
        # their facets) and those zeros: kept with its template, so that B's rows share their
        # index arrays too (csr_pattern) and no scipy constructor runs while it holds
        pat = self._b_pattern
        same = pat is not None and same_pattern(pat[0], gc)
        w = pat[1] if same else np.repeat(-self.pair.weights, np.diff(gc.indptr))
        if gc.data.dtype == np.float64 and same:
            # one call: the entries scaled, the kept ones, whether the zeros are where they
            # were (the same numbers as the numpy lines below, their reference)
            kept_data, keep, same, every = scaled_entries(gc.data, w, pat[2])
        else:
            data = gc.data * w
            keep = data != 0.0
            every = bool(keep.all())
            same = same and np.array_equal(pat[2], keep)
            kept_data = data if every else data[keep]
        if not same:
            if every:
                indices, indptr = gc.indices, gc.indptr
            else:
                kept = np.concatenate([[0], np.cumsum(keep)]).astype(gc.indptr.dtype)
                indices, indptr = gc.indices[keep], kept[gc.indptr]
            pat = (gc, w, keep, csr_pattern(indices.copy(), indptr.copy(), gc.shape))
            self._b_pattern = pat
        b = csr_with_data(pat[3], kept_data)
        self._b_cache = (g, b)
        return b

    def matrix(self) -> sp.csr_matrix:
        """Rows B = −W G in the reference configuration, shape (m, n) (m², or m per unit
        thickness in plane 2D)."""
        return self._make_b(self._geo0.rows)

    def geometry(self, u: np.ndarray) -> ContactGeometry:
        """Gaps and rows at displacement u (m): the current configuration, or the reference
        one linearised when ``update_geometry`` is False."""
        if not self.update_geometry:
            gap = self._geo0.gap + self._geo0.rows @ (u - self._u0)
            return ContactGeometry(self._geo0.rows, gap, self._geo0.normal, self._geo0.jump)
        return self.pair.geometry(u)

    def _u_geometry(self, u: np.ndarray) -> np.ndarray:
        """What a state keeps of the u its geometry was made at: u on the pair's geometry
        dofs (a new array), or a copy of u if the pair does not name them."""
        return u.copy() if self._gdofs is None else u[self._gdofs]

    def _geometry_from(self, state: ContactState, u: np.ndarray) -> ContactGeometry:
        last = state.u_geometry
        if last is u:
            return state.geometry
        # the geometry depends on the pair's dofs alone: compared there (a few hundred values,
        # not the whole system's at every step); == and all() as array_equal for equal shapes
        dofs = self._gdofs
        if u.shape != (self.pair.n_dofs,):
            same = False
        elif dofs is None:
            same = last.shape == u.shape and bool((last == u).all())
        elif last.shape != dofs.shape:  # not kept on the geometry dofs (an older state)
            same = False
        elif last.dtype != np.float64 or u.dtype != np.float64:
            same = bool((last == u[dofs]).all())
        else:
            same = equal_gathered(last, u, dofs)
        if same:
            return state.geometry
        return self.pair.geometry(u) if self.update_geometry else self.geometry(u)

    def gaps(self, u: np.ndarray) -> np.ndarray:
        """d_n (m) at the collocation points for displacement u, shape (m,)."""
        return self.geometry(u).gap

    def initial_state(self, u: np.ndarray, v: np.ndarray) -> ContactState:
        m = self.pair.n_points
        return ContactState(
            np.zeros(m, dtype=bool),
            0.0,
            None,
            np.zeros(m),
            self.geometry(u),
            self._u_geometry(u),
            np.zeros(m),
        )

    def _first_statuses(self, geo: ContactGeometry, v: np.ndarray, dt: float,
                        was: np.ndarray) -> tuple[np.ndarray, ...]:  # fmt: skip
        """``(vn0, gap_pred, s_d, active)`` of a step: [[v_n]] (m/s) at its start, the
        predicted gap (m), S_d and the first active statuses (bool), each (m,), from the
        geometry at its start, its free velocity v, its size dt (s) and the last statuses."""
        raise NotImplementedError

    def _trial(self, state, t, dt, u, v) -> ContactTrial:
        """The step's trial, its first statuses by :meth:`_first_statuses` (one trial object a
        step, not a copy for S_d)."""
        geo = self._geometry_from(state, u)
        vn0, gap_pred, s_d, active = self._first_statuses(geo, v, float(dt), state.active)
        zero, false = self._zeros
        # the geometry's gap is never modified: no copy of it for gap_start
        return build(
            ContactTrial, active=active, matrix=self._make_b(geo.rows), rhs=zero,
            changed=False, iterations=0, t=float(t), dt=float(dt), geometry=geo,
            gap_start=geo.gap, vn_start=vn0, gap_pred=gap_pred,
            s_d=s_d, s_v=false, used=false, lam=zero, vn=vn0, u_start=u,
        )  # fmt: skip

    def commit(
        self,
        state: ContactState,
        trial: ContactTrial,
        *,
        t: float,
        u: np.ndarray,
        v_before: np.ndarray,
        v_after: np.ndarray,
        multipliers: np.ndarray,
        impulse: np.ndarray,
    ) -> ContactState:
        """The state after the accepted step (see :class:`arlequin.contract.UnilateralConstraint`).

        The work of the step's forces −Bᵀλ, whose time integral over the step is ``impulse``
        (Pa·s at each collocation point), while the velocities go from v_before to v_after, is
        ``−impulse·B (v_before + v_after)/2`` (J): exactly the kinetic energy change an impulse
        causes.

        Raises
        ------
        ContactConvergenceError
            If the status fixed point did not converge and ``on_failure="raise"``.
        """
        if trial.changed:
            msg = (
                f"contact {self.name!r}: status fixed point not converged after "
                f"{trial.iterations} iterations in the step ending at t = {t:.6e} s"
            )
            if self.on_failure == "raise":
                raise ContactConvergenceError(msg, 0, t)
            logger.warning(msg)
        # B (v_before + v_after) with the sum on B's columns only (a full-size sum was most of
        # a commit); _make_b's rows are always CSR
        b = trial.matrix
        imp = np.asarray(impulse, dtype=float)
        if (_compiled(b, v_before, self._csr_b) and v_after.shape == v_before.shape
                and v_after.dtype == np.float64 and imp.shape == (b.shape[0],)):  # fmt: skip
            work = state.work - 0.5 * rows_sum_dot(b.indptr, b.indices, b.data, v_before,
                                                   v_after, imp)  # fmt: skip
        else:  # the kernel's reference
            work = state.work - 0.5 * float(imp @ (b @ (v_before + v_after)))
        # the explicit scheme commits at the configuration its step started from: reuse it
        same = trial.u_start is u or np.array_equal(trial.u_start, u)
        geo_end = trial.geometry if same else self.geometry(u)
        record = build(
            ContactRecord, t=float(t), iterations=trial.iterations, converged=not trial.changed,
            active=trial.used, s_d=trial.s_d, s_v=trial.s_v, gap=geo_end.gap,
            gap_start=trial.gap_start, vn_start=trial.vn_start, vn=trial.vn, lam=trial.lam,
            work=work, dt=trial.dt,
        )  # fmt: skip
        total = imp
        if state.impulse is not None:
            total = state.impulse + total
        # the trial's arrays are the constraint's own (update_status copied the multipliers),
        # never modified: kept without copies; u is the integrator's: its geometry dofs copied
        return build(ContactState, active=trial.used, work=work, record=record,
                     multipliers=trial.lam, geometry=geo_end, u_geometry=self._u_geometry(u),
                     impulse=total)  # fmt: skip

    def history(self, result: Any) -> ContactHistory:
        """The records of this constraint in a :class:`~arlequin.solvers.DynamicResult`,
        stacked into arrays (see :class:`ContactHistory`)."""
        return ContactHistory.from_records(result.history(self.name), self.pair.n_points)


class LevelSetContact(_ContactConstraint):
    """Level-set (Signorini–Moreau) frictionless contact, velocity-level rows.

    Statuses per collocation point (see the module docstring):
    ``S_d = 1(d_pred ≥ 0)`` (or the point was active in the previous step),
    ``S_v = 1(λ_v − κ[[v_n]] ≤ 0)``, active ⇔ ``S_d S_v = 1``; an active row enforces
    ``[[v_n]] = 0`` on the end-of-step velocity (θ-scheme) or on the next mid-step velocity
    (central differences), an inactive one ``λ_v = 0``.

    Parameters
    ----------
    pair : ContactPair
        Geometry (:class:`RigidContactPair` or :class:`DeformableContactPair`).
    kappa : float, optional
        κ > 0 (Pa·s/m). Default: :func:`acoustic_impedance` of ``material``.
    eta : float, optional
        η ≠ 0 (Pa·s/m) of ``λ_v = S_d S_v (λ_v − η[[v_n]])`` (default κ). With the nodal
        collocation the discrete solution does not depend on η; it scales
        :meth:`weak_residual`.
    material : IsotropicElastic, optional
        Used for the default κ (bar speed in 1D, dilatational speed otherwise).
    name : str
    max_iterations : int
        Cap of the status fixed point per step (default 25).
    on_failure : {"warn", "raise"}
        Non-convergence of the fixed point: a warning naming the step and time (the integrator
        also counts it in ``n_status_failures``), or :class:`ContactConvergenceError`.
    update_geometry : bool
        Recompute the pairing, normals and gaps in the current configuration at every step
        (default); False freezes the reference geometry (small-displacement contact).
    """

    def __init__(
        self,
        pair: ContactPair,
        kappa: float | None = None,
        eta: float | None = None,
        *,
        material: Any = None,
        name: str = "contact",
        max_iterations: int = 25,
        on_failure: str = "warn",
        update_geometry: bool = True,
    ) -> None:
        if kappa is None:
            if material is None:
                raise ValueError(
                    "LevelSetContact needs kappa (Pa·s/m) or a material for the default ρc"
                )
            nu = None if pair.slave.dim == 1 else material.poisson
            kappa = acoustic_impedance(material.young, material.density, nu)
        if not (np.isfinite(kappa) and kappa > 0.0):
            raise ValueError(f"kappa must be positive (Pa·s/m), got kappa={kappa}")
        eta = float(kappa) if eta is None else float(eta)
        if eta == 0.0 or not np.isfinite(eta):
            raise ValueError(f"eta must be non-zero and finite (Pa·s/m), got eta={eta}")
        self.kappa = float(kappa)
        self.eta = eta
        super().__init__(
            pair,
            name=name,
            level="velocity",
            max_iterations=max_iterations,
            on_failure=on_failure,
            update_geometry=update_geometry,
        )

    def begin_step(
        self, state: ContactState, t: float, dt: float, u: np.ndarray, v: np.ndarray
    ) -> ContactTrial:
        """Rows at u; S_d on the predicted end-of-step gap d_n + Δt [[v_n]] (v: the step's free
        velocity), kept at 1 for points active in the last step (their gap is frozen); first
        guess: persistent contacts and newly closed approaching points."""
        return self._trial(state, t, dt, u, v)

    def _first_statuses(self, geo, v, dt, was):
        g = geo.rows
        if _compiled(g, v, self._csr_rows) and was.shape == geo.gap.shape == (g.shape[0],):
            return level_set_begin(g.indptr, g.indices, g.data, v, geo.gap, dt, was)
        vn0 = g @ v  # the kernel's reference
        gap_pred = geo.gap + dt * vn0
        s_d = (gap_pred >= 0.0) | was
        return vn0, gap_pred, s_d, s_d & (was | (vn0 > 0.0))

    def update_status(
        self, trial: ContactTrial, u: np.ndarray, v: np.ndarray, multipliers: np.ndarray
    ) -> ContactTrial:
        """New active statuses from the trial fields (the indicator fields S_d, S_v at the
        collocation points); whether any changed."""
        lam = np.array(multipliers, dtype=float)  # a copy: the integrator's array
        g = trial.geometry.rows  # [[v_n]] with the step's rows
        used = trial.active  # made by this constraint, never modified: kept as it is
        if _compiled(g, v, self._csr_rows) and lam.shape == used.shape:
            vn, s_v, new, changed = level_set_status(g.indptr, g.indices, g.data, v, lam,
                                                     self.kappa, trial.s_d, used)  # fmt: skip
        else:  # the kernel's reference
            vn = g @ v
            s_v = lam - self.kappa * vn <= 0.0
            new = trial.s_d & s_v
            changed = bool((new != used).any())
        return evolve(
            trial, active=new, changed=changed,
            iterations=trial.iterations + 1, used=used, lam=lam, vn=vn, s_v=s_v,
        )  # fmt: skip

    def weak_residual(
        self,
        v: np.ndarray,
        multipliers: np.ndarray,
        status: np.ndarray,
        u: np.ndarray | None = None,
    ) -> np.ndarray:
        """Residual of the weak λ_v equation at each collocation point, shape (m,) (m³/s or m²/s).

        ``−(1/η) w_k [λ_k − S_k (λ_k − η[[v_n]]_k)]`` with the statuses ``status`` and the rows
        at u (default the reference configuration); zero for a converged step.
        """
        s = np.asarray(status, dtype=bool)
        rows = self.geometry(np.zeros(self.pair.n_dofs) if u is None else u).rows
        vn = rows @ v
        lam = np.asarray(multipliers, dtype=float)
        return -(self.pair.weights / self.eta) * (lam - s * (lam - self.eta * vn))


class SignoriniContact(_ContactConstraint):
    """Baseline: Signorini conditions on displacements with a Lagrange multiplier.

    ``d_n(u_{n+1}) ≤ 0``, ``λ_v ≤ 0``, ``λ_v d_n = 0`` at the collocation points, the gap
    linearised at the start of each step: an active row enforces
    ``d_n(u^n) + G (u^{n+1} − u^n) = 0``. Primal–dual active set: an inactive point becomes
    active when its predicted gap is positive (overlap), an active point is released when
    ``λ_v > 0`` (tension). Used with :class:`~arlequin.solvers.Newmark` (trapezoidal) or
    :class:`~arlequin.solvers.HHTAlpha` as in the paper's Figure 1.

    Parameters
    ----------
    pair : ContactPair
    name, max_iterations, on_failure, update_geometry : see :class:`LevelSetContact`
    gap_tol : float
        Activation threshold on the predicted gap (m), default 0.
    """

    def __init__(
        self,
        pair: ContactPair,
        *,
        name: str = "contact",
        max_iterations: int = 25,
        on_failure: str = "warn",
        update_geometry: bool = True,
        gap_tol: float = 0.0,
    ) -> None:
        super().__init__(
            pair,
            name=name,
            level="displacement",
            max_iterations=max_iterations,
            on_failure=on_failure,
            update_geometry=update_geometry,
        )
        self.gap_tol = float(gap_tol)

    def begin_step(
        self, state: ContactState, t: float, dt: float, u: np.ndarray, v: np.ndarray
    ) -> ContactTrial:
        """Rows at u, right-hand side ``B u^{n+1} = −W (G u^n − d_n(u^n))`` (the linearised
        ``d_n(u^{n+1}) = 0``); the statuses start from the last step's."""
        trial = self._trial(state, t, dt, u, v)
        rhs = -self.pair.weights * (trial.geometry.rows @ u - trial.geometry.gap)
        return evolve(trial, rhs=rhs)

    def _first_statuses(self, geo, v, dt, was):
        # the last step's statuses; S_d is not used here
        vn0 = geo.rows @ v
        return vn0, geo.gap + dt * vn0, np.zeros(self.pair.n_points, dtype=bool), was.copy()

    def update_status(
        self, trial: ContactTrial, u: np.ndarray, v: np.ndarray, multipliers: np.ndarray
    ) -> ContactTrial:
        """New active statuses from the trial fields (the indicator fields S_d, S_v at the
        collocation points), and whether any changed."""
        g = trial.geometry.rows
        lam = np.asarray(multipliers, dtype=float)
        gap = trial.gap_start + g @ (u - trial.u_start)
        used = trial.active
        new = np.where(used, lam <= 0.0, gap > self.gap_tol)
        return evolve(
            trial, active=new, changed=bool(np.any(new != used)),
            iterations=trial.iterations + 1, used=used, lam=lam.copy(), vn=g @ v,
            s_d=gap > self.gap_tol, s_v=lam <= 0.0,
        )  # fmt: skip
