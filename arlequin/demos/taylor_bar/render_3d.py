"""Pictures of the 3D Taylor bar (pyvista, off-screen): the final shape of the full bar.

The quarter bar is mirrored about x = 0 and y = 0 into the whole bar. A single mesh is drawn
coloured by the cell mean of ε̄p; the Arlequin pair as the coarse model translucent grey (its
cells reaching above the gluing band's lower edge) around the patch coloured by ε̄p.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...io import meshio_mesh
from ..render import _offscreen

__all__ = ["render_taylor_bar_3d"]

_MIRRORS = ((1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0))


def _full_bar(pv, mesh, displacement: np.ndarray, cells: np.ndarray, values=None):
    """The deformed cells of a quarter-bar mesh, mirrored into four copies (a pyvista grid)."""
    sub = mesh.restrict(cells) if cells.size < mesh.nelements else mesh
    keep = np.unique(mesh.t[:, cells]) if cells.size < mesh.nelements else np.arange(mesh.nvertices)
    x = mesh.p[:, keep] + displacement.reshape(-1, 3).T[:, keep]
    grids = []
    for sx, sy in _MIRRORS:
        m = meshio_mesh(type(sub)(x * np.array([[sx], [sy], [1.0]]), sub.t))
        m.points = np.ascontiguousarray(m.points)  # else pyvista copies it, with a message
        g = pv.from_meshio(m)
        if values is not None:
            g.cell_data["equivalent plastic strain (cell mean)"] = values
        grids.append(g)
    return grids[0].merge(grids[1:], merge_points=True)


def render_taylor_bar_3d(bar: Any, u: np.ndarray, state: Any, path: str, title: str = "") -> None:
    """The final state of a 3D Taylor bar (:mod:`arlequin.demos.taylor_bar.models_3d`) as a PNG.

    ``bar`` is a ``MonoBar3D`` (one mesh coloured by ε̄p) or an ``ArlequinBar3D`` (the coarse
    model translucent, the patch coloured by ε̄p); ``u`` the system's displacement (m).
    """
    pv = _offscreen()
    eqps = np.asarray(state.eqps).mean(axis=1)
    plotter = pv.Plotter(off_screen=True, window_size=(1000, 1100))
    plotter.set_background("white")
    bar_args = {"color": "black", "title": "plastic strain (cell mean)", "vertical": True,
                "position_x": 0.85, "position_y": 0.25, "height": 0.5, "width": 0.06}  # fmt: skip
    if hasattr(bar, "coarse_mesh"):
        uc, uf = bar.split(u)
        coarse = _full_bar(pv, bar.coarse_mesh, uc, bar.drawn_coarse_cells).extract_surface()
        plotter.add_mesh(coarse, color="#b0b0b0", opacity=0.25, show_edges=True,
                         edge_color="#404040", line_width=0.5)  # fmt: skip
    else:
        uf = u
    mesh = bar.fine_mesh
    patch = _full_bar(pv, mesh, uf, np.arange(mesh.nelements), eqps)
    plotter.add_mesh(patch, scalars="equivalent plastic strain (cell mean)", cmap="viridis",
                     show_edges=True, edge_color="#555555", line_width=0.3,
                     scalar_bar_args=bar_args)  # fmt: skip
    plotter.add_text(title, position="upper_left", font_size=10, color="black")
    plotter.view_vector((1.0, -0.8, 0.45), viewup=(0.0, 0.0, 1.0))  # the impacted end in front
    plotter.reset_camera()
    plotter.screenshot(path)
    plotter.close()
