"""The ball impact: Arlequin against the uniformly fine single meshes, in one process.

Runs ``run_ball_impact`` with ``model="arlequin"`` and ``model="mono"`` on the same set-up
(``mono-zoned`` and ``graded`` are not built yet: reported as such), and prints JSON: per model
the wall time of the time loop, steps, elements, the quantities of interest (peak force,
contact duration, restitution, dent depth, maximum ε̄p, energy balance) and their differences
from ``mono``; p (the patches' elements over the uniform meshes'), the ratios T_mono /
T_arlequin against the floor 0.8 / p, and the peak resident memory of the process (MB, at the
end: the larger run's). The compiled J2 kernel is warmed up before timing.

    python benchmarks/ball_impact.py [--regime plastic] [--block-size 0.04] [--rigid-wall]
        [--coarse-step-ratio 1]
"""

from __future__ import annotations

import argparse
import json
import resource


def _row(r) -> dict:
    return {"wall_time_s": round(r.wall_time_s, 2), "steps": r.n_steps,
            "elements": r.n_elements, "peak_force_N": round(r.peak_force, 3),
            "contact_duration_s": float(f"{r.contact_duration:.6g}"),
            "restitution": round(r.restitution, 5), "dent_depth_m": float(f"{r.dent_depth:.6g}"),
            "max_plastic_strain": round(r.max_plastic_strain, 5),
            "energy_balance_error": float(f"{r.energy_balance_error:.3g}"),
            "fine_cells_per_contact_radius": round(r.contact_radius_cells, 2)}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--regime", choices=["elastic", "plastic"], default="plastic")
    parser.add_argument("--block-size", type=float, default=0.04, help="R_B = H_B (m)")
    parser.add_argument("--rigid-wall", action="store_true")
    parser.add_argument("--coarse-step-ratio", type=int, default=1)
    parser.add_argument("--coarse-size", type=float, default=None)
    parser.add_argument("--fine-size", type=float, default=None)
    args = parser.parse_args(argv)
    from arlequin.demos.ball_impact import run_ball_impact
    from arlequin.models.j2_kernel import warm_up

    warm_up()
    common = dict(regime=args.regime, block_radius=args.block_size,
                  block_height=args.block_size, rigid_wall=args.rigid_wall,
                  coarse_size=args.coarse_size, fine_size=args.fine_size)  # fmt: skip
    arl = run_ball_impact(model="arlequin", coarse_step_ratio=args.coarse_step_ratio, **common)
    mono = run_ball_impact(model="mono", **common)
    out = {"benchmark": "ball_impact", "regime": args.regime, "block_size_m": args.block_size,
           "rigid_wall": args.rigid_wall, "coarse_step_ratio": args.coarse_step_ratio,
           "fine_size_m": arl.fine_size, "coarse_size_m": arl.coarse_size,
           "patch_fraction_p": round(arl.patch_fraction, 5),
           "arlequin": _row(arl), "mono": _row(mono),
           "mono-zoned": "not built yet", "graded": "not built yet"}  # fmt: skip
    for key, a, m in (("peak_force", arl.peak_force, mono.peak_force),
                      ("contact_duration", arl.contact_duration, mono.contact_duration),
                      ("restitution", arl.restitution, mono.restitution),
                      ("dent_depth", arl.dent_depth, mono.dent_depth)):  # fmt: skip
        out[f"{key}_difference_vs_mono"] = float(f"{a / m - 1:.3g}") if m else None
    ratio = mono.wall_time_s / arl.wall_time_s
    out["T_mono/T_arlequin"] = round(ratio, 3)
    out["floor_0.8/p"] = round(0.8 / arl.patch_fraction, 2)
    out["peak_memory_MB"] = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)
    print(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
