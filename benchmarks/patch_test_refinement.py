"""Patch-test error of the configurations that are not exact, under mesh refinement.

Prints JSON: for each configuration, the max nodal error / max |u| of the uniform-stress problem
on a 2D plate [0, 2] x [0, 1] with a nested patch strip 0.5 < x < 1.5 (two levels finer), glued on
bands of fixed physical width 0.25 m, as both meshes are refined together (n coarse cells across).
Used for the table in docs/theory.md.

    python benchmarks/patch_test_refinement.py
"""

from __future__ import annotations

import json

import numpy as np
import skfem

from arlequin import ArlequinProblem, Patch, refine_region, solve_static
from arlequin.models import IsotropicElastic, LinearElastic


def error(n: int, weights: str, mediator: str, coupling: str = "L2") -> float:
    steel = IsotropicElastic(young=210e9, poisson=0.3)
    cm = skfem.MeshQuad.init_tensor(np.linspace(0, 2, 2 * n + 1), np.linspace(0, 1, n + 1))
    fm = refine_region(cm, levels=2, box=((0.5, 0.0), (1.5, 1.0)))
    coarse, fine = LinearElastic(cm, steel), LinearElastic(fm, steel)
    problem = ArlequinProblem(
        coarse,
        [Patch(fine, gluing_width=0.25, weights=weights, mediator=mediator, coupling=coupling)],
    )
    a = np.array([[1e-3, 2e-4], [-3e-4, -5e-4]])
    stress = coarse.stress_at_quadrature(np.einsum("ij,jn->ni", a, cm.p).ravel())[:2, :2, 0, 0]
    problem.add_traction(lambda x, nrm: np.einsum("ij,j...->i...", stress, nrm))
    problem.add_dirichlet("coarse", lambda x: (x[0] < 1e-9) & (x[1] < 1e-9), None, lambda x: a @ x)
    problem.add_dirichlet(
        "coarse", lambda x: (x[0] > 2 - 1e-9) & (x[1] < 1e-9), [1], lambda x: a @ x
    )
    res = solve_static(problem)
    ue = {"coarse": (a @ cm.p).T.ravel(), "patch0": (a @ fm.p).T.ravel()}
    scale = max(np.abs(v).max() for v in ue.values())
    return float(max(np.abs(res.displacements[k] - v).max() for k, v in ue.items()) / scale)


def main() -> dict:
    out = {}
    for weights, mediator in (("constant", "coarse"), ("ramp", "coarse"), ("constant", "fine")):
        key = f"{weights}+{mediator}"
        out[key] = {str(n): error(n, weights, mediator) for n in (4, 8, 16, 32)}
    return out


if __name__ == "__main__":
    print(json.dumps(main(), indent=2))
