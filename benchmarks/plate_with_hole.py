"""Benchmark: the plate with a hole (``arlequin plate-with-hole``), its three models in one
process (issue 29, item 6).

Runs ``mono`` (the whole coarse mesh refined, J2 everywhere), ``arlequin`` (coarse elastic plate
+ J2 patch) and ``graded`` (one conforming mesh, J2 on the patch's cells) at the same
configuration, ``--repeat`` rounds each (the shortest wall time kept), and prints JSON: wall
times, Newton iterations, cells and dofs, T_mono / T_arlequin (target ≥ 10), T_arlequin /
T_graded (target ≤ 1.5), each run's split of its time (constitutive update, tangent assembly,
factorisation and the solves of the Newton systems, the rest), the largest Newton contraction
r_k+1 / r_k² below 1e-3, the accuracy against mono, and each model's peak traced memory (one
more run under :mod:`tracemalloc`).

``newton``: one more run of each model under :func:`_newton.newton_record`, item 5's
contraction constants C = r_k+1 / r_k² (below r_k = 1e-3) split into the iterations where the
plastic set stayed fixed and those where quadrature points crossed the yield surface, with
each step's C and crossings; ``newton_by_hardening``: the same split for the Arlequin run
with a linear hardening modulus H of 0, E/1000, E/100 and E/10 (perfect plasticity is not
what makes C large). ``--no-newton`` skips them.

The coarse elastic plate has fewer free dofs than a quarter of the patch's, so the quasi-static
solver does not condense it (:data:`arlequin.solvers.statics.condensation.MIN_LINEAR_SHARE`): the
Arlequin run is also timed with the condensation forced (that share set to 0),
``arlequin_condensed``, to show what condensing would give.

    python benchmarks/plate_with_hole.py [--levels 3] [--steps 10] [--repeat 1] [--no-newton]
"""

from __future__ import annotations

import argparse
import itertools
import json
import time
import tracemalloc
from contextlib import contextmanager

import _threads  # before numba runs: OpenMP threads sleep between parallel regions
import numpy as np
from _newton import contraction_summary, newton_record

from arlequin.demos.plate_with_hole import run_plate_with_hole
from arlequin.linalg import direct
from arlequin.models import SmallStrainJ2
from arlequin.solvers.statics import condensation

MODELS = ("mono", "arlequin", "graded")


@contextmanager
def condensation_forced():
    """The linear blocks condensed whatever their share of the dofs (restored after)."""
    saved = condensation.MIN_LINEAR_SHARE
    condensation.MIN_LINEAR_SHARE = 0.0
    try:
        yield
    finally:
        condensation.MIN_LINEAR_SHARE = saved


def timed_run(model: str, levels: int, steps: int, repeat: int):
    """The shortest of ``repeat`` runs: its result, wall time (s) and split."""
    best, split, result = None, None, None
    for _ in range(repeat):
        with timed_split() as s:
            t = time.perf_counter()
            r = run_plate_with_hole(model=model, levels=levels, steps=steps)
            wall = time.perf_counter() - t
        if best is None or wall < best:
            best, split, result = wall, dict(s), r
    split["rest"] = best - sum(split.values())
    return result, best, split


@contextmanager
def timed_split():
    """Wall time spent in the J2 return and force, its tangent's assembly, the Newton systems'
    factorisations and solves (:class:`arlequin.linalg.direct.SparseDirectSolver`, whichever
    backend), by wrapping those functions (restored after)."""
    split = {"constitutive_update": 0.0, "tangent_assembly": 0.0, "factorisation": 0.0,
             "solves": 0.0}  # fmt: skip
    originals = [(SmallStrainJ2, "internal_force"), (SmallStrainJ2, "tangent"),
                 (direct.SparseDirectSolver, "factor"),
                 (direct.SparseDirectSolver, "_solve")]  # fmt: skip
    saved = [getattr(owner, name) for owner, name in originals]

    def wrap(fn, key):
        def inner(*args, **kwargs):
            t = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                split[key] += time.perf_counter() - t

        return inner

    SmallStrainJ2.internal_force = wrap(saved[0], "constitutive_update")
    SmallStrainJ2.tangent = wrap(saved[1], "tangent_assembly")
    direct.SparseDirectSolver.factor = wrap(saved[2], "factorisation")
    direct.SparseDirectSolver._solve = wrap(saved[3], "solves")
    try:
        yield split
    finally:
        for (owner, name), fn in zip(originals, saved):
            setattr(owner, name, fn)


def max_contraction(residuals) -> float:
    """The largest r_k+1 / r_k² over the Newton iterations with r_k < 1e-3 and r_k+1 > 1e-10
    (issue 29, item 5: at most 10)."""
    worst = 0.0
    for res in residuals:
        for r0, r1 in itertools.pairwise(res):
            if r0 < 1e-3 and r1 > 1e-10:
                worst = max(worst, r1 / r0**2)
    return worst


def newton_diagnostics(levels: int, steps: int) -> dict:
    """Item 5's contraction constants of each model, split by plastic-set changes, and of the
    Arlequin run against the hardening modulus."""
    out: dict = {"models": {}, "hardening": {}}
    for model in MODELS:
        with newton_record() as records:
            run_plate_with_hole(model=model, levels=levels, steps=steps)
        out["models"][model] = contraction_summary(records)
    young = 210e9  # the demo's default E (Pa)
    for fraction in (0.0, 1e-3, 1e-2, 1e-1):
        with newton_record() as records:
            run_plate_with_hole(model="arlequin", levels=levels, steps=steps,
                                hardening=fraction * young)  # fmt: skip
        summary = contraction_summary(records)
        summary.pop("steps")
        out["hardening"][f"H={fraction:g}E"] = summary
    return out


def bench(levels: int, steps: int, repeat: int, memory: bool, newton: bool = True) -> dict:
    out: dict = {"levels": levels, "steps": steps, "repeat": repeat, "models": {}}
    out["threads"] = _threads.settings()
    results = {}
    for model in MODELS:
        r, best, split = timed_run(model, levels, steps, repeat)
        results[model] = r
        its = r.history["newton_iterations"][2:]
        out["models"][model] = {
            "wall_time_s": best,
            "split_s": split,
            "newton_iterations": int(sum(its)),
            "newton_max_per_step": int(max(its)),
            "newton_max_contraction": max_contraction(r.history["residuals"]),
            "n_elements": r.n_elements,
            "n_dofs": r.n_dofs,
            "patch_fraction": r.patch_fraction,
            "first_yield_load_Pa": r.first_yield_load,
            "final_displacement_m": r.history["displacement"][-1],
            "final_plastic_area_m2": r.history["plastic_area"][-1],
            "final_plastic_extent_m": r.history["plastic_extent"][-1],
        }
        if memory:
            tracemalloc.start()
            run_plate_with_hole(model=model, levels=levels, steps=steps)
            out["models"][model]["peak_traced_memory_MB"] = tracemalloc.get_traced_memory()[1] / 1e6
            tracemalloc.stop()
    with condensation_forced():
        r, best, split = timed_run("arlequin", levels, steps, repeat)
    out["models"]["arlequin_condensed"] = {
        "wall_time_s": best,
        "split_s": split,
        "newton_iterations": int(sum(r.history["newton_iterations"][2:])),
    }
    ref = results["mono"].history
    for model in ("arlequin", "graded"):
        h = results[model].history
        d = np.array(h["displacement"][1:]) / np.array(ref["displacement"][1:]) - 1.0
        out["models"][model]["max_displacement_deviation_from_mono"] = float(np.abs(d).max())
        out["models"][model]["plastic_area_deviation_from_mono"] = float(
            h["plastic_area"][-1] / ref["plastic_area"][-1] - 1.0
        )
    t = {m: out["models"][m]["wall_time_s"] for m in MODELS}
    out["T_mono_over_T_arlequin"] = t["mono"] / t["arlequin"]
    out["T_arlequin_over_T_graded"] = t["arlequin"] / t["graded"]
    out["T_arlequin_condensed_over_T_arlequin"] = (
        out["models"]["arlequin_condensed"]["wall_time_s"] / t["arlequin"]
    )
    out["targets"] = {"T_mono_over_T_arlequin": ">= 10", "T_arlequin_over_T_graded": "<= 1.5"}
    if newton:
        diagnostics = newton_diagnostics(levels, steps)
        out["newton"] = diagnostics["models"]
        out["newton_by_hardening"] = diagnostics["hardening"]
    return out


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--levels", type=int, default=3)
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--no-memory", action="store_true", help="skip the tracemalloc runs")
    parser.add_argument(
        "--no-newton",
        action="store_true",
        help="skip the Newton diagnostics (item 5's C by plastic-set changes)",
    )
    args = parser.parse_args(argv)
    out = bench(args.levels, args.steps, args.repeat, not args.no_memory, not args.no_newton)
    print(json.dumps(out, indent=2))
    return out


if __name__ == "__main__":
    main()
