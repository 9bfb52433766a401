"""The Arlequin patch test: a uniform stress state reproduced by a coarse model plus a patch.

A random configuration is built from a seed: a coarse mesh with random (but never tiny: every
element at least a third of the mean size) spacing, and a patch band spanning the domain in all
directions but one, glued along straight bands at both of its ends (axisymmetric: bands normal to
z). Bands are at least one coarse element wide and the free zone between them more than two coarse
elements wide, so that no coarse mediator function meets both bands. The exact field is a linear
displacement u(x) = A x (uniform strain and stress); the tractions σ n are applied on the whole
physical boundary and split by the partition weights in the overlap; Dirichlet data on the coarse
model only (exact values on a few dofs) remove the rigid motions.

Two numbers are reported (fractions, see ``docs/theory.md``):

``max_error``       max over the nodes of both models of |u_h − u| / max |u|
``exact_residual``  relative residual of the exact fields, with the best multipliers (least
                    squares), in the discrete equations: a direct check of the formulation that
                    does not depend on the conditioning of the solve.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import skfem

from ..coupling.patches import refine_region
from ..io import JsonResult, ResultsFolder, write_static
from ..problem.arlequin_problem import ArlequinProblem, Patch
from ..solvers.static import solve_static

__all__ = ["PatchTestResult", "build_patch_test_problem", "run_patch_test"]

DIMS = ("1", "2", "3", "axi")


@dataclass
class PatchTestResult(JsonResult):
    """Outcome of a patch test (all values dimensionless fractions or counts)."""

    max_error: float
    exact_residual: float
    n_coarse_dofs: int
    n_fine_dofs: int
    n_multipliers: int
    dim: str
    coupling: str
    weights: str
    mediator: str
    mesh: str
    seed: int
    overlap_method: str
    exact_expected: bool
    static: Any = field(default=None, repr=False, compare=False)

    json_exclude = ("static",)

    def summary(self) -> str:
        """One line: the configuration, the error and the residual of the exact solution."""
        return (
            f"patch test dim={self.dim} {self.mesh} {self.coupling} {self.weights} weights, "
            f"{self.mediator} mediator, seed {self.seed}: max_error={self.max_error:.3e}, "
            f"exact_residual={self.exact_residual:.3e} ({self.n_coarse_dofs} coarse + "
            f"{self.n_fine_dofs} fine dofs, {self.n_multipliers} multipliers)"
        )


def _spacing(n: int, length: float, rng: np.random.Generator) -> np.ndarray:
    """Random positive spacings, each within [0.6, 1.4] x the mean (so >= 1/3 of it)."""
    h = rng.uniform(0.6, 1.4, n)
    return h / h.sum() * length


def _columns(rng: np.random.Generator, n_total: int, length: float, i0: int, i1: int, nb: int):
    """Node coordinates along the coupled direction with equal-width bands at both patch ends.

    Coarse columns [i0, i1) form the patch; its first and last ``nb`` columns form the bands,
    each of total width ``w`` (so one gluing width fits both bands).
    """
    h = _spacing(n_total, length, rng)
    w = h[i0 : i0 + nb].sum()
    h[i1 - nb : i1] = w / nb
    h[i0 : i0 + nb] = w / nb
    h = h / h.sum() * length
    x = np.concatenate([[0.0], np.cumsum(h)])
    x[-1] = length
    return x, x[i0 + nb] - x[i0]


def _breakpoints(segments, counts, rng) -> np.ndarray:
    """Random nodes on consecutive segments, keeping every segment end exactly (band edges)."""
    pts = [np.array([segments[0][0]])]
    for (s0, s1), k in zip(segments, counts):
        inner = s0 + np.cumsum(_spacing(k, s1 - s0, rng))[:-1]
        pts.append(np.concatenate([inner, [s1]]))
    return np.concatenate(pts)


def _perturb(mesh, rng, axes, amount, keep):
    """Move interior nodes randomly along ``axes`` by up to ``amount`` x local spacing."""
    p = mesh.p.copy()
    for ax, h in zip(axes, amount):
        lo, hi = p[ax].min(), p[ax].max()
        interior = (p[ax] > lo + 1e-12) & (p[ax] < hi - 1e-12) & keep(p)
        p[ax, interior] += rng.uniform(-h, h, interior.sum())
    return type(mesh)(p, mesh.t)


def _linear_field(rng: np.random.Generator, dim: int, axisymmetric: bool) -> np.ndarray:
    if axisymmetric:
        # u_r = a r, u_z = b z: the uniform state compatible with the axis
        a, b = rng.uniform(0.5, 1.5, 2) * np.array([1e-3, -2e-3])
        return np.diag([a, b])
    return rng.uniform(-1.0, 1.0, (dim, dim)) * 1e-3


def _build_1d(rng, mesh_kind):
    n, length = 16, 1.0
    i0, nb = 3, 1 + int(rng.integers(0, 2))
    i1 = i0 + 2 * nb + 3 + int(rng.integers(0, 3))
    x, w = _columns(rng, n, length, i0, i1, nb)
    coarse = skfem.MeshLine(x)
    if mesh_kind == "nested":
        fine = refine_region(coarse, levels=int(rng.integers(1, 3)), cells=np.arange(i0, i1))
    else:
        a = x[i0] + rng.uniform(0.1, 0.4) * (x[i0 + 1] - x[i0])
        b = x[i1] - rng.uniform(0.1, 0.4) * (x[i1] - x[i1 - 1])
        # fine nodes: random, with the band inner edges a + w and b - w as nodes
        segs = [(a, a + w), (a + w, b - w), (b - w, b)]
        fine = skfem.MeshLine(_breakpoints(segs, (4, 9, 4), rng))
    return coarse, fine, w


def _build_2d(rng, mesh_kind, axisymmetric):
    # coupled direction: x (plane) or z (axisymmetric: bands normal to z)
    n_along, n_across = 12, 4
    length, width = (2.0, 1.0)
    i0, nb = 2, 1 + int(rng.integers(0, 2))
    i1 = i0 + 2 * nb + 3 + int(rng.integers(0, 3))
    s, w = _columns(rng, n_along, length, i0, i1, nb)
    t = np.concatenate([[0.0], np.cumsum(_spacing(n_across, width, rng))])
    along = 1 if axisymmetric else 0
    across = 1 - along
    cells = "quad" if mesh_kind == "nested" else "tri"

    def grid(a, b, kind):
        xs, ys = (b, a) if axisymmetric else (a, b)
        m = skfem.MeshQuad.init_tensor(xs, ys)
        return (
            m.to_meshtri()
            if kind == "tri" and hasattr(m, "to_meshtri")
            else (skfem.MeshTri.init_tensor(xs, ys) if kind == "tri" else m)
        )

    coarse = grid(s, t, cells)
    h_across = width / n_across
    coarse = _perturb(coarse, rng, [across], [0.2 * h_across], lambda p: np.ones(p.shape[1], bool))
    if mesh_kind == "nested":
        cen = coarse.p[:, coarse.t].mean(axis=1)[along]
        sel = np.nonzero((cen > s[i0]) & (cen < s[i1]))[0]
        fine = refine_region(coarse, levels=int(rng.integers(1, 3)), cells=sel)
    else:
        a = s[i0] + rng.uniform(0.1, 0.4) * (s[i0 + 1] - s[i0])
        b = s[i1] - rng.uniform(0.1, 0.4) * (s[i1] - s[i1 - 1])
        segs = [(a, a + w), (a + w, b - w), (b - w, b)]
        sf = _breakpoints(segs, (3, 10, 3), rng)
        tf = np.concatenate([[0.0], np.cumsum(_spacing(7, width, rng))])
        fine = grid(sf, tf, "tri")
        fine = _perturb(fine, rng, [across], [0.2 * width / 7], lambda p: np.ones(p.shape[1], bool))
    return coarse, fine, w


def _build_3d(rng, mesh_kind):
    n_along, length = 9, 2.0
    i0, nb = 1, 1
    i1 = i0 + 2 * nb + 3
    x, w = _columns(rng, n_along, length, i0, i1, nb)
    y = np.concatenate([[0.0], np.cumsum(_spacing(2, 1.0, rng))])
    z = np.concatenate([[0.0], np.cumsum(_spacing(2, 1.0, rng))])
    if mesh_kind == "nested":
        coarse = skfem.MeshHex.init_tensor(x, y, z)
        coarse = _perturb(coarse, rng, [1, 2], [0.1, 0.1], lambda p: np.ones(p.shape[1], bool))
        cen = coarse.p[:, coarse.t].mean(axis=1)[0]
        sel = np.nonzero((cen > x[i0]) & (cen < x[i1]))[0]
        fine = refine_region(coarse, levels=1, cells=sel)
        return coarse, fine, w
    # non-nested tetrahedra: the coarse grid's tetrahedra, and a patch slab (x in [a, b], all
    # of y and z) on its own grid, its band edges a + w and b − w node planes, both perturbed
    # across (the planes x = const stay planes: the ramp weights stay exact on the bands)
    coarse = skfem.MeshTet.init_tensor(x, y, z)
    coarse = _perturb(coarse, rng, [1, 2], [0.1, 0.1], lambda p: np.ones(p.shape[1], bool))
    a = x[i0] + rng.uniform(0.1, 0.4) * (x[i0 + 1] - x[i0])
    b = x[i1] - rng.uniform(0.1, 0.4) * (x[i1] - x[i1 - 1])
    xf = _breakpoints([(a, a + w), (a + w, b - w), (b - w, b)], (2, 5, 2), rng)
    yf = np.concatenate([[0.0], np.cumsum(_spacing(3, 1.0, rng))])
    zf = np.concatenate([[0.0], np.cumsum(_spacing(3, 1.0, rng))])
    fine = skfem.MeshTet.init_tensor(xf, yf, zf)
    fine = _perturb(fine, rng, [1, 2], [0.1, 0.1], lambda p: np.ones(p.shape[1], bool))
    return coarse, fine, w


#: Patch layouts of :func:`run_patch_test`.
LAYOUTS = ("random", "strip", "square")


def _build_grid_patch(layout: str, mesh_kind: str, ratio: int, band_cells: int):
    """Uniform 2D grids (coarse cell h = 0.25 m): a strip spanning the domain from bottom to
    top (it touches the coarse boundary), or a square inside it; the fine mesh has ``ratio``
    cells per coarse cell edge (nested quadrilaterals, or non-nested triangles)."""
    h = 0.25
    if layout == "strip":
        nx, ny = 4 + 2 * band_cells + 4, 4
        i0, i1, j0, j1 = 2, nx - 2, 0, ny
    else:
        n_patch = 2 * band_cells + 2
        nx = ny = n_patch + 4
        i0, i1, j0, j1 = 2, 2 + n_patch, 2, 2 + n_patch
    xc, yc = np.arange(nx + 1) * h, np.arange(ny + 1) * h
    xf = np.linspace(xc[i0], xc[i1], (i1 - i0) * ratio + 1)
    yf = np.linspace(yc[j0], yc[j1], (j1 - j0) * ratio + 1)
    if mesh_kind == "nested":
        coarse, fine = skfem.MeshQuad.init_tensor(xc, yc), skfem.MeshQuad.init_tensor(xf, yf)
    else:
        coarse, fine = skfem.MeshTri.init_tensor(xc, yc), skfem.MeshTri.init_tensor(xf, yf)
        # mirrored about the patch's mid-line: the same nodes, the other diagonals, so that
        # the fine triangles do not refine the coarse ones (an intersection overlap)
        p = fine.p.copy()
        p[0] = xc[i0] + xc[i1] - p[0]
        fine = skfem.MeshTri(p, fine.t)
    return coarse, fine, band_cells * h


def build_patch_test_problem(
    dim: str | int = "2",
    coupling: str = "H1",
    weights: str = "ramp",
    mediator: str = "coarse",
    mesh: str = "nested",
    seed: int = 0,
    layout: str = "random",
    ratio: int = 4,
    band_cells: int = 1,
):
    """Build the patch-test problem (see :func:`run_patch_test`).

    Returns
    -------
    problem : ArlequinProblem
        With tractions and rigid-motion supports applied.
    exact : callable
        The exact displacement u(x) = A x, x of shape (dim, ...) (m).
    """
    from ..models import IsotropicElastic, LinearElastic

    dim = str(dim)
    if dim not in DIMS:
        raise ValueError(f"dim must be one of {DIMS}, got {dim!r}")
    if mesh not in ("nested", "nonnested"):
        raise ValueError(f"mesh must be 'nested' or 'nonnested', got {mesh!r}")
    if layout not in LAYOUTS:
        raise ValueError(f"layout must be one of {LAYOUTS}, got {layout!r}")
    if isinstance(seed, bool) or int(seed) != seed or seed < 0:
        raise ValueError(f"seed must be a non-negative integer, got seed={seed}")
    rng = np.random.default_rng(seed)
    axi = dim == "axi"
    if layout != "random":
        if dim != "2":
            raise ValueError(f"layout={layout!r} is a 2D plane-strain layout, got dim={dim!r}")
        if isinstance(ratio, bool) or int(ratio) != ratio or ratio < 1:
            raise ValueError(f"ratio must be a positive integer, got ratio={ratio}")
        if isinstance(band_cells, bool) or int(band_cells) != band_cells or band_cells < 1:
            raise ValueError(f"band_cells must be a positive integer, got band_cells={band_cells}")
        coarse_mesh, fine_mesh, w = _build_grid_patch(layout, mesh, int(ratio), int(band_cells))
    elif dim == "1":
        coarse_mesh, fine_mesh, w = _build_1d(rng, mesh)
    elif dim == "3":
        coarse_mesh, fine_mesh, w = _build_3d(rng, mesh)
    else:
        coarse_mesh, fine_mesh, w = _build_2d(rng, mesh, axi)
    kind = {"1": "1d", "2": "plane_strain", "3": "3d", "axi": "axisymmetric"}[dim]
    material = IsotropicElastic(young=200e9, poisson=0.3, density=7800.0)
    coarse = LinearElastic(coarse_mesh, material, kind)
    fine = LinearElastic(fine_mesh, material, kind)
    patch = Patch(fine, gluing_width=w, weights=weights, coupling=coupling, mediator=mediator)
    problem = ArlequinProblem(coarse, [patch])
    d = coarse_mesh.dim()
    a = _linear_field(rng, d, axi)

    def exact(x):
        return np.einsum("ij,j...->i...", a, x)

    stress = coarse.stress_at_quadrature(_nodal(exact, coarse_mesh))[:d, :d, 0, 0]

    def traction(x, n):
        return np.einsum("ij,j...->i...", stress, n)

    problem.add_traction(traction)
    _remove_rigid_motions(problem, coarse_mesh, exact, axi)
    return problem, exact


def run_patch_test(
    dim: str | int = "2",
    coupling: str = "H1",
    weights: str = "ramp",
    mediator: str = "coarse",
    mesh: str = "nested",
    seed: int = 0,
    out: str | Path | None = None,
    layout: str = "random",
    ratio: int = 4,
    band_cells: int = 1,
) -> PatchTestResult:
    """Run one random patch test; see the module docstring.

    Parameters
    ----------
    dim : {"1", "2", "3", "axi"}
    coupling : {"L2", "H1"}
    weights : {"constant", "ramp"}
    mediator : {"coarse", "fine"}
    mesh : {"nested", "nonnested"}
    seed : int
        Seed of the random layout (≥ 0).
    out : path, optional
        Results folder to write (:class:`arlequin.io.ResultsFolder`): results.json,
        history.csv (the strain energies and the residual) and one frame per model (the
        displacement, the weight alpha, the multiplier field).
    layout : {"random", "strip", "square"}
        ``"random"``: the random configuration above; ``"strip"``: a uniform 2D grid with a
        patch spanning it from bottom to top (touching the coarse boundary), glued at its two
        ends; ``"square"``: a square patch inside the grid, glued all around (its band turns
        corners: not an exact configuration with the coarse mediator). 2D only.
    ratio : int
        Coarse/fine cell size ratio of the strip and square layouts.
    band_cells : int
        Gluing band width in coarse cells (strip and square layouts).
    """
    inputs = {"dim": str(dim), "coupling": coupling, "weights": weights, "mediator": mediator,
              "mesh": mesh, "seed": seed, "layout": layout, "ratio": ratio,
              "band_cells": band_cells}  # fmt: skip
    problem, exact = build_patch_test_problem(
        dim, coupling, weights, mediator, mesh, seed, layout, ratio, band_cells
    )
    units = {"seed": "1", "ratio": "1", "band_cells": "coarse cells"}
    folder = ResultsFolder(out, "arlequin patch-test", inputs, units) if out is not None else None
    dim = str(dim)
    coarse_mesh = problem.coarse.mesh
    fine_mesh = problem.patches[0].model.mesh
    result = solve_static(problem)
    name = problem.block_names[1]
    u_exact = {"coarse": _nodal(exact, coarse_mesh), name: _nodal(exact, fine_mesh)}
    scale = max(np.abs(v).max() for v in u_exact.values())
    max_error = max(np.abs(result.displacements[k] - v).max() for k, v in u_exact.items()) / scale
    sp_sys = result.saddle_point
    u_full = np.concatenate([u_exact["coarse"], u_exact[name]])
    solved = np.concatenate([result.multipliers[k] for k in sp_sys.multiplier_slices])
    lam = sp_sys.best_multipliers(u_full, initial=solved)
    residual = sp_sys.residual(u_full, lam)
    pc = problem.couplings[0]
    out_result = PatchTestResult(
        max_error=float(max_error),
        exact_residual=float(residual),
        n_coarse_dofs=int(problem.coarse.n_dofs),
        n_fine_dofs=int(problem.patches[0].model.n_dofs),
        n_multipliers=int(pc.coupling.n_multipliers),
        dim=dim,
        coupling=coupling,
        weights=weights,
        mediator=mediator,
        mesh=mesh,
        seed=int(seed),
        overlap_method=pc.overlap.method,
        exact_expected=not pc.exactness_failures,
    )
    out_result.static = result
    if folder is not None:
        write_static(folder, result.system, result, problem.field_layout())
        values = {k: v for k, v in out_result.to_json().items() if k not in inputs}
        units = {"max_error": "1", "exact_residual": "1", "n_coarse_dofs": "1",
                 "n_fine_dofs": "1", "n_multipliers": "1"}  # fmt: skip
        folder.add_results(values, units)
        from .plots import plot_patch_test_error

        d = {"coarse": coarse_mesh, name: fine_mesh}
        errors = {k: np.linalg.norm((result.displacements[k] - u_exact[k]).reshape(
            -1, d[k].dim()), axis=1) / scale for k in d}  # fmt: skip
        plot_patch_test_error(d, errors, str(folder.picture("patch_test_error")),
                              out_result.summary())  # fmt: skip
        folder.finish()
    return out_result


def _nodal(field, mesh) -> np.ndarray:
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
