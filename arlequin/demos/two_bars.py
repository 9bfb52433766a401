"""Impact of two elastic bars (the seed's Figure 1), a bar against a rigid wall, and 2D/3D blocks.

Two bars (SI units): bar 1 on [−L1, 0] at velocity v₀, bar 2 on [0, L2] at velocity v₂ (default
at rest), same material (E, ρ, c = √(E/ρ)), touching at t = 0. Exact solution for L1 = L2 = L:
interface velocity (v₀ + v₂)/2 and contact pressure ρc(v₀ − v₂)/2 during the contact, which lasts
2L/c; then the velocities are exchanged. With L1 ≠ L2 the contact lasts 2 min(L1, L2)/c.

Methods: the level-set (Signorini–Moreau) contact model (:class:`arlequin.models.LevelSetContact`)
with the θ-scheme (``integrator="theta"``, consistent mass) or central differences
(``integrator="explicit"``, lumped mass); the baseline Newmark + Signorini on displacements
(:class:`arlequin.models.SignoriniContact`): trapezoidal (β = ¼, γ = ½) or HHT-α (α = −0.1).

The time step is ``cfl × h_min / c``. Reported series (see :meth:`TwoBarsResult.to_json`) start at
t = 0. For the θ-scheme the multiplier of a record is the step's (the step ending at that time),
for Newmark the end-point value, for central differences the impulse at that time divided by Δt.

Sign conventions: λ_v ≤ 0 is the normal contact pressure; reports give ``contact_pressure = −λ_v``.
"""

from __future__ import annotations

import json
import logging
import math
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import skfem

from ..integrators import solve
from ..models import (
    ContactSurface,
    DeformableContactPair,
    IsotropicElastic,
    LevelSetContact,
    LinearElastic,
    PlaneObstacle,
    RigidContactPair,
    SignoriniContact,
)
from ..system import Block, BlockTerm, CoupledSystem

__all__ = [
    "BlockImpactResult",
    "TwoBarsResult",
    "exact_two_bars",
    "impact_metrics",
    "plot_two_bars",
    "run_block_impact",
    "run_two_bars",
    "run_wall",
]

logger = logging.getLogger(__name__)

AREA = 1e-4  # bar cross-section (m²); the pressures do not depend on it
JSON_KEYS = (
    "t", "interface_velocity", "contact_pressure", "kinetic", "internal", "total_energy",
    "contact_work", "final_velocities", "contact_duration", "dt", "fixed_point_iterations",
)


@dataclass
class TwoBarsResult:
    """Time histories of one impact run (SI units).

    Attributes
    ----------
    t : ndarray, shape (n_rec,)
        Times (s), from 0.
    interface_velocity : ndarray, shape (n_rec,)
        Velocity of bar 2's contact node (m/s) (the bar's for the wall).
    contact_pressure : ndarray, shape (n_rec,)
        −λ_v (Pa).
    kinetic, internal, total_energy : ndarray, shape (n_rec,)
        Kinetic, strain and their sum (J).
    contact_work : ndarray, shape (n_rec,)
        Accumulated work of the contact forces (J), from the multipliers (≤ 0: dissipated).
    final_velocities : list of float
        Mass-weighted mean velocities of the bars at the end (m/s).
    contact_duration : float
        (last − first record with λ_v ≠ 0) + Δt (s).
    dt : float
        Time step (s).
    fixed_point_iterations : ndarray of int, shape (n_rec,)
        Status iterations of the step ending at each record (0 at t = 0 for implicit schemes).
    method : str
        ``"levelset"``, ``"newmark-trapezoidal"`` or ``"newmark-hht"``.
    exact : dict
        Exact interface velocity (m/s), pressure (Pa), duration (s), final velocities (m/s).
    newmark : TwoBarsResult or None
        The baseline run of ``method="both"``.
    """

    t: np.ndarray
    interface_velocity: np.ndarray
    contact_pressure: np.ndarray
    kinetic: np.ndarray
    internal: np.ndarray
    total_energy: np.ndarray
    contact_work: np.ndarray
    final_velocities: list[float]
    contact_duration: float
    dt: float
    fixed_point_iterations: np.ndarray
    method: str = "levelset"
    integrator: str = "theta"
    exact: dict[str, Any] = field(default_factory=dict)
    config: dict[str, Any] = field(default_factory=dict)
    n_status_failures: int = 0
    newmark: TwoBarsResult | None = None

    def to_json(self) -> dict[str, Any]:
        """The JSON document of the CLI: exactly :data:`JSON_KEYS` (+ ``"newmark"``)."""
        out: dict[str, Any] = {}
        for k in JSON_KEYS:
            val = getattr(self, k)
            if isinstance(val, np.ndarray):
                val = val.tolist()
            elif isinstance(val, (list, tuple)):
                val = [float(x) for x in val]
            else:
                val = float(val)
            out[k] = val
        if self.newmark is not None:
            out["newmark"] = self.newmark.to_json()
        return out

    def dumps(self) -> str:
        return json.dumps(self.to_json(), indent=2)

    def metrics(self) -> dict[str, float]:
        """The Must-show figures against :attr:`exact` (see :func:`impact_metrics`)."""
        return impact_metrics(self)

    def summary(self) -> str:
        m = self.metrics()
        text = (
            f"{self.method} ({self.integrator}), dt = {self.dt:.4e} s: interface velocity rms "
            f"error {m['velocity_rms_error']:.3e}, pressure rms error "
            f"{m['pressure_rms_error']:.3e}, "
            f"duration {self.contact_duration:.6e} s (exact {self.exact['duration']:.6e} s, "
            f"{m['duration_error_steps']:+.2f} steps), final velocities "
            f"{[round(v, 6) for v in self.final_velocities]}, energy lost {m['energy_loss']:.3e}"
        )
        if self.newmark is not None:
            text += "\n" + self.newmark.summary()
        return text


def exact_two_bars(lengths=(1.0, 1.0), young=210e9, density=7850.0, velocity=1.0,
                   velocity2=0.0) -> dict[str, Any]:
    """Exact solution of the two-bar impact (same material, bars touching at t = 0).

    Returns
    -------
    dict
        ``interface_velocity`` (m/s), ``pressure`` (Pa), ``duration`` (s),
        ``final_velocities`` (m/s, mass-weighted means), ``c`` (m/s).
    """
    c = math.sqrt(young / density)
    l1, l2 = (float(x) for x in lengths)
    lmin = min(l1, l2)
    dv = velocity - velocity2
    # impulse per unit area: ρ c dv/2 during 2 L_min / c -> ρ L_min dv
    return {
        "interface_velocity": 0.5 * (velocity + velocity2),
        "pressure": 0.5 * density * c * dv,
        "duration": 2.0 * lmin / c,
        "final_velocities": [velocity - lmin * dv / l1, velocity2 + lmin * dv / l2],
        "c": c,
    }


def impact_metrics(result: TwoBarsResult, skip: int = 2) -> dict[str, float]:
    """Errors of an impact run against its exact solution.

    Over the records in contact (λ_v ≠ 0) except the first ``skip`` and the last ``skip``:
    rms of (interface velocity − exact)/|exact| and of (pressure − exact)/exact. Also the
    duration error in steps, the final-velocity error / v₀, and the energy lost
    (E(0) − E(end))/E(0).
    """
    ex = result.exact
    act = np.nonzero(result.contact_pressure != 0.0)[0]
    out = {"velocity_rms_error": math.nan, "pressure_rms_error": math.nan}
    if act.size > 2 * skip:
        sl = slice(act[0] + skip, act[-1] - skip + 1)
        vi = result.interface_velocity[sl]
        pr = result.contact_pressure[sl]
        vref = ex["interface_velocity"]
        scale_v = abs(vref) if vref != 0.0 else abs(ex["velocity_scale"])
        out["velocity_rms_error"] = float(np.sqrt(np.mean((vi - vref) ** 2)) / scale_v)
        p_err = np.sqrt(np.mean((pr - ex["pressure"]) ** 2))
        out["pressure_rms_error"] = float(p_err / ex["pressure"])
    out["duration_error_steps"] = (result.contact_duration - ex["duration"]) / result.dt
    fin = np.asarray(result.final_velocities) - np.asarray(ex["final_velocities"])
    out["final_velocity_error"] = float(np.max(np.abs(fin)) / abs(ex["velocity_scale"]))
    e = result.total_energy
    out["energy_loss"] = float((e[0] - e[-1]) / e[0])
    out["max_energy_gain"] = float((np.max(e) - e[0]) / e[0])
    w = result.contact_work
    out["contact_work"] = float(w[-1])
    out["balance_error"] = float(np.max(np.abs(e - e[0] - w)) / e[0])
    return out


# ---------------------------------------------------------------------------------------------
# 1D set-ups
# ---------------------------------------------------------------------------------------------
def _bar(x0: float, x1: float, n: int, material: IsotropicElastic) -> LinearElastic:
    mesh = skfem.MeshLine(np.linspace(x0, x1, n + 1))
    return LinearElastic(mesh, material, kind="1d", area=AREA)


def _contact(kind: str, pair, material, name: str = "contact"):
    if kind == "levelset":
        return LevelSetContact(pair, material=material, name=name)
    return SignoriniContact(pair, name=name)


def _integrator_options(
    method: str, newmark: str, integrator: str, theta: float
) -> tuple[str, dict]:
    if method == "levelset":
        if integrator == "theta":
            return "theta", {"theta": theta}
        if integrator == "explicit":
            return "explicit", {}
        raise ValueError(f"integrator must be 'theta' or 'explicit', got {integrator!r}")
    if newmark == "trapezoidal":
        return "newmark", {"beta": 0.25, "gamma": 0.5}
    if newmark == "hht":
        return "hht", {"alpha": -0.1}
    raise ValueError(f"newmark must be 'trapezoidal' or 'hht', got {newmark!r}")


def _run_1d(
    bodies: list[LinearElastic],
    names: list[str],
    v_init: list[float],
    pair_factory,
    method: str,
    newmark: str,
    integrator: str,
    theta: float,
    dt: float,
    t_end: float,
    interface_dof,
    exact: dict[str, Any],
    config: dict[str, Any],
    material: IsotropicElastic,
) -> TwoBarsResult:
    system = CoupledSystem([Block(n, b, [BlockTerm(b)]) for n, b in zip(names, bodies)])
    v0 = {n: np.full(b.n_dofs, v) for n, b, v in zip(names, bodies, v_init)}
    pair = pair_factory(system)
    kind = "levelset" if method == "levelset" else "signorini"
    con = _contact(kind, pair, material)
    integ, opts = _integrator_options(method, newmark, integrator, theta)
    if integ == "explicit":
        opts["safety"] = 1.0
    res = solve(system, integ, t_end=t_end, dt=dt, v0=v0, constraints=[con], save_fields=True,
                **opts)
    if res.n_status_failures:
        logger.warning("%s: %d steps reached the status iteration cap", method,
                       res.n_status_failures)
    t = res.times
    lam = res.multipliers[con.name][:, 0]
    pressure = -lam
    kin = res.total_kinetic
    strain = res.total_strain
    hist = con.history
    work = hist.work
    if work.size == t.size - 1:
        work = np.concatenate([[0.0], work])
    elif work.size != t.size:
        work = np.interp(t, hist.t, hist.work, left=0.0)
    act = np.nonzero(lam != 0.0)[0]
    duration = float(t[act[-1]] - t[act[0]] + res.dt) if act.size else 0.0
    finals = []
    lumped = integ == "explicit"
    for b in system.blocks:
        vb = res.v[b.dofs]
        mb = system.block_mass(b)
        if lumped:
            finals.append(float(np.asarray(mb.sum(axis=1)).ravel() @ vb / mb.sum()))
        else:
            finals.append(float(np.ones(b.n_dofs) @ (mb @ vb) / mb.sum()))
    meth = "levelset" if method == "levelset" else f"newmark-{newmark}"
    return TwoBarsResult(
        t=t,
        interface_velocity=res.fields["v"][:, interface_dof(system)],
        contact_pressure=pressure,
        kinetic=kin,
        internal=strain,
        total_energy=kin + strain,
        contact_work=work,
        final_velocities=finals,
        contact_duration=duration,
        dt=float(res.dt),
        fixed_point_iterations=res.status_iterations.astype(int),
        method=meth,
        integrator=integ,
        exact=exact,
        config=config,
        n_status_failures=int(res.n_status_failures),
    )


def run_two_bars(
    method: str = "levelset",
    newmark: str = "trapezoidal",
    lengths: tuple[float, float] = (1.0, 1.0),
    young: float = 210e9,
    density: float = 7850.0,
    velocity: float = 1.0,
    velocity2: float = 0.0,
    elements: int = 100,
    cfl: float = 1.0,
    theta: float = 0.5,
    t_end: float | None = None,
    integrator: str = "theta",
) -> TwoBarsResult:
    """Impact of two bars touching at t = 0 (see the module docstring).

    Parameters
    ----------
    method : {"levelset", "newmark", "both"}
        ``"both"`` runs the level-set model and the Newmark baseline (attached as ``.newmark``).
    newmark : {"trapezoidal", "hht"}
        Newmark variant: β = ¼, γ = ½, or HHT-α with α = −0.1.
    lengths : (float, float)
        L1, L2 (m).
    young, density : float
        E (Pa), ρ (kg/m³) of both bars.
    velocity, velocity2 : float
        Initial velocities of bar 1 and bar 2 (m/s); bar 1 must approach (v₀ > v₂).
    elements : int
        Elements per bar.
    cfl : float
        Δt = cfl × h_min / c.
    theta : float
        θ of the θ-scheme (level-set method), in [½, 1].
    t_end : float, optional
        End time (s); default 3 max(L1, L2)/c.
    integrator : {"theta", "explicit"}
        Time scheme of the level-set method (the θ-scheme with consistent mass, or central
        differences with lumped mass).

    Returns
    -------
    TwoBarsResult
    """
    if method not in ("levelset", "newmark", "both"):
        raise ValueError(f"method must be 'levelset', 'newmark' or 'both', got {method!r}")
    l1, l2 = (float(x) for x in lengths)
    if not (l1 > 0 and l2 > 0):
        raise ValueError(f"bar lengths must be positive, got lengths={lengths}")
    if int(elements) < 1:
        raise ValueError(f"elements must be >= 1, got {elements}")
    if not cfl > 0:
        raise ValueError(f"cfl must be positive, got cfl={cfl}")
    if not velocity > velocity2:
        raise ValueError(f"bar 1 must approach bar 2: velocity={velocity} <= velocity2={velocity2}")
    material = IsotropicElastic(young, 0.3, density)
    ex = exact_two_bars((l1, l2), young, density, velocity, velocity2)
    ex["velocity_scale"] = velocity - velocity2
    c = ex["c"]
    n = int(elements)
    dt = cfl * min(l1, l2) / n / c
    t_end = 3.0 * max(l1, l2) / c if t_end is None else float(t_end)
    bar1 = _bar(-l1, 0.0, n, material)
    bar2 = _bar(0.0, l2, n, material)
    config = {"lengths": [l1, l2], "young": young, "density": density, "velocity": velocity,
              "velocity2": velocity2, "elements": n, "cfl": cfl, "theta": theta, "t_end": t_end}

    def pair_factory(system):
        s = ContactSurface(bar1.mesh, where=lambda x: x[0] > -0.5 * l1,
                           offset=system.block("bar1").offset, area=AREA)
        m = ContactSurface(bar2.mesh, where=lambda x: x[0] < 0.5 * l2,
                           offset=system.block("bar2").offset, area=AREA)
        return DeformableContactPair(s, m, system.n_dofs)

    def interface_dof(system):
        return system.block("bar2").offset + int(np.argmin(bar2.mesh.p[0]))

    def one(meth: str) -> TwoBarsResult:
        return _run_1d([bar1, bar2], ["bar1", "bar2"], [velocity, velocity2], pair_factory, meth,
                       newmark, integrator, theta, dt, t_end, interface_dof, ex,
                       dict(config, method=meth), material)

    if method == "both":
        res = one("levelset")
        res.newmark = one("newmark")
        return res
    return one(method)


def run_wall(
    method: str = "levelset",
    newmark: str = "trapezoidal",
    length: float = 1.0,
    young: float = 210e9,
    density: float = 7850.0,
    velocity: float = 1.0,
    elements: int = 100,
    cfl: float = 1.0,
    theta: float = 0.5,
    t_end: float | None = None,
    integrator: str = "theta",
) -> TwoBarsResult:
    """A bar on [−L, 0] at velocity v₀ > 0 against a rigid wall at x = 0 (touching at t = 0).

    Exact: pressure ρ c v₀ during 2L/c, then the bar rebounds at −v₀. The wall is a
    :class:`~arlequin.models.PlaneObstacle` (φ = −x). Parameters as :func:`run_two_bars`; the
    result's ``final_velocities`` has one entry and ``interface_velocity`` is the bar's
    contact-node velocity (exact 0 during contact).
    """
    if method not in ("levelset", "newmark"):
        raise ValueError(f"method must be 'levelset' or 'newmark', got {method!r}")
    if not velocity > 0:
        raise ValueError(f"the bar must approach the wall: velocity={velocity}")
    material = IsotropicElastic(young, 0.3, density)
    c = math.sqrt(young / density)
    L = float(length)
    n = int(elements)
    dt = cfl * L / n / c
    t_end = 3.0 * L / c if t_end is None else float(t_end)
    bar = _bar(-L, 0.0, n, material)
    ex = {"interface_velocity": 0.0, "pressure": density * c * velocity, "duration": 2.0 * L / c,
          "final_velocities": [-velocity], "c": c, "velocity_scale": velocity}
    config = {"length": L, "young": young, "density": density, "velocity": velocity, "elements": n,
              "cfl": cfl, "theta": theta, "t_end": t_end, "method": method}

    def pair_factory(system):
        s = ContactSurface(bar.mesh, where=lambda x: x[0] > -0.5 * L, offset=0, area=AREA)
        return RigidContactPair(s, PlaneObstacle([0.0], [-1.0]), system.n_dofs)

    def interface_dof(system):
        return int(np.argmax(bar.mesh.p[0]))

    return _run_1d([bar], ["bar"], [velocity], pair_factory, method, newmark, integrator, theta, dt,
                   t_end, interface_dof, ex, config, material)


# ---------------------------------------------------------------------------------------------
# 2D / 3D blocks
# ---------------------------------------------------------------------------------------------
@dataclass
class BlockImpactResult:
    """A block launched onto a rigid plane or onto an identical block at rest (SI units).

    Attributes
    ----------
    dim : int
    target : str
        ``"plane"`` or ``"block"``.
    elements : int
        Elements in the impact direction.
    dt : float
        Time step (s); h the element size (m).
    h : float
    t : ndarray, shape (n_rec,)
    total_energy : ndarray, shape (n_rec,)
        Kinetic + strain (J).
    contact_work : ndarray, shape (n_rec,)
        Accumulated contact work (J).
    first_contact, separation : int
        Record indices: the first record with λ ≠ 0 and the first record after the last one
        with λ ≠ 0.
    energy_loss : float
        (E(first contact − 1) − E(separation)) / E(0).
    max_gap_drift : float
        max over active points and steps of |d_n(t) − d_n(t_activation)| (m).
    max_penetration_excess : float
        max over activations of d_n(t_act) − (1 − θ)Δt[[v_n]]⁻ (m) (≤ 0 means within the bound).
    max_penetration : float
        Largest d_n at activation (m).
    iterations : ndarray of int
        Fixed-point iterations of every step.
    iterations_contact : ndarray of int
        Those of the steps with an active point.
    n_status_failures : int
    final_velocities : list of float
        Mean velocity (impact component) of each body at the end (m/s).
    """

    dim: int
    target: str
    elements: int
    dt: float
    h: float
    t: np.ndarray
    total_energy: np.ndarray
    contact_work: np.ndarray
    first_contact: int
    separation: int
    energy_loss: float
    max_gap_drift: float
    max_penetration_excess: float
    max_penetration: float
    iterations: np.ndarray
    iterations_contact: np.ndarray
    n_status_failures: int
    final_velocities: list[float]
    theta: float = 0.5

    def to_json(self) -> dict[str, Any]:
        d = asdict(self)
        return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in d.items()}

    def iteration_distribution(self) -> dict[int, int]:
        """{iterations: number of steps} over the steps with contact."""
        vals, counts = np.unique(self.iterations_contact, return_counts=True)
        return {int(v): int(c) for v, c in zip(vals, counts)}


def run_block_impact(
    dim: int = 2,
    target: str = "plane",
    elements: int = 20,
    velocity: float = 1.0,
    young: float = 210e9,
    poisson: float = 0.3,
    density: float = 7850.0,
    height: float = 0.1,
    aspect: float = 0.25,
    theta: float = 0.5,
    cfl: float = 1.0,
    gap_steps: float = 2.3,
    t_end: float | None = None,
    integrator: str = "theta",
) -> BlockImpactResult:
    """A block launched at v₀ onto a rigid plane or onto an identical block at rest, no gravity.

    The block (height H in the impact direction, the last coordinate; width aspect·H) has
    ``elements`` elements along H and ``round(aspect·elements)`` (≥ 2) across; plane strain in
    2D (MeshQuad), hexahedra in 3D. It starts at a gap of ``gap_steps`` v₀Δt (so that the
    activation falls inside a step) and moves at −v₀. Δt = cfl·h/c_d (dilatational speed).

    Returns
    -------
    BlockImpactResult
    """
    if dim not in (2, 3):
        raise ValueError(f"dim must be 2 or 3, got {dim}")
    if target not in ("plane", "block"):
        raise ValueError(f"target must be 'plane' or 'block', got {target!r}")
    material = IsotropicElastic(young, poisson, density)
    ne = int(elements)
    nw = max(2, round(aspect * ne))
    H = float(height)
    W = aspect * H
    h = H / ne
    c_d = math.sqrt(material.young * (1 - poisson) / ((1 + poisson) * (1 - 2 * poisson)) / density)
    dt = cfl * h / c_d
    g0 = gap_steps * velocity * dt
    lateral = [np.linspace(0.0, W, nw + 1)] * (dim - 1)

    def make(z0: float) -> LinearElastic:
        z = np.linspace(z0, z0 + H, ne + 1)
        mesh = (skfem.MeshQuad if dim == 2 else skfem.MeshHex).init_tensor(*lateral, z)
        return LinearElastic(mesh, material, kind="plane_strain" if dim == 2 else "3d")

    top = make(g0)
    bodies = [top]
    names = ["block"]
    if target == "block":
        bodies.append(make(-H))
        names.append("target")
    system = CoupledSystem([Block(n, b, [BlockTerm(b)]) for n, b in zip(names, bodies)])
    slave = ContactSurface(top.mesh, where=lambda x: x[-1] < g0 + 0.25 * h, offset=0)
    if target == "plane":
        pair = RigidContactPair(slave, PlaneObstacle(np.zeros(dim), np.eye(dim)[-1]), system.n_dofs)
    else:
        master = ContactSurface(bodies[1].mesh, where=lambda x: x[-1] > -0.25 * h,
                                offset=system.block("target").offset)
        pair = DeformableContactPair(slave, master, system.n_dofs)
    con = LevelSetContact(pair, material=material)
    v0 = np.zeros(system.n_dofs)
    v0[system.block("block").dofs][dim - 1 :: dim] = -velocity  # a view: sets the block's dofs
    c_bar = math.sqrt(young / density)
    t_end = g0 / velocity + 3.0 * H / c_bar if t_end is None else float(t_end)
    if integrator == "theta":
        integ, opts = "theta", {"theta": theta}
    else:
        integ, opts = "explicit", {"safety": 1.0}
    res = solve(system, integ, t_end=t_end, dt=dt, v0=v0, constraints=[con], **opts)
    hist = con.history
    e = res.total_energy
    work = hist.work if hist.work.size == e.size else np.concatenate([[0.0], hist.work])
    lam = res.multipliers[con.name]
    in_contact = np.any(lam != 0.0, axis=1)
    idx = np.nonzero(in_contact)[0]
    first, last = (int(idx[0]), int(idx[-1])) if idx.size else (0, 0)
    sep = min(last + 1, e.size - 1)
    loss = float((e[max(first - 1, 0)] - e[sep]) / e[0])
    # gap drift of active points and penetration at activation (history is per step)
    act = hist.active
    gap = hist.gap
    prev = np.vstack([np.zeros((1, act.shape[1]), dtype=bool), act[:-1]])
    newly = act & ~prev
    ref_gap = np.full(act.shape[1], np.nan)
    drift = 0.0
    pen_excess = -np.inf
    pen_max = -np.inf
    for k in range(act.shape[0]):
        nk = newly[k]
        if np.any(nk):
            ref_gap[nk] = gap[k, nk]
            bound = (1.0 - theta) * hist.dt[k] * hist.vn_start[k, nk]
            pen_excess = max(pen_excess, float(np.max(gap[k, nk] - bound)))
            pen_max = max(pen_max, float(np.max(gap[k, nk])))
        ak = act[k] & ~nk
        if np.any(ak):
            drift = max(drift, float(np.max(np.abs(gap[k, ak] - ref_gap[ak]))))
    iters = hist.iterations.astype(int)
    iters_contact = iters[np.any(act, axis=1)]
    finals = []
    for b in system.blocks:
        vz = res.v[b.dofs][dim - 1 :: dim]
        finals.append(float(np.mean(vz)))
    return BlockImpactResult(
        dim=dim, target=target, elements=ne, dt=float(res.dt), h=h, t=res.times, total_energy=e,
        contact_work=work, first_contact=first, separation=sep, energy_loss=loss,
        max_gap_drift=drift, max_penetration_excess=pen_excess, max_penetration=pen_max,
        iterations=iters, iterations_contact=iters_contact,
        n_status_failures=int(res.n_status_failures), final_velocities=finals, theta=theta,
    )


# ---------------------------------------------------------------------------------------------
# plot
# ---------------------------------------------------------------------------------------------
def plot_two_bars(result: TwoBarsResult, path: str) -> None:
    """Interface velocity and contact pressure against time, with the exact solution (PNG).

    With a ``result.newmark`` both methods are overlaid (the paper's Figure 1).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ex = result.exact
    fig, axes = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True)
    t_exact = np.array([0.0, 0.0, ex["duration"], ex["duration"], result.t[-1]])
    v_after = ex["final_velocities"][-1]
    v_exact = np.array([ex["interface_velocity"]] * 3 + [v_after, v_after])
    v_exact[0] = result.interface_velocity[0]
    p_exact = np.array([0.0, ex["pressure"], ex["pressure"], 0.0, 0.0])
    runs = [result] + ([result.newmark] if result.newmark is not None else [])
    styles = {"levelset": ("C0", "-"), "newmark-trapezoidal": ("C3", "-"),
              "newmark-hht": ("C1", "-")}
    for r in runs:
        col, ls = styles.get(r.method, ("C2", "-"))
        axes[0].plot(r.t * 1e6, r.interface_velocity, color=col, ls=ls, lw=1.0, label=r.method)
        axes[1].plot(r.t * 1e6, r.contact_pressure / 1e6, color=col, ls=ls, lw=1.0, label=r.method)
    axes[0].plot(t_exact * 1e6, v_exact, "k--", lw=1.2, label="exact")
    axes[1].plot(t_exact * 1e6, p_exact / 1e6, "k--", lw=1.2, label="exact")
    axes[0].set_ylabel("interface velocity (m/s)")
    axes[1].set_ylabel("contact pressure (MPa)")
    axes[1].set_xlabel("time (µs)")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    cfg = result.config
    fig.suptitle(
        f"two-bar impact: {cfg.get('elements')} elements per bar, CFL {cfg.get('cfl')}, "
        f"v0 = {cfg.get('velocity')} m/s"
    )
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
