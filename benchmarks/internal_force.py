"""Cost of one internal-force evaluation of the finite-strain J2 model against the linear model.

Axisymmetric copper cylinder (Taylor bar size, 3.2 mm × 32.4 mm) with ``--nr`` cells across the
radius, loaded into plastic flow by a homogeneous compression. Prints JSON: cells, quadrature
points, seconds per evaluation, quadrature-point updates per second and the ratio to the linear
model's sparse mat-vec on the same mesh for the numpy path and the compiled kernel, and their
ratio (all measured in the same process; the kernel's compilation is excluded).

    python benchmarks/internal_force.py [--nr 30] [--repeat 5]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import tracemalloc

import numpy as np
import skfem

from arlequin.models import FiniteStrainJ2, J2Material, LinearElastic

COPPER = J2Material(117e9, 0.35, 8930.0, 0.4e9, 0.1e9)


def best_time(fun, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fun()
        times.append(time.perf_counter() - t0)
    return min(times)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nr", type=int, default=30, help="cells across the radius")
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args(argv)
    nz = round(args.nr * 32.4 / 3.2)
    mesh = skfem.MeshQuad.init_tensor(
        np.linspace(0, 3.2e-3, args.nr + 1), np.linspace(0, 32.4e-3, nz + 1)
    )
    linear = LinearElastic(mesh, COPPER.elastic, kind="axisymmetric", intorder=3)
    k = linear.stiffness()
    record: dict = {"cells": int(mesh.t.shape[1])}
    for backend in ("numpy", "numba"):
        model = FiniteStrainJ2(mesh, COPPER, backend=backend)
        u = np.zeros(model.n_dofs)
        u[model.nodal_dofs()] = np.diag([0.05, -0.1]) @ mesh.p  # plastic everywhere
        state = model.initial_state()
        _, trial = model.internal_force(u, state)  # compiles the kernel (numba) once
        tracemalloc.start()
        model.internal_force(u, state)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        t_j2 = best_time(lambda m=model, u=u, s=state: m.internal_force(u, s), args.repeat)
        t_lin = best_time(lambda u=u: k @ u, args.repeat)
        n_qp = int(np.prod(model.shape))
        record["quadrature_points"] = n_qp
        record["plastic_fraction"] = float(np.mean(trial.eqps > 0))
        record[backend] = {
            "seconds_per_evaluation": t_j2,
            "updates_per_second": n_qp / t_j2,
            "ratio_to_linear_matvec": t_j2 / t_lin,
            # numpy allocations only (the kernel's own buffers are not traced)
            "peak_traced_memory_mb": peak / 2**20,
        }
    record["numpy_numba_ratio"] = (
        record["numpy"]["seconds_per_evaluation"] / record["numba"]["seconds_per_evaluation"]
    )
    sys.stdout.write(json.dumps(record, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
