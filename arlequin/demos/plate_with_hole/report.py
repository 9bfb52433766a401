"""What a plate-with-hole run writes besides its history: the cell fields of each frame and
its pictures (the load against the loaded edge's displacement; the plastic zone at the end)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ...io import ResultsFolder
from .result import PlateWithHoleResult
from .setup import PlateSetup

__all__ = ["cell_fields", "plot_load_curve", "plot_plastic_zone", "write_pictures"]


def _on_block_cells(setup: PlateSetup, values: np.ndarray) -> np.ndarray:
    """Values on the J2 model's cells as values on its block's cells (graded: 0 outside the
    zone)."""
    if setup.zone_cells is None:
        return values
    out = np.zeros(setup.problem.mesh.nelements)
    out[setup.zone_cells] = values
    return out


def cell_fields(setup: PlateSetup) -> Callable[[Any], dict[str, dict[str, np.ndarray]]]:
    """The cell data of a frame: the J2 model's ε̄p and von Mises stress, cell means."""

    def fields(solver: Any) -> dict[str, dict[str, np.ndarray]]:
        state = solver.states[setup.plastic_block][setup.plastic_term]
        return {
            setup.plastic_block: {
                "eqps": _on_block_cells(setup, np.asarray(state.eqps).mean(axis=1)),
                "von_mises": _on_block_cells(setup, np.asarray(state.von_mises).mean(axis=1)),
            }
        }

    return fields


def plot_load_curve(result: PlateWithHoleResult, path: str) -> None:
    """The remote traction S against the mean displacement of the loaded edge."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    h, c = result.history, result.config
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(np.array(h["displacement"]) * 1e6, np.array(h["load"]) / 1e6, "o-",
            label=f"{c['model']} ({c['material']})")  # fmt: skip
    ax.axhline(result.first_yield_load / 1e6, color="0.5", ls=":", label="first yield")
    ax.set_xlabel("mean x-displacement of the loaded edge (µm)")
    ax.set_ylabel("remote traction S (MPa)")
    ax.set_title(f"plate with a hole, a = {c['radius'] * 1e3:g} mm")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_plastic_zone(setup: PlateSetup, state: Any, path: str, radius: float) -> None:
    """ε̄p over the J2 model's cells at the end of the run (within 5 hole radii), the coarse
    mesh's edges beside."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    mesh = setup.plastic_model.mesh
    polys = np.transpose(mesh.p[:, mesh.t], (2, 1, 0))
    fig, ax = plt.subplots(figsize=(5.5, 5))
    coll = PolyCollection(polys, array=np.asarray(state.eqps).mean(axis=1), cmap="viridis",
                          edgecolors="none")  # fmt: skip
    ax.add_collection(coll)
    coarse = setup.coarse
    ax.add_collection(PolyCollection(np.transpose(coarse.p[:, coarse.t], (2, 1, 0)),
                                     facecolors="none", edgecolors="0.6",
                                     linewidths=0.4))  # fmt: skip
    eqps = np.asarray(state.eqps)
    x = np.asarray(setup.plastic_model.quadrature_points())
    ax.plot(x[0][eqps > 0], x[1][eqps > 0], ",", color="w")
    ax.set_xlim(0.0, 5.0 * radius)
    ax.set_ylim(0.0, 5.0 * radius)
    ax.set_aspect("equal")
    fig.colorbar(coll, ax=ax, label="equivalent plastic strain")
    ax.set_title("plastic zone (white: points with ε̄p > 0)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def write_pictures(folder: ResultsFolder, setup: PlateSetup, qs: Any,
                   result: PlateWithHoleResult) -> None:  # fmt: skip
    """The run's pictures in its results folder."""
    plot_load_curve(result, str(folder.picture("load_displacement")))
    state = qs.states[setup.plastic_block][setup.plastic_term]
    plot_plastic_zone(setup, state, str(folder.picture("plastic_zone")), result.config["radius"])
