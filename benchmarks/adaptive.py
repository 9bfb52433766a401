"""Benchmark: adaptive patches (issue 31), each case adaptive / fixed patch / mono in one
process.

Cases (``--case``):

``sphere``  the pressure sphere at the quasi-static issue's defaults (300 MPa in 10 steps, 8
            coarse rings, 64 fine cells across the wall): adaptive from the one-ring seed,
            the fixed patch to 187.5 mm (the demo's default: the ring nearest 185 mm), mono.
            Criterion 3: c and u_b within 0.5% of the fixed patch, the coarse σ_vm/σy outside
            the patch below 1 at every step, T_adaptive ≤ 1.3 T_fixed.
``plate``   the plate with a hole at its defaults (195 MPa in 10 steps past first yield, 3
            levels): adaptive from the coarse ring on the hole, the fixed patch [0, 3.5a]², mono.
            Criterion 4: the load–displacement curve within 0.5% of mono at every state, the
            final patch at most 1.5 times the plastic zone (ε̄p > 0 at quadrature points) and
            the final patch's gluing band (``patch_over_plastic_zone_and_band``; also over the
            plastic zone's coarse cells and one ring, ``patch_over_plastic_cover``),
            T_mono / T_adaptive ≥ 8.
``ball``    the ball impact, plastic regime (copper block, 10 m/s, multi-time-step M = 2), the
            set-up of ``tests/test_ball_impact.py``'s plastic runs (block R_B = H_B = 2 R,
            coarse π R/80, fine π R/160; ``--size quick``: coarse π R/32, the seed 0.45 R,
            3 m/s, to check the benchmark in minutes): adaptive from the seed of radius 0.4 R
            at the contact point, the demo's fixed block patch (0.8 R), mono. Criterion 5:
            dent depth, peak force and restitution within 2% of mono, T_mono / T_adaptive ≥
            0.8 T_mono / T_fixed. The time adapting: the rebuilt problem and contact, the
            moved fields, the new integrator (stable step, impulse factorisation), its first
            impulse, the rejected intervals.

For each run: the wall time (the shortest of ``--repeat`` rounds, the three models
alternating), the number of growths, the time spent adapting (rebuilding the patch, its
overlap, weights, band and coupling rows, moving the fields; the solver's new operators; the
re-solve at the same load; the rejected steps computed again) and its share of the run, the
final patch fraction, the largest coarse σ_vm/σy outside the patch, and the peak traced memory
(one more run under :mod:`tracemalloc`, unless ``--no-memory``). Prints JSON.

    python benchmarks/adaptive.py [--case {sphere,plate,ball,all}] [--repeat 1] [--no-memory]
                                  [--size {full,quick}]
"""

from __future__ import annotations

import argparse
import functools
import json
import math
import sys
import time
import tracemalloc
import warnings
from collections.abc import Callable

import _threads  # before numba runs: OpenMP threads sleep between parallel regions
import numpy as np

#: The parts of a growth's time in its JSON entry (s).
ADAPT_PARTS = ("rebuild_time_s", "system_time_s", "resolve_time_s", "discarded_time_s")


def _timed(runs: dict[str, Callable[[], object]], repeat: int) -> tuple[dict, dict]:
    """The runs alternating, ``repeat`` rounds: each one's last result and shortest time."""
    results, best = {}, {}
    for _ in range(repeat):
        for name, fn in runs.items():
            start = time.perf_counter()
            results[name] = fn()
            wall = time.perf_counter() - start
            best[name] = min(best.get(name, np.inf), wall)
            # progress on stderr: a long case's figures before its JSON
            summary = getattr(results[name], "summary", None)
            print(f"{name}: {wall:.1f} s", summary() if callable(summary) else "",
                  file=sys.stderr, flush=True)  # fmt: skip
    return results, best


def _peak_memory(fn: Callable[[], object]) -> float:
    """The peak traced memory of a run (MB)."""
    tracemalloc.start()
    try:
        fn()
        return tracemalloc.get_traced_memory()[1] / 1e6
    finally:
        tracemalloc.stop()


def _adapt_figures(adaptations: list[dict], wall: float) -> dict:
    """The growths' count and time (s, and as a share of the run's wall time ``wall``)."""
    parts = {k: float(sum(a.get(k, 0.0) for a in adaptations)) for k in ADAPT_PARTS}
    total = sum(parts.values())
    return {
        "n_adaptations": len(adaptations),
        "n_rejected_steps": sum(bool(a.get("rejected")) for a in adaptations),
        "adapt_time_s": total,
        "adapt_time_split_s": parts,
        "adapt_share": total / wall,
        "energy_jumps": [a["energy_jump"] for a in adaptations],
        "growth_steps": [a["step"] for a in adaptations],
    }


def _with_memory(out: dict, runs: dict, memory: bool) -> None:
    for name, fn in runs.items():
        if memory:
            out[name]["peak_traced_memory_MB"] = _peak_memory(fn)


def sphere_case(repeat: int, memory: bool) -> dict:
    """The pressure sphere, adaptive / fixed patch / mono (criterion 3)."""
    from arlequin.demos.pressure_vessel import run_pressure_vessel

    runs = {
        "adaptive": lambda: run_pressure_vessel(adaptive=True),
        "fixed": lambda: run_pressure_vessel(),
        "mono": lambda: run_pressure_vessel(model="mono"),
    }
    results, best = _timed(runs, repeat)
    out: dict = {}
    for name, r in results.items():
        h = r.history
        out[name] = {
            "wall_time_s": best[name],
            "n_elements": r.n_elements,
            "n_dofs": r.n_dofs,
            "patch_fraction": r.patch_fraction,
            "plastic_radius_m": h["plastic_radius"][-1],
            "outer_displacement_m": h["outer_displacement"][-1],
            "first_yield_pressure_Pa": r.first_yield_pressure,
            "max_coarse_yield_ratio": r.max_coarse_yield_ratio,
            "newton_iterations": int(sum(h["newton_iterations"])),
        }
    out["adaptive"].update(_adapt_figures(results["adaptive"].adaptations, best["adaptive"]))
    _with_memory(out, runs, memory)
    a, f = out["adaptive"], out["fixed"]
    out["criterion_3"] = {
        "plastic_radius_deviation": a["plastic_radius_m"] / f["plastic_radius_m"] - 1.0,
        "outer_displacement_deviation": a["outer_displacement_m"] / f["outer_displacement_m"] - 1.0,
        "max_coarse_yield_ratio": a["max_coarse_yield_ratio"],
        "T_adaptive_over_T_fixed": a["wall_time_s"] / f["wall_time_s"],
        "targets": {
            "deviations": "<= 0.005",
            "max_coarse_yield_ratio": "< 1",
            "T_adaptive_over_T_fixed": "<= 1.3",
        },
    }
    out["reference"] = results["fixed"].reference
    return out


def _displacement_deviation(run, mono) -> float:
    """The largest |run / mono − 1| of the loaded edge's displacement from first yield on,
    mono's curve interpolated at the run's loads (an adaptive run probes its first yield on a
    small fixed patch: 0.3% above mono's)."""
    load = np.array(run.history["load"][1:])
    ref = np.interp(load, mono.history["load"], mono.history["displacement"])
    return float(np.abs(np.array(run.history["displacement"][1:]) / ref - 1.0).max())


def plate_case(repeat: int, memory: bool) -> dict:
    """The plate with a hole, adaptive / fixed patch / mono (criterion 4)."""
    from arlequin.demos.plate_with_hole import PlateWithHoleConfig, run_plate_with_hole

    runs = {
        "adaptive": lambda: run_plate_with_hole(adaptive=True),
        "fixed": lambda: run_plate_with_hole(),
        "mono": lambda: run_plate_with_hole(model="mono"),
    }
    results, best = _timed(runs, repeat)
    mono = results["mono"]
    config = PlateWithHoleConfig()
    plate = config.width**2 - np.pi * config.radius**2 / 4.0  # the quarter plate (m²)
    out: dict = {}
    for name, r in results.items():
        h = r.history
        out[name] = {
            "wall_time_s": best[name],
            "n_elements": r.n_elements,
            "n_dofs": r.n_dofs,
            "patch_fraction": r.patch_fraction,
            "plastic_cover_fraction": r.plastic_cover_fraction,
            "band_fraction": r.band_fraction,
            "plastic_fraction": h["plastic_area"][-1] / plate,
            "first_yield_load_Pa": r.first_yield_load,
            "final_displacement_m": h["displacement"][-1],
            "final_plastic_area_m2": h["plastic_area"][-1],
            "final_plastic_extent_m": h["plastic_extent"][-1],
            "max_coarse_yield_ratio": r.max_coarse_yield_ratio,
            "max_displacement_deviation_from_mono": _displacement_deviation(r, mono),
            "newton_iterations": int(sum(h["newton_iterations"])),
        }
    out["adaptive"].update(_adapt_figures(results["adaptive"].adaptations, best["adaptive"]))
    _with_memory(out, runs, memory)
    a, m = out["adaptive"], out["mono"]
    out["criterion_4"] = {
        "max_displacement_deviation_from_mono": a["max_displacement_deviation_from_mono"],
        # the test's measure: the plastic zone (ε̄p > 0 at quadrature points) and the final
        # patch's gluing band; and the coarse cells over a plastic fine cell plus one ring
        "patch_over_plastic_zone_and_band": a["patch_fraction"]
        / (a["plastic_fraction"] + a["band_fraction"]),
        "fixed_patch_over_plastic_zone_and_band": out["fixed"]["patch_fraction"]
        / (out["fixed"]["plastic_fraction"] + out["fixed"]["band_fraction"]),
        "patch_over_plastic_cover": a["patch_fraction"] / a["plastic_cover_fraction"],
        "fixed_patch_over_plastic_cover": out["fixed"]["patch_fraction"]
        / out["fixed"]["plastic_cover_fraction"],
        "T_mono_over_T_adaptive": m["wall_time_s"] / a["wall_time_s"],
        "T_mono_over_T_fixed": m["wall_time_s"] / out["fixed"]["wall_time_s"],
        "max_coarse_yield_ratio": a["max_coarse_yield_ratio"],
        "targets": {
            "max_displacement_deviation_from_mono": "<= 0.005",
            "patch_over_plastic_zone_and_band": "<= 1.5",
            "T_mono_over_T_adaptive": ">= 8",
        },
    }
    return out


#: The ball impact's configurations (``--size``): the keywords of ``run_ball_impact`` (SI).
BALL_SIZES = {
    "full": {"regime": "plastic", "block_radius": 0.02, "block_height": 0.02,
             "coarse_size": 0.25 * math.pi * 0.01 / 20},
    # coarser: the seed widened to 0.45 R and 3 m/s, so that the contact stays on the contact
    # surfaces (patch_size − 3 coarse cells)
    "quick": {"regime": "plastic", "block_radius": 0.02, "block_height": 0.02,
              "coarse_size": 0.25 * math.pi * 0.01 / 8, "velocity": 3.0, "patch_size": 0.0045},
}  # fmt: skip

#: The measures of criterion 5, compared with mono's.
BALL_MEASURES = ("dent_depth", "peak_force", "restitution")


def ball_case(repeat: int, memory: bool, size: str = "full") -> dict:
    """The ball impact, plastic regime, adaptive / fixed patch / mono (criterion 5)."""
    from arlequin.demos.ball_impact import run_ball_impact

    kw = BALL_SIZES[size]
    runs = {
        "adaptive": lambda: run_ball_impact(adaptive=True, **kw),
        "fixed": lambda: run_ball_impact(**kw),
        "mono": lambda: run_ball_impact(model="mono", **kw),
    }
    results, best = _timed(runs, repeat)
    out: dict = {"size": size, "config": dict(kw)}
    for name, r in results.items():
        out[name] = {
            "wall_time_s": best[name],
            "n_elements": r.n_elements,
            "n_steps": r.n_steps,
            # the patches' elements over those of mono's meshes (mono: 1)
            "patch_fraction": r.patch_fraction,
            **{k: getattr(r, k) for k in BALL_MEASURES},
            "contact_duration_s": r.contact_duration,
            "max_plastic_strain": r.max_plastic_strain,
            "band_max_plastic_strain": r.band_max_plastic_strain,
            "energy_balance_error": r.energy_balance_error,
        }
    a = results["adaptive"]
    out["adaptive"].update(_adapt_figures(a.adaptations, best["adaptive"]))
    out["adaptive"]["block_patch_fraction"] = (a.adaptations[-1]["patch_fraction"]
                                               if a.adaptations else None)  # fmt: skip
    out["adaptive"]["max_coarse_yield_ratio"] = a.max_coarse_yield_ratio
    _with_memory(out, runs, memory)
    m, f = out["mono"], out["fixed"]
    t_mono_over_fixed = m["wall_time_s"] / f["wall_time_s"]
    out["criterion_5"] = {
        **{f"{k}_deviation": out["adaptive"][k] / m[k] - 1.0 for k in BALL_MEASURES},
        **{f"fixed_{k}_deviation": f[k] / m[k] - 1.0 for k in BALL_MEASURES},
        "T_mono_over_T_adaptive": m["wall_time_s"] / out["adaptive"]["wall_time_s"],
        "T_mono_over_T_fixed": t_mono_over_fixed,
        "bound_0.8_T_mono_over_T_fixed": 0.8 * t_mono_over_fixed,
        "T_fixed_over_T_adaptive": f["wall_time_s"] / out["adaptive"]["wall_time_s"],
        "targets": {
            "deviations": "|.| <= 0.02",
            "T_mono_over_T_adaptive": ">= 0.8 T_mono_over_T_fixed",
        },
    }
    return out


#: The cases, by ``--case`` name.
CASES: dict[str, Callable[..., dict]] = {
    "sphere": sphere_case,
    "plate": plate_case,
    "ball": ball_case,
}


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", choices=(*CASES, "all"), default="all")
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--no-memory", action="store_true", help="skip the tracemalloc runs")
    parser.add_argument("--size", choices=tuple(BALL_SIZES), default="full",
                        help="the ball impact's configuration (quick: coarser, to check the "
                        "benchmark)")  # fmt: skip
    args = parser.parse_args(argv)
    names = list(CASES) if args.case == "all" else [args.case]
    out: dict = {"repeat": args.repeat, "threads": _threads.settings(), "cases": {}}
    with warnings.catch_warnings():  # the JSON gives the coarse-yield figures
        warnings.simplefilter("ignore")
        for name in names:
            case = CASES[name]
            if name == "ball":
                case = functools.partial(case, size=args.size)
            out["cases"][name] = case(args.repeat, not args.no_memory)
    print(json.dumps(out, indent=2, default=float))
    return out


if __name__ == "__main__":
    main()
