"""The Arlequin Taylor bar against its choices: patch length, band width, weights, mediator,
coupling, each varied alone from the defaults, at one resolution, against the uniform mesh.

Prints JSON: per case the final length, footprint radius, maximum ε̄p (and their differences to
the uniform single mesh at the patch's resolution, run first in the same process), the energy
balance error, the largest ε̄p in the gluing band, the multipliers' step-to-step chatter and the
wall time. The table of docs/arlequin_taylor.md comes from

    python benchmarks/taylor_sensitivity.py --elements-radial 10
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings

CASES: list[tuple[str, dict]] = [
    ("defaults (patch 0.9 L, band 2 rows, ramp, fine mediator, H1)", {}),
    ("patch 0.5 L", {"patch_length": 0.5}),
    ("patch 0.7 L", {"patch_length": 0.7}),
    ("patch 0.8 L", {"patch_length": 0.8}),
    ("patch 0.95 L", {"patch_length": 0.95}),
    ("band 1 row", {"gluing_rows": 1}),
    ("band 4 rows", {"gluing_rows": 4}),
    ("constant weights", {"weights": "constant"}),
    ("coarse mediator", {"mediator": "coarse"}),
    ("L2 coupling", {"coupling": "L2"}),
    ("coarse mediator, L2", {"mediator": "coarse", "coupling": "L2"}),
]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--elements-radial", type=int, default=10)
    parser.add_argument("--cases", type=int, nargs="*", default=None,
                        help="indices of CASES to run (default all)")  # fmt: skip
    args = parser.parse_args(argv)
    from arlequin.demos.taylor_bar import GluingBandPlasticityWarning, run_taylor_bar
    from arlequin.demos.taylor_bar.meshes import arlequin_bar_sizes
    from arlequin.models.plasticity.j2_kernel import warm_up

    warm_up()
    n = args.elements_radial
    length = 32.4e-3
    uni = run_taylor_bar(model="mono", elements_radial=n)
    rows = []
    chosen = CASES if args.cases is None else [CASES[i] for i in args.cases]
    hz = arlequin_bar_sizes(length, 3.2e-3, n).axial_size
    for label, case in chosen:
        kw = dict(case)
        if "patch_length" in kw:
            kw["patch_length"] *= length
        if "gluing_rows" in kw:
            kw["gluing_width"] = kw.pop("gluing_rows") * hz
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", GluingBandPlasticityWarning)
            r = run_taylor_bar(model="arlequin", elements_radial=n, **kw)
        a = r.arlequin
        rows.append({
            "case": label,
            "patch_length_mm": round(a["patch_length"] * 1e3, 3),
            "gluing_width_mm": round(a["gluing_width"] * 1e3, 3),
            "patch_fraction": round(a["patch_fraction"], 3),
            "final_length_mm": round(r.final_length * 1e3, 4),
            "mushroom_radius_mm": round(r.mushroom_radius * 1e3, 4),
            "max_plastic_strain": round(r.max_plastic_strain, 4),
            "length_difference": round(r.final_length / uni.final_length - 1, 5),
            "radius_difference": round(r.mushroom_radius / uni.mushroom_radius - 1, 5),
            "max_plastic_strain_difference": round(
                r.max_plastic_strain / uni.max_plastic_strain - 1, 5),
            "energy_balance_error": float(f"{r.energy_balance_error:.3g}"),
            "band_max_plastic_strain": round(a["band_max_plastic_strain"], 4),
            "band_warning": bool(caught),
            "multiplier_chatter_per_row": round(a["multiplier_chatter_per_row"], 4),
            "wall_time_s": round(r.wall_time_s, 1),
        })  # fmt: skip
        print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    uniform = {"final_length_mm": round(uni.final_length * 1e3, 4),
               "mushroom_radius_mm": round(uni.mushroom_radius * 1e3, 4),
               "max_plastic_strain": round(uni.max_plastic_strain, 4),
               "wall_time_s": round(uni.wall_time_s, 1)}  # fmt: skip
    print(json.dumps({"benchmark": "taylor_sensitivity", "elements_radial": n,
                      "uniform": uniform, "cases": rows}, indent=2))  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
