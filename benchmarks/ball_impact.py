"""The ball impact: Arlequin against the single-mesh references, in one process.

Runs ``run_ball_impact`` with the models ``arlequin``, ``mono`` (uniformly fine, J2 in the whole
block), ``mono-zoned`` (uniformly fine, J2 in the patch region) and ``graded`` (conforming
graded meshes, the laws of mono-zoned) on the same set-up, and prints JSON: per model the wall
time of the time loop, steps, elements, the quantities of interest (peak force, contact
duration, restitution, dent depth, maximum ε̄p, energy balance) and their differences from
``mono``; p (the patches' elements over the uniform meshes'), the ratios T_mono / T_arlequin
against the floor 0.8 / p, T_mono-zoned / T_arlequin, T_arlequin / T_graded against 1.3, and
the peak resident memory of the process (MB, the largest run's). The compiled J2 kernel is
warmed up before timing. With ``--repeat N`` every model runs N times in rounds and its
shortest run is its time (all of them listed in ``wall_times_s``). ``arlequin`` runs with
multi-time-step (the demo's default, or ``--coarse-step-ratio M``) and, as ``arlequin-1``,
without it; the ratios are given for both.

    python benchmarks/ball_impact.py [--regime plastic] [--block-size 0.02] [--rigid-wall]
        [--coarse-step-ratio M] [--coarse-size H] [--fine-size H] [--friction MU]
        [--models arlequin,mono] [--repeat N]
"""

from __future__ import annotations

import argparse
import json
import resource

import _threads  # before numba runs: OpenMP threads sleep between parallel regions


def _row(r) -> dict:
    return {"wall_time_s": round(r.wall_time_s, 2), "steps": r.n_steps,
            "elements": r.n_elements, "peak_force_N": round(r.peak_force, 3),
            "contact_duration_s": float(f"{r.contact_duration:.6g}"),
            "restitution": round(r.restitution, 5), "dent_depth_m": float(f"{r.dent_depth:.6g}"),
            "max_plastic_strain": round(r.max_plastic_strain, 5),
            "energy_balance_error": float(f"{r.energy_balance_error:.3g}"),
            "fine_cells_per_contact_radius": round(r.contact_radius_cells, 2),
            "mean_step_ratio": round(r.mean_step_ratio, 3)}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--regime", choices=["elastic", "plastic"], default="plastic")
    parser.add_argument("--block-size", type=float, default=0.02, help="R_B = H_B (m)")
    parser.add_argument("--models", default="arlequin,arlequin-1,mono,mono-zoned,graded")
    parser.add_argument("--rigid-wall", action="store_true")
    parser.add_argument(
        "--coarse-step-ratio",
        type=int,
        default=None,
        help="arlequin's multi-time-step ratio (default: the demo's, 2)",
    )
    parser.add_argument("--coarse-size", type=float, default=None)
    parser.add_argument("--fine-size", type=float, default=None)
    parser.add_argument("--friction", type=float, default=0.0, help="Coulomb μ between the bodies")
    parser.add_argument("--repeat", type=int, default=1,
                        help="rounds of every model in turn; each model's shortest run is its "
                             "time (the machine's noise only adds)")  # fmt: skip
    args = parser.parse_args(argv)
    if args.repeat < 1:
        parser.error(f"--repeat must be at least 1, got {args.repeat}")
    from arlequin.demos.ball_impact import run_ball_impact
    from arlequin.models.plasticity.j2_kernel import warm_up

    warm_up()
    common = dict(regime=args.regime, block_radius=args.block_size,
                  block_height=args.block_size, rigid_wall=args.rigid_wall,
                  coarse_size=args.coarse_size, fine_size=args.fine_size,
                  friction=args.friction)  # fmt: skip
    runs, times = {}, {}
    for _ in range(args.repeat):  # rounds of every model, so that drifts hit them alike
        for model in args.models.split(","):
            ratio = {"arlequin": args.coarse_step_ratio, "arlequin-1": 1}.get(model)
            r = run_ball_impact(model=model.removesuffix("-1"), coarse_step_ratio=ratio,
                                **common)  # fmt: skip
            times.setdefault(model, []).append(r.wall_time_s)
            if model not in runs or r.wall_time_s < runs[model].wall_time_s:
                runs[model] = r
    first = next(iter(runs.values()))
    out = {"benchmark": "ball_impact", "regime": args.regime, "block_size_m": args.block_size,
           "rigid_wall": args.rigid_wall, "friction": args.friction,
           "fine_size_m": first.fine_size, "coarse_size_m": first.coarse_size}  # fmt: skip
    for model, r in runs.items():
        out[model] = _row(r)
        out[model]["wall_times_s"] = [round(t, 2) for t in times[model]]
    mono, arl = runs.get("mono"), runs.get("arlequin", runs.get("arlequin-1"))
    if arl is not None:
        out["patch_fraction_p"] = round(arl.patch_fraction, 5)
        out["floor_0.8/p"] = round(0.8 / arl.patch_fraction, 2)
    for model, r in runs.items():
        if mono is None or model == "mono":
            continue
        for key in ("peak_force", "contact_duration", "restitution", "dent_depth"):
            a, m = getattr(r, key), getattr(mono, key)
            out[model][f"{key}_difference_vs_mono"] = float(f"{a / m - 1:.3g}") if m else None
    for name in ("arlequin", "arlequin-1"):
        arl = runs.get(name)
        if arl is None:
            continue
        out[name]["coarse_step_ratio"] = arl.coarse_step_ratio
        for model in ("mono", "mono-zoned"):
            if model in runs:
                out[f"T_{model}/T_{name}"] = round(runs[model].wall_time_s / arl.wall_time_s, 3)
        if "graded" in runs:
            out[f"T_{name}/T_graded"] = round(arl.wall_time_s / runs["graded"].wall_time_s, 3)
    out["peak_memory_MB"] = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)
    out["threads"] = _threads.settings()
    print(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
