"""The Taylor bar on one mesh at several refinements: results, cost and the kernel's speed-up.

For each level (cells across the radius) a full run (80 µs, F-bar, the compiled kernel) in its
own process (so that its peak memory is its own), then the same mesh over a short window with the
numpy backend and with the kernel, for the numpy/numba ratio (same steps, same process). Prints
JSON, one record per level: cells, steps, wall time, quadrature-point updates per second of the
explicit loop (n_qp × n_steps / loop time, contact and records included; the kernel's
compilation and the integrator's set-up excluded), peak resident memory, the ratio, and the
results (final length, footprint radius, maximum ε̄p, energy balance error) against the published
values. ``--plain`` levels also run without F-bar (the locking comparison).

``--compare N`` instead runs, in one process and at N fine cells across the radius, the
Arlequin bar (defaults: patch 0.9 L, fine mediator, H1, ramp), the uniform single mesh at the
patch's resolution (``--model mono --mesh-size R/N``) and the graded single mesh (``--model
graded``), and prints their wall times, the ratios T_arlequin / T_uniform against the bound
(1 + p)/2 with p the patch's share of the fine cells and T_arlequin / T_graded against 1.3, the
three quantities of interest of each and the process's peak memory after each run. With
``--repeat N`` the models run N times in rounds and each one's shortest run is its time (all
of them in ``wall_times_s``).

    python benchmarks/taylor_bar.py [--levels 5 10 20 30] [--plain 10 20] [--window 1e-6]
    python benchmarks/taylor_bar.py --compare 20 [--coarse-step-ratio 4]
    python benchmarks/taylor_bar.py --geometry 3d --levels 4 6 8 --plain
    python benchmarks/taylor_bar.py --geometry 3d --compare 8 [--patch-length LP] [--repeat N]

``--geometry 3d``: the quarter bar of hexahedra. There the uniform reference of ``--compare`` is
the single mesh with the patch's nodes (``--model mono --coarse-size``: the coarse O-grid
refined), and the graded mesh has three sheets of 2:1 transition templates
(:mod:`arlequin.demos.taylor_bar.graded_3d`).

With ``--coarse-step-ratio M`` the Arlequin bar is also run with the multi-time-step scheme
(the coarse model's force every m ≤ M fine steps): its wall time, the gain over the one-step
run, its results and energy balance error beside the others.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys

import _threads  # before numba runs: OpenMP threads sleep between parallel regions


def one_level(n: int, fbar: bool, window: float, geometry: str = "axisymmetric") -> dict:
    from arlequin.demos.taylor_bar import TAYLOR_REFERENCE, run_taylor_bar

    r = run_taylor_bar(model="mono", elements_radial=n, fbar=fbar, geometry=geometry)
    ref = TAYLOR_REFERENCE
    record = {
        "elements_radial": n,
        "geometry": geometry,
        "fbar": fbar,
        "elements": r.n_elements,
        "quadrature_points": int(r.state.eqps.size),
        "steps": r.n_steps,
        "wall_time_s": round(r.wall_time_s, 2),
        "setup_time_s": round(r.setup_time_s, 2),
        "qp_updates_per_second": float(f"{r.qp_updates_per_second:.4g}"),
        "min_dt_s": r.min_dt,
        "final_length_mm": round(r.final_length * 1e3, 4),
        "mushroom_radius_mm": round(r.mushroom_radius * 1e3, 4),
        "length_error": round(r.final_length / ref["final_length"] - 1.0, 5),
        "radius_error": round(r.mushroom_radius / ref["mushroom_radius"] - 1.0, 5),
        "max_plastic_strain": round(r.max_plastic_strain, 3),
        "max_plastic_strain_at_mm": [round(x * 1e3, 4) for x in r.max_plastic_strain_at],
        "energy_balance_error": float(f"{r.energy_balance_error:.3g}"),
        "impact_loss_J": round(r.impact_loss, 4),
    }
    if fbar and window > 0:
        # the same mesh and window with both backends: the loop time ratio
        kw = dict(model="mono", elements_radial=n, t_end=window, geometry=geometry)
        fast = run_taylor_bar(backend="numba", **kw)
        slow = run_taylor_bar(backend="numpy", **kw)
        assert fast.n_steps == slow.n_steps
        loop = [x.wall_time_s - x.setup_time_s for x in (slow, fast)]
        record["numpy_numba_ratio"] = round(loop[0] / loop[1], 2)
        record["ratio_window_s"] = window
        record["ratio_window_steps"] = fast.n_steps
    record["peak_rss_mib"] = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)
    return record


def _qoi(r) -> dict:
    return {
        "elements": r.n_elements,
        "steps": r.n_steps,
        "wall_time_s": round(r.wall_time_s, 2),
        "final_length_mm": round(r.final_length * 1e3, 4),
        "mushroom_radius_mm": round(r.mushroom_radius * 1e3, 4),
        "max_plastic_strain": round(r.max_plastic_strain, 4),
        "energy_balance_error": float(f"{r.energy_balance_error:.3g}"),
        "peak_rss_mib_after": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
    }


def compare(n: int, coarse_size: float | None = None, ratio_mts: int = 1,
            geometry: str = "axisymmetric", patch_length: float | None = None,
            repeat: int = 1) -> dict:  # fmt: skip
    """Arlequin against the uniform fine mesh, in this process (see the module docstring)."""
    import warnings

    from arlequin.demos.taylor_bar import GluingBandPlasticityWarning, run_taylor_bar

    three_d = geometry == "3d"
    common = dict(elements_radial=n, geometry=geometry)
    runs: dict[str, list] = {"arlequin": [], "mts": [], "uniform": [], "graded": []}
    caught: list = []
    for _ in range(repeat):  # rounds of every model, so that drifts hit them alike
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always", GluingBandPlasticityWarning)
            arl = run_taylor_bar(model="arlequin", coarse_size=coarse_size,
                                 patch_length=patch_length, **common)  # fmt: skip
        caught += seen
        runs["arlequin"].append(arl)
        if ratio_mts > 1:
            runs["mts"].append(run_taylor_bar(
                model="arlequin", coarse_size=coarse_size, patch_length=patch_length,
                coarse_step_ratio=ratio_mts, **common))  # fmt: skip
        # 3D: the single mesh with the patch's nodes (the coarse O-grid refined)
        runs["uniform"].append(run_taylor_bar(
            model="mono", coarse_size=arl.arlequin["coarse_size"] if three_d else None,
            **common))  # fmt: skip
        runs["graded"].append(run_taylor_bar(model="graded", coarse_size=coarse_size,
                                             patch_length=patch_length, **common))  # fmt: skip
    # each model's shortest run (the machine's noise only adds), all of them listed
    fastest = {k: min(v, key=lambda r: r.wall_time_s) if v else None for k, v in runs.items()}
    arl, mts, uni, graded = (fastest[k] for k in ("arlequin", "mts", "uniform", "graded"))
    a = arl.arlequin
    p = a["patch_fraction"]
    ratio = arl.wall_time_s / uni.wall_time_s
    out = {
        "fine_cells_across": n,
        "patch_fraction": round(p, 4),
        "coarse_size": a["coarse_size"],
        "arlequin": {**_qoi(arl), **{k: a[k] for k in ("coarse_elements", "fine_elements",
                     "band_max_plastic_strain", "multiplier_chatter_per_row")},
                     "band_warning": bool(caught)},
        "geometry": geometry,
        "uniform": _qoi(uni),
        "graded": None if graded is None else _qoi(graded),
        "time_ratio_arlequin_uniform": round(ratio, 4),
        "time_bound_(1+p)/2": round((1 + p) / 2, 4),
        "time_bound_graded": 1.3,
        "length_difference": round(arl.final_length / uni.final_length - 1, 5),
        "radius_difference": round(arl.mushroom_radius / uni.mushroom_radius - 1, 5),
        "max_plastic_strain_difference": round(arl.max_plastic_strain / uni.max_plastic_strain
                                               - 1, 5),
    }  # fmt: skip
    if graded is not None:
        out.update({
            "time_ratio_arlequin_graded": round(arl.wall_time_s / graded.wall_time_s, 4),
            "graded_length_difference": round(graded.final_length / uni.final_length - 1, 5),
            "graded_radius_difference": round(graded.mushroom_radius / uni.mushroom_radius - 1,
                                              5),
        })  # fmt: skip
    for key, name in (("arlequin", "arlequin"), ("uniform", "uniform"), ("graded", "graded")):
        if out.get(name) is not None:
            out[name]["wall_times_s"] = [round(r.wall_time_s, 2) for r in runs[key]]
    if mts is not None:
        m = mts.arlequin
        out["multi_time_step"] = {
            **_qoi(mts), "coarse_step_ratio": ratio_mts, "mean_step_ratio":
            round(m["mean_step_ratio"], 3), "macro_steps": m["macro_steps"],
            "gain_T_one_step/T_mts": round(arl.wall_time_s / mts.wall_time_s, 4),
            "length_difference_vs_one_step": round(mts.final_length / arl.final_length - 1, 6),
            "radius_difference_vs_one_step": round(mts.mushroom_radius / arl.mushroom_radius - 1,
                                                   6),
            "multiplier_chatter": round(m["multiplier_chatter"], 4),
        }  # fmt: skip
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--levels", type=int, nargs="+", default=[5, 10, 20, 30])
    parser.add_argument("--plain", type=int, nargs="*", default=[10, 20],
                        help="levels also run without F-bar")  # fmt: skip
    parser.add_argument("--window", type=float, default=1e-6,
                        help="simulated time (s) of the numpy/numba comparison")  # fmt: skip
    parser.add_argument("--compare", type=int, default=None, metavar="N",
                        help="Arlequin vs the uniform mesh, N fine cells across")  # fmt: skip
    parser.add_argument("--coarse-size", type=float, default=None,
                        help="with --compare: the Arlequin coarse size (m)")  # fmt: skip
    parser.add_argument(
        "--coarse-step-ratio",
        type=int,
        default=1,
        metavar="M",
        help="with --compare: also the Arlequin run with multi-time-step M",
    )
    parser.add_argument("--geometry", choices=["axisymmetric", "3d"], default="axisymmetric")
    parser.add_argument("--patch-length", type=float, default=None,
                        help="with --compare: the Arlequin patch length (m)")  # fmt: skip
    parser.add_argument("--repeat", type=int, default=1,
                        help="with --compare: rounds of every model; each model's shortest run "
                             "is its time")  # fmt: skip
    parser.add_argument("--single", type=int, default=None, help=argparse.SUPPRESS)
    parser.add_argument("--no-fbar", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.compare is not None:
        from arlequin.models.plasticity.j2_kernel import warm_up
        from arlequin.models.plasticity.j2_kernel_3d import warm_up_solid

        warm_up_solid() if args.geometry == "3d" else warm_up()
        if args.repeat < 1:
            parser.error(f"--repeat must be at least 1, got {args.repeat}")
        out = compare(args.compare, args.coarse_size, args.coarse_step_ratio, args.geometry,
                      args.patch_length, args.repeat)  # fmt: skip
        print(
            json.dumps(
                {"benchmark": "taylor_bar_compare", **out, "threads": _threads.settings()}, indent=2
            )
        )
        return 0
    if args.single is not None:
        print(json.dumps(one_level(args.single, not args.no_fbar, args.window, args.geometry)))
        return 0
    # compile (or load) the kernel once, outside every measurement
    from arlequin.models.plasticity.j2_kernel import warm_up
    from arlequin.models.plasticity.j2_kernel_3d import warm_up_solid

    warm_up_solid() if args.geometry == "3d" else warm_up()
    records = []
    runs = [(n, True) for n in args.levels] + [(n, False) for n in args.plain]
    for n, fbar in runs:
        cmd = [sys.executable, __file__, "--single", str(n), "--window", str(args.window),
               "--geometry", args.geometry]  # fmt: skip
        if not fbar:
            cmd.append("--no-fbar")
        out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
        records.append(json.loads(out.strip().splitlines()[-1]))
        print(json.dumps(records[-1]), file=sys.stderr, flush=True)
    print(
        json.dumps(
            {"benchmark": "taylor_bar", "levels": records, "threads": _threads.settings()}, indent=2
        )
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
