"""What a plate-with-hole run writes besides its history: the cell fields of each frame and
its pictures (the load against the loaded edge's displacement; the plastic zone at the end)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ...io import ResultsFolder
from ...problem.arlequin_problem import von_mises_of
from ..adaptive_options import growth_title
from ..plastic_report import mark_peak
from .result import PlateWithHoleResult
from .setup import PlateSetup

__all__ = [
    "AdaptationPictures",
    "cell_fields",
    "plot_load_curve",
    "plot_patch_size",
    "plot_plastic_zone",
    "write_pictures",
]


def _on_block_cells(setup: PlateSetup, values: np.ndarray) -> np.ndarray:
    """Values on the J2 model's cells as values on its block's cells (graded: 0 outside the
    zone)."""
    if setup.zone_cells is None:
        return values
    out = np.zeros(setup.problem.mesh.nelements)
    out[setup.zone_cells] = values
    return out


def cell_fields(setup: PlateSetup) -> Callable[[Any], dict[str, dict[str, np.ndarray]]]:
    """The cell data of a frame: the J2 model's ε̄p and von Mises stress, and the coarse
    elastic model's von Mises stress (where it has a patch over it), cell means."""

    def fields(solver: Any) -> dict[str, dict[str, np.ndarray]]:
        state = solver.states[setup.plastic_block][setup.plastic_term]
        out = {
            setup.plastic_block: {
                "eqps": _on_block_cells(setup, np.asarray(state.eqps).mean(axis=1)),
                "von_mises": _on_block_cells(setup, np.asarray(state.von_mises).mean(axis=1)),
            }
        }
        if setup.plastic_block != "coarse":
            u = solver.u[solver.system.dofmap["coarse"].slice]
            stress = setup.problem.coarse.stress_at_quadrature(u)
            out["coarse"] = {"von_mises": von_mises_of(stress).mean(axis=1)}
        return out

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


def plot_plastic_zone(setup: PlateSetup, state: Any, path: str, radius: float,
                      title: str = "plastic zone (white: points with ε̄p > 0)",
                      peak: dict[str, Any] | None = None) -> None:  # fmt: skip
    """ε̄p over the J2 model's cells (within 5 hole radii), the coarse mesh's edges beside."""
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
    ax.set_title(title, fontsize=10)
    if peak is not None:  # where the largest plastic strain lies, in the band or not
        mark_peak(ax, peak)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


class AdaptationPictures:
    """A listener of an adaptive run: the plastic zone over the grown patch, one picture a
    growth (``patch_K.png``, from the fields re-solved after it)."""

    def __init__(self, folder: ResultsFolder, setup: PlateSetup, radius: float,
                 load: float) -> None:  # fmt: skip
        # load: the full remote traction S (Pa), the growths' load factors scale it
        self.folder, self.setup, self.radius, self.load, self.count = folder, setup, radius, \
            load, 0  # fmt: skip

    def __call__(self, solver: Any) -> None:
        """Nothing after a step."""

    def on_adapt(self, solver: Any, adapt: Any) -> None:
        """A picture of the patch just grown (called by the adaptation after each growth)."""
        self.count += 1
        s = self.setup
        state = solver.states[s.plastic_block][s.plastic_term]
        rec = adapt.records[-1]
        load = f"S = {rec.time * self.load / 1e6:.4g} MPa (step {rec.step})"
        title = growth_title(self.count, load, rec.rejected, f"{rec.patch_fraction:.3f} of the "
                             "plate")  # fmt: skip
        plot_plastic_zone(s, state, str(self.folder.picture(f"patch_{self.count}")),
                          self.radius, title)  # fmt: skip


def plot_patch_size(result: PlateWithHoleResult, path: str) -> None:
    """The patch's and the plastic zone's shares of the plate against the remote traction."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    h = result.history
    s = np.array(h["load"]) / 1e6
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.step(s, h["patch_fraction"], where="post", label="patch")
    a = result.config["radius"]
    w = result.config.get("half_width") or 10.0 * a
    total = w * w - 0.25 * np.pi * a * a  # the quarter plate's area (m²)
    ax.plot(s, np.array(h["plastic_area"]) / total, "o-", label="plastic zone")
    ax.set_xlabel("remote traction S (MPa)")
    ax.set_ylabel("share of the quarter plate's area")
    ax.set_title(f"adaptive patch: {result.patch_fraction:.3f} of the plate at the end")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def write_pictures(folder: ResultsFolder, setup: PlateSetup, qs: Any,
                   result: PlateWithHoleResult) -> None:  # fmt: skip
    """The run's pictures in its results folder."""
    plot_load_curve(result, str(folder.picture("load_displacement")))
    if setup.adapt is not None:
        plot_patch_size(result, str(folder.picture("patch_size")))
    state = qs.states[setup.plastic_block][setup.plastic_term]
    plot_plastic_zone(
        setup,
        state,
        str(folder.picture("plastic_zone")),
        result.config["radius"],
        peak=result.to_json(),
    )
