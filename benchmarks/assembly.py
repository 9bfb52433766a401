"""Assembly speed of the small-strain J2 consistent tangent: the former COO build against the
compiled assembly into a CSR pattern computed once (issue 43, part 3).

Unit cubes of tetrahedra (six a cube) and of hexahedra (2 × 2 × 2 Gauss points) at about 50k
and 200k cells, in a plastic state (part of the points yielded, so D varies). For each mesh,
the tangent's assembly from a given return map (``SmallStrainJ2._assemble_tangent``) is timed,
the shortest of ``--rounds`` rounds after a warm-up call (numba's compilation and the pattern's
computation are excluded; the pattern's one-off seconds are printed apart): "old" is the
former numpy assembly (local Bᵀ D B blocks by einsum/matmul, COO triplets summed by scipy,
a sort at every call), "new" the fused numba kernel. Prints JSON: tangent quadrature points
per second (n_cells · n_qp / seconds) of both and their ratio.

    python benchmarks/assembly.py [--rounds 5] [--old-rounds 2] [--small-only]
"""

from __future__ import annotations

import argparse
import json
import time

import _threads  # before numba runs: OpenMP threads sleep between parallel regions
import numpy as np
import scipy.sparse as sp
import skfem

from arlequin.models import J2Material, SmallStrainJ2
from arlequin.models.plasticity.small_strain_kernel import numpy_tangent_blocks


def _old(model, ret, w, pattern):
    """The former ``_assemble_tangent``: numpy blocks, COO with the cached triplet indices."""
    data = numpy_tangent_blocks(model, ret, w)
    rows, cols = pattern
    return sp.csr_matrix((data.ravel(), (rows, cols)), shape=(model.n_dofs, model.n_dofs))


def _best(call, rounds: int) -> float:
    times = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        call()
        times.append(time.perf_counter() - t0)
    return min(times)


def case(mesh: skfem.Mesh, rounds: int, old_rounds: int) -> dict:
    model = SmallStrainJ2(mesh, J2Material(200e9, 0.3, 7800.0, 250e6, 2e9), "3d")
    x = mesh.p
    u = np.stack([2e-3 * x[0] ** 2, -1e-3 * x[0] * x[1], 1e-3 * x[2] * x[1] ** 2]).T.ravel()
    state = model.initial_state()
    ret, w = model._return(u, state), model._weights(None)
    t0 = time.perf_counter()
    model._assemble_tangent(ret, w)  # the pattern, and numba's compilation (cached on disk)
    first = time.perf_counter() - t0
    new = _best(lambda: model._assemble_tangent(ret, w), rounds)
    dofs = model._cell_dofs
    nd = dofs.shape[1]
    pattern = (np.repeat(dofs, nd, axis=1).ravel(), np.tile(dofs, (1, nd)).ravel())
    old = _best(lambda: _old(model, ret, w, pattern), old_rounds)
    n_qp = int(np.prod(model.shape))
    return {"cells": int(mesh.t.shape[1]), "dofs": int(model.n_dofs), "quadrature_points": n_qp,
            "yielded_fraction": round(float(np.mean(ret.reduction > 0)), 3),
            "first_call_s (pattern + compile)": round(first, 3),
            "old_s": round(old, 4), "new_s": round(new, 4),
            "old_qp_per_s": round(n_qp / old), "new_qp_per_s": round(n_qp / new),
            "ratio": round(old / new, 1)}  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5, help="rounds of the new assembly")
    parser.add_argument("--old-rounds", type=int, default=2, help="rounds of the COO assembly")
    parser.add_argument("--small-only", action="store_true", help="the ~50k-cell meshes only")
    args = parser.parse_args()
    grid = lambda n: np.linspace(0.0, 1.0, n + 1)  # noqa: E731
    meshes = {"tet_50k": lambda: skfem.MeshTet.init_tensor(*[grid(20)] * 3),
              "hex_50k": lambda: skfem.MeshHex.init_tensor(*[grid(37)] * 3),
              "tet_200k": lambda: skfem.MeshTet.init_tensor(*[grid(32)] * 3),
              "hex_200k": lambda: skfem.MeshHex.init_tensor(*[grid(58)] * 3)}  # fmt: skip
    if args.small_only:
        meshes = {k: v for k, v in meshes.items() if k.endswith("50k")}
    out = {name: case(make(), args.rounds, args.old_rounds) for name, make in meshes.items()}
    out["rounds"] = {"new": args.rounds, "old": args.old_rounds}
    out["threads"] = _threads.settings()
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
