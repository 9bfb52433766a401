"""User meshes through meshio (arlequin/io/meshes.py): the shared round-trip helper
(tests/_roundtrip.py) over every supported cell type and several formats, then the refusals.

Exact references: the written mesh itself (nodes and cells, up to the file's node order), the
volume of a unit cube written in meshio's (VTK's) hexahedron node order, which scikit-fem's
differs from.
"""

from __future__ import annotations

import meshio
import numpy as np
import pytest
import skfem
from _roundtrip import assert_mesh_round_trip

from arlequin.geometry.meshcheck import MeshError
from arlequin.io import UnsupportedMeshError, read_mesh

FORMATS = ("vtu", "msh", "xdmf")


def _meshes():
    x = np.linspace(0.0, 2.0, 4)
    y = np.linspace(0.0, 1.0, 3)
    return {"triangle": skfem.MeshTri.init_tensor(x, y),
            "quad": skfem.MeshQuad.init_tensor(x, y),
            "tetra": skfem.MeshTet.init_tensor(x, y, y),
            "hexahedron": skfem.MeshHex.init_tensor(x, y, y)}  # fmt: skip


def _volume(mesh) -> float:
    return float(skfem.CellBasis(mesh, mesh.elem()).dx.sum())


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("kind", sorted(_meshes()))
def test_round_trip_of_every_supported_type(tmp_path, kind, fmt):
    mesh = _meshes()[kind]
    kwargs = {"file_format": "gmsh22", "binary": False} if fmt == "msh" else {}
    back = assert_mesh_round_trip(mesh, tmp_path / f"m.{fmt}", **kwargs)
    # the volume (area) of the box it meshes: 2 × 1 (× 1)
    assert _volume(back) == pytest.approx(2.0, rel=1e-12)


def test_a_hexahedron_in_vtk_order_is_a_positive_unit_cube():
    # meshio's (VTK's) order: the bottom face counter-clockwise, then the top one
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                    [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=float)  # fmt: skip
    mesh = read_mesh(meshio.Mesh(pts, [("hexahedron", np.arange(8)[None, :])]), scale=1e-3)
    assert _volume(mesh) == pytest.approx(1e-9, rel=1e-12)  # 1 mm³ after the scale


def test_unused_nodes_are_dropped_and_physical_boundaries_named():
    pts = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [5, 5]], dtype=float)  # the last unused
    m = meshio.Mesh(pts, [("quad", np.array([[0, 1, 2, 3]])), ("line", np.array([[0, 1]]))],
                    cell_sets={"bottom": [np.zeros(0, dtype=int), np.array([0])]})  # fmt: skip
    mesh = read_mesh(m)
    assert mesh.p.shape == (2, 4)
    assert "bottom" in mesh.boundaries and mesh.boundaries["bottom"].size == 1
    facet = mesh.facets[:, mesh.boundaries["bottom"][0]]
    assert np.allclose(mesh.p[1, facet], 0.0)


def test_unsupported_meshes_are_refused():
    pts = np.random.default_rng(0).uniform(size=(10, 3))
    with pytest.raises(UnsupportedMeshError, match="'tetra10'"):
        read_mesh(meshio.Mesh(pts, [("tetra10", np.arange(10)[None, :])]))
    with pytest.raises(UnsupportedMeshError, match="mixes cell types"):
        read_mesh(meshio.Mesh(pts, [("tetra", np.array([[0, 1, 2, 3]])),
                                    ("wedge", np.array([[0, 1, 2, 3, 4, 5]]))]))  # fmt: skip
    with pytest.raises(UnsupportedMeshError, match="no cells"):
        read_mesh(meshio.Mesh(pts, []))
    tri = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.5]], dtype=float)
    with pytest.raises(MeshError, match="in 3D space"):
        read_mesh(meshio.Mesh(tri, [("triangle", np.array([[0, 1, 2]]))]))
    # a bow-tie quadrilateral (its Jacobian changes sign inside it): folded
    quad = np.array([[0, 0], [1, 1], [1, 0], [0, 1]], dtype=float)
    with pytest.raises(MeshError, match="is folded"):
        read_mesh(meshio.Mesh(quad, [("quad", np.array([[0, 1, 2, 3]]))]))
    with pytest.raises(ValueError, match="scale"):
        read_mesh(meshio.Mesh(quad, [("quad", np.array([[0, 2, 1, 3]]))]), scale=0.0)


def test_unreadable_and_missing_files_are_clear_errors(tmp_path):
    junk = tmp_path / "junk.msh"
    junk.write_text("not a mesh\n")
    with pytest.raises(MeshError, match="could not read"):  # meshio exits; not the process
        read_mesh(junk)
    with pytest.raises(FileNotFoundError, match=r"missing\.vtu"):
        read_mesh(tmp_path / "missing.vtu")
