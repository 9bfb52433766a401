"""The static solve's linear algebra at growing size: SuperLU against GMRES + augmented-Lagrangian
smoothed-aggregation multigrid (``solve_static(..., linear_solver="amg")``, issue 43).

3D linear elasticity on the quarter plate with a hole of ``tests/data/plate3d_fine.vtu``
(tetrahedra, 50 mm × 50 mm × 5 mm, hole radius 10 mm), refined ``--levels`` times by
``read_mesh(...).refined(k)``, clamped at x = 0 and pulled by 100 MPa at x = W = 0.05 m; with
``--cases coarse`` the coarse plate (``plate3d_coarse.vtu``) with the ring patch
(``plate3d_ring.vtu``, non-nested) refined the same number of times (level 2 fails: the refined
ring's facets of the hole leave the coarse plate's), ``--cases fine`` the fine plate with the
ring refined once more than it (mesh ratio 2, the ring's facets on the plate's).

Each (case, level, solver) runs in a fresh process so that its peak resident memory
(``resource.getrusage``) is its own. Prints one JSON document: per case and level the dofs,
the assembly time (the saddle point with Dirichlet elimination), the multigrid set-up, Krylov
time and iterations, the SuperLU time (below ``--superlu-max-dofs``), peak RSS of each run,
the relative difference of the two solutions, and per case the exponents of time against dofs
fitted over the levels (least squares in log-log).

    python benchmarks/scaling.py --levels 0 1 2
    python benchmarks/scaling.py --cases coarse fine --levels 0 1
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parent.parent / "tests" / "data"
W = 0.05


def _problem(case: str, level: int):
    from arlequin import ArlequinProblem, Patch
    from arlequin.io import read_mesh
    from arlequin.models import IsotropicElastic, LinearElastic

    material = IsotropicElastic(young=200e9, poisson=0.3, density=7800.0)
    if case == "mono":
        coarse = LinearElastic(read_mesh(DATA / "plate3d_fine.vtu").refined(level), material, "3d")
        problem = ArlequinProblem(coarse, [])
    else:  # "coarse": the coarse plate and the ring; "fine": the fine plate, the ring refined
        coarse_mesh = read_mesh(DATA / f"plate3d_{case}.vtu").refined(level)
        fine_mesh = read_mesh(DATA / "plate3d_ring.vtu").refined(level + (case == "fine"))
        coarse = LinearElastic(coarse_mesh, material, "3d")
        patch = Patch(LinearElastic(fine_mesh, material, "3d"), gluing_width=6e-3)
        problem = ArlequinProblem(coarse, [patch])
    tol = 1e-9
    problem.add_dirichlet("coarse", lambda x: x[0] < tol)
    problem.add_traction(np.array([100e6, 0.0, 0.0]), where=lambda x: x[0] > W - tol)
    return problem


def run_one(case: str, level: int, solver: str, out: str) -> None:
    """One solve in this process; writes its figures and solution to ``out`` (.npz)."""
    from arlequin.solvers.statics import static

    t0 = time.perf_counter()
    system = _problem(case, level).system()
    sp_sys = static.assemble_saddle_point(system)
    t1 = time.perf_counter()
    rec = {"dofs": int(system.n_dofs), "unknowns": int(sp_sys.matrix.shape[0]),
           "assembly_s": t1 - t0}  # fmt: skip
    if solver == "amg":
        x, info = static._solve_amg(system, sp_sys, {"rtol": 1e-10})
        rec.update(
            setup_s=info.setup_seconds,
            krylov_s=info.krylov_seconds,
            iterations=info.iterations,
            residual=info.residual,
            levels=info.levels,
        )
        rec["solve_s"] = info.setup_seconds + info.krylov_seconds
    else:
        x = static._solve_saddle(sp_sys.matrix, sp_sys.rhs)
        rec["solve_s"] = time.perf_counter() - t1
    rec["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    u = sp_sys.full_displacement(x[: sp_sys.n_free])
    np.savez(out, u=u, rec=json.dumps(rec))


def _spawn(case: str, level: int, solver: str, tmp: Path) -> tuple[dict, np.ndarray]:
    out = tmp / f"{case}_{level}_{solver}.npz"
    subprocess.run([sys.executable, __file__, "--one", case, str(level), solver, str(out)],
                   check=True)  # fmt: skip
    data = np.load(out)
    return json.loads(str(data["rec"])), data["u"]


def _exponent(n, t) -> float | None:
    if len(n) < 2:
        return None
    return float(np.polyfit(np.log(n), np.log(t), 1)[0])


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--levels", type=int, nargs="+", default=[0, 1])
    ap.add_argument("--superlu-max-dofs", type=int, default=200_000)
    ap.add_argument(
        "--cases",
        nargs="+",
        default=["mono"],
        choices=["mono", "coarse", "fine"],
        help="mono: the single fine plate; arlequin: the coarse plate + ring patch",
    )
    ap.add_argument("--one", nargs=4, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one:
        case, level, solver, out = args.one
        run_one(case, int(level), solver, out)
        return {}
    report: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        for case in args.cases:
            rows = []
            for level in args.levels:
                amg, u_amg = _spawn(case, level, "amg", Path(tmp))
                row = {"level": level, "dofs": amg["dofs"], "unknowns": amg["unknowns"],
                       "amg": amg}  # fmt: skip
                if amg["dofs"] <= args.superlu_max_dofs:
                    lu, u_lu = _spawn(case, level, "superlu", Path(tmp))
                    row["superlu"] = lu
                    row["relative_difference"] = float(
                        np.linalg.norm(u_amg - u_lu) / np.linalg.norm(u_lu)
                    )
                    row["superlu_over_amg"] = lu["solve_s"] / amg["solve_s"]
                rows.append(row)
            n = [r["dofs"] for r in rows]
            fit = {"amg_solve": _exponent(n, [r["amg"]["solve_s"] for r in rows]),
                   "assembly": _exponent(n, [r["amg"]["assembly_s"] for r in rows])}  # fmt: skip
            with_lu = [r for r in rows if "superlu" in r]
            fit["superlu_solve"] = _exponent(
                [r["dofs"] for r in with_lu], [r["superlu"]["solve_s"] for r in with_lu]
            )
            report[case] = {"levels": rows, "time_exponent": fit}
    print(json.dumps(report, indent=1))
    return report


if __name__ == "__main__":
    main()
