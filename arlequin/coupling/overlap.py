"""Where a patch mesh overlaps the coarse mesh: the shared integration mesh and transfer operators.

Every integral that mixes the two models is computed on one *integration mesh* I whose cells each
lie inside one coarse cell and one fine cell, with first-order transfer operators

    P_coarse : coarse nodal values -> nodal values on I     (n_I_nodes, n_coarse_nodes)
    P_fine   : fine nodal values   -> nodal values on I     (n_I_nodes, n_fine_nodes)

Because both models' first-order functions restricted to a cell of I are (bi/tri)linear in that
cell's own reference coordinates, ``P @ u`` represents them *exactly* on I, so that any integral of
products of coarse and fine functions and a piecewise-linear weight, integrated on I with enough
quadrature, is exact. Three constructions:

``nested``
    the patch refines the coarse cells it covers: I is the fine mesh itself, P_fine = identity.
    Detected automatically (coarse functions are reproduced by their fine interpolants at
    interior points of every fine cell to 1e-10).
``merged``
    1D non-nested: I is the line mesh on the merged breakpoints of both meshes.
``intersection``
    2D non-nested simplices: I is made of the triangles of the exact polygon intersections of
    fine and coarse cells (shapely/GEOS clipping, then a fan triangulation), each with its own
    nodes (a discontinuous P1 space on I); 3D non-nested tetrahedra: the tetrahedra of the exact
    convex-polyhedron intersections (:mod:`arlequin.geometry.intersect3d`), likewise.

Non-nested quadrilaterals and hexahedra are refused with a clear error: bilinear and trilinear
cells have no exact intersection (use a nested patch).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from skfem import Mesh, MeshLine, MeshTet, MeshTri

from ..dofs import vector_operator
from ..geometry.locate import LocateResult, cell_centroids, cell_sizes, locate_points
from ..geometry.reference import interpolation_matrix, map_to_physical

__all__ = ["Overlap", "OverlapError", "PairFilter", "build_overlap", "check_meshes"]

logger = logging.getLogger(__name__)


#: ``pair_filter(fine_cells, coarse_cells) -> keep``: which candidate pairs to intersect.
PairFilter = Callable[[np.ndarray, np.ndarray], np.ndarray]


class OverlapError(ValueError):
    """The patch and the coarse mesh cannot be overlapped as requested."""


@dataclass(frozen=True)
class Overlap:
    """The overlap of a coarse mesh and a patch mesh.

    Attributes
    ----------
    coarse_mesh, fine_mesh : skfem.Mesh
    integration_mesh : skfem.Mesh
        The mesh I on which mixed integrals are computed (see module docstring).
    coarse_transfer : scipy.sparse.csr_matrix, shape (n_I_nodes, n_coarse_nodes)
    fine_transfer : scipy.sparse.csr_matrix, shape (n_I_nodes, n_fine_nodes)
    coarse_cells, fine_cells : ndarray of int, shape (n_I_cells,)
        The coarse and fine cell containing each cell of I.
    method : {"nested", "merged", "intersection"}
    trimmed : bool
        The intersection was restricted to the pairs of cells a ``pair_filter`` kept (I does
        not cover the whole overlap; see :func:`build_overlap`).
    """

    coarse_mesh: Mesh
    fine_mesh: Mesh
    integration_mesh: Mesh
    coarse_transfer: sp.csr_matrix
    fine_transfer: sp.csr_matrix
    coarse_cells: np.ndarray
    fine_cells: np.ndarray
    method: str
    trimmed: bool = False

    def vector_transfer(self, which: str, n_components: int) -> sp.csr_matrix:
        """Transfer for vector fields with node-interleaved dofs (``d * node + component``).

        Parameters
        ----------
        which : {"coarse", "fine"}
        n_components : int

        Returns
        -------
        scipy.sparse.csr_matrix, shape (n_components n_I_nodes, n_components n_model_nodes)
        """
        p = self.coarse_transfer if which == "coarse" else self.fine_transfer
        return vector_operator(p, n_components)


def _located(mesh: Mesh, points: np.ndarray, tol: float, what: str) -> LocateResult:
    res = locate_points(mesh, points, tol=tol)
    if not np.all(res.found):
        i = int(np.nonzero(~res.found)[0][0])
        n_out = int(np.count_nonzero(~res.found))
        raise OverlapError(
            f"{what}: {n_out} point(s) lie outside the coarse mesh beyond the boundary tolerance "
            f"(tol={tol} of the local cell size); first at x = {points[:, i]}, distance "
            f"{res.distance[i]:.4g} m"
        )
    return res


def _interior_points(mesh: Mesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centroid and two off-centre interior points per cell: (cells, ref, x)."""
    dim = mesh.dim()
    nv = mesh.t.shape[0]
    simplex = nv == dim + 1
    if simplex:
        bary = np.array(
            [
                np.full(dim + 1, 1.0 / (dim + 1)),
                np.linspace(1, 2, dim + 1),
                np.linspace(3, 1, dim + 1),
            ]
        )
        bary = bary / bary.sum(axis=1, keepdims=True)
        refs = bary[:, 1:].T  # (dim, 3)
    else:
        refs = np.array(
            [np.full(dim, 0.5), np.linspace(0.2, 0.7, dim), np.linspace(0.85, 0.3, dim)]
        ).T
    n_ref = refs.shape[1]
    cells = np.repeat(np.arange(mesh.nelements), n_ref)
    ref = np.tile(refs, (1, mesh.nelements))
    x = map_to_physical(mesh, cells, ref)
    return cells, ref, x


def _is_nested(coarse: Mesh, fine: Mesh, p_coarse: sp.csr_matrix, tol: float) -> bool:
    """Do the fine interpolants of coarse functions reproduce them inside every fine cell?"""
    cells, ref, x = _interior_points(fine)
    loc = locate_points(coarse, x, tol=tol)
    if not np.all(loc.found):
        return False
    q = interpolation_matrix(coarse, loc.cells, loc.ref)
    r = interpolation_matrix(fine, cells, ref)
    rng = np.random.default_rng(12345)
    z = rng.standard_normal((coarse.nvertices, 3))
    mismatch = np.max(np.abs(q @ z - r @ (p_coarse @ z)))
    logger.debug("nested check: max mismatch %.3e", mismatch)
    return bool(mismatch <= 1e-10 * np.max(np.abs(z)))


def check_meshes(coarse: Mesh, fine: Mesh) -> None:
    """Raise :class:`OverlapError` unless the two meshes have one dimension and one cell type."""
    if coarse.dim() != fine.dim():
        raise OverlapError(
            f"mismatched dimensions: coarse mesh is {coarse.dim()}D, patch mesh is {fine.dim()}D"
        )
    if coarse.t.shape[0] != fine.t.shape[0]:
        raise OverlapError(
            f"mismatched cell types: coarse {type(coarse).__name__}, patch {type(fine).__name__}"
        )


def build_overlap(coarse: Mesh, fine: Mesh, method: str = "auto", tol: float = 0.05,
                  pair_filter: PairFilter | None = None) -> Overlap:  # fmt: skip
    """Build the integration mesh and transfer operators of a patch over a coarse mesh.

    Parameters
    ----------
    coarse, fine : skfem.Mesh
        First-order meshes of the same dimension and cell type family.
    method : {"auto", "nested", "intersection"}
        ``auto`` detects nested patches and otherwise intersects the meshes (1D: merged
        breakpoints; 2D triangles: polygon clipping). ``nested`` forces the nested construction
        (for a refined patch whose boundary nodes were moved onto a curved boundary; coarse
        functions are then extrapolated slightly outside the coarse mesh).
    tol : float
        Boundary tolerance as a fraction of the local coarse cell size: fine nodes farther than
        this outside the coarse mesh are an error.
    pair_filter : callable, optional
        ``pair_filter(fine_cells, coarse_cells) -> keep`` (int arrays of the candidate pairs ->
        bool array): the non-nested intersections (2D and 3D) cut only the pairs it keeps, and
        the overlap is marked ``trimmed``. A patch coupling uses it to skip the pieces on which
        its weights are constant (:class:`~arlequin.coupling.gluing.PatchCoupling`). Ignored by
        nested and 1D overlaps.

    Raises
    ------
    OverlapError
        Mismatched dimensions, a patch outside the coarse mesh, or an unsupported non-nested case.
    """
    if method not in ("auto", "nested", "intersection"):
        raise ValueError(
            f"overlap method must be 'auto', 'nested' or 'intersection', got {method!r}"
        )
    check_meshes(coarse, fine)
    loc = _located(coarse, fine.p, tol, "patch mesh outside the coarse mesh")
    p_coarse = interpolation_matrix(coarse, loc.cells, loc.ref)
    if method == "nested" or (method == "auto" and _is_nested(coarse, fine, p_coarse, tol)):
        centroid_loc = locate_points(coarse, cell_centroids(fine), tol=tol)
        return Overlap(
            coarse,
            fine,
            fine,
            p_coarse.tocsr(),
            sp.identity(fine.nvertices, format="csr"),
            centroid_loc.cells,
            np.arange(fine.nelements),
            "nested",
        )
    if isinstance(fine, MeshLine):
        return _merged_1d(coarse, fine, tol)
    if isinstance(fine, MeshTri):
        return _intersection_2d(coarse, fine, pair_filter)
    if isinstance(fine, MeshTet):
        return _intersection_3d(coarse, fine, pair_filter)
    raise OverlapError(
        f"non-nested overlap of {type(fine).__name__} meshes is not supported (exact intersection "
        "exists for 1D lines, 2D triangles and 3D tetrahedra); build the patch by refining "
        "coarse cells (arlequin.refine_region) or use simplices"
    )


def _merged_1d(coarse: Mesh, fine: Mesh, tol: float) -> Overlap:
    xf = fine.p[0]
    lo, hi = xf.min(), xf.max()
    xc = coarse.p[0]
    pts = np.concatenate([xf, xc[(xc > lo) & (xc < hi)]])
    pts = np.sort(pts)
    h = np.min(cell_sizes(fine))
    keep = np.concatenate([[True], np.diff(pts) > 1e-12 * h])
    mesh = MeshLine(pts[keep])
    lc = locate_points(coarse, mesh.p, tol=tol)
    lf = locate_points(fine, mesh.p, tol=1e-9)
    cc = locate_points(coarse, cell_centroids(mesh), tol=tol).cells
    fc = locate_points(fine, cell_centroids(mesh), tol=1e-9).cells
    return Overlap(
        coarse,
        fine,
        mesh,
        interpolation_matrix(coarse, lc.cells, lc.ref).tocsr(),
        interpolation_matrix(fine, lf.cells, lf.ref).tocsr(),
        cc,
        fc,
        "merged",
    )


def _simplex_ref(mesh: Mesh, cells: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Reference coordinates (dim, n) of points x (dim, n) in given simplex cells."""
    v = mesh.p[:, mesh.t[:, cells]]  # (dim, dim+1, n)
    jac = np.transpose(v[:, 1:] - v[:, :1], (2, 0, 1))  # (n, dim, dim): columns p_k - p_0
    rhs = (x - v[:, 0]).T[..., None]
    return np.linalg.solve(jac, rhs)[..., 0].T


def _intersection_2d(coarse: Mesh, fine: Mesh, pair_filter: PairFilter | None) -> Overlap:
    import shapely

    if not isinstance(coarse, MeshTri):
        raise OverlapError("non-nested 2D overlaps need triangular meshes on both sides")
    fpoly = shapely.polygons(np.transpose(fine.p[:, fine.t], (2, 1, 0)))
    cpoly = shapely.polygons(np.transpose(coarse.p[:, coarse.t], (2, 1, 0)))
    tree = shapely.STRtree(cpoly)
    fi, ci = tree.query(fpoly, predicate="intersects")
    if pair_filter is not None:
        keep = np.asarray(pair_filter(fi, ci), dtype=bool)
        fi, ci = fi[keep], ci[keep]
    inter = shapely.intersection(fpoly[fi], cpoly[ci])
    area = shapely.area(inter)
    fine_area = shapely.area(fpoly)
    keep = (area > 1e-12 * fine_area[fi]) & (shapely.get_type_id(inter) == 3)  # 3: Polygon
    # an intersection of two convex cells is convex: any non-polygon result has no area
    inter, fi, ci = inter[keep], fi[keep], ci[keep]
    inter = shapely.orient_polygons(inter) if hasattr(shapely, "orient_polygons") else inter
    coords, owner = shapely.get_coordinates(shapely.get_exterior_ring(inter), return_index=True)
    counts = np.bincount(owner, minlength=len(inter))
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    n_vert = counts - 1  # rings are closed: last point repeats the first
    n_tri = n_vert - 2
    poly_of_tri = np.repeat(np.arange(len(inter)), n_tri)
    k = np.arange(n_tri.sum()) - np.repeat(np.cumsum(n_tri) - n_tri, n_tri)
    a = starts[poly_of_tri]
    b = a + k + 1
    c = a + k + 2
    tri = np.stack([coords[a], coords[b], coords[c]], axis=1)  # (n_tri, 3, 2)
    e1 = tri[:, 1] - tri[:, 0]
    e2 = tri[:, 2] - tri[:, 0]
    signed = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    ok = np.abs(signed) > 1e-12 * fine_area[fi[poly_of_tri]]
    tri, poly_of_tri, signed = tri[ok], poly_of_tri[ok], signed[ok]
    flip = signed < 0
    tri[flip] = tri[flip][:, [0, 2, 1]]
    n = tri.shape[0]
    p = np.ascontiguousarray(tri.reshape(-1, 2).T)
    t = np.arange(3 * n).reshape(n, 3).T
    mesh = MeshTri(p, np.ascontiguousarray(t))
    fcells = np.repeat(fi[poly_of_tri], 3)
    ccells = np.repeat(ci[poly_of_tri], 3)
    p_coarse = interpolation_matrix(coarse, ccells, _simplex_ref(coarse, ccells, p))
    p_fine = interpolation_matrix(fine, fcells, _simplex_ref(fine, fcells, p))
    covered = float(np.abs(signed).sum())
    logger.info(
        "intersection overlap: %d cells, covered area %.6g of patch area %.6g",
        n,
        covered,
        float(fine_area.sum()),
    )
    return Overlap(
        coarse,
        fine,
        mesh,
        p_coarse.tocsr(),
        p_fine.tocsr(),
        ci[poly_of_tri],
        fi[poly_of_tri],
        "intersection",
        pair_filter is not None,
    )


def _intersection_3d(coarse: Mesh, fine: Mesh, pair_filter: PairFilter | None) -> Overlap:
    from ..geometry.intersect3d import candidate_pairs, tetrahedra_intersections

    if not isinstance(coarse, MeshTet):
        raise OverlapError("non-nested 3D overlaps need tetrahedral meshes on both sides")
    fcoords = np.transpose(fine.p[:, fine.t], (2, 1, 0))
    ccoords = np.transpose(coarse.p[:, coarse.t], (2, 1, 0))
    fi, ci = candidate_pairs(fcoords, ccoords)
    if pair_filter is not None:
        keep = np.asarray(pair_filter(fi, ci), dtype=bool)
        fi, ci = fi[keep], ci[keep]
    tets, fcell, ccell = tetrahedra_intersections(fcoords, ccoords, pairs=(fi, ci))
    n = tets.shape[0]
    if n == 0:
        raise OverlapError("the patch mesh does not intersect the coarse mesh")
    p = np.ascontiguousarray(tets.reshape(-1, 3).T)
    mesh = MeshTet(p, np.ascontiguousarray(np.arange(4 * n).reshape(n, 4).T))
    fnodes, cnodes = np.repeat(fcell, 4), np.repeat(ccell, 4)
    p_coarse = interpolation_matrix(coarse, cnodes, _simplex_ref(coarse, cnodes, p))
    p_fine = interpolation_matrix(fine, fnodes, _simplex_ref(fine, fnodes, p))
    logger.info("intersection overlap: %d tetrahedra for %d patch cells", n, fine.nelements)
    return Overlap(coarse, fine, mesh, p_coarse.tocsr(), p_fine.tocsr(), ccell, fcell,
                   "intersection", pair_filter is not None)  # fmt: skip
