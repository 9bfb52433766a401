"""Evaluate first-order nodal fields at arbitrary points (built on the bounded point locator)."""

from __future__ import annotations

import numpy as np
from skfem import Mesh

from .locate import locate_points
from .reference import interpolation_matrix

__all__ = ["evaluate_field"]


def evaluate_field(
    mesh: Mesh, values: np.ndarray, points: np.ndarray, n_components: int = 1, tol: float = 0.05
) -> np.ndarray:
    """Interpolate a P1/Q1 nodal field at points.

    Parameters
    ----------
    mesh : skfem.Mesh
    values : ndarray, shape (n_components * n_nodes,)
        Nodal values, node-interleaved (``d * node + component``) for vector fields.
    points : ndarray, shape (dim, n_points) or (dim,)
        Points (m).
    n_components : int
    tol : float
        Points within ``tol`` × local cell size outside the mesh are extrapolated from the
        nearest cell; farther points raise ``ValueError``.

    Returns
    -------
    ndarray, shape (n_components, n_points)
    """
    points = np.asarray(points, dtype=float)
    if points.ndim == 1:
        points = points[:, None]
    values = np.asarray(values, dtype=float)
    if values.size != n_components * mesh.nvertices:
        raise ValueError(
            f"field has {values.size} values, expected n_components * n_nodes = "
            f"{n_components} * {mesh.nvertices}"
        )
    loc = locate_points(mesh, points, tol=tol)
    loc.raise_if_outside("evaluation point")
    p = interpolation_matrix(mesh, loc.cells, loc.ref)
    return np.asarray((p @ values.reshape(-1, n_components)).T)
