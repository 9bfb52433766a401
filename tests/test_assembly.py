"""Compiled assembly into a CSR pattern computed once (issue 43, part 3): the scatter map
against np.add.at and scipy's COO build, and the small-strain J2 tangent's fused kernel
against the former numpy assembly (local Bᵀ D B blocks, COO with a sort) to 1e-12 relative."""

import numpy as np
import pytest
import scipy.sparse as sp
import skfem

from arlequin.models import J2Material, SmallStrainJ2
from arlequin.models.assembly import CellPattern
from arlequin.models.plasticity.small_strain_kernel import numpy_tangent_blocks

E, NU, SY, H = 200e9, 0.3, 250e6, 2e9


def _coo(cells: np.ndarray, dim: int, n_dofs: int, local: np.ndarray) -> sp.csr_matrix:
    """The former assembly: COO triplets of every local entry, summed by scipy (a sort)."""
    dofs = (dim * cells[:, :, None] + np.arange(dim)).reshape(cells.shape[0], -1)
    nd = dofs.shape[1]
    rows = np.repeat(dofs, nd, axis=1).ravel()
    cols = np.tile(dofs, (1, nd)).ravel()
    return sp.csr_matrix((local.ravel(), (rows, cols)), shape=(n_dofs, n_dofs))


def _rel(a: sp.csr_matrix, b: sp.csr_matrix) -> float:
    return abs(a - b).max() / abs(b).max()


MESHES = {
    "tri": lambda: skfem.MeshTri().refined(3),
    "quad": lambda: skfem.MeshQuad().refined(3),
    "tet": lambda: skfem.MeshTet().refined(2),
    "hex": lambda: skfem.MeshHex().refined(2),
}


@pytest.mark.parametrize("name", sorted(MESHES))
def test_scatter_map_matches_add_at_and_coo(name):
    mesh = MESHES[name]()
    cells, dim = mesh.t.T, mesh.dim()
    nd = cells.shape[1] * dim
    local = np.random.default_rng(1).standard_normal((cells.shape[0], nd, nd))
    pattern = CellPattern(cells, dim, mesh.p.shape[1])
    reference = _coo(cells, dim, pattern.n_dofs, local)
    compiled, by_add_at = pattern.assemble(local), pattern.assemble_reference(local)
    assert pattern.n_colours > 1
    assert np.array_equal(compiled.indptr, reference.indptr)
    assert np.array_equal(compiled.indices, reference.indices)
    assert _rel(by_add_at, reference) < 1e-13
    assert _rel(compiled, by_add_at) < 1e-13
    # no cells of a colour share a node
    for c in range(pattern.n_colours):
        nodes = cells[pattern.order[pattern.colour_ptr[c] : pattern.colour_ptr[c + 1]]].ravel()
        assert np.unique(nodes).size == nodes.size


def _plastic_displacement(model: SmallStrainJ2) -> np.ndarray:
    """A displacement whose strain grows across the mesh: part of the points yield."""
    x = model.mesh.p
    u = np.zeros((model.dim, x.shape[1]))
    u[0] = 4e-3 * x[0] ** 2 + 1e-3 * x[1] * x[-1]
    u[1] = -2e-3 * x[1] * x[0] + 5e-4 * np.sin(3 * x[0])
    if model.dim == 3:
        u[2] = 1.5e-3 * x[2] * x[1] ** 2
    return u.T.ravel()


CASES = [
    ("tri", "plane_strain", False),
    ("quad", "plane_strain", False),
    ("quad", "plane_strain", True),
    ("quad", "axisymmetric", False),
    ("quad", "axisymmetric", True),
    ("tri", "axisymmetric", False),
    ("tet", "3d", False),
    ("hex", "3d", False),
    ("hex", "3d", True),
]


@pytest.mark.parametrize(("name", "kind", "bbar"), CASES)
def test_j2_tangent_matches_coo_assembly(name, kind, bbar):
    mesh = MESHES[name]()
    if kind == "axisymmetric":
        mesh = mesh.translated((0.5, 0.0))
    model = SmallStrainJ2(mesh, J2Material(E, NU, 7800.0, SY, H), kind, bbar=bbar)
    state = model.initial_state()
    for scale in (1.0, 0.5, 0.25, 0.1, 0.05):  # part of the points yield: D varies
        u = scale * _plastic_displacement(model)
        ret = model._return(u, state)
        if 0.05 < np.mean(ret.reduction > 0) < 0.95:
            break
    assert 0.05 < np.mean(ret.reduction > 0) < 0.95
    w = model._weights(None)
    reference = _coo(mesh.t.T, model.dim, model.n_dofs, numpy_tangent_blocks(model, ret, w))
    tangent = model.tangent(u, state)
    assert _rel(tangent, reference) < 1e-12
    again = model.tangent(0.5 * u, state)
    assert again.indices is tangent.indices and again.indptr is tangent.indptr  # computed once
    assert _rel(again, reference) > 1e-6  # a new state, new entries, the same pattern
    assert tangent.has_canonical_format
