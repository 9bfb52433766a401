"""Quasi-static elastoplastic runs: wall times, Newton iterations and where an iteration's time
goes, the saving from condensing the linear blocks once, the tangent assembly rate, and the
sparse direct solvers of the Newton systems compared.

Cases (``--case``), in one process (shortest of ``--repeat`` rounds):

* ``sphere-2d`` (default): the pressure sphere at 300 MPa in 10 steps, 2D axisymmetric at the
  demo's defaults: ``arlequin``, ``arlequin`` with ``condense=False`` and ``mono`` with SuperLU,
  and ``arlequin`` and ``mono`` with each other linear solver of ``--linear-solvers``;
* ``sphere-3d``: the eighth of the sphere on hexahedra, model ``arlequin`` (the coarse shell
  and a J2 patch to 183 mm; ``--dim3-coarse`` and ``--dim3-fine`` sizes), loaded to
  ``--pressure-3d`` in ``--steps-3d`` steps (the last two plastic at the defaults), with each
  solver of ``--linear-solvers``;
* ``all``: both.

Each run's time is split by the quasi-static solver's own timers
(:attr:`arlequin.QuasiStaticResult.timings`, summed over the solvers the demo builds: the
first-yield probe and the run):

* ``constitutive_and_tangent_s``: the models' internal forces, return maps and tangent
  assembly;
* ``factorisation_s`` and ``solve_s``: the Newton systems' factorisations and solves
  (:mod:`arlequin.linalg.direct`: SuperLU, or PARDISO keeping its symbolic analysis);
* ``other_s``: the rest of the load steps (residuals, line search, the condensation's
  products);
* ``setup_s``: the wall time outside the load steps (meshes, couplings, the operators'
  assembly, the demo's measures).

``linear_solve_share`` is (factorisation + solve) over the load steps' time. The tangent
assembly rate is the quadrature points per second of ``SmallStrainJ2.tangent`` in a plastic
state (2D and 3D), and also that of each run (its quadrature points times its tangent
evaluations over ``constitutive_and_tangent_s``: internal forces included). Peak memory: the
largest resident set sampled during each run (every 50 ms) and the process's peak.

``--limit-load`` adds ``cylinder_limit_load``: the plane-strain ``mono`` cylinder of item 4
pressed to 240 MPa in 12 steps (it stops at its limit load, 192.09 MPa) and driven by the
bore's displacement to 1 mm, under :func:`_newton.newton_record`: per converged step item 5's
contraction constants C = r_k+1 / r_k² (below r_k = 1e-3) with the number of quadrature points
that crossed the yield surface in each iteration, and the smallest eigenvalue of the converged
tangent over the elastic one (C grows as it falls toward the limit point). Several minutes.

    PYTHONPATH=. python benchmarks/quasi_static.py [--case {sphere-2d,sphere-3d,all}]
        [--repeat 2] [--linear-solvers superlu,pardiso] [--dim3-fine 0.0045] [--limit-load]

Prints JSON.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import resource
import threading
import time

import _threads  # before numba runs
import numpy as np


class _PeakRSS:
    """The largest resident set size (MB) of this process while the block runs, sampled."""

    def __init__(self, every: float = 0.05) -> None:
        self.every, self.peak_mb = every, 0.0
        self._stop = threading.Event()

    @staticmethod
    def _rss_mb() -> float:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20

    def _watch(self) -> None:
        while not self._stop.wait(self.every):
            self.peak_mb = max(self.peak_mb, self._rss_mb())

    def __enter__(self):
        self.peak_mb = self._rss_mb()
        self._thread = threading.Thread(target=self._watch, daemon=True)
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join()
        self.peak_mb = max(self.peak_mb, self._rss_mb())


def sphere(model: str, dim: int = 2, condense: bool = True, linear_solver: str = "superlu",
           **config) -> dict:  # fmt: skip
    """One sphere run, timed; its accuracy against Hill at the final pressure."""
    import arlequin.solvers.statics.quasi_static as qs_module
    from arlequin.demos.pressure_vessel import PressureVesselConfig
    from arlequin.demos.pressure_vessel.run import run

    real = qs_module.QuasiStaticSolver.__init__
    solvers = []

    def init(self, *args, **kwargs):
        kwargs.setdefault("condense", condense)
        kwargs.setdefault("linear_solver", linear_solver)
        real(self, *args, **kwargs)
        solvers.append(self)

    qs_module.QuasiStaticSolver.__init__ = init
    try:
        with _PeakRSS() as memory:
            t0 = time.perf_counter()
            r = run(PressureVesselConfig(model=model, dim=dim, **config))
            wall = time.perf_counter() - t0
    finally:
        qs_module.QuasiStaticSolver.__init__ = real
    h = r.history
    split = {k: sum(s.timings[k] for s in solvers) for k in solvers[-1].timings}
    steps_s = sum(split.values())
    split["setup_s"] = wall - steps_s
    main = solvers[-1]
    n_qp = sum(int(np.asarray(state[0].eqps).size) for state in main.states.values()
               if state and hasattr(state[0], "eqps"))  # fmt: skip
    tangents = sum(s.iterations + 1 for s in main.history)  # one tangent an iteration + 1
    ref = r.reference
    name = f"sphere-{dim}d-{model}" + ("" if condense else "-full") + f"-{linear_solver}"
    return {
        "case": name,
        "linear_solver": main.saddle.direct.name,
        "wall_time_s": round(wall, 3),
        "n_elements": r.n_elements,
        "n_dofs": r.n_dofs,
        "n_multipliers": int(main.saddle.n_multipliers),
        "condensed": bool(main.saddle.condensed),
        "patch_fraction": round(r.patch_fraction, 4),
        "load_steps": len(h["newton_iterations"]) - 1,
        "newton_iterations": sum(h["newton_iterations"]),
        "newton_iterations_per_step": h["newton_iterations"][1:],
        "factorisations": sum(s.saddle.direct.factorisations for s in solvers),
        "symbolic_analyses": sum(s.saddle.direct.analyses for s in solvers),
        "split_s": {k: round(v, 3) for k, v in split.items()},
        "linear_solve_share": round(
            (split["factorisation_s"] + split["solve_s"]) / max(steps_s, 1e-300), 3
        ),
        "tangent_rate_in_run_qp_per_s": round(
            n_qp * tangents / max(split["constitutive_and_tangent_s"], 1e-300)
        ),
        "outer_displacement_error": h["outer_displacement"][-1] / ref["outer_displacement"] - 1,
        "plastic_radius_error": h["plastic_radius"][-1] / ref["plastic_radius"] - 1,
        "first_yield_error": r.first_yield_pressure / ref["first_yield_pressure"] - 1,
        "peak_rss_mb": round(memory.peak_mb, 1),
        "process_peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
    }


def tangent_rate(dim: int) -> dict:
    """Quadrature points per second of SmallStrainJ2.tangent in a plastic state."""
    import numpy as np
    import skfem

    from arlequin.models import J2Material, SmallStrainJ2

    n = 100 if dim == 2 else 24
    axes = [np.linspace(0.0, 1.0, n + 1)] * dim
    mesh = (skfem.MeshQuad if dim == 2 else skfem.MeshHex).init_tensor(*axes)
    model = SmallStrainJ2(mesh, J2Material(210e9, 0.3, 7850.0, 1e6), "plane_strain" if dim == 2
                          else "3d", bbar=True)  # fmt: skip
    u = 1e-3 * mesh.p.T.ravel() * np.tile([1.0, -0.3, 0.2][:dim], mesh.nvertices)
    state = model.internal_force(u, None)[1]
    best = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        model.tangent(u, state)
        best = min(best, time.perf_counter() - t0)
    n_qp = int(np.asarray(state.eqps).size)
    return {"dim": dim, "quadrature_points": n_qp, "seconds": round(best, 4),
            "points_per_second": round(n_qp / best)}  # fmt: skip


def cylinder_limit_load() -> dict:
    """The mono cylinder pressed past its limit load and driven by the bore's displacement:
    Newton's contraction constants and the tangent's smallest eigenvalue per step."""
    from _newton import contraction_summary, newton_record

    from arlequin.demos.pressure_vessel import run_pressure_vessel

    drives = {"pressure": ({"pressure": 2.4e8, "steps": 12}, 2.4e8, "Pa"),
              "bore_displacement": ({"inner_displacement": 1e-3}, 1e-3, "m")}  # fmt: skip
    out = {}
    for drive, (options, scale, unit) in drives.items():
        with newton_record(eigenvalues=True) as records:
            r = run_pressure_vessel(shape="cylinder", model="mono", **options)
        summary = contraction_summary(records)
        summary["load_at_factor_1"], summary["load_unit"] = scale, unit
        summary["limit_load_Pa"] = r.limit_load if r.limit_load_reached else None
        out[drive] = summary
    return out


def _cases(args) -> list[tuple]:
    """(model, dim, condense, linear solver, config) of each run."""
    solvers = [name.strip() for name in args.linear_solvers.split(",") if name.strip()]
    cases = []
    if args.case in ("sphere-2d", "all"):
        cases += [("arlequin", 2, True, "superlu", {}), ("arlequin", 2, False, "superlu", {}),
                  ("mono", 2, True, "superlu", {})]  # fmt: skip
        cases += [(model, 2, True, name, {}) for name in solvers if name != "superlu"
                  for model in ("arlequin", "mono")]  # fmt: skip
    if args.case in ("sphere-3d", "all"):
        config = {"coarse_size": args.dim3_coarse, "fine_size": args.dim3_fine,
                  "pressure": args.pressure_3d, "steps": args.steps_3d}  # fmt: skip
        cases += [("arlequin", 3, True, name, config) for name in solvers]
    return cases


def main() -> None:
    from arlequin.linalg.direct import pardiso_available

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--case", choices=("sphere-2d", "sphere-3d", "all"), default="sphere-2d")
    parser.add_argument("--repeat", type=int, default=1, help="rounds; each case's shortest")
    parser.add_argument("--linear-solvers", default="superlu,pardiso" if pardiso_available()
                        else "superlu", help="comma-separated: superlu, pardiso")  # fmt: skip
    # 6 shells of 6 x 6 x 3 cells, the patch 5 shells refined twice: 118k dofs
    parser.add_argument("--dim3-coarse", type=float, default=0.018, help="3D coarse size (m)")
    parser.add_argument("--dim3-fine", type=float, default=0.0045, help="3D fine size (m)")
    parser.add_argument("--pressure-3d", type=float, default=3e8, help="3D final pressure (Pa)")
    parser.add_argument("--steps-3d", type=int, default=3, help="3D load steps")
    parser.add_argument(
        "--limit-load",
        action="store_true",
        help="also Newton's contraction near the cylinder's limit load",
    )
    args = parser.parse_args()
    best: dict[str, dict] = {}
    for _ in range(args.repeat):
        for model, dim, condense, solver, config in _cases(args):
            rec = sphere(model, dim, condense, solver, **config)
            logging.getLogger("benchmark").info("%s", json.dumps(rec))
            if rec["case"] not in best or rec["wall_time_s"] < best[rec["case"]]["wall_time_s"]:
                best[rec["case"]] = rec
    out = {"settings": _threads.settings(), "args": vars(args), "cases": list(best.values()),
           "tangent_assembly": [tangent_rate(2), tangent_rate(3)]}  # fmt: skip
    out["mkl_threads"] = os.environ.get("MKL_NUM_THREADS")
    for dim in (2, 3):
        a, f, m = (best.get(f"sphere-{dim}d-{k}-superlu") for k in ("arlequin", "arlequin-full",
                                                                      "mono"))  # fmt: skip
        if a and f:
            out[f"condensation_saving_{dim}d"] = round(f["wall_time_s"] / a["wall_time_s"], 3)
        if a and m:
            out[f"T_mono_over_T_arlequin_{dim}d"] = round(m["wall_time_s"] / a["wall_time_s"], 3)
        p = best.get(f"sphere-{dim}d-arlequin-pardiso")
        if a and p:
            out[f"T_superlu_over_T_pardiso_{dim}d"] = round(a["wall_time_s"] / p["wall_time_s"], 3)
            fa, fp = (c["split_s"]["factorisation_s"] / c["factorisations"] for c in (a, p))
            out[f"factorisation_superlu_over_pardiso_{dim}d"] = round(fa / fp, 3)
    if args.limit_load:
        out["cylinder_limit_load"] = cylinder_limit_load()
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    logging.basicConfig(level=logging.WARNING, format="%(message)s")
    logging.getLogger("benchmark").setLevel(logging.INFO)  # each run as it ends, on stderr
    main()
