"""The patch test's meshes: random coarse + patch layouts (1D, 2D, axisymmetric, 3D) and the
uniform 2D grids of the strip and square layouts (lengths in m).

A random layout has a coarse mesh with random (but never tiny: every element at least a third of
the mean size) spacing and a patch band spanning the domain in all directions but one, glued
along straight bands at both of its ends (axisymmetric: bands normal to z). Bands are at least
one coarse element wide and the free zone between them more than two coarse elements wide, so
that no coarse mediator function meets both bands.
"""

from __future__ import annotations

import numpy as np
import skfem

from ...coupling.patches import refine_region

__all__ = ["build_layout"]


def _spacing(n: int, length: float, rng: np.random.Generator) -> np.ndarray:
    """Random positive spacings, each within [0.6, 1.4] x the mean (so >= 1/3 of it)."""
    h = rng.uniform(0.6, 1.4, n)
    return h / h.sum() * length


def _columns(rng: np.random.Generator, n_total: int, length: float, i0: int, i1: int, nb: int):
    """Node coordinates along the coupled direction with equal-width bands at both patch ends.

    Coarse columns [i0, i1) form the patch; its first and last ``nb`` columns form the bands,
    each of total width ``w`` (so one gluing width fits both bands).
    """
    h = _spacing(n_total, length, rng)
    w = h[i0 : i0 + nb].sum()
    h[i1 - nb : i1] = w / nb
    h[i0 : i0 + nb] = w / nb
    h = h / h.sum() * length
    x = np.concatenate([[0.0], np.cumsum(h)])
    x[-1] = length
    return x, x[i0 + nb] - x[i0]


def _breakpoints(segments, counts, rng) -> np.ndarray:
    """Random nodes on consecutive segments, keeping every segment end exactly (band edges)."""
    pts = [np.array([segments[0][0]])]
    for (s0, s1), k in zip(segments, counts):
        inner = s0 + np.cumsum(_spacing(k, s1 - s0, rng))[:-1]
        pts.append(np.concatenate([inner, [s1]]))
    return np.concatenate(pts)


def _perturb(mesh, rng, axes, amount, keep):
    """Move interior nodes randomly along ``axes`` by up to ``amount`` x local spacing."""
    p = mesh.p.copy()
    for ax, h in zip(axes, amount):
        lo, hi = p[ax].min(), p[ax].max()
        interior = (p[ax] > lo + 1e-12) & (p[ax] < hi - 1e-12) & keep(p)
        p[ax, interior] += rng.uniform(-h, h, interior.sum())
    return type(mesh)(p, mesh.t)


def _build_1d(rng, mesh_kind):
    n, length = 16, 1.0
    i0, nb = 3, 1 + int(rng.integers(0, 2))
    i1 = i0 + 2 * nb + 3 + int(rng.integers(0, 3))
    x, w = _columns(rng, n, length, i0, i1, nb)
    coarse = skfem.MeshLine(x)
    if mesh_kind == "nested":
        fine = refine_region(coarse, levels=int(rng.integers(1, 3)), cells=np.arange(i0, i1))
    else:
        a = x[i0] + rng.uniform(0.1, 0.4) * (x[i0 + 1] - x[i0])
        b = x[i1] - rng.uniform(0.1, 0.4) * (x[i1] - x[i1 - 1])
        # fine nodes: random, with the band inner edges a + w and b - w as nodes
        segs = [(a, a + w), (a + w, b - w), (b - w, b)]
        fine = skfem.MeshLine(_breakpoints(segs, (4, 9, 4), rng))
    return coarse, fine, w


def _build_2d(rng, mesh_kind, axisymmetric):
    # coupled direction: x (plane) or z (axisymmetric: bands normal to z)
    n_along, n_across = 12, 4
    length, width = (2.0, 1.0)
    i0, nb = 2, 1 + int(rng.integers(0, 2))
    i1 = i0 + 2 * nb + 3 + int(rng.integers(0, 3))
    s, w = _columns(rng, n_along, length, i0, i1, nb)
    t = np.concatenate([[0.0], np.cumsum(_spacing(n_across, width, rng))])
    along = 1 if axisymmetric else 0
    across = 1 - along
    cells = "quad" if mesh_kind == "nested" else "tri"

    def grid(a, b, kind):
        xs, ys = (b, a) if axisymmetric else (a, b)
        m = skfem.MeshQuad.init_tensor(xs, ys)
        return (
            m.to_meshtri()
            if kind == "tri" and hasattr(m, "to_meshtri")
            else (skfem.MeshTri.init_tensor(xs, ys) if kind == "tri" else m)
        )

    coarse = grid(s, t, cells)
    h_across = width / n_across
    coarse = _perturb(coarse, rng, [across], [0.2 * h_across], lambda p: np.ones(p.shape[1], bool))
    if mesh_kind == "nested":
        cen = coarse.p[:, coarse.t].mean(axis=1)[along]
        sel = np.nonzero((cen > s[i0]) & (cen < s[i1]))[0]
        fine = refine_region(coarse, levels=int(rng.integers(1, 3)), cells=sel)
    else:
        a = s[i0] + rng.uniform(0.1, 0.4) * (s[i0 + 1] - s[i0])
        b = s[i1] - rng.uniform(0.1, 0.4) * (s[i1] - s[i1 - 1])
        segs = [(a, a + w), (a + w, b - w), (b - w, b)]
        sf = _breakpoints(segs, (3, 10, 3), rng)
        tf = np.concatenate([[0.0], np.cumsum(_spacing(7, width, rng))])
        fine = grid(sf, tf, "tri")
        fine = _perturb(fine, rng, [across], [0.2 * width / 7], lambda p: np.ones(p.shape[1], bool))
    return coarse, fine, w


def _build_3d(rng, mesh_kind):
    n_along, length = 9, 2.0
    i0, nb = 1, 1
    i1 = i0 + 2 * nb + 3
    x, w = _columns(rng, n_along, length, i0, i1, nb)
    y = np.concatenate([[0.0], np.cumsum(_spacing(2, 1.0, rng))])
    z = np.concatenate([[0.0], np.cumsum(_spacing(2, 1.0, rng))])
    if mesh_kind == "nested":
        coarse = skfem.MeshHex.init_tensor(x, y, z)
        coarse = _perturb(coarse, rng, [1, 2], [0.1, 0.1], lambda p: np.ones(p.shape[1], bool))
        cen = coarse.p[:, coarse.t].mean(axis=1)[0]
        sel = np.nonzero((cen > x[i0]) & (cen < x[i1]))[0]
        fine = refine_region(coarse, levels=1, cells=sel)
        return coarse, fine, w
    # non-nested tetrahedra: the coarse grid's tetrahedra, and a patch slab (x in [a, b], all
    # of y and z) on its own grid, its band edges a + w and b − w node planes, both perturbed
    # across (the planes x = const stay planes: the ramp weights stay exact on the bands)
    coarse = skfem.MeshTet.init_tensor(x, y, z)
    coarse = _perturb(coarse, rng, [1, 2], [0.1, 0.1], lambda p: np.ones(p.shape[1], bool))
    a = x[i0] + rng.uniform(0.1, 0.4) * (x[i0 + 1] - x[i0])
    b = x[i1] - rng.uniform(0.1, 0.4) * (x[i1] - x[i1 - 1])
    xf = _breakpoints([(a, a + w), (a + w, b - w), (b - w, b)], (2, 5, 2), rng)
    yf = np.concatenate([[0.0], np.cumsum(_spacing(3, 1.0, rng))])
    zf = np.concatenate([[0.0], np.cumsum(_spacing(3, 1.0, rng))])
    fine = skfem.MeshTet.init_tensor(xf, yf, zf)
    fine = _perturb(fine, rng, [1, 2], [0.1, 0.1], lambda p: np.ones(p.shape[1], bool))
    return coarse, fine, w


def _build_grid_patch(layout: str, mesh_kind: str, ratio: int, band_cells: int):
    """Uniform 2D grids (coarse cell h = 0.25 m): a strip spanning the domain from bottom to
    top (it touches the coarse boundary), or a square inside it; the fine mesh has ``ratio``
    cells per coarse cell edge (nested quadrilaterals, or non-nested triangles)."""
    h = 0.25
    if layout == "strip":
        nx, ny = 4 + 2 * band_cells + 4, 4
        i0, i1, j0, j1 = 2, nx - 2, 0, ny
    else:
        n_patch = 2 * band_cells + 2
        nx = ny = n_patch + 4
        i0, i1, j0, j1 = 2, 2 + n_patch, 2, 2 + n_patch
    xc, yc = np.arange(nx + 1) * h, np.arange(ny + 1) * h
    xf = np.linspace(xc[i0], xc[i1], (i1 - i0) * ratio + 1)
    yf = np.linspace(yc[j0], yc[j1], (j1 - j0) * ratio + 1)
    if mesh_kind == "nested":
        coarse, fine = skfem.MeshQuad.init_tensor(xc, yc), skfem.MeshQuad.init_tensor(xf, yf)
    else:
        coarse, fine = skfem.MeshTri.init_tensor(xc, yc), skfem.MeshTri.init_tensor(xf, yf)
        # mirrored about the patch's mid-line: the same nodes, the other diagonals, so that
        # the fine triangles do not refine the coarse ones (an intersection overlap)
        p = fine.p.copy()
        p[0] = xc[i0] + xc[i1] - p[0]
        fine = skfem.MeshTri(p, fine.t)
    return coarse, fine, band_cells * h


def build_layout(rng: np.random.Generator, dim: str, mesh_kind: str, layout: str, ratio: int,
                 band_cells: int):  # fmt: skip
    """The coarse mesh, the patch mesh and the gluing width (m) of a checked configuration."""
    if layout != "random":
        return _build_grid_patch(layout, mesh_kind, int(ratio), int(band_cells))
    if dim == "1":
        return _build_1d(rng, mesh_kind)
    if dim == "3":
        return _build_3d(rng, mesh_kind)
    return _build_2d(rng, mesh_kind, dim == "axi")
