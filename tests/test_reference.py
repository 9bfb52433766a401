"""Tests of arlequin.geometry.reference: first-order reference elements at per-point reference
coordinates.

Ground truth is scikit-fem itself (its element definitions ``lbasis``, its ``mesh.mapping().F``
and its ``CellBasis`` gradients) and elementary facts of P1/Q1 elements (nodal basis, partition
of unity, exact reproduction of affine functions by the isoparametric P1/Q1 spaces).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import skfem
from _meshes import perturb

from arlequin.geometry.reference import (
    evaluate_basis,
    interpolation_matrix,
    map_to_physical,
    reference_element,
    shape_functions,
    shape_gradients,
)

KINDS = ["line", "tri", "quad", "tet", "hex"]

ELEMENTS = {
    "line": skfem.ElementLineP1,
    "tri": skfem.ElementTriP1,
    "quad": skfem.ElementQuad1,
    "tet": skfem.ElementTetP1,
    "hex": skfem.ElementHex1,
}


def make_mesh(kind: str) -> skfem.Mesh:
    """Small meshes of every supported type; quads and hexes are distorted (non-affine cells)."""
    if kind == "line":
        rng = np.random.default_rng(0)
        return skfem.MeshLine(np.sort(np.concatenate([[0.0, 1.0], rng.uniform(0, 1, 12)])))
    if kind == "tri":
        return perturb(skfem.MeshTri.init_symmetric().refined(2), 0.25, 0.15, 1)
    if kind == "quad":
        m = skfem.MeshQuad.init_tensor(np.linspace(0, 1, 6), np.linspace(0, 2, 9))
        return perturb(m, 0.2, 0.2, 2)
    if kind == "tet":
        return skfem.MeshTet.init_tensor(
            np.linspace(0, 1, 4), np.linspace(0, 1, 5), np.linspace(0, 2, 4)
        )
    m = skfem.MeshHex.init_tensor(*(np.linspace(0, 1, 5),) * 3)
    return perturb(m, 0.25, 0.2, 3)


def random_ref(kind: str, n: int, rng: np.random.Generator) -> np.ndarray:
    """Random reference points inside the reference domain, shape (dim, n)."""
    dim = {"line": 1, "tri": 2, "quad": 2, "tet": 3, "hex": 3}[kind]
    if reference_element(make_mesh(kind)).simplex:
        lam = rng.dirichlet(np.ones(dim + 1), n).T  # barycentric coordinates
        return lam[1:]
    return rng.random((dim, n))


@pytest.mark.parametrize("kind", KINDS)
def test_shape_functions_match_skfem_lbasis(kind):
    # expected: scikit-fem's own element definitions (lbasis value and reference gradient of
    # local function i), which fix the reference domain and the local node order of mesh.t
    rng = np.random.default_rng(10)
    mesh = make_mesh(kind)
    element = ELEMENTS[kind]()
    x = rng.uniform(-0.2, 1.2, (mesh.dim(), 7))  # also outside the domain: same polynomials
    phi = shape_functions(mesh, x)
    dphi = shape_gradients(type(mesh), x)
    assert phi.shape == (mesh.t.shape[0], 7)
    assert dphi.shape == (mesh.dim(), mesh.t.shape[0], 7)
    for i in range(mesh.t.shape[0]):
        value, grad = element.lbasis(x, i)
        np.testing.assert_allclose(phi[i], value, atol=1e-15)
        np.testing.assert_allclose(dphi[:, i], grad, atol=1e-15)


@pytest.mark.parametrize("kind", KINDS)
def test_nodal_basis_at_reference_vertices(kind):
    # expected: a nodal (Lagrange) basis is the identity at its nodes; the vertices are
    # scikit-fem's ``doflocs`` of the element, in local order
    mesh = make_mesh(kind)
    vertices = ELEMENTS[kind].doflocs.T
    np.testing.assert_allclose(reference_element(mesh).vertices, vertices.T)
    np.testing.assert_allclose(shape_functions(mesh, vertices), np.eye(vertices.shape[1]))


@pytest.mark.parametrize("kind", KINDS)
def test_map_matches_skfem_mapping(kind):
    # expected: scikit-fem's own reference-to-physical map mesh.mapping().F(X), which returns
    # (dim, n_cells, n_points) for the same reference points X in every cell
    rng = np.random.default_rng(11)
    mesh = make_mesh(kind)
    x = rng.uniform(-0.1, 1.1, (mesh.dim(), 5))
    expected = mesh.mapping().F(x)
    cells = np.repeat(np.arange(mesh.nelements), x.shape[1])
    ref = np.tile(x, (1, mesh.nelements))
    got = map_to_physical(mesh, cells, ref).reshape(mesh.dim(), mesh.nelements, x.shape[1])
    np.testing.assert_allclose(got, expected, atol=1e-14)


@pytest.mark.parametrize("kind", KINDS)
def test_physical_gradients_match_skfem_cellbasis(kind):
    # expected: scikit-fem's CellBasis gradients at the quadrature points X (same X in every
    # cell; for P1/Q1 the basis element dofs are mesh.t)
    rng = np.random.default_rng(12)
    mesh = make_mesh(kind)
    x = random_ref(kind, 4, rng)
    basis = skfem.CellBasis(mesh, ELEMENTS[kind](), quadrature=(x, np.ones(x.shape[1])))
    cells = np.repeat(np.arange(mesh.nelements), x.shape[1])
    ref = np.tile(x, (1, mesh.nelements))
    values, nodes, grads = evaluate_basis(mesh, cells, ref, gradients=True)
    np.testing.assert_array_equal(nodes, mesh.t[:, cells])
    for i in range(mesh.t.shape[0]):
        expected = basis.basis[i][0].grad.reshape(mesh.dim(), -1)  # (dim, n_cells * n_points)
        np.testing.assert_allclose(grads[:, i], expected, atol=1e-10)
        np.testing.assert_allclose(values[i], np.asarray(basis.basis[i][0]).ravel(), atol=1e-14)


@pytest.mark.parametrize("kind", KINDS)
def test_partition_of_unity_and_linear_reproduction(kind):
    # expected: sum_i phi_i = 1 and sum_i f(x_i) phi_i = f(x) for affine f, because P1 and
    # isoparametric Q1 spaces contain the affine functions (also on distorted quads/hexes)
    rng = np.random.default_rng(13)
    mesh = make_mesh(kind)
    n = 300
    cells = rng.integers(0, mesh.nelements, n)
    ref = random_ref(kind, n, rng)
    x = map_to_physical(mesh, cells, ref)
    a = np.array([0.7, -1.3, 2.1])[: mesh.dim()]

    def f(y):
        return 0.4 + a @ y

    values, nodes = evaluate_basis(mesh, cells, ref)
    np.testing.assert_allclose(values.sum(axis=0), 1.0, atol=1e-14)
    p = interpolation_matrix(mesh, cells, ref)
    assert isinstance(p, sp.csr_matrix)
    assert p.shape == (n, mesh.nvertices)
    np.testing.assert_allclose(p @ f(mesh.p), f(x), atol=1e-13)
    np.testing.assert_allclose((values * f(mesh.p)[nodes]).sum(axis=0), f(x), atol=1e-13)
    # several fields at once (columns)
    u = np.stack([f(mesh.p), 2.0 * f(mesh.p)], axis=1)
    np.testing.assert_allclose(p @ u, np.stack([f(x), 2.0 * f(x)], axis=1), atol=1e-13)


@pytest.mark.parametrize("kind", KINDS)
def test_physical_gradients_reproduce_linear_gradient(kind):
    # expected: grad of the interpolant of the affine f(x) = c + a.x is the constant a
    rng = np.random.default_rng(14)
    mesh = make_mesh(kind)
    n = 200
    cells = rng.integers(0, mesh.nelements, n)
    ref = random_ref(kind, n, rng)
    a = np.array([0.7, -1.3, 2.1])[: mesh.dim()]
    nodal = 0.4 + a @ mesh.p
    _, nodes, grads = evaluate_basis(mesh, cells, ref, gradients=True)
    assert grads.shape == (mesh.dim(), mesh.t.shape[0], n)
    grad_f = np.einsum("din,in->dn", grads, nodal[nodes])
    np.testing.assert_allclose(grad_f, np.broadcast_to(a[:, None], (mesh.dim(), n)), atol=1e-12)
    # basis gradients sum to zero (partition of unity)
    np.testing.assert_allclose(grads.sum(axis=1), 0.0, atol=1e-12)


def test_interpolation_matrix_broadcasting_and_unlocated_rows():
    mesh = make_mesh("tri")
    # one cell, many reference points: the rows are the cell's shape functions
    ref = np.array([[0.2, 0.5, 0.0], [0.3, 0.1, 0.0]])
    p = interpolation_matrix(mesh, 4, ref)
    assert p.shape == (3, mesh.nvertices)
    # expected: P1 values (1 - x - y, x, y) on local nodes mesh.t[:, 4]
    expected = np.array([[0.5, 0.2, 0.3], [0.4, 0.5, 0.1], [1.0, 0.0, 0.0]])
    np.testing.assert_allclose(p[:, mesh.t[:, 4]].toarray(), expected, atol=1e-15)
    # n_points repeats one (cell, ref) pair
    q = interpolation_matrix(mesh, 4, ref[:, 0], n_points=5)
    assert q.shape == (5, mesh.nvertices)
    np.testing.assert_allclose(q.toarray(), np.tile(p[0].toarray(), (5, 1)))
    # cell -1 (a point not located) gives an empty row, nan reference coordinates are ignored
    r = interpolation_matrix(mesh, np.array([4, -1]), np.array([[0.2, np.nan], [0.3, np.nan]]))
    assert r[1].nnz == 0
    np.testing.assert_allclose(r[0].toarray(), p[0].toarray())


def test_interpolation_matrix_stores_a_nested_patch_exactly():
    # a 2:1 nested patch's nodes located in distorted coarse quads: each lies on a coarse vertex
    # (one value, 1), on an edge midpoint (two, 1/2 each) or at a cell centre (four, 1/4 each).
    # The located reference coordinates carry round-off (the inverse map's Newton iterations),
    # which gave values of 1e-17 to 1e-14 where the basis vanishes: no such entry is stored,
    # each row still sums to one, and the interpolant of an affine field is exact.
    from arlequin.geometry.locate import locate_points
    from arlequin.geometry.reference import FACE_SNAP, snapped_values

    coarse = skfem.MeshQuad.init_tensor(np.linspace(0.0, 1.0, 5), np.linspace(0.0, 2.0, 9))
    fine = coarse.refined(1)
    # the same affine distortion for both: the fine nodes stay at the coarse edges' midpoints
    stretch = np.array([[1.3, 0.4], [-0.2, 0.9]])
    coarse = skfem.MeshQuad(stretch @ coarse.p, coarse.t)
    fine = skfem.MeshQuad(stretch @ fine.p, fine.t)
    loc = locate_points(coarse, fine.p)
    assert loc.found.all()
    p = interpolation_matrix(coarse, loc.cells, loc.ref)
    counts = np.diff(p.indptr)
    # expected: 45 coarse vertices (5 × 9), 4 × 9 + 5 × 8 = 76 edge midpoints, 32 cell centres
    assert np.bincount(counts, minlength=5)[[1, 2, 4]].tolist() == [45, 76, 32]
    assert np.abs(p.data).min() > FACE_SNAP
    np.testing.assert_allclose(np.asarray(p.sum(axis=1)).ravel(), 1.0, rtol=0, atol=4e-16)
    expected = {1: 1.0, 2: 0.5, 4: 0.25}
    for k, value in expected.items():
        rows = np.nonzero(counts == k)[0]
        np.testing.assert_allclose(p[rows].toarray()[p[rows].toarray() != 0], value, atol=1e-14)
    f = lambda x: 0.3 + 1.7 * x[0] - 0.6 * x[1]  # noqa: E731
    np.testing.assert_allclose(p @ f(coarse.p), f(fine.p), rtol=0, atol=1e-14)
    # values without a small one are returned unchanged, bit for bit
    phi = np.array([[0.25, 0.5], [0.25, 1e-15], [0.25, 0.5 - 1e-15], [0.25, 0.0]])
    out = snapped_values(phi)
    assert np.array_equal(out[:, 0], phi[:, 0])
    assert out[1, 1] == 0.0 and out[:, 1].sum() == 1.0


def test_single_point_and_1d_flat_ref():
    mesh = make_mesh("line")
    # (dim,) is one point; for a 1D mesh a flat array is a row of points
    assert shape_functions(mesh, np.array([0.25])).shape == (2, 1)
    # expected: P1 on [0, 1]: (1 - x, x)
    phi = shape_functions(mesh, np.array([0.25, 1.0]))
    np.testing.assert_allclose(phi, [[0.75, 0.0], [0.25, 1.0]])
    x = map_to_physical(mesh, 0, np.array([0.5]))
    # expected: midpoint of cell 0
    np.testing.assert_allclose(x[:, 0], mesh.p[:, mesh.t[:, 0]].mean(axis=1))


def test_skfem_meshline_constructor_is_accepted():
    # skfem.MeshLine is a constructor object, not a class: it still names the line element
    assert reference_element(skfem.MeshLine).name == "line"
    assert reference_element(skfem.MeshHex).name == "hexahedron"


def test_invalid_input():
    mesh = make_mesh("quad")
    with pytest.raises(ValueError, match="not supported"):
        reference_element(skfem.MeshTri2.init_symmetric())  # quadratic geometry
    with pytest.raises(ValueError, match="dim = 2"):
        shape_functions(mesh, np.zeros((3, 4)))
    with pytest.raises(ValueError, match="cell indices"):
        map_to_physical(mesh, np.array([mesh.nelements]), np.zeros((2, 1)))
    with pytest.raises(ValueError, match="cell indices"):
        evaluate_basis(mesh, np.array([-1]), np.zeros((2, 1)))
    with pytest.raises(ValueError, match="broadcast"):
        map_to_physical(mesh, np.array([0, 1, 2]), np.zeros((2, 2)))
    with pytest.raises(ValueError, match="integer"):
        map_to_physical(mesh, np.array([0.0]), np.zeros((2, 1)))
    # a collapsed quad (two coincident vertices): singular Jacobian at that corner
    p = np.array([[0.0, 1.0, 1.0, 1.0], [0.0, 0.0, 1.0, 1.0]])
    flat = skfem.MeshQuad(p, np.array([[0], [1], [2], [3]]))
    with pytest.raises(ValueError, match="singular Jacobian"):
        evaluate_basis(flat, 0, np.array([1.0, 1.0]), gradients=True)
