"""The ball-impact demo's results folder: its results with units and its pictures.

``ball_impact.png``: the contact force against time with Hertz's (elastic regime), and the final
meshes near the contact (coarse cells outlined, fine cells filled, the block's equivalent plastic
strain in the plastic regime). With an adaptive block patch, ``patch_K.png`` after growth K (the
block's patch over its coarse mesh, the plastic zone in it: :class:`AdaptationPictures`) and
``patch_size.png`` (the patch's share of the block against time, with the contact force). SI
units; see :mod:`arlequin.demos.ball_impact`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..adaptive_options import growth_title
from .result import RESULT_UNITS, BallImpactResult, hertz_force_history

__all__ = ["AdaptationPictures", "picture", "plot_block_patch", "plot_patch_size",
           "write_outputs"]  # fmt: skip


def picture(result: BallImpactResult, bodies, res, path: str) -> None:
    """Save the run's picture to ``path`` (PNG): the contact force (kN) against time (µs) with
    Hertz's, and the final meshes near the contact (module docstring)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.8))
    t = np.asarray(result.history["t"]) * 1e6
    ax1.plot(t, np.asarray(result.history["contact_force"]) * 1e-3, lw=1.2,
             label=f"{result.config.get('model')}")  # fmt: skip
    if result.hertz:
        th, fh = hertz_force_history(bodies.ball_mass, result.config["velocity"],
                                     result.hertz["hertz_peak_force"],
                                     result.hertz["hertz_contact_duration"])  # fmt: skip
        ax1.plot(th * 1e6, fh * 1e-3, "k--", lw=1.0, label="Hertz")
    ax1.set_xlabel("t (µs)")
    ax1.set_ylabel("contact force (kN)")
    ax1.legend()
    ax1.set_title(f"ball impact, {result.config.get('regime')} regime, "
                  f"v0 = {result.config.get('velocity')} m/s")  # fmt: skip
    dm = bodies.system.dofmap

    def polygons(mesh, u):
        x = mesh.p + np.stack([u[0::2], u[1::2]])
        return np.transpose(np.moveaxis(x[:, mesh.t], 0, -1), (1, 0, 2))  # (cells, 4, 2)

    for name, mesh in bodies.meshes.items():
        fine = name.endswith(".patch") or bodies.model != "arlequin"
        pc = PolyCollection(polygons(mesh, res.u[dm[name].slice]),
                            facecolors="#c8d7e8" if fine else "none",
                            edgecolors="#a9bccf" if fine else "#7a8da3",
                            linewidths=0.15 if fine else 0.4)  # fmt: skip
        ax2.add_collection(pc)
    plastic = bodies.plastic_strain(res.states)
    if plastic is not None:
        mesh, eqps = plastic
        pc = PolyCollection(polygons(mesh, bodies.j2_displacement(res.u)), array=eqps,
                            cmap="viridis", edgecolors="none")  # fmt: skip
        ax2.add_collection(pc)
        fig.colorbar(pc, ax=ax2, label="equivalent plastic strain (cell mean)")
    if bodies.block_block is None:
        ax2.axhline(0.0, color="k", lw=1.5)  # the rigid wall
    reach = 2.0 * bodies.sizes.reach
    ax2.set_xlim(0.0, reach)
    ax2.set_ylim(-reach, reach)
    ax2.set_aspect("equal")
    ax2.set_title("final state: coarse cells outlined, fine cells filled")
    ax2.set_xlabel("r (m)")
    ax2.set_ylabel("z (m)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _quads(mesh) -> np.ndarray:
    """The cells of a quadrilateral mesh as polygons, shape (n_cells, 4, 2) (m)."""
    return np.transpose(mesh.p[:, mesh.t], (2, 1, 0))


def plot_block_patch(bodies, states: dict, path: str, title: str) -> None:
    """The block's patch over its coarse mesh near the contact (undeformed: the dent is a
    hundredth of the patch), the patch's elastic cells filled, its plastic cells coloured by
    their mean ε̄p, saved to ``path`` (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    coarse, patch = bodies.meshes["block.coarse"], bodies.meshes["block.patch"]
    eqps = bodies.plastic_strain(states)[1]
    plastic = eqps > 0.0
    fig, ax = plt.subplots(figsize=(5.5, 5))
    polys = _quads(patch)
    ax.add_collection(PolyCollection(polys[~plastic], facecolors="#c8d7e8", edgecolors="#a9bccf",
                                     linewidths=0.15))  # fmt: skip
    if plastic.any():
        pc = PolyCollection(polys[plastic], array=eqps[plastic], cmap="viridis",
                            edgecolors="none")  # fmt: skip
        ax.add_collection(pc)
        fig.colorbar(pc, ax=ax, label="equivalent plastic strain (cell mean)")
    ax.add_collection(PolyCollection(_quads(coarse), facecolors="none", edgecolors="#5a6d83",
                                     linewidths=0.4))  # fmt: skip
    # the view: the patch and a quarter more, within the block
    reach = 1.25 * float(np.hypot(patch.p[0], patch.p[1]).max())
    ax.set_xlim(0.0, min(reach, float(coarse.p[0].max())))
    ax.set_ylim(max(-reach, float(coarse.p[1].min())), 0.0)
    ax.set_aspect("equal")
    ax.set_xlabel("r (m)")
    ax.set_ylabel("z (m)")
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


class AdaptationPictures:
    """An ``on_step`` listener of an adaptive run (after the :class:`ImpactRecorder`, which
    follows the grown bodies): ``patch_K.png`` after growth K, from the fields moved onto the
    grown patch."""

    def __init__(self, folder, bodies) -> None:
        self.folder, self.bodies, self.count = folder, bodies, 0

    def __call__(self, integ: Any) -> None:
        """Nothing after a step."""

    def on_adapt(self, integ: Any, adapt: Any) -> None:
        """The picture of the patch just grown."""
        self.count += 1
        rec = adapt.records[-1]
        title = growth_title(self.count, f"t = {rec.time * 1e6:.3g} µs", rec.rejected,
                             f"{rec.patch_fraction:.3f} of the block")  # fmt: skip
        plot_block_patch(self.bodies, integ.states,
                         str(self.folder.picture(f"patch_{self.count}")), title)  # fmt: skip


def plot_patch_size(history: dict, growths: list[tuple[float, float]], path: str) -> None:
    """The adaptive patch's share of the block's area against time (``history``'s ``t``,
    ``patch_fraction`` and ``contact_force``, the recorder's rows), the ``growths`` (time s,
    share after it) marked, the contact force beside, saved to ``path`` (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.asarray(history["t"]) * 1e6
    fig, ax = plt.subplots(figsize=(6.5, 4))
    ax.step(t, history["patch_fraction"], where="post", color="C0", label="patch")
    if growths:
        ax.plot([g[0] * 1e6 for g in growths], [g[1] for g in growths], "o", color="C0", ms=3,
                label="growths")  # fmt: skip
    ax.set_xlabel("t (µs)")
    ax.set_ylabel("patch's share of the block's (r, z) area")
    ax.legend(loc="lower right")
    force = ax.twinx()
    force.plot(t, np.asarray(history["contact_force"]) * 1e-3, color="0.6", lw=0.8)
    force.set_ylabel("contact force (kN)", color="0.4")
    last = history["patch_fraction"][-1] if len(t) else float("nan")
    ax.set_title(f"adaptive block patch: {len(growths)} growths, {last:.3f} at t = "
                 f"{t[-1] if len(t) else 0.0:.3g} µs")  # fmt: skip
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def write_outputs(folder, result: BallImpactResult, bodies, res) -> None:
    """The results with units and the picture, then close the folder."""
    data = result.to_json()
    keys = [k for k in RESULT_UNITS if k in data]
    folder.add_results({k: data[k] for k in keys}, RESULT_UNITS)
    picture(result, bodies, res, str(folder.picture("ball_impact")))
    if "patch_fraction" in result.history:  # an adaptive block patch
        growths = [(a["time"], a["patch_fraction"]) for a in result.adaptations]
        plot_patch_size(result.history, growths, str(folder.picture("patch_size")))
    # a message like the other demos' (the quasi-static ones say where the load stopped)
    folder.finish("complete", f"reached t = {result.t_end:.6g} s")
