"""Tests of arlequin.geometry.locate: the bounded-memory point locator.

Expected values come from construction: points are mapped from known (cell, reference) pairs,
placed at known distances outside boxes whose boundary is not perturbed, or follow from the
geometry of tensor-product grids (cell diameters, centroids, distances to corners).
"""

from __future__ import annotations

import time
import tracemalloc

import numpy as np
import pytest
import skfem
from _meshes import perturb

from arlequin.geometry.locate import LocateResult, cell_centroids, cell_sizes, locate_points
from arlequin.geometry.reference import (
    interpolation_matrix,
    map_to_physical,
    reference_element,
    shape_functions,
)

KINDS = ["line", "tri", "quad", "tet", "hex"]


def make_mesh(kind: str) -> skfem.Mesh:
    """Meshes of the box [0, 1] x [0, Ly] (x [0, Lz]); quads and hexes are distorted."""
    if kind == "line":
        rng = np.random.default_rng(0)
        return skfem.MeshLine(np.sort(np.concatenate([[0.0, 1.0], rng.uniform(0, 1, 30)])))
    if kind == "tri":
        return perturb(skfem.MeshTri.init_symmetric().refined(3), 0.125, 0.15, 1)
    if kind == "quad":
        m = skfem.MeshQuad.init_tensor(np.linspace(0, 1, 9), np.linspace(0, 2, 17))
        return perturb(m, 0.125, 0.2, 2)
    if kind == "tet":
        return skfem.MeshTet.init_tensor(
            np.linspace(0, 1, 5), np.linspace(0, 1, 6), np.linspace(0, 2, 7)
        )
    m = skfem.MeshHex.init_tensor(*(np.linspace(0, 1, 6),) * 3)
    return perturb(m, 0.2, 0.2, 3)


def interior_ref(mesh: skfem.Mesh, n: int, rng: np.random.Generator, margin: float) -> np.ndarray:
    """Random reference points at least ``margin`` inside the reference domain, (dim, n)."""
    dim = mesh.dim()
    if mesh.t.shape[0] == dim + 1:  # simplex: barycentric coordinates >= margin
        lam = margin + (1.0 - (dim + 1) * margin) * rng.dirichlet(np.ones(dim + 1), n).T
        return lam[1:]
    return margin + (1.0 - 2.0 * margin) * rng.random((dim, n))


@pytest.mark.parametrize("kind", KINDS)
def test_round_trip_of_mapped_points(kind):
    # expected: a point mapped from (cell, ref) with ref strictly inside the reference domain
    # lies in that cell only, so it is located back to the same (cell, ref)
    rng = np.random.default_rng(20)
    mesh = make_mesh(kind)
    n = 3000
    cells = rng.integers(0, mesh.nelements, n)
    ref = interior_ref(mesh, n, rng, margin=0.02)
    x = map_to_physical(mesh, cells, ref)
    res = locate_points(mesh, x)
    assert isinstance(res, LocateResult)
    assert res.cells.dtype == np.int64 and res.cells.shape == (n,)
    assert res.ref.shape == (mesh.dim(), n)
    assert res.inside.all() and res.found.all()
    np.testing.assert_array_equal(res.distance, 0.0)
    np.testing.assert_array_equal(res.cells, cells)
    np.testing.assert_allclose(res.ref, ref, atol=1e-10)
    np.testing.assert_allclose(map_to_physical(mesh, res.cells, res.ref), x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(shape_functions(mesh, res.ref).sum(axis=0), 1.0, atol=1e-14)


@pytest.mark.parametrize("kind", KINDS)
def test_points_on_cell_boundaries_and_vertices(kind):
    # expected: points on shared faces, edges and mesh vertices (including the domain
    # boundary) are inside some cell (either neighbour is fine) and map back exactly
    rng = np.random.default_rng(21)
    mesh = make_mesh(kind)
    n = 1000
    cells = rng.integers(0, mesh.nelements, n)
    ref = interior_ref(mesh, n, rng, margin=0.0)
    ref[0, : n // 2] = 0.0  # on a face of the reference cell
    x = np.hstack([map_to_physical(mesh, cells, ref), mesh.p])
    res = locate_points(mesh, x, tol=0.0)
    assert res.inside.all()
    np.testing.assert_allclose(map_to_physical(mesh, res.cells, res.ref), x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(shape_functions(mesh, res.ref).sum(axis=0), 1.0, atol=1e-14)


@pytest.mark.parametrize("kind", KINDS)
def test_points_outside_are_flagged(kind):
    mesh = make_mesh(kind)
    dim = mesh.dim()
    # expected: the box is [0, 1] x ...; (1.5, mid...) is 0.5 from the face x = 1, and the
    # corner point (-0.3, -0.4, ...) is |(0.3, 0.4, ...)| from the corner at the origin
    far = np.array([1.5, 0.5, 0.5])[:dim]
    corner = np.array([-0.3, -0.4, -1.2])[:dim]
    inner = np.full(dim, 0.37)
    res = locate_points(mesh, np.stack([far, inner, corner], axis=1))
    np.testing.assert_array_equal(res.found, [False, True, False])
    np.testing.assert_array_equal(res.inside, [False, True, False])
    assert res.cells[0] == -1 and res.cells[2] == -1 and res.cells[1] >= 0
    assert np.isnan(res.ref[:, [0, 2]]).all()
    np.testing.assert_allclose(res.distance, [0.5, 0.0, np.linalg.norm(corner)], rtol=1e-12)
    with pytest.raises(ValueError, match=r"2 node\(s\) of 3 lie outside") as info:
        res.raise_if_outside("node")
    assert "distance 0.5 m" in str(info.value)
    # P @ u leaves the unlocated rows empty
    p = interpolation_matrix(mesh, res.cells, res.ref)
    np.testing.assert_array_equal(np.diff(p.indptr)[[0, 2]], 0)


@pytest.mark.parametrize("kind", KINDS)
def test_near_boundary_tolerance(kind):
    rng = np.random.default_rng(22)
    mesh = make_mesh(kind)
    dim = mesh.dim()
    # a generic point of the boundary face x = 1 (not on an edge of a boundary facet), its
    # unique boundary cell c and that cell's diameter h
    x0 = np.concatenate([[1.0], rng.uniform(0.1, 0.9, dim - 1)])
    base = locate_points(mesh, x0, tol=0.0)
    assert base.inside[0]
    c = base.cells[0]
    h = cell_sizes(mesh)[c]
    # expected: 0.01 h straight out of the planar face x = 1, so the distance is 0.01 h
    x = x0.copy()
    x[0] += 0.01 * h
    accepted = locate_points(mesh, x, tol=0.05)
    assert accepted.found[0] and not accepted.inside[0]
    assert accepted.cells[0] == c
    np.testing.assert_allclose(accepted.distance[0], 0.01 * h, rtol=1e-9)
    np.testing.assert_allclose(accepted.tolerance[0], 0.05 * h, rtol=1e-12)
    # evaluated with unclipped reference coordinates: the map extrapolates to the point
    assert not reference_element(mesh).contains(accepted.ref)[0]
    np.testing.assert_allclose(
        map_to_physical(mesh, accepted.cells, accepted.ref)[:, 0], x, atol=1e-12
    )
    accepted.raise_if_outside()  # nothing to raise
    rejected = locate_points(mesh, x, tol=0.001)
    assert not rejected.found[0] and rejected.cells[0] == -1
    np.testing.assert_allclose(rejected.distance[0], 0.01 * h, rtol=1e-9)
    with pytest.raises(ValueError, match="1 point"):
        rejected.raise_if_outside()


def test_extrapolation_on_curved_boundary_reproduces_linear_field():
    # a faceted disk: nodes of a finer mesh on the true circle lie slightly outside the coarse
    # mesh; the located (extrapolated) P1 interpolant of an affine field is still exact
    coarse = skfem.MeshTri.init_circle(3)
    theta = np.linspace(0.0, 2.0 * np.pi, 400, endpoint=False)
    x = np.stack([np.cos(theta), np.sin(theta)])
    res = locate_points(coarse, x, tol=0.05)
    res.raise_if_outside()
    assert (~res.inside).any()  # some points are between the facets and the circle
    p = interpolation_matrix(coarse, res.cells, res.ref)
    # expected: P1 reproduces affine fields (also when extrapolated)
    np.testing.assert_allclose(
        p @ (1.0 + 2.0 * coarse.p[0] - coarse.p[1]), 1.0 + 2.0 * x[0] - x[1], atol=1e-12
    )


def test_single_point_input():
    mesh = make_mesh("quad")
    res = locate_points(mesh, np.array([0.3, 0.7]))
    assert res.cells.shape == (1,) and res.ref.shape == (2, 1) and res.inside[0]
    np.testing.assert_allclose(
        map_to_physical(mesh, res.cells, res.ref)[:, 0], [0.3, 0.7], atol=1e-12
    )
    # for a 1D mesh a flat array is a row of points
    line = make_mesh("line")
    assert locate_points(line, np.array([0.1, 0.2, 0.3])).cells.shape == (3,)


def test_input_validation():
    mesh = make_mesh("tri")
    with pytest.raises(ValueError, match=r"dimension 3 .* mesh is 2D"):
        locate_points(mesh, np.zeros((3, 4)))
    with pytest.raises(ValueError, match=r"dimension 3 .* mesh is 2D"):
        locate_points(mesh, np.zeros(3))
    with pytest.raises(ValueError, match="NaN"):
        locate_points(mesh, np.array([[0.1, np.nan], [0.2, 0.3]]))
    with pytest.raises(ValueError, match="tol"):
        locate_points(mesh, np.zeros((2, 1)), tol=-1.0)
    with pytest.raises(ValueError, match="k_candidates"):
        locate_points(mesh, np.zeros((2, 1)), k_candidates=(8, 4))
    with pytest.raises(ValueError, match="not supported"):
        locate_points(skfem.MeshTri2.init_symmetric(), np.zeros((2, 1)))
    empty = locate_points(mesh, np.zeros((2, 0)))
    assert empty.cells.shape == (0,) and empty.ref.shape == (2, 0)


def test_graded_mesh_needs_many_candidates():
    # one big cell [1, 100] next to 2000 tiny cells: a point in the big cell has thousands of
    # nearer centroids, so k must escalate past 512 (to 2048) to find it
    nodes = np.concatenate([np.linspace(0.0, 1.0, 2001), [100.0]])
    mesh = skfem.MeshLine(nodes)
    x = np.array([[1.5, 0.25, 99.0]])
    res = locate_points(mesh, x, tol=0.0, chunk_size=2)
    assert res.inside.all()
    # expected: the big cell is the last one; its reference coordinate is (x - 1) / 99
    assert res.cells[0] == mesh.nelements - 1 and res.cells[2] == mesh.nelements - 1
    np.testing.assert_allclose(res.ref[0, [0, 2]], [0.5 / 99.0, 98.0 / 99.0], rtol=1e-12)
    np.testing.assert_allclose(map_to_physical(mesh, res.cells, res.ref), x, atol=1e-12)


@pytest.mark.parametrize("kind", ["tri", "hex"])
def test_chunking_does_not_change_results(kind):
    # expected: batching is an implementation detail; tiny chunks give the same answer
    rng = np.random.default_rng(23)
    mesh = make_mesh(kind)
    x = rng.uniform(-0.05, 1.05, (mesh.dim(), 500))
    a = locate_points(mesh, x)
    b = locate_points(mesh, x, chunk_size=7, k_candidates=(2, 5, 9))
    np.testing.assert_array_equal(a.found, b.found)
    np.testing.assert_array_equal(a.inside, b.inside)
    np.testing.assert_allclose(a.distance, b.distance, atol=1e-14)
    found = a.found
    np.testing.assert_allclose(
        map_to_physical(mesh, a.cells[found], a.ref[:, found]),
        map_to_physical(mesh, b.cells[found], b.ref[:, found]),
        atol=1e-12,
    )


def test_cell_sizes_and_centroids():
    # expected: on a uniform 4 x 2 grid of 0.25 x 0.5 rectangles the diameter is the diagonal
    # and the centroid the rectangle's centre; triangles of the same grid share the diagonal
    quad = skfem.MeshQuad.init_tensor(np.linspace(0, 1, 5), np.linspace(0, 1, 3))
    np.testing.assert_allclose(cell_sizes(quad), np.hypot(0.25, 0.5))
    c = cell_centroids(quad)
    assert c.shape == (2, 8)
    np.testing.assert_allclose(np.sort(np.unique(c[0])), [0.125, 0.375, 0.625, 0.875])
    np.testing.assert_allclose(np.sort(np.unique(c[1])), [0.25, 0.75])
    tri = skfem.MeshTri.init_tensor(np.linspace(0, 1, 5), np.linspace(0, 1, 3))
    np.testing.assert_allclose(cell_sizes(tri), np.hypot(0.25, 0.5))
    # unit cube hexahedron: space diagonal sqrt(3); centroid (0.5, 0.5, 0.5)
    hexa = skfem.MeshHex()
    np.testing.assert_allclose(cell_sizes(hexa), np.sqrt(3.0))
    np.testing.assert_allclose(cell_centroids(hexa)[:, 0], 0.5)


def test_large_point_set_has_bounded_memory():
    # ~20k triangles (100 x 100 grid, 2 per square), 200k random points in the unit square
    mesh = skfem.MeshTri.init_tensor(np.linspace(0, 1, 101), np.linspace(0, 1, 101))
    assert mesh.nelements == 20_000
    rng = np.random.default_rng(24)
    x = rng.random((2, 200_000))
    tracemalloc.start()
    try:
        t0 = time.perf_counter()
        res = locate_points(mesh, x)
        elapsed = time.perf_counter() - t0
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert res.inside.all()
    # measured: peak ~32 MB, ~0.4 s (a dense points x cells array would need 32 GB)
    assert peak < 500e6, f"peak traced memory {peak / 1e6:.0f} MB"
    assert elapsed < 5.0
    sample = rng.choice(x.shape[1], 1000, replace=False)
    np.testing.assert_allclose(
        map_to_physical(mesh, res.cells[sample], res.ref[:, sample]), x[:, sample], atol=1e-12
    )
