"""The block impact's run, as named steps: the integrator run, the energy lost in the impact,
the activation figures (gap drift, penetration against its bound)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ...solvers import solve
from .result import BlockImpactResult
from .setup import build_block_impact

if TYPE_CHECKING:
    from .config import BlockImpactConfig

__all__ = ["run_config"]


def _activation(hist, theta: float) -> tuple[float, float, float]:
    """Over the steps (the contact history has one row a step): the largest drift (m) of an
    active point's gap from its value at activation, the largest excess of the gap at
    activation over the bound (1 − θ)Δt[[v_n]] (m), and the largest gap at activation (m)."""
    act = hist.active
    gap = hist.gap
    prev = np.vstack([np.zeros((1, act.shape[1]), dtype=bool), act[:-1]])
    newly = act & ~prev
    ref_gap = np.full(act.shape[1], np.nan)
    drift = 0.0
    pen_excess = -np.inf
    pen_max = -np.inf
    # a loop over steps (each reads the reference gaps the earlier activations set)
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
    return drift, pen_excess, pen_max


def run_config(config: BlockImpactConfig) -> BlockImpactResult:
    """Run the block impact of ``config`` (see :func:`run_block_impact`)."""
    setup = build_block_impact(config)
    system, con, dim, theta = setup.system, setup.contact, config.dim, config.theta
    if config.integrator == "theta":
        integ, opts = "theta", {"theta": theta}
    else:
        integ, opts = "explicit", {"safety": 1.0}
    res = solve(system, integ, t_end=setup.t_end, dt=setup.dt, v0=setup.v0, constraints=[con],
                **opts)  # fmt: skip
    hist = con.history(res)
    e = res.total_energy
    work = np.concatenate([[0.0], hist.work])  # one record per step: times[1:]
    lam = res.multipliers[con.name]
    in_contact = np.any(lam != 0.0, axis=1)
    idx = np.nonzero(in_contact)[0]
    first, last = (int(idx[0]), int(idx[-1])) if idx.size else (0, 0)
    sep = min(last + 1, e.size - 1)
    loss = float((e[max(first - 1, 0)] - e[sep]) / e[0])
    drift, pen_excess, pen_max = _activation(hist, theta)
    iters = hist.iterations.astype(int)
    iters_contact = iters[np.any(hist.active, axis=1)]
    dofmap = system.dofmap
    finals = [float(np.mean(res.v[dofmap[b.name].component_dofs(dim - 1)])) for b in system.blocks]
    return BlockImpactResult(
        dim=dim,
        target=config.target,
        elements=setup.elements,
        dt=float(res.dt),
        h=setup.h,
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
