"""Patch regions (arlequin/geometry/regions.py, arlequin/coupling/patches.py): closed surfaces,
level sets, boxes.

Exact references: the inside of a box and of a sphere (the winding number is 1 inside, 0
outside, to round-off away from the surface); the same region given as a surface (STL file),
a level set and a box selects the same coarse cells, and then the same coupled problem gives
the same solution to round-off, the patch test's linear field to 1e-10 (nested, 3D).
"""

from __future__ import annotations

import numpy as np
import pytest
import skfem
import trimesh

from arlequin import ArlequinProblem, Patch, solve_static
from arlequin.coupling.patches import refine_region, select_cells
from arlequin.geometry.regions import SurfaceRegion
from arlequin.models import IsotropicElastic, LinearElastic

STEEL = IsotropicElastic(young=200e9, poisson=0.3, density=7800.0)


def test_winding_number_of_a_box_and_a_sphere():
    rng = np.random.default_rng(0)
    box = SurfaceRegion(trimesh.creation.box(extents=(2.0, 1.0, 0.5)))
    x = rng.uniform(-1.5, 1.5, (3, 4000))
    inside = np.all(np.abs(x) < np.array([[1.0], [0.5], [0.25]]), axis=0)
    # points within 1e-6 of a face are ambiguous at round-off: keep clear of them
    clear = np.min(np.abs(np.abs(x) - np.array([[1.0], [0.5], [0.25]])), axis=0) > 1e-6
    w = box.winding_number(x)
    assert np.allclose(w[clear], inside[clear].astype(float), atol=1e-9)
    assert np.array_equal(box(x)[clear], inside[clear])
    # the inverted surface (faces turned inside out) has the same inside
    flipped = trimesh.creation.box(extents=(2.0, 1.0, 0.5))
    flipped.invert()
    assert np.array_equal(SurfaceRegion(flipped)(x), box(x))
    # an icosphere of radius 1: its facets lie within its sagitta (1.2e-3 at 5 subdivisions)
    sphere = SurfaceRegion(trimesh.creation.icosphere(subdivisions=5, radius=1.0))
    r = np.linalg.norm(x, axis=0)
    far = np.abs(r - 1.0) > 2e-3
    assert np.array_equal(sphere(x)[far], (r < 1.0)[far])


def test_bad_surfaces_are_refused(tmp_path):
    open_box = trimesh.creation.box()
    open_box.update_faces(np.arange(len(open_box.faces)) > 1)  # two triangles removed
    with pytest.raises(ValueError, match="not closed"):
        SurfaceRegion(open_box)
    with pytest.raises(ValueError, match=r"trimesh\.Trimesh"):
        SurfaceRegion(np.zeros((3, 3)))
    with pytest.raises(ValueError, match=r"shape \(3, n\)"):
        SurfaceRegion(trimesh.creation.box())(np.zeros((2, 4)))
    quads = skfem.MeshQuad.init_tensor(np.linspace(0, 1, 3), np.linspace(0, 1, 3))
    with pytest.raises(ValueError, match="3D mesh"):
        select_cells(quads, surface=trimesh.creation.box())
    hexes = skfem.MeshHex.init_tensor(*(np.linspace(0, 1, 3),) * 3)
    far = trimesh.creation.box(extents=(0.1, 0.1, 0.1))
    far.apply_translation((5.0, 5.0, 5.0))
    with pytest.raises(ValueError, match="selects no cell"):
        select_cells(hexes, surface=far)
    with pytest.raises(ValueError, match="exactly one"):
        select_cells(hexes, box=((0, 0, 0), (1, 1, 1)), surface=far)


def _coarse() -> skfem.MeshHex:
    return skfem.MeshHex.init_tensor(np.linspace(0.0, 3.0, 7), np.linspace(0.0, 1.0, 3),
                                     np.linspace(0.0, 1.0, 3))  # fmt: skip


def _patch_box(tmp_path):
    """The region x ∈ (0.9, 2.1) (two coarse columns) as an STL file, a level set and a box."""
    solid = trimesh.creation.box(extents=(1.2, 1.4, 1.4))
    solid.apply_translation((1.5, 0.5, 0.5))
    path = tmp_path / "patch.stl"
    solid.export(path)
    lo, hi = np.array([0.9, -0.2, -0.2]), np.array([2.1, 1.2, 1.2])

    def level_set(x):
        return np.max(np.maximum(lo[:, None] - x, x - hi[:, None]), axis=0)

    return path, level_set, (lo, hi)


def test_surface_level_set_and_box_select_the_same_cells(tmp_path):
    coarse = _coarse()
    path, level_set, box = _patch_box(tmp_path)
    by_surface = select_cells(coarse, surface=path)
    assert np.array_equal(by_surface, select_cells(coarse, level_set=level_set))
    assert np.array_equal(by_surface, select_cells(coarse, box=box))
    # the cells of centroid x = 1.25 and 1.75 (columns of width 0.5): two columns of 2 × 2
    assert by_surface.size == 2 * 2 * 2
    patch = refine_region(coarse, 1, surface=path)
    assert patch.nelements == 8 * by_surface.size


def _solve(patch: Patch, coarse_mesh):
    """The patch test's linear field u = A x with its uniform traction on the coarse
    boundary; the solution and its largest error at the coarse nodes."""
    a = np.array([[1.0, 0.3, -0.2], [0.1, -0.5, 0.4], [0.2, 0.6, 0.8]]) * 1e-3
    coarse = LinearElastic(coarse_mesh, STEEL, "3d")
    problem = ArlequinProblem(coarse, [patch])
    nodal = (a @ coarse_mesh.p).T.ravel()
    stress = coarse.stress_at_quadrature(nodal)[:, :, 0, 0]
    problem.add_traction(lambda x, n: np.einsum("ij,j...->i...", stress, n))
    # rigid motions fixed by the exact values at three corners
    corner = lambda x: (x[0] < 1e-9) & (x[1] < 1e-9) & (x[2] < 1e-9)  # noqa: E731
    problem.add_dirichlet("coarse", corner, value=lambda x: a @ x)
    edge = lambda x: (x[0] > 3.0 - 1e-9) & (x[1] < 1e-9) & (x[2] < 1e-9)  # noqa: E731
    problem.add_dirichlet("coarse", edge, value=lambda x: a @ x, components=[1, 2])
    top = lambda x: (x[0] < 1e-9) & (x[1] > 1.0 - 1e-9) & (x[2] < 1e-9)  # noqa: E731
    problem.add_dirichlet("coarse", top, value=lambda x: a @ x, components=[2])
    res = solve_static(problem)
    u = res.u[problem.dofmap()["coarse"].slice]
    return res.u, float(np.max(np.abs(u - nodal)))


def test_a_patch_from_a_surface_is_the_patch_from_its_level_set(tmp_path):
    # Must show 4 of the 3D issue: the same region by an STL surface and by a level set gives
    # the same coupled solution; both pass the patch test (nested: exact to round-off)
    coarse = _coarse()
    path, level_set, box = _patch_box(tmp_path)
    options = dict(gluing_width=0.5, coupling="L2", mediator="fine")

    def model(mesh):
        return LinearElastic(mesh, STEEL, "3d")

    u_s, err_s = _solve(Patch.from_surface(coarse, path, model, levels=1, **options), coarse)
    u_l, err_l = _solve(Patch.from_level_set(coarse, level_set, model, levels=1, **options),
                        coarse)  # fmt: skip
    u_b, _ = _solve(Patch.from_box(coarse, box, model, levels=1, **options), coarse)
    assert np.array_equal(u_s, u_l) and np.array_equal(u_s, u_b)
    assert max(err_s, err_l) < 1e-10 * 3e-3  # relative to the largest displacement, 3 mm


def test_a_missing_surface_file_is_a_clear_error(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"nope\.stl"):
        SurfaceRegion(tmp_path / "nope.stl")
