"""Cost of one internal-force evaluation of the finite-strain J2 model against the linear model.

Axisymmetric copper cylinder (Taylor bar size, 3.2 mm × 32.4 mm) with ``--nr`` cells across the
radius, loaded into plastic flow by a homogeneous compression. Prints JSON: cells, quadrature
points, seconds per evaluation, quadrature-point updates per second and the ratio to the linear
model's sparse mat-vec on the same mesh for the numpy path and the compiled kernel, and their
ratio (all measured in the same process; the kernel's compilation is excluded). Beside it, the
same figures (key ``"3d"``) on a copper block of hexahedra (3.2 × 3.2 × 12.8 mm, ``--nr3d``
cells across) and (key ``"small_patch"``) on a small axisymmetric patch of ``--patch`` ×
``--patch`` cells (4,096 points at 32), whose updates per second are per point as above.
``--threads`` sets numba's threads (default: all); the settings are in ``"threads"``.

    python benchmarks/internal_force.py [--nr 30] [--nr3d 10] [--patch 32] [--repeat 5]
        [--threads N]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import tracemalloc

import _threads  # before numba runs: OpenMP threads sleep between parallel regions
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


def measure(mesh: skfem.Mesh, strain: np.ndarray, repeat: int) -> dict:
    """Both backends on one mesh under the homogeneous displacement ``strain @ X``."""
    kind = "axisymmetric" if mesh.dim() == 2 else "3d"
    linear = LinearElastic(mesh, COPPER.elastic, kind=kind, intorder=3)
    k = linear.stiffness()
    record: dict = {"cells": int(mesh.t.shape[1])}
    for backend in ("numpy", "numba"):
        model = FiniteStrainJ2(mesh, COPPER, backend=backend)
        u = np.zeros(model.n_dofs)
        u[model.nodal_dofs()] = strain @ mesh.p  # plastic everywhere
        state = model.initial_state()
        _, trial = model.internal_force(u, state)  # compiles the kernel (numba) once
        tracemalloc.start()
        model.internal_force(u, state)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        t_j2 = best_time(lambda m=model, u=u, s=state: m.internal_force(u, s), repeat)
        t_lin = best_time(lambda u=u: k @ u, repeat)
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
    return record


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nr", type=int, default=30, help="cells across the radius")
    parser.add_argument("--nr3d", type=int, default=10, help="hexahedra across the 3D block")
    parser.add_argument("--patch", type=int, default=32, help="cells across the small patch")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--threads", type=int, default=None, help="numba threads (default all)")
    args = parser.parse_args(argv)
    for name in ("nr", "nr3d", "patch", "repeat"):
        if getattr(args, name) < 1:
            parser.error(f"--{name} must be >= 1, got {getattr(args, name)}")
    if args.threads is not None:
        import numba

        if not 1 <= args.threads <= numba.config.NUMBA_NUM_THREADS:
            parser.error(f"--threads must be in 1..{numba.config.NUMBA_NUM_THREADS}, "
                         f"got {args.threads}")  # fmt: skip
        numba.set_num_threads(args.threads)
    nz = round(args.nr * 32.4 / 3.2)
    mesh = skfem.MeshQuad.init_tensor(
        np.linspace(0, 3.2e-3, args.nr + 1), np.linspace(0, 32.4e-3, nz + 1)
    )
    planar = np.diag([0.05, -0.1])
    record = measure(mesh, planar, args.repeat)
    n = args.nr3d
    block = skfem.MeshHex.init_tensor(
        np.linspace(0, 3.2e-3, n + 1), np.linspace(0, 3.2e-3, n + 1),
        np.linspace(0, 12.8e-3, 4 * n + 1),
    )  # fmt: skip
    record["3d"] = measure(block, np.diag([0.05, 0.05, -0.1]), args.repeat)
    n = args.patch
    patch = skfem.MeshQuad.init_tensor(*[np.linspace(0, 3.2e-3, n + 1)] * 2)
    record["small_patch"] = measure(patch, planar, max(args.repeat, 20))  # short: more rounds
    record["threads"] = _threads.settings()
    sys.stdout.write(json.dumps(record, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
