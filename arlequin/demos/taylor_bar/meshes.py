"""The meshes of the Taylor bar: uniform, the nested Arlequin pair's sizes, and graded.

All (r, z) meridional sections, z ∈ [0, L] from the impact face, r ∈ [0, R]; Q1 cells
(``skfem.MeshQuad``), counterclockwise. SI units.

``graded_bar_mesh`` is the single conforming mesh a user would otherwise build: the fine size
over the patch region, one transition row of 2:1 quadrilateral templates (a unit of four fine
edges below and two coarse edges above, six quadrilaterals: no hanging node, no triangle), and
the coarse size above.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import skfem

__all__ = [
    "ArlequinBarSizes",
    "arlequin_bar_sizes",
    "elements_radial_of",
    "fine_radial",
    "graded_bar_mesh",
    "positive",
    "taylor_bar_mesh",
]


def taylor_bar_mesh(length: float, radius: float, elements_radial: int) -> skfem.MeshQuad:
    """Meridional (r, z) Q1 mesh of the bar: ``elements_radial`` cells across the radius and
    round(L / h) along the axis, h = R / elements_radial (nearly square cells), z ∈ [0, L]."""
    n_r = int(elements_radial)
    n_z = max(1, round(length / (radius / n_r)))
    return skfem.MeshQuad.init_tensor(np.linspace(0.0, radius, n_r + 1),
                                      np.linspace(0.0, length, n_z + 1))  # fmt: skip


class ArlequinBarSizes:
    """The nested meshes of :class:`ArlequinBar`, snapped to coarse cell edges (SI units).

    Attributes
    ----------
    coarse_radial, coarse_axial : int
        Coarse cells across the radius and along the bar.
    ratio : int
        Fine cells per coarse cell edge (k = coarse size / fine size).
    patch_rows, band_rows : int
        Coarse rows under the patch and in the gluing band (the band is the top of the patch).
    coarse_size, fine_size : float
        Cell edges across the radius (m).
    patch_length, gluing_width : float
        The snapped patch length and band width (m).
    """

    def __init__(self, coarse_radial, coarse_axial, ratio, patch_rows, band_rows, length,
                 radius) -> None:  # fmt: skip
        self.coarse_radial, self.coarse_axial, self.ratio = coarse_radial, coarse_axial, ratio
        self.patch_rows, self.band_rows = patch_rows, band_rows
        self.coarse_size = radius / coarse_radial
        self.fine_size = self.coarse_size / ratio
        self.axial_size = length / coarse_axial  # coarse cell height
        self.patch_length = patch_rows * self.axial_size
        self.gluing_width = band_rows * self.axial_size

    def as_dict(self) -> dict[str, Any]:
        """The sizes as a dict (counts; lengths in m), for the results' inputs."""
        return {
            "coarse_radial": self.coarse_radial, "coarse_axial": self.coarse_axial,
            "ratio": self.ratio, "patch_rows": self.patch_rows, "band_rows": self.band_rows,
            "coarse_size": self.coarse_size, "fine_size": self.fine_size,
            "patch_length": self.patch_length, "gluing_width": self.gluing_width,
        }  # fmt: skip


def _smallest_divisor(n: int) -> int | None:
    for k in range(2, n + 1):
        if n % k == 0:
            return k
    return None


def arlequin_bar_sizes(
    length: float,
    radius: float,
    fine_radial: int,
    coarse_size: float | None = None,
    patch_length: float | None = None,
    gluing_width: float | None = None,
) -> ArlequinBarSizes:
    """Snap the Arlequin bar's sizes to nested meshes.

    Parameters
    ----------
    length, radius : float
        L and R (m).
    fine_radial : int
        Fine cells across the radius (fine size R / fine_radial).
    coarse_size : float, optional
        Coarse cell edge across the radius (m), a multiple k ≥ 1 of the fine size; default the
        smallest multiple k ≥ 2 that divides ``fine_radial`` (2 for an even count).
    patch_length : float, optional
        Patch length from the impact face (m), rounded to whole coarse rows; default 0.9 L.
    gluing_width : float, optional
        Gluing band width (m), rounded to whole coarse rows (at least one); default two rows.

    Raises
    ------
    ValueError
        If the coarse size is not a multiple of the fine size, if the patch does not leave at
        least one coarse row above it, or if the band does not leave at least one patch row
        under it.
    """
    n_f = int(fine_radial)
    fine = radius / n_f
    if coarse_size is None:
        k = _smallest_divisor(n_f)
        if k is None:
            raise ValueError(
                f"with 1 fine cell across the radius the coarse cells cannot be larger; give "
                f"more fine cells (got fine size {fine} m)"
            )
    else:
        if not (math.isfinite(coarse_size) and coarse_size > 0.0):
            raise ValueError(f"coarse_size must be positive and finite, got {coarse_size}")
        ratio = coarse_size / fine
        k = round(ratio)
        if k < 1 or abs(ratio - k) > 1e-6 * ratio or n_f % k:
            raise ValueError(
                f"coarse_size must be a multiple of the fine size dividing the radius: got "
                f"coarse_size={coarse_size} m, fine size {fine} m (ratio {ratio:.6g}) with "
                f"{n_f} fine cells across the radius"
            )
    n_rc = n_f // k
    n_zc = max(1, round(length / (radius / n_rc)))
    hz = length / n_zc
    if patch_length is None:
        patch_length = 0.9 * length
    if not (math.isfinite(patch_length) and 0.0 < patch_length < length):
        raise ValueError(
            f"patch_length must lie in (0, L = {length}) m, got patch_length={patch_length}"
        )
    rows = round(patch_length / hz)
    if rows < 2 or rows > n_zc - 1:
        raise ValueError(
            f"patch_length={patch_length} m gives {rows} coarse rows of {hz:.4g} m; the patch "
            f"needs at least 2 rows and must leave at least one of the {n_zc} rows above it"
        )
    if gluing_width is None:
        band = 2
    else:
        if not (math.isfinite(gluing_width) and gluing_width > 0.0):
            raise ValueError(f"gluing_width must be positive and finite, got {gluing_width}")
        band = max(1, round(gluing_width / hz))
    if band >= rows:
        raise ValueError(
            f"gluing_width={gluing_width} m gives a band of {band} coarse rows of {hz:.4g} m, "
            f"the whole patch of {rows} rows; the band must leave patch rows under it"
        )
    return ArlequinBarSizes(n_rc, n_zc, k, rows, band, length, radius)


#: The 2:1 template on the unit [0, 4] × [0, 1] (fine edges of length 1 below, coarse of length
#: 2 above): node coordinates and six counterclockwise quadrilaterals.
_TEMPLATE_NODES = np.array(
    [
        [0, 0],
        [1, 0],
        [2, 0],
        [3, 0],
        [4, 0],  # b0..b4
        [1, 0.5],
        [2, 0.5],
        [3, 0.5],  # m1, c, m3
        [0, 1],
        [2, 1],
        [4, 1],
    ],
    dtype=float,
).T  # t0, t2, t4
_TEMPLATE_QUADS = np.array([[0, 1, 5, 8], [1, 2, 6, 5], [5, 6, 9, 8],
                            [2, 3, 7, 6], [3, 4, 10, 7], [6, 7, 10, 9]]).T  # fmt: skip


def graded_bar_mesh(length: float, radius: float, sizes: ArlequinBarSizes) -> skfem.MeshQuad:
    """One conforming mesh: fine over the patch region, coarse above, one transition row.

    The fine region is the Arlequin patch's (its fine cells, z ∈ [0, patch_length]); the
    transition row is the coarse row above it, made of 2:1 templates; the coarse rows above are
    the coarse model's. With an odd number of coarse cells across the radius the outermost
    coarse column stays split in two fine-width columns (a quadrilateral layer cannot halve an
    odd number of edges).

    Raises
    ------
    ValueError
        Unless the coarse size is twice the fine size (one 2:1 transition), or if the patch
        leaves no coarse row above the transition.
    """
    s = sizes
    if s.ratio != 2:
        raise ValueError(
            f"the graded mesh joins fine and coarse cells of ratio 2 (one 2:1 transition row); "
            f"got coarse size {s.coarse_size} m = {s.ratio} x the fine size"
        )
    if s.patch_rows + 1 > s.coarse_axial:
        raise ValueError("the graded mesh needs one coarse row above the patch for its transition")
    h_f, h_z = s.fine_size, s.axial_size
    n_f = s.coarse_radial * 2
    z_p = s.patch_length
    quads: list[np.ndarray] = []  # each (2, 4, n) corner coordinates
    # fine region: a tensor grid
    fine = skfem.MeshQuad.init_tensor(np.linspace(0.0, radius, n_f + 1),
                                      np.linspace(0.0, z_p, 2 * s.patch_rows + 1))  # fmt: skip
    quads.append(fine.p[:, fine.t])
    # transition row: one template per pair of coarse columns, a pass-through pair if odd
    units = s.coarse_radial // 2
    x0 = 4.0 * h_f * np.arange(units)  # (units,)
    nodes = _TEMPLATE_NODES * np.array([[h_f], [h_z]])  # (2, 11)
    corners = nodes[:, _TEMPLATE_QUADS]  # (2, 4, 6)
    shift = np.stack([np.repeat(x0, 6), np.full(6 * units, z_p)])  # (2, 6 units)
    quads.append(np.tile(corners, (1, 1, units)) + shift[:, None, :])
    widths = [2 * h_f] * (2 * units)
    if s.coarse_radial % 2:
        r0 = 4.0 * h_f * units
        for j in range(2):  # the two fine-width columns, one cell tall
            r = r0 + j * h_f
            quads.append(np.array([[r, r + h_f, r + h_f, r], [z_p, z_p, z_p + h_z, z_p + h_z]]
                                  )[:, :, None])  # fmt: skip
        widths += [h_f, h_f]
    # coarse region above
    r_edges = np.concatenate([[0.0], np.cumsum(widths)])
    r_edges[-1] = radius
    coarse = skfem.MeshQuad.init_tensor(
        r_edges, np.linspace(z_p + h_z, length, s.coarse_axial - s.patch_rows)
    )
    quads.append(coarse.p[:, coarse.t])
    corners_all = np.concatenate(quads, axis=2)  # (2, 4, n_cells)
    pts = corners_all.transpose(0, 2, 1).reshape(2, -1)
    key = np.round(pts / (1e-6 * h_f)).astype(np.int64)
    _, first, inverse = np.unique(key, axis=1, return_index=True, return_inverse=True)
    p = pts[:, first]
    t = inverse.reshape(-1, 4).T
    p[0, np.abs(p[0] - radius) < 1e-9 * radius] = radius
    return skfem.MeshQuad(np.ascontiguousarray(p), np.ascontiguousarray(t))


def positive(name: str, value: Any) -> float:
    """``value`` as a float, or a ValueError naming ``name`` unless it is positive and finite."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.number)):
        raise ValueError(f"{name} must be a number, got {name}={value!r}")
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} must be positive and finite, got {name}={value}")
    return float(value)


def elements_radial_of(elements_radial, mesh_size, radius) -> int:
    """Cells across the radius from ``elements_radial`` (default 10) or ``mesh_size`` (m)."""
    if elements_radial is not None and mesh_size is not None:
        raise ValueError(
            f"give elements_radial or mesh_size, not both (got elements_radial={elements_radial}, "
            f"mesh_size={mesh_size})"
        )
    if mesh_size is not None:
        h = positive("mesh_size", mesh_size)
        if h > radius:
            raise ValueError(f"mesh_size must not exceed the radius {radius} m, got {h}")
        return max(1, round(radius / h))
    n = 10 if elements_radial is None else elements_radial
    if isinstance(n, bool) or int(n) != n or n < 1:
        raise ValueError(f"elements_radial must be a positive integer, got elements_radial={n}")
    return int(n)


def fine_radial(elements_radial, mesh_size, fine_size, radius) -> int:
    """Fine cells across the radius from the three aliases (the Arlequin and graded models)."""
    given = [(k, v) for k, v in (("elements_radial", elements_radial), ("mesh_size", mesh_size),
                                 ("fine_size", fine_size)) if v is not None]  # fmt: skip
    if len(given) > 1:
        raise ValueError(f"give one of elements_radial, mesh_size or fine_size, got {dict(given)}")
    size = fine_size if fine_size is not None else mesh_size
    return elements_radial_of(elements_radial, size, radius)
