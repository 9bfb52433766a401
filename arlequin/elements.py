"""First-order Lagrange elements matching scikit-fem mesh types (P1 simplices, Q1 quads/hexes)."""

from __future__ import annotations

from skfem import (
    ElementHex1,
    ElementLineP1,
    ElementQuad1,
    ElementTetP1,
    ElementTriP1,
    Mesh,
    MeshHex,
    MeshLine,
    MeshQuad,
    MeshTet,
    MeshTri,
)

__all__ = ["scalar_element_for"]

_TABLE = (
    (MeshLine, ElementLineP1),
    (MeshTri, ElementTriP1),
    (MeshQuad, ElementQuad1),
    (MeshTet, ElementTetP1),
    (MeshHex, ElementHex1),
)


def scalar_element_for(mesh: Mesh):
    """Return the first-order Lagrange element (P1 or Q1) matching ``mesh``'s cell type."""
    for mesh_type, element in _TABLE:
        if isinstance(mesh, mesh_type):
            return element()
    raise ValueError(
        f"mesh type {type(mesh).__name__} is not supported; use a MeshLine, MeshTri, MeshQuad, "
        "MeshTet or MeshHex (first order)"
    )
