"""Building refinement patches in Python: :class:`Patch` (a refined model and how it is glued)
and the nested patches of a region of the coarse mesh (:func:`refine_region`,
:meth:`Patch.from_region`).

A *nested* patch is a region of the coarse mesh refined ``levels`` times; its cells then refine the
coarse cells they cover, which is what makes every mixed integral exact (``docs/theory.md``).
Any other user mesh overlapping the coarse one is a *non-nested* patch (pass it directly to
:class:`arlequin.problem.arlequin_problem.Patch`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from skfem import Mesh

from ..contract import Model, check_protocol
from ..geometry.locate import cell_centroids
from .weights import PartitionWeights, make_weights

__all__ = ["MEDIATORS", "Patch", "refine_region", "resolve_mediator", "select_cells"]

#: The mediator spaces a patch may ask for (``"auto"``: :func:`resolve_mediator`).
MEDIATORS = ("auto", "coarse", "fine")


def resolve_mediator(mediator: str, unheld_cells: int) -> str:
    """The mediator space a patch's ``mediator`` option gives.

    ``"auto"`` is the coarse space unless ``unheld_cells`` (the band's patch cells with
    α_fine = 0 at every vertex, :func:`arlequin.coupling.exactness.unheld_band_cells`) is
    positive, then the fine one: the coarse mediator holds only the coarse-scale part of the
    band's patch field, and such cells, which carry no stiffness of their own, deform freely
    under the multipliers (a plastic patch yields there: docs/theory.md, "The band's
    fine-scale modes"); the fine mediator holds every patch dof of the band (and is exact on
    a nested patch). Where every band cell has some weight the coarse mediator stays: it lets
    the band's patch field keep its fine-scale part, closer to a single fine mesh (the thick
    sphere's first yield at 16 fine cells across the wall: +1.6% off Hill with the fine
    mediator, +0.5% with the coarse one). ``"coarse"`` and ``"fine"`` are kept.

    Examples
    --------
    >>> resolve_mediator("auto", 0), resolve_mediator("auto", 25), resolve_mediator("coarse", 25)
    ('coarse', 'fine', 'coarse')
    """
    if mediator not in MEDIATORS:
        raise ValueError(f"mediator must be one of {MEDIATORS}, got {mediator!r}")
    if mediator != "auto":
        return mediator
    return "fine" if unheld_cells > 0 else "coarse"


def select_cells(
    mesh: Mesh,
    box: Sequence[Sequence[float]] | None = None,
    level_set: Callable[[np.ndarray], np.ndarray] | None = None,
    cells: Sequence[int] | np.ndarray | None = None,
    surface: Any = None,
) -> np.ndarray:
    """Cells of ``mesh`` selected by exactly one of a box, a level set, a list or a surface.

    Parameters
    ----------
    box : ((xmin, ...), (xmax, ...))
        Cells whose centroid lies inside the box (m).
    level_set : callable
        φ(x) with x of shape (dim, n): cells whose centroid has φ < 0.
    cells : sequence of int
        Explicit cell indices.
    surface : trimesh.Trimesh, path or SurfaceRegion
        A closed triangulated surface (m; a 3D mesh): cells whose centroid lies inside it
        (:class:`arlequin.geometry.regions.SurfaceRegion`).

    Returns
    -------
    ndarray of int
        Sorted unique cell indices.
    """
    given = [a is not None for a in (box, level_set, cells, surface)]
    if sum(given) != 1:
        raise ValueError("give exactly one of box, level_set, cells or surface to select a patch "
                         "region")  # fmt: skip
    if surface is not None:
        from ..geometry.regions import SurfaceRegion

        if mesh.dim() != 3:
            raise ValueError(f"a surface selects cells of a 3D mesh, got a {mesh.dim()}D mesh: "
                             "give a box or a level set")  # fmt: skip
        region = surface if isinstance(surface, SurfaceRegion) else SurfaceRegion(surface)
        level_set = region.level_set
    if cells is not None:
        sel = np.unique(np.asarray(cells, dtype=np.int64))
        if sel.size and (sel.min() < 0 or sel.max() >= mesh.nelements):
            raise ValueError(
                f"patch cell indices must lie in [0, {mesh.nelements}), got range "
                f"[{sel.min()}, {sel.max()}]"
            )
    else:
        c = cell_centroids(mesh)
        if box is not None:
            lo, hi = (np.asarray(b, dtype=float).reshape(-1) for b in box)
            if lo.size != mesh.dim() or hi.size != mesh.dim():
                raise ValueError(
                    f"box corners must have {mesh.dim()} coordinates, got {lo.size} and {hi.size}"
                )
            inside = np.all((c >= lo[:, None]) & (c <= hi[:, None]), axis=0)
        else:
            inside = np.asarray(level_set(c)) < 0.0
        sel = np.nonzero(inside)[0]
    if sel.size == 0:
        raise ValueError("the patch region selects no cell of the coarse mesh")
    return sel


def refine_region(
    mesh: Mesh,
    levels: int = 1,
    box: Sequence[Sequence[float]] | None = None,
    level_set: Callable[[np.ndarray], np.ndarray] | None = None,
    cells: Sequence[int] | np.ndarray | None = None,
    surface: Any = None,
) -> Mesh:
    """A nested patch: the coarse cells selected as in :func:`select_cells`, uniformly refined
    ``levels`` times.

    Each refinement level halves the cell size (scikit-fem's uniform refinement), so the patch
    cells refine the coarse cells they cover.

    Examples
    --------
    >>> import numpy as np, skfem
    >>> coarse = skfem.MeshQuad.init_tensor(np.linspace(0, 4, 9), np.linspace(0, 1, 3))
    >>> patch = refine_region(coarse, levels=2, box=((0, 0), (1, 1)))
    >>> patch.nelements
    64
    """
    if int(levels) != levels or levels < 0:
        raise ValueError(f"refinement levels must be a non-negative integer, got levels={levels}")
    sel = select_cells(mesh, box=box, level_set=level_set, cells=cells, surface=surface)
    sub = mesh.restrict(sel)
    return sub.refined(int(levels)) if levels else sub


@dataclass
class Patch:
    """A refined model superposed on part of the coarse model.

    Parameters
    ----------
    model : Model
        The patch's model on its own (fine) mesh.
    gluing_width : float, optional
        Width (m) of the gluing band inside the patch along its interior boundary (the part of
        its boundary inside the coarse domain). Snapped outwards to the fine cells whose centroid
        lies within it, so the band's inner edge is made of fine-cell faces.
    weights : {"ramp", "constant"} or PartitionWeights
    epsilon : float
        Floor of α_coarse inside the patch beyond the band.
    coupling : {"L2", "H1"}
    mediator : {"auto", "coarse", "fine"}
        The mediator space: the coarse space restricted to the gluing zone, or the patch's.
        ``"auto"`` (default) takes the coarse one unless some patch cells of the band have
        α_fine = 0 at every vertex (a nested tetrahedral patch's staircase edge; triangles at
        a corner): the coarse mediator holds only the coarse-scale part of the band's patch
        field, so those cells, with no stiffness of their own, would deform freely under the
        multipliers (measured on a 3D plate with a hole: a largest plastic strain 12 to 90
        times the single fine mesh's, in the band); the fine mediator holds them
        (:func:`resolve_mediator`; docs/theory.md, "The band's fine-scale modes").
    length : float, optional
        H1 coupling length ℓ (m); default: the mean coarse cell size on the gluing zone
        (:meth:`PatchCoupling.default_h1_length`).
    gluing_region : callable, optional
        Instead of a band: fine cells whose centroid x (dim, n) satisfies ``gluing_region(x)``.
    overlap_method : {"auto", "nested", "intersection"}
        See :func:`arlequin.coupling.overlap.build_overlap`.
    boundary_tol : float
        Fraction of the local coarse cell size within which patch points outside the coarse mesh
        are accepted (faceted curved boundaries) and patch facets count as lying on the coarse
        boundary.
    name : str, optional
        Block name; default ``"patch<i>"``.
    """

    model: Any
    gluing_width: float | None = None
    weights: str | PartitionWeights = "ramp"
    epsilon: float = 1e-3
    coupling: str = "H1"
    mediator: str = "auto"
    length: float | None = None
    gluing_region: Callable[[np.ndarray], np.ndarray] | None = None
    overlap_method: str = "auto"
    boundary_tol: float = 0.05
    name: str | None = None

    def __post_init__(self) -> None:
        check_protocol(self.model, Model, "the patch's model")
        if self.gluing_width is None and self.gluing_region is None:
            raise ValueError("a patch needs a gluing_width (m) or a gluing_region")
        if self.gluing_width is not None and not self.gluing_width > 0.0:
            raise ValueError(f"gluing_width must be positive, got gluing_width={self.gluing_width}")
        if self.coupling not in ("L2", "H1"):
            raise ValueError(f"coupling must be 'L2' or 'H1', got {self.coupling!r}")
        if self.mediator not in MEDIATORS:
            raise ValueError(
                f"mediator must be one of {', '.join(map(repr, MEDIATORS))}, got {self.mediator!r}"
            )
        if self.length is not None and not self.length > 0.0:
            raise ValueError(f"H1 length must be positive, got length={self.length}")
        self.weights = make_weights(self.weights, self.epsilon)

    @classmethod
    def from_region(
        cls,
        coarse_mesh,
        model: Callable[[Any], Any],
        levels: int = 1,
        *,
        box=None,
        level_set=None,
        surface=None,
        cells=None,
        **options,
    ) -> Patch:
        """A nested patch on the coarse cells of a region, refined ``levels`` times.

        Parameters
        ----------
        coarse_mesh : skfem.Mesh
            The coarse model's mesh.
        model : callable
            ``model(mesh) -> Model``: the patch's model on its refined mesh, e.g.
            ``lambda m: FiniteStrainJ2(m, copper)``.
        levels : int
            Uniform refinements (each halves the cell size).
        box, level_set, surface, cells
            Exactly one: the region, as in :func:`arlequin.coupling.patches.select_cells` (the
            cells whose centroid lies in a box, where φ < 0, inside a closed surface).
        **options
            The other fields of :class:`Patch` (``gluing_width``, ``coupling``, …);
            ``overlap_method`` defaults to ``"nested"``.
        """
        mesh = refine_region(coarse_mesh, levels, box=box, level_set=level_set,
                             surface=surface, cells=cells)  # fmt: skip
        options.setdefault("overlap_method", "nested")
        return cls(model(mesh), **options)

    @classmethod
    def from_box(cls, coarse_mesh, box, model, levels: int = 1, **options) -> Patch:
        """:meth:`from_region` of the cells whose centroid lies in ``box`` ((lo…), (hi…)) (m)."""
        return cls.from_region(coarse_mesh, model, levels, box=box, **options)

    @classmethod
    def from_level_set(cls, coarse_mesh, level_set, model, levels: int = 1,
                       **options) -> Patch:  # fmt: skip
        """:meth:`from_region` of the cells whose centroid has ``level_set(x) < 0`` (x: (dim, n),
        m)."""
        return cls.from_region(coarse_mesh, model, levels, level_set=level_set, **options)

    @classmethod
    def from_surface(cls, coarse_mesh, surface, model, levels: int = 1, **options) -> Patch:
        """:meth:`from_region` of the cells whose centroid lies inside a closed surface (a
        trimesh mesh or an STL/OBJ/PLY file, m;
        :class:`arlequin.geometry.regions.SurfaceRegion`)."""
        return cls.from_region(coarse_mesh, model, levels, surface=surface, **options)
