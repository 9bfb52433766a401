"""Where a refinement patch goes: the inside of a closed triangulated surface.

A patch region is a predicate on points: a box, a level set φ < 0 (both in
:func:`arlequin.coupling.patches.select_cells`) or, here, the inside of a closed surface given as a
trimesh mesh or a file trimesh reads (STL, OBJ, PLY, OFF, …). The inside test is the generalised
winding number (the solid angle the surface subtends at the point over 4π: 1 inside, 0
outside): it needs no spatial index, does not miss points the way a ray grazing an edge can,
and degrades gracefully near small defects. A surface that is not closed (open edges) is
refused, since its inside is not defined.

Cost: one solid angle per (point, triangle) pair, for the points inside the surface's bounding
box only, in chunks of :data:`CHUNK` pairs (bounded memory, about 0.2 s per million pairs).
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

__all__ = ["CHUNK", "SurfaceRegion"]

#: (point, triangle) pairs evaluated at once: about 100 MB of temporaries.
CHUNK = 2_000_000


class SurfaceRegion:
    """The inside of a closed triangulated surface, as a patch region.

    Parameters
    ----------
    surface : trimesh.Trimesh, str or path
        The surface (m), or a file :func:`trimesh.load` reads as one mesh.

    Raises
    ------
    FileNotFoundError
        No such file.
    ValueError
        If the file has no triangles, or the surface is not closed (open edges: its inside is
        not defined) or its faces are not consistently oriented.

    Examples
    --------
    >>> import numpy as np, trimesh
    >>> region = SurfaceRegion(trimesh.creation.box(extents=(2.0, 2.0, 2.0)))
    >>> region(np.array([[0.0, 1.5], [0.0, 0.0], [0.0, 0.0]])).tolist()
    [True, False]
    """

    def __init__(self, surface: Any) -> None:
        import trimesh

        name = "the surface"
        if isinstance(surface, (str, os.PathLike)):
            name = f"surface file {os.fspath(surface)!r}"
            if not os.path.isfile(os.fspath(surface)):
                raise FileNotFoundError(f"{name} not found")
            surface = trimesh.load(os.fspath(surface), force="mesh")
        if not isinstance(surface, trimesh.Trimesh):
            raise ValueError(f"{name} must be a trimesh.Trimesh or a file trimesh reads as one "
                             f"mesh, got {type(surface).__name__}")  # fmt: skip
        if len(surface.faces) == 0:
            raise ValueError(f"{name} has no triangles")
        if not surface.is_watertight:
            # an edge used by one face only is open
            edges = np.sort(surface.edges, axis=1)
            _, counts = np.unique(edges, axis=0, return_counts=True)
            raise ValueError(f"{name} is not closed (watertight): {int(np.sum(counts == 1))} open "
                             "edge(s), so it has no inside; close it (e.g. trimesh's "
                             "fill_holes) or give the region as a box or a level set")  # fmt: skip
        if not surface.is_winding_consistent:
            raise ValueError(f"{name} has inconsistently oriented faces: fix its normals "
                             "(trimesh.repair.fix_normals)")  # fmt: skip
        self.vertices = np.asarray(surface.vertices, dtype=float)
        self.faces = np.asarray(surface.faces, dtype=np.int64)
        self.bounds = np.asarray(surface.bounds, dtype=float)  # (2, 3)
        self.name = name

    def winding_number(self, x: np.ndarray) -> np.ndarray:
        """The generalised winding number at points x, shape (3, n) (m): about 1 inside, 0
        outside, whatever the faces' orientation (its absolute value)."""
        x = np.asarray(x, dtype=float)
        if x.ndim != 2 or x.shape[0] != 3:
            raise ValueError(f"points must have shape (3, n) for a surface region, got {x.shape}")
        w = np.zeros(x.shape[1])
        span = self.bounds[1] - self.bounds[0]
        pad = 1e-9 * float(np.max(span))
        boxed = np.nonzero(np.all((x.T >= self.bounds[0] - pad) & (x.T <= self.bounds[1] + pad),
                                  axis=1))[0]  # fmt: skip
        tri = self.vertices[self.faces]  # (n_t, 3 corners, 3)
        step = max(1, CHUNK // len(self.faces))
        for start in range(0, boxed.size, step):
            idx = boxed[start : start + step]
            rel = tri[None, :, :, :] - x.T[idx, None, None, :]  # (k, n_t, 3, 3)
            a, b, c = rel[:, :, 0], rel[:, :, 1], rel[:, :, 2]
            la, lb, lc = (np.linalg.norm(v, axis=-1) for v in (a, b, c))
            # Van Oosterom & Strackee: tan(Ω/2) = a·(b×c) / (|a||b||c| + (a·b)|c| + …)
            num = np.einsum("ktj,ktj->kt", a, np.cross(b, c))
            den = (
                la * lb * lc
                + np.einsum("ktj,ktj->kt", a, b) * lc
                + np.einsum("ktj,ktj->kt", b, c) * la
                + np.einsum("ktj,ktj->kt", c, a) * lb
            )
            w[idx] = np.abs(np.arctan2(num, den).sum(axis=1)) / (2.0 * np.pi)
        return w

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """True at the points x, shape (3, n) (m), inside the surface."""
        return self.winding_number(x) > 0.5

    def level_set(self, x: np.ndarray) -> np.ndarray:
        """½ − winding number at x (3, n): negative inside, a level set for
        :func:`arlequin.coupling.patches.select_cells`."""
        return 0.5 - self.winding_number(x)
