"""The patch test's problem: the exact linear field, its tractions and the supports.

The exact field is a linear displacement u(x) = A x (uniform strain and stress); the tractions
σ n are applied on the whole physical boundary and split by the partition weights in the
overlap; Dirichlet data on the coarse model only (exact values on a few dofs) remove the rigid
motions (SI units).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ...problem.arlequin_problem import ArlequinProblem, Patch
from .meshes import build_layout

if TYPE_CHECKING:
    from .config import PatchTestConfig

__all__ = ["build_problem", "nodal"]


def _linear_field(rng: np.random.Generator, dim: int, axisymmetric: bool) -> np.ndarray:
    if axisymmetric:
        # u_r = a r, u_z = b z: the uniform state compatible with the axis
        a, b = rng.uniform(0.5, 1.5, 2) * np.array([1e-3, -2e-3])
        return np.diag([a, b])
    return rng.uniform(-1.0, 1.0, (dim, dim)) * 1e-3


def build_problem(config: PatchTestConfig):
    """The problem and the exact displacement of a (checked) configuration (see
    :func:`build_patch_test_problem`)."""
    from ...models import IsotropicElastic, LinearElastic

    dim = config.dim
    rng = np.random.default_rng(config.seed)
    axi = dim == "axi"
    coarse_mesh, fine_mesh, w = build_layout(
        rng, dim, config.mesh, config.layout, config.ratio, config.band_cells
    )
    kind = {"1": "1d", "2": "plane_strain", "3": "3d", "axi": "axisymmetric"}[dim]
    material = IsotropicElastic(young=200e9, poisson=0.3, density=7800.0)
    coarse = LinearElastic(coarse_mesh, material, kind)
    fine = LinearElastic(fine_mesh, material, kind)
    patch = Patch(fine, gluing_width=w, weights=config.weights, coupling=config.coupling,
                  mediator=config.mediator)  # fmt: skip
    problem = ArlequinProblem(coarse, [patch])
    d = coarse_mesh.dim()
    a = _linear_field(rng, d, axi)

    def exact(x):
        return np.einsum("ij,j...->i...", a, x)

    stress = coarse.stress_at_quadrature(nodal(exact, coarse_mesh))[:d, :d, 0, 0]

    def traction(x, n):
        return np.einsum("ij,j...->i...", stress, n)

    problem.add_traction(traction)
    _remove_rigid_motions(problem, coarse_mesh, exact, axi)
    return problem, exact


def nodal(field, mesh) -> np.ndarray:
    """Node-interleaved nodal values of a vector field."""
    return np.asarray(field(mesh.p)).T.ravel()


def _remove_rigid_motions(problem: ArlequinProblem, mesh, exact, axi: bool) -> None:
    p = mesh.p
    lo = p.min(axis=1)
    hi = p.max(axis=1)
    d = mesh.dim()
    tol = 1e-9 * np.max(hi - lo)
    origin = np.all(np.abs(p - lo[:, None]) < tol, axis=0)
    if axi:
        # the only rigid motion is a translation along z
        problem.add_dirichlet("coarse", lambda x: _is(x, origin_pt=lo, tol=tol), [1], exact)
        return
    problem.add_dirichlet("coarse", lambda x: _is(x, lo, tol), None, exact)
    if d >= 2:
        corner = lo.copy()
        corner[0] = hi[0]
        problem.add_dirichlet("coarse", lambda x: _is(x, corner, tol), list(range(1, d)), exact)
    if d == 3:
        corner2 = lo.copy()
        corner2[1] = hi[1]
        problem.add_dirichlet("coarse", lambda x: _is(x, corner2, tol), [2], exact)
    del origin


def _is(x, origin_pt, tol):
    return np.all(np.abs(x - np.asarray(origin_pt)[:, None]) < tol, axis=0)
