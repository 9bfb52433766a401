"""A block launched onto a rigid plane or onto an identical block (2D plane strain, 3D).

The level-set contact model's checks beyond 1D: a block of height H (the impact direction is the
last coordinate) starts at a small gap above the target at −v₀ and hits it; the gap of active
points must not drift, the penetration at activation must stay within the velocity-level bound
(1 − θ)Δt[[v_n]], and the energy lost in the impact must vanish with refinement. SI units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import skfem

from ..io import JsonResult
from ..models import (
    ContactSurface,
    DeformableContactPair,
    IsotropicElastic,
    LevelSetContact,
    LinearElastic,
    PlaneObstacle,
    RigidContactPair,
)
from ..problem.system import Block, BlockTerm, CoupledSystem
from ..solvers import solve

__all__ = ["BlockImpactResult", "run_block_impact"]


@dataclass
class BlockImpactResult(JsonResult):
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
    dofmap = system.dofmap
    slave = ContactSurface(top.mesh, where=lambda x: x[-1] < g0 + 0.25 * h, offset=dofmap["block"])
    if target == "plane":
        pair = RigidContactPair(slave, PlaneObstacle(np.zeros(dim), np.eye(dim)[-1]), dofmap)
    else:
        master = ContactSurface(
            bodies[1].mesh, where=lambda x: x[-1] > -0.25 * h, offset=dofmap["target"]
        )
        pair = DeformableContactPair(slave, master, dofmap)
    con = LevelSetContact(pair, material=material)
    v0 = np.zeros(dofmap.n_dofs)
    v0[dofmap["block"].component_dofs(dim - 1)] = -velocity
    c_bar = math.sqrt(young / density)
    t_end = g0 / velocity + 3.0 * H / c_bar if t_end is None else float(t_end)
    if integrator == "theta":
        integ, opts = "theta", {"theta": theta}
    else:
        integ, opts = "explicit", {"safety": 1.0}
    res = solve(system, integ, t_end=t_end, dt=dt, v0=v0, constraints=[con], **opts)
    hist = con.history(res)
    e = res.total_energy
    work = np.concatenate([[0.0], hist.work])  # one record per step: times[1:]
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
    finals = [float(np.mean(res.v[dofmap[b.name].component_dofs(dim - 1)])) for b in system.blocks]
    return BlockImpactResult(
        dim=dim,
        target=target,
        elements=ne,
        dt=float(res.dt),
        h=h,
        t=res.times,
        total_energy=e,
        contact_work=work,
        first_contact=first,
        separation=sep,
        energy_loss=loss,
        max_gap_drift=drift,
        max_penetration_excess=pen_excess,
        max_penetration=pen_max,
        iterations=iters,
        iterations_contact=iters_contact,
        n_status_failures=int(res.n_status_failures),
        final_velocities=finals,
        theta=theta,
    )
