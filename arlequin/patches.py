"""Building refinement patches in Python.

A *nested* patch is a region of the coarse mesh refined ``levels`` times; its cells then refine the
coarse cells they cover, which is what makes every mixed integral exact (``docs/theory.md``).
Any other user mesh overlapping the coarse one is a *non-nested* patch (pass it directly to
:class:`arlequin.problem.Patch`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from skfem import Mesh

from .locate import cell_centroids

__all__ = ["refine_region", "select_cells"]


def select_cells(
    mesh: Mesh,
    box: Sequence[Sequence[float]] | None = None,
    level_set: Callable[[np.ndarray], np.ndarray] | None = None,
    cells: Sequence[int] | np.ndarray | None = None,
) -> np.ndarray:
    """Cells of ``mesh`` selected by exactly one of a box, a level set or a list.

    Parameters
    ----------
    box : ((xmin, ...), (xmax, ...))
        Cells whose centroid lies inside the box (m).
    level_set : callable
        φ(x) with x of shape (dim, n): cells whose centroid has φ < 0.
    cells : sequence of int
        Explicit cell indices.

    Returns
    -------
    ndarray of int
        Sorted unique cell indices.
    """
    given = [a is not None for a in (box, level_set, cells)]
    if sum(given) != 1:
        raise ValueError("give exactly one of box, level_set or cells to select a patch region")
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
) -> Mesh:
    """A nested patch: the selected coarse cells, uniformly refined ``levels`` times.

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
    sel = select_cells(mesh, box=box, level_set=level_set, cells=cells)
    sub = mesh.restrict(sel)
    return sub.refined(int(levels)) if levels else sub
