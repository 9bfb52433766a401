"""How the 3D plate-with-hole meshes of tests/test_band_plasticity.py were made (gmsh 4.15,
``pip install gmsh``; not a dependency: the tests read the VTU files).

A quarter plate 50 mm × 50 mm × 5 mm with a hole of radius R = 10 mm at the corner, in
tetrahedra: ``plate3d_coarse.vtu`` (characteristic length 5 mm, 898 cells), and one mesh of
2.5 mm made of two volumes, the ring R < r < 4R and the rest, so that ``plate3d_ring.vtu``
(the ring's cells: a non-nested patch) is exactly part of ``plate3d_fine.vtu`` (the whole
plate: the single fine mesh that patch is compared with). ``python tests/data/make_plate3d.py``
"""

from pathlib import Path

import gmsh
import meshio
import numpy as np

R, W, T = 10e-3, 50e-3, 5e-3
HERE = Path(__file__).parent


def _plate(occ):
    box = occ.addBox(0, 0, 0, W, W, T)
    hole = occ.addCylinder(0, 0, 0, 0, 0, T, R)
    return occ.cut([(3, box)], [(3, hole)])[0]


def _write(points, tets, name):
    used = np.unique(tets)
    index = np.full(len(points), -1)
    index[used] = np.arange(used.size)
    mesh = meshio.Mesh(points[used], [("tetra", index[tets])])
    meshio.write(HERE / name, mesh, binary=True, compression="zlib")


def _mesh(lc, path):
    gmsh.option.setNumber("Mesh.CharacteristicLengthMax", lc)
    gmsh.model.mesh.generate(3)
    gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
    gmsh.write(str(path))
    gmsh.finalize()
    return meshio.read(path)


def main(tmp: Path = Path("/tmp")) -> None:
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    _plate(gmsh.model.occ)
    gmsh.model.occ.synchronize()
    m = _mesh(5e-3, tmp / "coarse.msh")
    _write(m.points, m.cells_dict["tetra"], "plate3d_coarse.vtu")

    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    occ = gmsh.model.occ
    plate = _plate(occ)
    disc = occ.intersect([(3, occ.addCylinder(0, 0, 0, 0, 0, T, 4 * R))],
                         [(3, occ.addBox(0, 0, 0, W, W, T))])[0]  # fmt: skip
    ring = occ.cut(disc, [(3, occ.addCylinder(0, 0, 0, 0, 0, T, R))])[0]
    occ.fragment(plate, ring)
    occ.synchronize()
    volumes = [t for _, t in gmsh.model.getEntities(3)]
    inner = [t for t in volumes if np.hypot(*occ.getCenterOfMass(3, t)[:2]) < 3 * R]
    gmsh.model.addPhysicalGroup(3, inner, 1)
    gmsh.model.addPhysicalGroup(3, [t for t in volumes if t not in inner], 2)
    m = _mesh(2.5e-3, tmp / "fine.msh")
    tets, group = m.cells_dict["tetra"], m.cell_data_dict["gmsh:physical"]["tetra"]
    _write(m.points, tets, "plate3d_fine.vtu")
    _write(m.points, tets[group == 1], "plate3d_ring.vtu")


if __name__ == "__main__":
    main()
