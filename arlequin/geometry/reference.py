"""First-order reference elements: the one table of supported cells, evaluated at any point.

scikit-fem evaluates a basis at the *same* reference points in every cell. Transfer operators
between non-matching meshes need the opposite: each physical point has its own cell and its own
reference coordinates (from :func:`arlequin.geometry.locate.locate_points`). This module evaluates
the first-order nodal basis (P1 on simplices, Q1 on quadrilaterals/hexahedra) and the isoparametric
map for such ``(cell, ref)`` pairs, vectorised over points.

Reference domains and local vertex orders are those of scikit-fem (so that ``mesh.t[i, c]`` is
the node of the ``i``-th shape function of cell ``c`` and the map equals
``mesh.mapping().F``):

==========  =================================  ==============================================
mesh        reference domain                   local vertices (rows of ``vertices``)
==========  =================================  ==============================================
MeshLine    [0, 1]                             0, 1
MeshTri     triangle (0,0), (1,0), (0,1)       (0,0), (1,0), (0,1)
MeshQuad    square [0, 1]^2                    (0,0), (1,0), (1,1), (0,1)
MeshTet     tetrahedron (0,0,0), e1, e2, e3    (0,0,0), (1,0,0), (0,1,0), (0,0,1)
MeshHex     cube [0, 1]^3                      (1,1,1), (1,1,0), (1,0,1), (0,1,1),
                                               (1,0,0), (0,1,0), (0,0,1), (0,0,0)
==========  =================================  ==============================================

(The hexahedron order is scikit-fem's ``ElementHex1.doflocs``; it is not the usual VTK order.)
Physical coordinates are in the mesh's length unit (m throughout arlequin); reference
coordinates are dimensionless.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from skfem import (
    ElementHex1,
    ElementLineP1,
    ElementQuad1,
    ElementTetP1,
    ElementTriP1,
    Mesh,
    MeshLine,
)
from skfem.mesh import MeshHex1, MeshLine1, MeshQuad1, MeshTet1, MeshTri1

__all__ = [
    "FACE_SNAP",
    "ReferenceElement",
    "evaluate_basis",
    "interpolation_matrix",
    "map_to_physical",
    "reference_element",
    "scalar_element_for",
    "shape_functions",
    "shape_gradients",
    "snapped_values",
]


@dataclass(frozen=True)
class ReferenceElement:
    """A first-order reference cell.

    Attributes
    ----------
    name : str
        ``"line"``, ``"triangle"``, ``"quadrilateral"``, ``"tetrahedron"`` or ``"hexahedron"``.
    dim : int
        Reference (and physical) dimension.
    vertices : ndarray, shape (n_nodes, dim)
        Reference coordinates of the local vertices, in scikit-fem's local node order.
    simplex : bool
        True for lines, triangles and tetrahedra (P1, affine map); False for Q1 cells
        (multilinear map, reference domain ``[0, 1]^dim``).
    """

    name: str
    dim: int
    vertices: np.ndarray
    simplex: bool

    @property
    def n_nodes(self) -> int:
        """Number of vertices (= shape functions) per cell."""
        return int(self.vertices.shape[0])

    def contains(self, ref: np.ndarray, eps: float = 1e-10) -> np.ndarray:
        """Are reference points inside the (closed) reference domain, up to ``eps``?

        Parameters
        ----------
        ref : ndarray, shape (dim, n_points)
        eps : float
            Tolerance on each reference (or barycentric) coordinate.

        Returns
        -------
        ndarray of bool, shape (n_points,)
        """
        ref = np.asarray(ref, dtype=float)
        if self.simplex:
            return np.all(ref >= -eps, axis=0) & (ref.sum(axis=0) <= 1.0 + eps)
        return np.all((ref >= -eps) & (ref <= 1.0 + eps), axis=0)


def _vertices(rows: list[list[float]]) -> np.ndarray:
    v = np.array(rows, dtype=float)
    v.setflags(write=False)
    return v


_LINE = ReferenceElement("line", 1, _vertices([[0.0], [1.0]]), True)
_TRI = ReferenceElement("triangle", 2, _vertices([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), True)
_QUAD = ReferenceElement(
    "quadrilateral", 2, _vertices([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]), False
)
_TET = ReferenceElement(
    "tetrahedron",
    3,
    _vertices([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
    True,
)
_HEX = ReferenceElement(
    "hexahedron",
    3,
    _vertices(
        [
            [1.0, 1.0, 1.0],
            [1.0, 1.0, 0.0],
            [1.0, 0.0, 1.0],
            [0.0, 1.0, 1.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, 0.0],
        ]
    ),
    False,
)

# (mesh class, the scikit-fem element of its geometry, reference element)
_TABLE = (
    (MeshLine1, ElementLineP1, _LINE),
    (MeshTri1, ElementTriP1, _TRI),
    (MeshQuad1, ElementQuad1, _QUAD),
    (MeshTet1, ElementTetP1, _TET),
    (MeshHex1, ElementHex1, _HEX),
)


def reference_element(mesh_or_type: Mesh | type[Mesh]) -> ReferenceElement:
    """Return the first-order reference element of a scikit-fem mesh (instance or class).

    Parameters
    ----------
    mesh_or_type : skfem.Mesh or subclass of skfem.Mesh (or ``skfem.MeshLine``)
        A first-order ``MeshLine``, ``MeshTri``, ``MeshQuad``, ``MeshTet`` or ``MeshHex``.

    Raises
    ------
    ValueError
        For any other mesh type, including higher-order and DG meshes (their geometry is not
        described by ``mesh.p[:, mesh.t]`` alone).
    """
    if mesh_or_type is MeshLine:  # scikit-fem's ``MeshLine`` is a constructor object, not a class
        mesh_or_type = MeshLine1
    cls = mesh_or_type if isinstance(mesh_or_type, type) else type(mesh_or_type)
    for mesh_type, element, ref_el in _TABLE:
        if issubclass(cls, mesh_type) and getattr(cls, "elem", None) is element:
            return ref_el
    raise ValueError(
        f"mesh type {cls.__name__} is not supported; use a first-order MeshLine, MeshTri, "
        "MeshQuad, MeshTet or MeshHex"
    )


def scalar_element_for(mesh: Mesh):
    """The first-order Lagrange element (P1 or Q1) of ``mesh``'s cell type, a new instance.

    Raises
    ------
    ValueError
        For any mesh type other than first-order lines, triangles, quadrilaterals, tetrahedra
        and hexahedra.
    """
    cls = type(mesh)
    for mesh_type, element, _ in _TABLE:
        if issubclass(cls, mesh_type) and getattr(cls, "elem", None) is element:
            return element()
    raise ValueError(
        f"mesh type {cls.__name__} is not supported; use a MeshLine, MeshTri, MeshQuad, "
        "MeshTet or MeshHex (first order)"
    )


def _as_ref(ref: np.ndarray, dim: int) -> np.ndarray:
    """Coerce reference coordinates to shape (dim, n_points)."""
    ref = np.asarray(ref, dtype=float)
    if ref.ndim == 1:
        # (dim,) is a single point; for 1D cells a flat array is a row of points
        ref = ref.reshape(1, -1) if dim == 1 else ref[:, None]
    if ref.ndim != 2 or ref.shape[0] != dim:
        raise ValueError(
            f"reference coordinates must have shape (dim, n_points) with dim = {dim}, "
            f"got shape {ref.shape}"
        )
    return ref


def shape_functions(mesh_or_type: Mesh | type[Mesh], ref: np.ndarray) -> np.ndarray:
    """Values of the first-order shape functions at reference points.

    Parameters
    ----------
    mesh_or_type : skfem.Mesh or subclass of skfem.Mesh
    ref : ndarray, shape (dim, n_points)
        Reference coordinates (dimensionless); points outside the reference domain are
        allowed (polynomial extrapolation). A single point of shape (dim,) is accepted.

    Returns
    -------
    ndarray, shape (n_nodes_per_cell, n_points)
        ``phi[i, k]`` is shape function ``i`` (scikit-fem's local node ``i``) at point ``k``.
    """
    ref_el = reference_element(mesh_or_type)
    x = _as_ref(ref, ref_el.dim)
    if ref_el.simplex:
        return np.vstack([1.0 - x.sum(axis=0, keepdims=True), x])
    return _tensor_factors(ref_el, x).prod(axis=0)


def _tensor_factors(ref_el: ReferenceElement, x: np.ndarray) -> np.ndarray:
    """1D factors ``x_d`` or ``1 - x_d`` of each Q1 shape function, shape (dim, n_nodes, n)."""
    upper = ref_el.vertices.T[:, :, None] > 0.5
    return np.where(upper, x[:, None, :], 1.0 - x[:, None, :])


def shape_gradients(mesh_or_type: Mesh | type[Mesh], ref: np.ndarray) -> np.ndarray:
    """Reference gradients of the first-order shape functions.

    Parameters
    ----------
    mesh_or_type : skfem.Mesh or subclass of skfem.Mesh
    ref : ndarray, shape (dim, n_points)
        Reference coordinates (dimensionless). A single point of shape (dim,) is accepted.

    Returns
    -------
    ndarray, shape (dim, n_nodes_per_cell, n_points)
        ``dphi[d, i, k]`` = d phi_i / d xi_d at point ``k`` (dimensionless).
    """
    ref_el = reference_element(mesh_or_type)
    x = _as_ref(ref, ref_el.dim)
    dim, n = ref_el.dim, x.shape[1]
    if ref_el.simplex:
        g = np.vstack([-np.ones((1, dim)), np.eye(dim)]).T  # (dim, n_nodes)
        return np.repeat(g[:, :, None], n, axis=2)
    f = _tensor_factors(ref_el, x)
    sign = np.where(ref_el.vertices.T > 0.5, 1.0, -1.0)[:, :, None]  # d/dx of x or 1 - x
    out = np.empty((dim, ref_el.n_nodes, n))
    for d in range(dim):  # loop over the (<= 3) reference directions only
        out[d] = sign[d] * np.prod(np.delete(f, d, axis=0), axis=0)
    return out


def _prepare(
    mesh: Mesh,
    cells: np.ndarray | int,
    ref: np.ndarray,
    n_points: int | None = None,
    allow_outside: bool = False,
) -> tuple[ReferenceElement, np.ndarray, np.ndarray]:
    """Validate and broadcast ``cells`` to (n,) and ``ref`` to (dim, n)."""
    ref_el = reference_element(mesh)
    ref = _as_ref(ref, ref_el.dim)
    cells_arr = np.asarray(cells)
    if cells_arr.ndim > 1:
        raise ValueError(f"cells must be a scalar or a 1D array, got shape {cells_arr.shape}")
    if cells_arr.size and not np.issubdtype(cells_arr.dtype, np.integer):
        raise ValueError(f"cells must be integer cell indices, got dtype {cells_arr.dtype}")
    cells_arr = cells_arr.astype(np.int64, copy=False).reshape(-1)
    n = max(cells_arr.size, ref.shape[1]) if n_points is None else int(n_points)
    try:
        cells_arr = np.broadcast_to(cells_arr, (n,))
        ref = np.broadcast_to(ref, (ref_el.dim, n))
    except ValueError:
        raise ValueError(
            f"cells (shape {cells_arr.shape}) and ref (shape {ref.shape}) do not broadcast to "
            f"{n} points"
        ) from None
    lo = -1 if allow_outside else 0
    if n and (cells_arr.min() < lo or cells_arr.max() >= mesh.nelements):
        raise ValueError(
            f"cell indices must lie in [{lo}, {mesh.nelements - 1}] for a mesh of "
            f"{mesh.nelements} cells, got range [{cells_arr.min()}, {cells_arr.max()}]"
        )
    return ref_el, cells_arr, ref


def _inverse_small(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form inverse and determinant of a batch of 1x1, 2x2 or 3x3 matrices.

    Parameters
    ----------
    a : ndarray, shape (n, d, d)

    Returns
    -------
    inv : ndarray, shape (n, d, d)
        Inverse; ``inf``/``nan`` entries where ``det == 0`` (no exception is raised).
    det : ndarray, shape (n,)
    """
    d = a.shape[-1]
    with np.errstate(divide="ignore", invalid="ignore"):
        if d == 1:
            det = a[:, 0, 0]
            return (1.0 / det)[:, None, None], det
        if d == 2:
            det = a[:, 0, 0] * a[:, 1, 1] - a[:, 0, 1] * a[:, 1, 0]
            adj = np.empty_like(a)
            adj[:, 0, 0] = a[:, 1, 1]
            adj[:, 1, 1] = a[:, 0, 0]
            adj[:, 0, 1] = -a[:, 0, 1]
            adj[:, 1, 0] = -a[:, 1, 0]
            return adj / det[:, None, None], det
        if d == 3:
            # rows of the adjugate are cross products of the columns
            c0, c1, c2 = a[:, :, 0], a[:, :, 1], a[:, :, 2]
            r0, r1, r2 = np.cross(c1, c2), np.cross(c2, c0), np.cross(c0, c1)
            det = np.einsum("ni,ni->n", c0, r0)
            adj = np.stack([r0, r1, r2], axis=1)
            return adj / det[:, None, None], det
    raise ValueError(f"only 1x1, 2x2 and 3x3 matrices are supported, got {d}x{d}")


def map_to_physical(mesh: Mesh, cells: np.ndarray | int, ref: np.ndarray) -> np.ndarray:
    """Map reference coordinates in given cells to physical coordinates.

    Parameters
    ----------
    mesh : skfem.Mesh
        First-order mesh (see :func:`reference_element`).
    cells : ndarray of int, shape (n_points,), or int
        Cell of each point (broadcast against ``ref``).
    ref : ndarray, shape (dim, n_points)
        Reference coordinates (dimensionless; values outside the reference domain extrapolate
        the isoparametric map).

    Returns
    -------
    ndarray, shape (dim, n_points)
        Physical coordinates (mesh length unit, m).
    """
    _, cells, ref = _prepare(mesh, cells, ref)
    phi = shape_functions(mesh, ref)
    x = mesh.p[:, mesh.t[:, cells]]  # (dim, n_nodes, n)
    return np.einsum("din,in->dn", x, phi)


def evaluate_basis(
    mesh: Mesh, cells: np.ndarray | int, ref: np.ndarray, gradients: bool = False
) -> tuple[np.ndarray, np.ndarray] | tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Evaluate the nodal basis functions of the given cells at per-point reference coordinates.

    Parameters
    ----------
    mesh : skfem.Mesh
        First-order mesh.
    cells : ndarray of int, shape (n_points,), or int
        Cell of each point (broadcast against ``ref``).
    ref : ndarray, shape (dim, n_points)
        Reference coordinates of each point in its cell (dimensionless).
    gradients : bool
        Also return physical gradients.

    Returns
    -------
    values : ndarray, shape (n_nodes_per_cell, n_points)
        Basis function values (dimensionless).
    nodes : ndarray of int, shape (n_nodes_per_cell, n_points)
        Global node of each value, ``mesh.t[:, cells]``.
    grads : ndarray, shape (dim, n_nodes_per_cell, n_points)
        Only if ``gradients``: physical gradients ``J^{-T} grad_ref phi`` (1/m), with ``J`` the
        Jacobian of the isoparametric map at the point.

    Raises
    ------
    ValueError
        Invalid cells or shapes, or (gradients only) a singular Jacobian at some point.
    """
    _, cells, ref = _prepare(mesh, cells, ref)
    values = shape_functions(mesh, ref)
    nodes = mesh.t[:, cells]
    if not gradients:
        return values, nodes
    dphi = shape_gradients(mesh, ref)  # (dim, n_nodes, n)
    x = mesh.p[:, nodes]  # (dim, n_nodes, n)
    jac = np.einsum("din,ein->nde", x, dphi)  # jac[n, d, e] = dx_d / dxi_e
    inv, det = _inverse_small(jac)
    scale = np.max(np.abs(jac), axis=(1, 2)) ** mesh.dim() if jac.size else det
    bad = ~(np.abs(det) > 1e-14 * scale)
    if np.any(bad):
        k = int(np.nonzero(bad)[0][0])
        raise ValueError(
            f"singular Jacobian (det = {det[k]:.3g}) of cell {int(cells[k])} at reference point "
            f"{ref[:, k]}: degenerate cell"
        )
    grads = np.einsum("ned,ein->din", inv, dphi)
    return values, nodes, grads


def interpolation_matrix(
    mesh: Mesh, cells: np.ndarray | int, ref: np.ndarray, n_points: int | None = None
) -> sp.csr_matrix:
    """Sparse matrix evaluating first-order nodal fields at points.

    Parameters
    ----------
    mesh : skfem.Mesh
        First-order mesh.
    cells : ndarray of int, shape (n_points,), or int
        Cell containing each point (broadcast against ``ref``). ``-1`` (a point not located,
        see :class:`arlequin.geometry.locate.LocateResult`) gives an empty row.
    ref : ndarray, shape (dim, n_points)
        Reference coordinates of each point in its cell (ignored where ``cells == -1``, so
        ``nan`` is allowed there).
    n_points : int, optional
        Number of rows; defaults to the broadcast length of ``cells`` and ``ref`` (use it to
        evaluate many reference points of one cell, ``cells`` scalar, or vice versa).

    Returns
    -------
    scipy.sparse.csr_matrix, shape (n_points, mesh.nvertices)
        Row ``k`` holds the basis values of ``cells[k]`` at ``ref[:, k]``, so ``P @ u``
        evaluates the nodal field ``u`` (shape (n_vertices,) or (n_vertices, m)) at the points.
        Only the non-zero values are stored, values of at most :data:`FACE_SNAP` being taken
        for zeros (the round-off of a point on a face of its cell), see :func:`snapped_values`.
    """
    _, cells, ref = _prepare(mesh, cells, ref, n_points, allow_outside=True)
    n = cells.size
    keep = np.nonzero(cells >= 0)[0]
    phi = snapped_values(shape_functions(mesh, ref[:, keep]))  # (n_nodes, n_keep)
    nonzero = phi != 0.0
    rows = np.broadcast_to(keep, phi.shape)[nonzero]
    cols = mesh.t[:, cells[keep]][nonzero]
    return sp.csr_matrix((phi[nonzero], (rows, cols)), shape=(n, mesh.nvertices))


#: Basis values of at most this size (dimensionless; the values lie in [0, 1] inside a cell) are
#: taken for zeros by :func:`interpolation_matrix`: the round-off of a point located on a face
#: of its cell (a nested patch's nodes on the coarse cells' edges came out at 1e-17 to 1e-14).
FACE_SNAP = 1e-12


def snapped_values(phi: np.ndarray) -> np.ndarray:
    """First-order basis values with those of at most :data:`FACE_SNAP` set to zero and each
    such point's others divided by their sum (a partition of unity again).

    At a point on a face of its cell (a nested patch's node on a coarse edge) the values of the
    nodes off the face vanish, and what the located reference coordinates give there is
    round-off: the point then depends on the face's nodes alone. (A value that small elsewhere,
    e.g. a Q1 corner's at 1e-6 from two faces, is dropped too: the point's values change by at
    most about 1e-11, as if it moved by that fraction of its cell.) Kept, those round-off
    values nearly doubled the entries of the transfers and of the operators built from them,
    which the explicit loop multiplies at every step (the Arlequin Taylor bar's coarse
    stiffness at 20 fine cells across the radius: 72,726 entries, 41,044 of them below 1e-12 of
    the largest).

    Parameters
    ----------
    phi : ndarray, shape (n_nodes, n_points)
        Basis values at each point (dimensionless), as from :func:`shape_functions`.

    Returns
    -------
    ndarray, shape (n_nodes, n_points)
        ``phi`` itself when no point has a small non-zero value, else a copy in which only the
        points that have one differ.
    """
    small = (np.abs(phi) <= FACE_SNAP) & (phi != 0.0)
    touched = np.nonzero(small.any(axis=0))[0]
    if touched.size == 0:
        return phi
    phi = phi.copy()
    part = np.where(small[:, touched], 0.0, phi[:, touched])
    phi[:, touched] = part / part.sum(axis=0)
    return phi
