"""Quasi-static elastoplastic runs: wall times, Newton iterations and where an iteration's time
goes, the saving from condensing the linear blocks once, the tangent assembly rate.

For each case, in one process (shortest of ``--repeat`` rounds): the pressure sphere at 300 MPa
in 10 steps (``arlequin`` and ``mono``, 2D axisymmetric at the demo's defaults; the 3D eighth
on hexahedra with ``--dim3``), each run timed with its Newton iterations split into:

* ``constitutive_and_tangent_s``: the models' internal forces, return maps and tangent
  assembly (``SystemOperators.internal_force``);
* ``factorisation_s`` and ``solve_s``: SuperLU's factorisations and triangular solves;
* ``other_s``: the rest (residuals, the line search's bookkeeping, the condensation's
  products).

The Arlequin run is also timed with ``condense=False`` (the whole saddle point factorised at
every iteration): ``condensation_saving`` is T(condense=False)/T(condense=True). The tangent
assembly rate is the quadrature points per second of ``SmallStrainJ2.tangent`` in a plastic
state (2D and 3D). Peak memory: the process's resident peak after each case.

``--limit-load`` adds ``cylinder_limit_load``: the plane-strain ``mono`` cylinder of item 4
pressed to 240 MPa in 12 steps (it stops at its limit load, 192.09 MPa) and driven by the
bore's displacement to 1 mm, under :func:`_newton.newton_record`: per converged step item 5's
contraction constants C = r_k+1 / r_k² (below r_k = 1e-3) with the number of quadrature points
that crossed the yield surface in each iteration, and the smallest eigenvalue of the converged
tangent over the elastic one (C grows as it falls toward the limit point). Several minutes.

    python benchmarks/quasi_static.py [--repeat 2] [--dim3] [--dim3-fine 0.00625] [--limit-load]

Prints JSON.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import resource
import time

import _threads  # before numba runs


class _Timers:
    """Wall time spent in the wrapped callables (benchmark instrumentation only)."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}

    def wrap(self, owner, name: str, key: str) -> None:
        fn = getattr(owner, name)

        def timed(*args, **kwargs):
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                self.seconds[key] = self.seconds.get(key, 0.0) + time.perf_counter() - t0

        setattr(owner, name, timed)


@contextlib.contextmanager
def _instrumented():
    """Time the constitutive updates, SuperLU's factorisations and solves of every solver."""
    import scipy.sparse.linalg as spla

    from arlequin.solvers import condensation, operators

    timers = _Timers()
    saved = (operators.SystemOperators.internal_force, spla.splu, condensation.spla.splu)
    timers.wrap(operators.SystemOperators, "internal_force", "constitutive_and_tangent_s")
    real_splu = spla.splu

    def splu(*args, **kwargs):
        t0 = time.perf_counter()
        lu = real_splu(*args, **kwargs)
        timers.seconds["factorisation_s"] = (
            timers.seconds.get("factorisation_s", 0.0) + time.perf_counter() - t0
        )
        return _TimedLU(lu, timers)

    condensation.spla.splu = splu
    try:
        yield timers
    finally:
        operators.SystemOperators.internal_force = saved[0]
        condensation.spla.splu = saved[2]


class _TimedLU:
    def __init__(self, lu, timers: _Timers) -> None:
        self._lu, self._timers = lu, timers

    def solve(self, rhs):
        t0 = time.perf_counter()
        x = self._lu.solve(rhs)
        s = self._timers.seconds
        s["solve_s"] = s.get("solve_s", 0.0) + time.perf_counter() - t0
        return x


def sphere(model: str, dim: int = 2, condense: bool = True, **sizes) -> dict:
    """One sphere run, timed; its accuracy against Hill at 300 MPa."""
    import arlequin.solvers.quasi_static as qs_module
    from arlequin.demos.pressure_vessel import PressureVesselConfig
    from arlequin.demos.pressure_vessel.run import run

    real = qs_module.QuasiStaticSolver.__init__

    def init(self, *args, **kwargs):
        kwargs.setdefault("condense", condense)
        real(self, *args, **kwargs)

    qs_module.QuasiStaticSolver.__init__ = init
    try:
        with _instrumented() as timers:
            t0 = time.perf_counter()
            r = run(PressureVesselConfig(model=model, dim=dim, **sizes))
            wall = time.perf_counter() - t0
    finally:
        qs_module.QuasiStaticSolver.__init__ = real
    h = r.history
    split = {k: round(v, 3) for k, v in timers.seconds.items()}
    split["other_s"] = round(wall - sum(timers.seconds.values()), 3)
    ref = r.reference
    return {
        "case": f"sphere-{dim}d-{model}" + ("" if condense else "-full"),
        "wall_time_s": round(wall, 3),
        "n_elements": r.n_elements,
        "n_dofs": r.n_dofs,
        "patch_fraction": round(r.patch_fraction, 4),
        "newton_iterations": sum(h["newton_iterations"]),
        "newton_iterations_per_step": h["newton_iterations"][1:],
        "split": split,
        "outer_displacement_error": h["outer_displacement"][-1] / ref["outer_displacement"] - 1,
        "plastic_radius_error": h["plastic_radius"][-1] / ref["plastic_radius"] - 1,
        "first_yield_error": r.first_yield_pressure / ref["first_yield_pressure"] - 1,
        "peak_memory_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=1, help="rounds; each case's shortest")
    parser.add_argument("--dim3", action="store_true", help="also the 3D eighth of the sphere")
    parser.add_argument("--dim3-coarse", type=float, default=0.1 / 6, help="3D coarse size (m)")
    parser.add_argument("--dim3-fine", type=float, default=0.1 / 24, help="3D fine size (m)")
    parser.add_argument(
        "--limit-load",
        action="store_true",
        help="also Newton's contraction near the cylinder's limit load",
    )
    args = parser.parse_args()
    cases = [("arlequin", 2, True, {}), ("arlequin", 2, False, {}), ("mono", 2, True, {})]
    if args.dim3:
        sizes = {"coarse_size": args.dim3_coarse, "fine_size": args.dim3_fine}
        cases += [("arlequin", 3, True, sizes), ("arlequin", 3, False, sizes),
                  ("mono", 3, True, sizes)]  # fmt: skip
    best: dict[str, dict] = {}
    for _ in range(args.repeat):
        for model, dim, condense, sizes in cases:
            rec = sphere(model, dim, condense, **sizes)
            if rec["case"] not in best or rec["wall_time_s"] < best[rec["case"]]["wall_time_s"]:
                best[rec["case"]] = rec
    out = {"settings": _threads.settings(), "cases": list(best.values()),
           "tangent_assembly": [tangent_rate(2), tangent_rate(3)]}  # fmt: skip
    for dim in (2, 3):
        a, f, m = (best.get(f"sphere-{dim}d-{k}") for k in ("arlequin", "arlequin-full", "mono"))
        if a and f:
            out[f"condensation_saving_{dim}d"] = round(f["wall_time_s"] / a["wall_time_s"], 3)
        if a and m:
            out[f"T_mono_over_T_arlequin_{dim}d"] = round(m["wall_time_s"] / a["wall_time_s"], 3)
    if args.limit_load:
        out["cylinder_limit_load"] = cylinder_limit_load()
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
