"""Friction on the Taylor bar: the footprint against μ, the energy balance and the fixed point.

Runs ``run_taylor_bar(model, elements_radial=N, friction=μ)`` for each model and μ (80 µs) and
prints JSON: final length, footprint radius, maximum ε̄p, energy balance error, friction work
(J, ≤ 0), steps, wall time and the distribution of the contact fixed-point iterations per step.

    python benchmarks/taylor_friction.py [--cells 10] [--mu 0 0.1 0.3] [--models mono arlequin]
"""

from __future__ import annotations

import argparse
import json
import warnings


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=10)
    parser.add_argument("--mu", type=float, nargs="+", default=[0.0, 0.1, 0.3])
    parser.add_argument("--models", nargs="+", default=["mono", "arlequin"])
    parser.add_argument("--t-end", type=float, default=8e-5)
    args = parser.parse_args(argv)
    from arlequin.demos.taylor_bar import GluingBandPlasticityWarning, run_taylor_bar
    from arlequin.models.plasticity.j2_kernel import warm_up

    warm_up()
    rows = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GluingBandPlasticityWarning)
        for model in args.models:
            for mu in args.mu:
                r = run_taylor_bar(model=model, elements_radial=args.cells, friction=mu,
                                   t_end=args.t_end)  # fmt: skip
                rows.append({
                    "model": model, "friction": mu, "cells_across": args.cells,
                    "final_length_mm": round(r.final_length * 1e3, 4),
                    "mushroom_radius_mm": round(r.mushroom_radius * 1e3, 4),
                    "max_plastic_strain": round(r.max_plastic_strain, 4),
                    "energy_balance_error": float(f"{r.energy_balance_error:.3g}"),
                    "friction_work_J": round(r.history.get("friction_work", [0.0])[-1], 4),
                    "steps": r.n_steps, "wall_time_s": round(r.wall_time_s, 2),
                    "fixed_point_iterations": r.fixed_point_iterations,
                })  # fmt: skip
    print(json.dumps({"benchmark": "taylor_friction", "runs": rows}, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
