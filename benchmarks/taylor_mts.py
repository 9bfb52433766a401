"""Multi-time-step on the Arlequin Taylor bar: the gain of ``--coarse-step-ratio M`` over the
one-step run, in one process, interleaved runs (A, B, A, B) so that a drift of the machine's
speed shows as a spread; the minimum wall time of each is the figure.

Prints JSON: per ratio the wall times, steps, macro steps and mean ratio used, the results
(length, radius, maximum ε̄p, energy balance) and their differences from the one-step run, and
the gain T_one_step / T_mts. The compiled kernel is warmed up before timing.

    python benchmarks/taylor_mts.py [--cells 20] [--t-end 8e-5] [--ratio 4] [--repeat 2]
"""

from __future__ import annotations

import argparse
import json
import warnings


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=20)
    parser.add_argument("--t-end", type=float, default=8e-5)
    parser.add_argument("--ratio", type=int, default=4)
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args(argv)
    from arlequin.demos.taylor_bar import GluingBandPlasticityWarning, run_taylor_bar
    from arlequin.models.plasticity.j2_kernel import warm_up

    warm_up()
    runs: dict[int, list] = {1: [], args.ratio: []}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GluingBandPlasticityWarning)
        for _ in range(args.repeat):
            for m in runs:
                runs[m].append(run_taylor_bar(elements_radial=args.cells, t_end=args.t_end,
                                              coarse_step_ratio=m))  # fmt: skip
    one = runs[1][0]
    out = {"benchmark": "taylor_mts", "cells": args.cells, "t_end_s": args.t_end}
    for m, rs in runs.items():
        r = rs[0]
        out[f"ratio_{m}"] = {
            "wall_times_s": [round(x.wall_time_s, 2) for x in rs],
            "steps": r.n_steps,
            "macro_steps": r.arlequin.get("macro_steps", r.n_steps),
            "mean_step_ratio": round(r.arlequin.get("mean_step_ratio", 1.0), 3),
            "final_length_mm": round(r.final_length * 1e3, 5),
            "mushroom_radius_mm": round(r.mushroom_radius * 1e3, 5),
            "max_plastic_strain": round(r.max_plastic_strain, 4),
            "energy_balance_error": float(f"{r.energy_balance_error:.3g}"),
            "length_difference": float(f"{r.final_length / one.final_length - 1:.3g}"),
            "radius_difference": float(f"{r.mushroom_radius / one.mushroom_radius - 1:.3g}"),
        }
    t1 = min(x.wall_time_s for x in runs[1])
    tm = min(x.wall_time_s for x in runs[args.ratio])
    out["gain_T_one_step/T_mts"] = round(t1 / tm, 4)
    print(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
