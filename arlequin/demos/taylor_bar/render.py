"""Pictures of the axisymmetric Taylor bar with pyvista, off-screen (PNG): the final (r, z)
section of one mesh, and the Arlequin pair as the source paper's Figure 2."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..render import _offscreen

__all__ = ["render_arlequin_bar", "render_taylor_bar"]


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
    grid.cell_data["equivalent plastic strain (cell mean)"] = np.concatenate([eqps, eqps])
    ref = _quad_grid(mesh.p, mesh.t, mirror=True).extract_feature_edges(
        boundary_edges=True, feature_edges=False, manifold_edges=False
    )
    plotter = pv.Plotter(off_screen=True, window_size=(1000, 1100))
    plotter.set_background("white")
    bar_args = {"color": "black", "title": "plastic strain (cell mean)",
                "vertical": True, "position_x": 0.85, "position_y": 0.25, "height": 0.5,
                "width": 0.06}  # fmt: skip
    plotter.add_mesh(grid, scalars="equivalent plastic strain (cell mean)", cmap="viridis",
                     show_edges=True, edge_color="#555555", line_width=0.3,
                     scalar_bar_args=bar_args)  # fmt: skip
    plotter.add_mesh(ref, color="gray", line_width=1.0)
    plotter.add_text(title, position="upper_left", font_size=10, color="black")
    plotter.view_xy()
    plotter.screenshot(path)
    plotter.close()


def _mirrored(grid):
    """A grid reflected about r = 0 (the left half of a section picture)."""
    out = grid.copy()
    out.points = out.points * np.array([-1.0, 1.0, 1.0])
    return out


def render_arlequin_bar(bar: Any, u: np.ndarray, state: Any, path: str, title: str = "") -> None:
    """The Arlequin Taylor bar as the source paper's Figure 2, initial and final (PNG).

    Each panel shows the (r, z) section: on the left of the axis the coarse model, on the right
    the refined patch, with the gluing band's edges in red. Left panel, the reference
    configuration: the coarse cells outside the patch (grey), in the gluing band (orange) and
    under the patch below the band (white: weight ε, not glued), the patch in blue. Right panel,
    the end of the run: the coarse cells reaching above the band's lower edge and the patch
    coloured by ε̄p.
    """
    pv = _offscreen()
    s = bar.sizes
    cmesh, fmesh = bar.coarse_mesh, bar.fine_mesh
    z_mid = cmesh.p[1, cmesh.t].mean(axis=0)
    z_band = s.patch_length - s.gluing_width
    zone = np.where(z_mid > s.patch_length, 0.0, np.where(z_mid > z_band, 1.0, 2.0))
    eqps = np.asarray(state.eqps).mean(axis=1)
    uc, uf = bar.split(u)
    plotter = pv.Plotter(off_screen=True, shape=(1, 2), window_size=(1400, 1000))
    bar_args = {"color": "black", "title": "plastic strain (cell mean)",
                "vertical": True, "position_x": 0.72, "position_y": 0.25, "height": 0.5,
                "width": 0.05}  # fmt: skip
    band = fmesh.p[1] >= z_band - 1e-9 * s.patch_length
    edge_nodes = [np.nonzero(np.isclose(fmesh.p[1], z) & band)[0] for z in (z_band, s.patch_length)]
    for col in (0, 1):
        plotter.subplot(0, col)
        plotter.set_background("white")
        final = col == 1
        xc = cmesh.p + uc.reshape(-1, 2).T if final else cmesh.p
        xf = fmesh.p + uf.reshape(-1, 2).T if final else fmesh.p
        cells = bar.drawn_coarse_cells if final else np.arange(cmesh.nelements)
        coarse = _mirrored(_quad_grid(xc, cmesh.t[:, cells], mirror=False))
        coarse.cell_data["zone"] = zone[cells]
        plotter.add_mesh(coarse, scalars="zone", cmap=["#b0b0b0", "#f4a261", "#ffffff"],
                         clim=(0, 2), show_edges=True, edge_color="black", line_width=1.0,
                         show_scalar_bar=False)  # fmt: skip
        patch = _quad_grid(xf, fmesh.t, mirror=False)
        if final:
            patch.cell_data["equivalent plastic strain (cell mean)"] = eqps
            plotter.add_mesh(patch, scalars="equivalent plastic strain (cell mean)",
                             cmap="viridis",
                             show_edges=True, edge_color="#444444", line_width=0.2,
                             scalar_bar_args=bar_args)  # fmt: skip
        else:
            plotter.add_mesh(patch, color="#a8c5e8", show_edges=True, edge_color="#3a5f8f",
                             line_width=0.3)  # fmt: skip
        for nodes in edge_nodes:
            nodes = nodes[np.argsort(fmesh.p[0, nodes])]
            pts = np.column_stack([xf[0, nodes], xf[1, nodes], np.zeros(nodes.size)])
            plotter.add_lines(np.repeat(pts, 2, axis=0)[1:-1], color="#d62828", width=3)
        text = title if final else (
            "initial: coarse model (left: grey alone, orange gluing band,\n"
            "white weight eps under the patch) | refined patch (right)")  # fmt: skip
        plotter.add_text(text, position="upper_left", font_size=9, color="black")
        plotter.view_xy()
    plotter.screenshot(path)
    plotter.close()
