"""Meshes of the ball-impact demo: the meridional half disk of a ball (an O-grid of quads) and
its refined contact patch with the nodes of its boundary on the sphere.

The ball of radius R has its centre at (0, R) in the meridional plane (r, z), so that its south
pole, where it strikes, is the origin. The O-grid has an inner block [0, s] × [R − s, R + s]
(s = 0.45 R; n × 2n cells) and three outer blocks between its edges and the arcs of the
semicircle (θ from −90° to −45°, −45° to 45°, 45° to 90°; n, 2n and n cells along, n across),
6 n² cells in all, blended linearly between the inner edge and the arc (transfinite in one
direction), every boundary node on the sphere. Along the arc the cells are 0.785 R / n long,
across 0.55 R / n.

The block of radius R_B and height H_B has its top face at z = 0 and the axis at r = 0. Its
coarse mesh is a tensor grid graded away from the contact point (first cell h_c, then each cell
:data:`GROWTH` times the last, scaled to end on R_B and −H_B); the uniform one (``mono``) has
cells of the fine size everywhere.

The contact patch refines the coarse cells within a distance of the pole ``levels`` times
(:func:`arlequin.refine_region`) and moves the new nodes of the ball's boundary radially onto
the sphere: the patch then carries the ball's curvature at its own resolution (the Hertz
contact depends on it) and reaches out of the coarse polygon by at most the sagitta h_c²/(8R)
of a coarse facet, where the coarse functions are extrapolated (the nested overlap,
``overlap_method="nested"``).
"""

from __future__ import annotations

import numpy as np
import skfem

from ...coupling.patches import refine_region

__all__ = [
    "ball_patch_mesh",
    "block_mesh",
    "block_patch_mesh",
    "graded_coordinates",
    "half_disk_mesh",
    "snap_to_sphere",
]

#: Growth ratio of the coarse block's cells away from the contact point.
GROWTH = 1.15

#: Half side of the O-grid's inner block, as a fraction of R.
INNER = 0.45


def _block(inner: np.ndarray, arc: np.ndarray, layers: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points (2, (k+1)(L+1)) and quads of the linear blend from the polyline ``inner``
    (2, k+1) to ``arc`` (2, k+1), both running with the arc's angle, at the fractions
    ``layers`` (L+1,) from 0 (inner) to 1 (arc)."""
    k = inner.shape[1] - 1
    s = np.asarray(layers, dtype=float)
    pts = (1 - s)[None, :, None] * inner[:, None, :] + s[None, :, None] * arc[:, None, :]
    pts = pts.reshape(2, -1)  # index j (k+1) + i: layer j, station i
    i, j = np.meshgrid(np.arange(k), np.arange(s.size - 1), indexing="ij")
    a = (j * (k + 1) + i).ravel()
    # stations run with the angle, layers outwards: the corner order of skfem's tensor quads
    quads = np.stack([a, a + 1, a + k + 2, a + k + 1])
    return pts, quads


def half_disk_mesh(radius: float, n: int, pole_spacing: float | None = None,
                   growth: float = GROWTH, uniform: float = 0.0) -> skfem.MeshQuad:  # fmt: skip
    """The meridional half disk r ≥ 0 of a ball of radius ``radius`` (m) centred at (0, R).

    Without ``pole_spacing``: the uniform O-grid of 6 n² quads (module docstring). With it
    (m): a conforming graded O-grid, cells of that size at the south pole (up to the distance
    ``uniform``, m, along the arc and inwards) then growing by ``growth`` along the arc
    (mirrored at the north pole, the inner block's radial lines being shared), and layers
    growing by ``growth`` inwards from the sphere (all around it: the outer blocks share their
    layers); the right block's cells along the arc match the last graded ones. ``n`` is then
    unused.
    """
    big = float(radius)
    s = INNER * big
    if pole_spacing is None:
        if int(n) != n or n < 1:
            raise ValueError(f"the ball's O-grid needs n >= 1 cells per inner side, got n={n}")
        n = int(n)
        phi = np.linspace(0.0, 0.25 * np.pi, n + 1)
        z_in = np.linspace(-s, s, 2 * n + 1)
        layers = np.linspace(0.0, 1.0, n + 1)
    else:
        if not 0.0 < pole_spacing < 0.1 * big:
            raise ValueError(f"pole_spacing must lie in (0, 0.1 R), got {pole_spacing}")
        phi = graded_coordinates(pole_spacing / big, 0.25 * np.pi, growth, uniform / big)
        last = big * (phi[-1] - phi[-2])
        m = max(1, round(0.25 * np.pi * big / last))
        z_in = np.linspace(-s, s, 2 * m + 1)
        layers = 1.0 - graded_coordinates(pole_spacing / (big - s), 1.0, growth,
                                          uniform / (big - s))[::-1]  # fmt: skip
        layers[0] = 0.0
    r_in = s * phi / phi[-1]
    k = r_in.size - 1
    q = skfem.MeshQuad.init_tensor(r_in, z_in)
    parts = [(q.p, q.t)]

    def arc(theta: np.ndarray) -> np.ndarray:
        return big * np.stack([np.cos(theta), np.sin(theta)])

    bottom = np.stack([r_in, np.full(k + 1, -s)])
    right = np.stack([np.full(z_in.size, s), z_in])
    top = np.stack([r_in[::-1], np.full(k + 1, s)])
    theta_right = np.linspace(-0.25 * np.pi, 0.25 * np.pi, z_in.size)
    for edge, a in ((bottom, arc(-0.5 * np.pi + phi)), (right, arc(theta_right)),
                    (top, arc(0.5 * np.pi - phi[::-1]))):  # fmt: skip
        parts.append(_block(edge, a, layers))
    pts = np.concatenate([p for p, _ in parts], axis=1)
    offsets = np.cumsum([0] + [p.shape[1] for p, _ in parts[:-1]])
    cells = np.concatenate([t + o for (_, t), o in zip(parts, offsets)], axis=1)
    # merge the nodes shared by the blocks (same coordinates to round-off)
    key = np.round(pts / (1e-9 * big)).astype(np.int64)
    _, first, inverse = np.unique(key, axis=1, return_index=True, return_inverse=True)
    pts = pts[:, first]
    cells = inverse.ravel()[cells]
    pts[1] += big
    pts[0, np.abs(pts[0]) < 1e-12 * big] = 0.0
    return skfem.MeshQuad(np.ascontiguousarray(pts), np.ascontiguousarray(cells))


def snap_to_sphere(mesh: skfem.Mesh, radius: float, gap: float) -> skfem.Mesh:
    """``mesh`` with its boundary nodes within ``gap`` (m) inside the sphere of radius
    ``radius`` centred at (0, R) moved radially onto it."""
    p = mesh.p.copy()
    centre = np.array([0.0, float(radius)])
    d = p - centre[:, None]
    dist = np.linalg.norm(d, axis=0)
    nodes = np.unique(mesh.facets[:, mesh.boundary_facets()])
    near = nodes[(radius - dist[nodes] <= gap) & (dist[nodes] > 0.0)]
    p[:, near] = centre[:, None] + d[:, near] * (radius / dist[near])
    p[0, np.abs(p[0]) < 1e-12 * radius] = 0.0
    return type(mesh)(np.ascontiguousarray(p), np.ascontiguousarray(mesh.t))


def ball_patch_mesh(coarse: skfem.MeshQuad, radius: float, reach: float,
                    levels: int) -> skfem.MeshQuad:  # fmt: skip
    """The contact patch: the coarse cells whose centroid lies within ``reach`` (m) of the south
    pole, refined ``levels`` times, its new boundary nodes on the sphere (module docstring)."""
    patch = refine_region(coarse, levels, level_set=lambda x: np.hypot(x[0], x[1]) - reach)
    facets = coarse.facets[:, coarse.boundary_facets()]
    longest = float(np.max(np.linalg.norm(np.diff(coarse.p[:, facets], axis=1), axis=0)))
    # the sagitta of the longest coarse facet, with a margin, bounds the new nodes' gap
    return snap_to_sphere(patch, radius, gap=1.5 * longest**2 / (8.0 * radius))


def graded_coordinates(first: float, length: float, growth: float = GROWTH,
                       uniform: float = 0.0) -> np.ndarray:  # fmt: skip
    """0 = x₀ < x₁ < … < x_k = ``length`` (m): cells of size ``first`` up to ``uniform`` (m),
    then growing from ``first`` by ``growth``, the graded part scaled so that the last node
    lands on ``length``."""
    if not (first > 0.0 and length > 0.0):
        raise ValueError(f"graded coordinates need first > 0 and length > 0, got {first}, {length}")
    n_u = int(np.ceil(uniform / first - 1e-9)) if uniform > 0.0 else 0
    if growth == 1.0 or n_u * first >= length:
        return np.linspace(0.0, length, max(1, round(length / first)) + 1)
    start = n_u * first
    rest = length - start
    k = max(1, round(np.log1p(rest * (growth - 1.0) / first) / np.log(growth)))
    x = np.concatenate([[0.0], np.cumsum(first * growth ** np.arange(k))])
    graded = start + x * (rest / x[-1])
    return np.concatenate([first * np.arange(n_u), graded])


def block_mesh(radius: float, height: float, first: float, growth: float = GROWTH,
               uniform: float = 0.0) -> skfem.MeshQuad:  # fmt: skip
    """The block's meridional rectangle [0, R_B] × [−H_B, 0] (m): cells of size ``first`` up to
    ``uniform`` (m) from the contact point along r and z, then growing by ``growth`` (1:
    uniform everywhere)."""
    r = graded_coordinates(first, radius, growth, uniform)
    z = -graded_coordinates(first, height, growth, uniform)[::-1]
    z[-1] = 0.0
    return skfem.MeshQuad.init_tensor(r, z)


def block_patch_mesh(coarse: skfem.MeshQuad, reach: float, levels: int) -> skfem.MeshQuad:
    """The block's contact patch: the coarse cells whose centroid lies within ``reach`` (m) of
    the contact point, refined ``levels`` times."""
    return refine_region(coarse, levels, level_set=lambda x: np.hypot(x[0], x[1]) - reach)
