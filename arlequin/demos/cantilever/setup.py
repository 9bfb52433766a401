"""A plane-strain cantilever with a non-nested refined patch at its clamped end (dynamics tests).

Geometry (SI): length L = 4 m, height H = 1 m (L/H = 4), steel (E = 210 GPa, ν = 0.3,
ρ = 7800 kg/m³), clamped at x = 0. The coarse model is a triangulated grid of size h over the
whole beam; the patch covers [0, a] × [0, H] with triangles of size ``ratio`` × h whose interior
nodes are jittered (so the two meshes are not nested: the overlap is integrated on the exact
polygon intersections), glued in a band of width ``gluing_width`` along its interior edge x = a.
Both models are clamped at x = 0.

The initial state is the static deflection under a uniform downward body force (a smooth shape,
mostly the first bending mode), released at rest: a free vibration.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import skfem

from ...models import IsotropicElastic, LinearElastic
from ...problem.arlequin_problem import ArlequinProblem, Patch
from ...solvers import solve_static

__all__ = ["Cantilever", "build_cantilever", "tri_grid"]

STEEL = IsotropicElastic(210e9, 0.3, 7800.0)


def tri_grid(x: np.ndarray, y: np.ndarray, jitter: float = 0.0, seed: int = 0) -> skfem.MeshTri:
    """Triangulated tensor grid; interior nodes moved randomly by up to ``jitter`` × spacing."""
    mesh = skfem.MeshTri.init_tensor(np.asarray(x, float), np.asarray(y, float))
    if jitter > 0.0:
        rng = np.random.default_rng(seed)
        p = mesh.p.copy()
        hx, hy = np.min(np.diff(x)), np.min(np.diff(y))
        lo, hi = p.min(axis=1, keepdims=True), p.max(axis=1, keepdims=True)
        inner = np.all((p > lo + 1e-12) & (p < hi - 1e-12), axis=0)
        p[0, inner] += rng.uniform(-jitter, jitter, inner.sum()) * hx
        p[1, inner] += rng.uniform(-jitter, jitter, inner.sum()) * hy
        mesh = skfem.MeshTri(p, mesh.t)
    return mesh


@dataclass
class Cantilever:
    """A built cantilever problem and its initial state.

    Attributes
    ----------
    problem : ArlequinProblem
    u0 : dict
        Block name -> initial displacement (m) (the static deflection).
    omega1 : float
        First bending frequency (rad/s), Rayleigh quotient of the initial shape (consistent mass).
    period : float
        2π/ω₁ (s).
    n_coarse_elements, n_fine_elements : int
    """

    problem: ArlequinProblem
    u0: dict
    omega1: float
    period: float
    n_coarse_elements: int
    n_fine_elements: int


def build_cantilever(
    ratio: float = 0.5,
    h: float = 0.25,
    length: float = 4.0,
    height: float = 1.0,
    patch_length: float = 1.5,
    gluing_width: float = 0.5,
    weights: str = "ramp",
    coupling: str = "H1",
    mediator: str = "coarse",
    jitter: float = 0.2,
    seed: int = 0,
    material: IsotropicElastic = STEEL,
    initial_state: bool = True,
) -> Cantilever:
    """Build the cantilever (see the module docstring).

    Parameters
    ----------
    ratio : float
        Fine/coarse element size ratio (0.75, 0.5...).
    h : float
        Coarse element size (m).
    length, height, patch_length, gluing_width : float
        Beam length and height, patch length a and gluing band width (m).
    weights, coupling, mediator : str
        See :class:`arlequin.problem.arlequin_problem.Patch`.
    jitter : float
        Random displacement of the patch's interior nodes, as a fraction of its spacing.
    initial_state : bool
        Compute the static deflection (False: u0 is empty and ω₁ is NaN).
    """
    nx, ny = round(length / h), round(height / h)
    coarse = tri_grid(np.linspace(0.0, length, nx + 1), np.linspace(0.0, height, ny + 1))
    hf = ratio * h
    fx, fy = max(2, round(patch_length / hf)), max(2, round(height / hf))
    fine = tri_grid(
        np.linspace(0.0, patch_length, fx + 1),
        np.linspace(0.0, height, fy + 1),
        jitter=jitter,
        seed=seed,
    )
    cm = LinearElastic(coarse, material, "plane_strain")
    fm = LinearElastic(fine, material, "plane_strain")
    problem = ArlequinProblem(
        cm,
        [
            Patch(
                fm, gluing_width=gluing_width, weights=weights, coupling=coupling, mediator=mediator
            )
        ],
    )
    for block in ("coarse", "patch0"):
        problem.add_dirichlet(block, where=lambda x: x[0] < 1e-9)
    u0: dict = {}
    omega1 = math.nan
    if initial_state:
        loaded = ArlequinProblem(cm, problem.patches)
        loaded._couplings = problem.couplings  # same overlap and coupling matrices
        for block in ("coarse", "patch0"):
            loaded.add_dirichlet(block, where=lambda x: x[0] < 1e-9)
        loaded.add_body_force([0.0, -material.density * 9.81 * 100.0])
        static = solve_static(loaded)
        u = static.u
        system = problem.system()
        k = system.stiffness()
        m = system.mass()
        omega1 = math.sqrt(float(u @ (k @ u)) / float(u @ (m @ u)))
        u0 = system.split(u)
    return Cantilever(
        problem=problem,
        u0=u0,
        omega1=omega1,
        period=2.0 * math.pi / omega1 if omega1 == omega1 else math.nan,
        n_coarse_elements=int(coarse.nelements),
        n_fine_elements=int(fine.nelements),
    )
