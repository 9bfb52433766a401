"""What a pressure-vessel run writes besides its history: the cell fields of each frame and
its pictures (the pressure against the outer displacement with Hill's curve; the plastic zone
at the end)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ...geometry.facets import cyclic_quad_faces
from ...io import ResultsFolder
from ...problem.arlequin_problem import von_mises_of
from ..adaptive_options import growth_title
from ..plastic_report import mark_peak
from .hill import cylinder_limit_load, sphere_limit_load, sphere_outer_displacement
from .measures import von_mises
from .result import PressureVesselResult
from .setup import VesselSetup

__all__ = [
    "AdaptationPictures",
    "cell_fields",
    "coarse_von_mises",
    "plane_polygons",
    "plot_patch_size",
    "plot_plastic_zone",
    "plot_pressure_curve",
    "write_pictures",
]


def cell_fields(setup: VesselSetup) -> Callable[[Any], dict[str, dict[str, np.ndarray]]]:
    """The cell data of a frame: the J2 model's ε̄p and von Mises stress, and the coarse
    elastic model's von Mises stress (where it has a patch over it), cell means."""

    def fields(solver: Any) -> dict[str, dict[str, np.ndarray]]:
        state = solver.states[setup.plastic_block][0]
        out = {
            setup.plastic_block: {
                "eqps": np.asarray(state.eqps).mean(axis=1),
                "von_mises": von_mises(state).mean(axis=1),
            }
        }
        if setup.plastic_block != "coarse":
            out["coarse"] = {"von_mises": coarse_von_mises(setup.problem.coarse, solver)}
        return out

    return fields


def coarse_von_mises(coarse: Any, solver: Any) -> np.ndarray:
    """The von Mises stress (Pa) of the coarse elastic model at the solver's displacement,
    cell means, shape (n_cells,): where it exceeds σy outside the patch, the patch is too
    small (``max_coarse_yield_ratio``); over the patch it is the coarse model's elastic field,
    not the material's (the patch's own ``von_mises`` is)."""
    u = solver.u[solver.system.dofmap["coarse"].slice]
    return von_mises_of(coarse.stress_at_quadrature(u)).mean(axis=1)


def plot_pressure_curve(result: PressureVesselResult, config: dict, path: str) -> None:
    """The bore pressure against the outer displacement, and Hill's (sphere) or the limit
    load (cylinder)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    h = result.history
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(np.array(h["outer_displacement"]) * 1e6, np.array(h["pressure"]) / 1e6, "o-",
            label=f"{config['model']} ({config['material']})")  # fmt: skip
    a, b, sy = config["inner"], config["outer"], config["yield_stress"]
    if config["shape"] == "sphere":
        p = np.linspace(0.0, 0.999 * sphere_limit_load(a, b, sy), 200)
        u = [sphere_outer_displacement(x, a, b, config["young"], config["poisson"], sy)
             for x in p]  # fmt: skip
        ax.plot(np.array(u) * 1e6, p / 1e6, "k--", label="Hill (exact)")
    else:
        ax.axhline(cylinder_limit_load(a, b, sy) / 1e6, color="k", ls="--",
                   label="limit load (2/√3) σy ln(b/a)")  # fmt: skip
    ax.set_xlabel("outer radial displacement (µm)")
    ax.set_ylabel("bore pressure (MPa)")
    ax.set_title(f"thick {config['shape']}, a = {a * 1e3:g} mm, b = {b * 1e3:g} mm")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plane_polygons(mesh: Any) -> tuple[np.ndarray, np.ndarray]:
    """The mesh's cells as polygons in the plane of the pictures, and the cell of each.

    A plane mesh gives its cells; a solid mesh the faces of its boundary lying on the symmetry
    plane z = 0 (drawn in x, y), each with the cell it bounds, so the plastic zone of a 3D
    run shows on that plane (matplotlib draws plane polygons only).

    Parameters
    ----------
    mesh : skfem.Mesh
        A 2D or 3D mesh.

    Returns
    -------
    polygons : ndarray, shape (n_polygons, n_vertices, 2)
        The vertices (m), in order around each polygon.
    cells : ndarray of int, shape (n_polygons,)
        The cell each polygon belongs to.
    """
    if mesh.p.shape[0] == 2:
        return np.transpose(mesh.p[:, mesh.t], (2, 1, 0)), np.arange(mesh.t.shape[1])
    facets = mesh.boundary_facets()
    tol = 1e-9 * float(np.ptp(mesh.p, axis=1).max())
    on_plane = np.all(np.abs(mesh.p[2, mesh.facets[:, facets]]) <= tol, axis=0)
    facets = facets[on_plane]
    nodes = mesh.facets[:, facets]
    if nodes.shape[0] == 4:  # scikit-fem stores a hexahedron's faces with sorted vertices
        nodes = cyclic_quad_faces(mesh.p, nodes)
    return np.transpose(mesh.p[:2, nodes], (2, 1, 0)), mesh.f2t[0, facets]


def plot_plastic_zone(setup: VesselSetup, state: Any, path: str,
                      title: str = "plastic zone over the coarse mesh",
                      peak: dict[str, Any] | None = None) -> None:  # fmt: skip
    """ε̄p over the J2 model's cells at the end of the run, the coarse mesh's edges beside
    (a 3D run: on its symmetry plane z = 0, :func:`plane_polygons`)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    polys, cells = plane_polygons(setup.plastic_model.mesh)
    fig, ax = plt.subplots(figsize=(5, 5))
    coll = PolyCollection(polys, array=np.asarray(state.eqps).mean(axis=1)[cells],
                          cmap="viridis", edgecolors="none")  # fmt: skip
    ax.add_collection(coll)
    coarse, _ = plane_polygons(setup.meshes.coarse)
    ax.add_collection(PolyCollection(coarse, facecolors="none", edgecolors="0.6",
                                     linewidths=0.4))  # fmt: skip
    ax.autoscale()
    ax.set_aspect("equal")
    fig.colorbar(coll, ax=ax, label="equivalent plastic strain")
    if setup.meshes.coarse.p.shape[0] == 3:
        title += " (plane z = 0)"
    ax.set_title(title, fontsize=10)
    if peak is not None:  # where the largest plastic strain lies, in the band or not
        mark_peak(ax, peak)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def write_pictures(folder: ResultsFolder, setup: VesselSetup, qs: Any,
                   result: PressureVesselResult) -> None:  # fmt: skip
    """The run's pictures in its results folder."""
    plot_pressure_curve(result, result.config, str(folder.picture("pressure_displacement")))
    state = qs.states[setup.plastic_block][0]
    plot_plastic_zone(setup, state, str(folder.picture("plastic_zone")), peak=result.to_json())
    if result.adaptations:
        plot_patch_size(result, str(folder.picture("patch_size")))


class AdaptationPictures:
    """A listener of an adaptive run: the plastic zone over the grown patch, one picture a
    growth (``patch_K.png``, from the fields the growth started from, re-solved); ``count``
    the growths so far (a resumed run: their pictures, on disk, listed again)."""

    def __init__(self, folder: ResultsFolder, setup: VesselSetup,
                 history: dict[str, list[Any]], count: int = 0) -> None:  # fmt: skip
        # history: the recorder's, whose last pressure is the committed state's (the growth's)
        self.folder, self.setup, self.history, self.count = folder, setup, history, int(count)
        for k in range(1, self.count + 1):
            folder.picture(f"patch_{k}")

    def __call__(self, solver: Any) -> None:
        """Nothing after a step."""

    def on_adapt(self, solver: Any, adapt: Any) -> None:
        """A picture of the patch just grown (called by the adaptation after each growth)."""
        self.count += 1
        state = solver.states[self.setup.plastic_block][0]
        rec = adapt.records[-1]
        pressure = self.history["pressure"][-1]  # the committed step the patch grew from
        title = growth_title(self.count, f"P = {pressure / 1e6:.4g} MPa (step {rec.step})",
                             rec.rejected, f"{rec.patch_fraction:.3f} of the wall")  # fmt: skip
        plot_plastic_zone(self.setup, state, str(self.folder.picture(f"patch_{self.count}")),
                          title)  # fmt: skip


def plot_patch_size(result: PressureVesselResult, path: str) -> None:
    """The patch's share of the wall and the plastic zone's, in the same measure, against the
    bore pressure.

    The patch's share is of the wall's section area (2D: the quarter annulus of the plane-strain
    cylinder or the sphere's meridian section; 3D: of the octant's volume); the plastic zone
    a ≤ r ≤ c covers (c² − a²)/(b² − a²) of that area in 2D, (c³ − a³)/(b³ − a³) of the volume
    in 3D, so the two curves compare (the patch must stay above the plastic zone).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    h = result.history
    p = np.array(h["pressure"]) / 1e6
    a, b = result.config["inner"], result.config["outer"]
    dim = int(result.config.get("dim", 2))
    measure = "volume" if dim == 3 else "section area"
    c = np.clip(np.array(h["plastic_radius"], dtype=float), a, b)
    plastic = (c**dim - a**dim) / (b**dim - a**dim)
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.step(p, h["patch_fraction"], where="post", label="J2 patch")
    ax.plot(p, plastic, "o-", label="plastic zone a ≤ r ≤ c")
    ax.set_xlabel("bore pressure (MPa)")
    ax.set_ylabel(f"share of the wall's {measure}")
    ax.set_ylim(0.0, 1.05)
    ax.set_title(f"adaptive patch: {len(result.adaptations)} growths, plastic front c "
                 f"{c[-1] * 1e3:.4g} mm at {p[-1]:.4g} MPa", fontsize=10)  # fmt: skip
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
