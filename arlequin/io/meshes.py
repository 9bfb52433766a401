"""User meshes from disk: any format meshio reads (Gmsh ``.msh``, ``.vtu``, ``.xdmf``, ``.inp``, …)
as a scikit-fem mesh for a coarse model or a patch.

The cells of the highest dimension make the mesh; they must be of one type the library's models
support (:data:`SUPPORTED`: first-order triangles, quadrilaterals, tetrahedra, hexahedra).
Lower-dimensional cells only name boundaries (Gmsh physical groups become the mesh's
``boundaries``, cell sets of the main type its ``subdomains``: scikit-fem's ``from_meshio``).
Nodes no cell uses (Gmsh's geometry points) are dropped. The mesh is then checked
(:func:`arlequin.geometry.meshcheck.check_mesh`: inverted or degenerate cells, non-finite
coordinates). Coordinates are multiplied by ``scale`` to give metres (1e-3 for a file in
millimetres).
"""

from __future__ import annotations

import logging
import os
from typing import Any

import numpy as np
import skfem
from skfem.io.meshio import from_meshio

from ..geometry.meshcheck import MeshError, check_mesh

__all__ = ["SUPPORTED", "UnsupportedMeshError", "read_mesh"]

logger = logging.getLogger(__name__)

#: The meshio cell types read (scikit-fem's MeshTri, MeshQuad, MeshTet, MeshHex).
SUPPORTED = ("hexahedron", "quad", "tetra", "triangle")


class UnsupportedMeshError(MeshError):
    """The file's cells are of a type the library has no model for (second-order, wedges,
    pyramids, polygons) or of several types at once."""


def _dimension(cell_type: str) -> int:
    from meshio._mesh import topological_dimension

    return int(topological_dimension.get(cell_type, -1))


def read_mesh(source: Any, scale: float = 1.0) -> skfem.Mesh:
    """Read a mesh file (or a ``meshio.Mesh``) into a scikit-fem mesh (module docstring).

    Parameters
    ----------
    source : str, path or meshio.Mesh
        The file (its format from its extension, as meshio decides).
    scale : float
        Factor from the file's length unit to metres.

    Returns
    -------
    skfem.MeshTri, MeshQuad, MeshTet or MeshHex
        Coordinates in m, shape (dim, n_nodes); 2D meshes drop a constant z.

    Raises
    ------
    UnsupportedMeshError
        Mixed types in the highest dimension, or a type outside :data:`SUPPORTED`.
    MeshError
        A file meshio cannot read, a 2D mesh not in a plane z = const, folded or degenerate
        cells (the cell named).
    ValueError
        A scale that is not a positive finite number.
    FileNotFoundError
        No such file.
    """
    if not (isinstance(scale, (int, float)) and np.isfinite(scale) and scale > 0):
        raise ValueError(f"scale must be a positive number (file unit -> m), got scale={scale!r}")
    source, name = _read_source(source)
    kind, top = _main_type(source, name)
    points = np.asarray(source.points, dtype=float)
    if top == 2 and points.shape[1] == 3 and np.ptp(points[:, 2]) > 0.0:
        raise MeshError(f"{name}: {kind} cells in 3D space (z from {points[:, 2].min():.6g} to "
                        f"{points[:, 2].max():.6g}): a 2D model's mesh lies in a plane z = const "
                        "(a surface mesh is not a domain)")  # fmt: skip
    mesh = from_meshio(source, force_meshio_type=kind)
    used = np.zeros(mesh.p.shape[1], dtype=bool)
    used[mesh.t.ravel()] = True
    if not used.all():
        logger.info("%s: %d node(s) no cell uses dropped", name, int((~used).sum()))
        mesh = mesh.remove_unused_nodes()
    if scale != 1.0:
        mesh = mesh.scaled([float(scale)] * mesh.dim())
    check_mesh(mesh, what=name)
    return mesh


def _read_source(source: Any) -> tuple[Any, str]:
    """The ``meshio.Mesh`` of ``source`` (read if a path) and its name in error messages."""
    import meshio

    if isinstance(source, meshio.Mesh):
        return source, "the mesh"
    name = f"mesh file {os.fspath(source)!r}"
    if not os.path.isfile(os.fspath(source)):
        raise FileNotFoundError(f"{name} not found")
    try:
        return meshio.read(os.fspath(source)), name
    except SystemExit as exc:  # meshio exits on a file no reader accepts
        raise MeshError(
            f"{name}: meshio could not read it (not a mesh, or a format it "
            "guesses wrongly from the extension)"
        ) from exc
    except Exception as exc:
        raise MeshError(f"{name}: meshio could not read it: {exc}") from exc


def _main_type(source: Any, name: str) -> tuple[str, int]:
    """The one cell type of the highest dimension of a ``meshio.Mesh`` and that dimension,
    refused unless single and supported (:data:`SUPPORTED`)."""
    types = sorted({block.type for block in source.cells if len(block.data)})
    if not types:
        raise UnsupportedMeshError(f"{name} has no cells")
    top = max(_dimension(t) for t in types)
    main = [t for t in types if _dimension(t) == top]
    if len(main) > 1:
        raise UnsupportedMeshError(f"{name} mixes cell types {main} in dimension {top}: the "
                                   "library's models take one type a mesh (split it into "
                                   "one mesh per type)")  # fmt: skip
    kind = main[0]
    if kind not in SUPPORTED:
        raise UnsupportedMeshError(f"{name} has cells of type {kind!r}, which no model of the "
                                   f"library supports: give first-order {list(SUPPORTED)} "
                                   "cells (e.g. Gmsh's Mesh.ElementOrder = 1)")  # fmt: skip
    return kind, top
