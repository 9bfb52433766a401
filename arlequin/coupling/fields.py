"""Evaluate first-order nodal fields at arbitrary points (built on the bounded point locator) and
at the quadrature points of a scalar basis."""

from __future__ import annotations

import numpy as np
from skfem import Mesh

from ..geometry.locate import locate_points
from ..geometry.reference import interpolation_matrix

__all__ = ["evaluate_field", "scalar_at_quadrature"]


def scalar_at_quadrature(basis, nodal: np.ndarray, gradient: bool = False) -> np.ndarray:
    """A scalar nodal field (or its gradient) at the quadrature points of a scalar basis.

    scikit-fem's ``basis.interpolate`` with the same sum in the same order (the same values bit
    for bit), without its split of the dofs into components, which costs more than the sum on
    meshes of a million cells.

    Parameters
    ----------
    basis : skfem.CellBasis
        A basis of a scalar element.
    nodal : ndarray, shape (basis.N,)
    gradient : bool

    Returns
    -------
    ndarray, shape (n_elems, n_qp), or (dim, n_elems, n_qp) with ``gradient``
    """
    nodal = np.asarray(nodal, dtype=float)
    if nodal.shape[0] != basis.N:
        raise ValueError(f"nodal field has {nodal.shape[0]} values for a basis of {basis.N}")
    out = None
    for i in range(basis.Nbfun):
        phi = basis.basis[i][0]
        term = np.einsum("...,...j->...j", nodal[basis.element_dofs[i]],
                         phi.grad if gradient else np.asarray(phi))  # fmt: skip
        out = term if out is None else out + term
    return out


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
