"""Cost of one explicit coupled step against one step of each model alone (same run).

A plane-strain cantilever (4 m × 1 m) with a coarse triangle mesh of size h = 1/64 m and a
non-nested refined patch (size h/2, jittered nodes) on [0, 1.5] m at the clamped end: about 33k
coarse and 49k fine elements, glued (H1, coarse mediator, ramp weights) in a band of
``--gluing-elements`` coarse elements (default 4) along the patch's interior edge. The same
central-difference integrator steps

* the coupled system (mediator rows, Dirichlet rows on both models),
* the fine patch alone (its own mesh, weight 1, clamped),
* the coarse model alone (clamped),

all at the coupled system's default step, and the wall time spent in the coupling impulses
(the transfers B v and M⁻¹Bᵀ Λ plus the triangular solves with the factorised B M⁻¹ Bᵀ) is measured
inside the coupled steps (the constraint rows include the clamps of both models). Times are the
best of 5 repeats of ``--steps`` steps (mean per step), the overhead that of the same repeat.
Prints JSON (times in seconds per step).

    python benchmarks/coupling_overhead.py [--h 0.015625] [--steps 300] [--json PATH]
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import time

import numpy as np

from arlequin.demos.cantilever import build_cantilever
from arlequin.problem.system import Block, BlockTerm, CoupledSystem, LinearConstraint
from arlequin.solvers import CentralDifference

logger = logging.getLogger("coupling_overhead")


def _alone(model, name: str) -> CoupledSystem:
    dofs = model.dofs_where(lambda x: x[0] < 1e-9)
    import scipy.sparse as sp

    rows = sp.csr_matrix(
        (np.ones(dofs.size), (np.arange(dofs.size), dofs)), shape=(dofs.size, model.n_dofs)
    )
    return CoupledSystem(
        [Block(name, model, [BlockTerm(model)])],
        [LinearConstraint(rows, None, "clamp", kind="dirichlet")],
    )


def _time_steps(integ: CentralDifference, steps: int, repeats: int = 5) -> tuple[float, float]:
    """Best (over repeats) mean step time, and the mean constraint time of that same repeat."""
    best, best_c = np.inf, np.nan
    for _ in range(repeats):
        c0 = getattr(integ, "constraint_time", 0.0)
        t0 = time.perf_counter()
        for _ in range(steps):
            integ.step()
        t = (time.perf_counter() - t0) / steps
        if t < best:
            best, best_c = t, (getattr(integ, "constraint_time", 0.0) - c0) / steps
    return best, best_c


def run(h: float = 1.0 / 64.0, steps: int = 300, gluing_elements: int = 4) -> dict:
    t0 = time.perf_counter()
    cant = build_cantilever(ratio=0.5, h=h, gluing_width=gluing_elements * h, initial_state=False)
    system = cant.problem.system()
    build_s = time.perf_counter() - t0
    rng = np.random.default_rng(0)
    coupled = CentralDifference(system, u0=None, v0=1e-3 * rng.standard_normal(system.n_dofs))
    dt = coupled.dt
    coarse_model = cant.problem.model("coarse")
    fine_model = cant.problem.model("patch0")
    fine = CentralDifference(
        _alone(fine_model, "fine"), dt=dt, v0=1e-3 * rng.standard_normal(fine_model.n_dofs)
    )
    coarse = CentralDifference(
        _alone(coarse_model, "coarse"), dt=dt, v0=1e-3 * rng.standard_normal(coarse_model.n_dofs)
    )
    # warm-up
    for integ in (coupled, fine, coarse):
        for _ in range(10):
            integ.step()
    t_coupled, overhead_total = _time_steps(coupled, steps)
    t_fine, _ = _time_steps(fine, steps)
    t_coarse, _ = _time_steps(coarse, steps)
    coupling_rows = sum(c.n_rows for c in system.constraints if c.kind == "coupling")
    return {
        "n_coarse_elements": cant.n_coarse_elements,
        "n_fine_elements": cant.n_fine_elements,
        "n_dofs": system.n_dofs,
        "n_coupling_rows": coupling_rows,
        "gluing_band_coarse_elements": gluing_elements,
        "overlap_method": cant.problem.couplings[0].overlap.method,
        "setup_seconds": build_s,
        "dt": dt,
        "steps_timed": steps,
        "coupled_step_seconds": t_coupled,
        "fine_alone_step_seconds": t_fine,
        "coarse_alone_step_seconds": t_coarse,
        "coupling_overhead_seconds": overhead_total,
        "coupling_overhead_fraction": overhead_total / t_coupled,
        "coupled_over_sum_of_models": t_coupled / (t_fine + t_coarse),
        "target_overhead_fraction": 0.30,
    }


def main(argv=None) -> int:
    p = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    p.add_argument("--h", type=float, default=1.0 / 64.0, help="coarse element size (m)")
    p.add_argument("--steps", type=int, default=300)
    p.add_argument(
        "--gluing-elements", type=int, default=4, help="gluing band width in coarse elements"
    )
    p.add_argument("--json", default=None)
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    out = run(args.h, args.steps, args.gluing_elements)
    text = json.dumps(out, indent=2)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as fh:
            fh.write(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
