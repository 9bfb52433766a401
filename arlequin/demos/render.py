"""Pictures of deformed meshes with pyvista, off-screen (PNG).

pyvista renders through VTK's off-screen path (EGL with the pip wheel) when
``pyvista.OFF_SCREEN`` is set, so no display is needed.
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

__all__ = ["render_taylor_bar"]


def _offscreen():
    """pyvista, off-screen; without a display, VTK's EGL window directly (it would try X first
    and print a warning)."""
    if not os.environ.get("DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import pyvista as pv

    pv.OFF_SCREEN = True
    return pv


def _quad_grid(points2d: np.ndarray, cells: np.ndarray, mirror: bool):
    """A pyvista grid of Q1 cells (4, n) on (r, z) points (2, n_p), mirrored about r = 0."""
    import pyvista as pv

    pts = np.column_stack([points2d[0], points2d[1], np.zeros(points2d.shape[1])])
    conn = cells.T
    if mirror:
        flipped = pts * np.array([-1.0, 1.0, 1.0])
        conn = np.vstack([conn, conn[:, ::-1] + pts.shape[0]])
        pts = np.vstack([pts, flipped])
    flat = np.hstack([np.full((conn.shape[0], 1), 4), conn]).ravel()
    types = np.full(conn.shape[0], pv.CellType.QUAD, dtype=np.uint8)
    return pv.UnstructuredGrid(flat, types, pts)


def render_taylor_bar(model: Any, u: np.ndarray, state: Any, path: str, title: str = "") -> None:
    """The final (r, z) section of a Taylor bar, mirrored about the axis, coloured by ε̄p, with
    the reference outline; written to ``path`` (PNG)."""
    pv = _offscreen()
    mesh = model.mesh
    x = model.current_coordinates(u)
    eqps = np.asarray(state.eqps).mean(axis=1)
    grid = _quad_grid(x, mesh.t, mirror=True)
    grid.cell_data["equivalent plastic strain"] = np.concatenate([eqps, eqps])
    ref = _quad_grid(mesh.p, mesh.t, mirror=True).extract_feature_edges(
        boundary_edges=True, feature_edges=False, manifold_edges=False
    )
    plotter = pv.Plotter(off_screen=True, window_size=(1000, 1100))
    plotter.set_background("white")
    bar_args = {"color": "black", "title": "equivalent plastic strain", "vertical": True,
                "position_x": 0.85, "position_y": 0.25, "height": 0.5, "width": 0.06}
    plotter.add_mesh(grid, scalars="equivalent plastic strain", cmap="viridis", show_edges=True,
                     edge_color="#555555", line_width=0.3, scalar_bar_args=bar_args)  # fmt: skip
    plotter.add_mesh(ref, color="gray", line_width=1.0)
    plotter.add_text(title, position="upper_left", font_size=10, color="black")
    plotter.view_xy()
    plotter.screenshot(path)
    plotter.close()
