"""Patch-test error of an interior square patch against the mesh ratio and the band width.

The square layout of :func:`arlequin.demos.patch_test.run_patch_test` (coarse quadrilaterals of
0.25 m, a nested square patch of 2b + 2 coarse cells glued all around in a band of b coarse
cells) with the default options (ramp weights, H1 coupling, coarse mediator), and the same with
the fine mediator (condition A). Prints JSON: for each (ratio, band), max_error, exact_residual,
whether an ExactnessWarning was raised, fine dofs and wall time.

    python benchmarks/patch_test_square.py [--ratios 2 5 10 20 50] [--bands 1 2 3 4]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings

from arlequin.coupling.gluing import ExactnessWarning
from arlequin.demos.patch_test import run_patch_test


def case(ratio: int, band: int, mediator: str) -> dict:
    tic = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = run_patch_test(layout="square", ratio=ratio, band_cells=band, mediator=mediator)
    return {
        "ratio": ratio,
        "band_cells": band,
        "mediator": mediator,
        "max_error": r.max_error,
        "exact_residual": r.exact_residual,
        "warned": any(issubclass(w.category, ExactnessWarning) for w in caught),
        "n_fine_dofs": r.n_fine_dofs,
        "wall_time_s": time.perf_counter() - tic,
    }


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--ratios", type=int, nargs="+", default=[2, 5, 10, 20, 50])
    p.add_argument("--bands", type=int, nargs="+", default=[1, 2, 3, 4])
    p.add_argument("--mediators", nargs="+", default=["coarse", "fine"])
    args = p.parse_args(argv)
    rows = []
    for mediator in args.mediators:
        for ratio in args.ratios:
            for band in args.bands:
                rows.append(case(ratio, band, mediator))
                print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    json.dump({"cases": rows}, sys.stdout, indent=1)
    print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
