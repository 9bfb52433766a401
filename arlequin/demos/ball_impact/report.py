"""The ball-impact demo's results folder: its results with units and its picture.

``ball_impact.png``: the contact force against time with Hertz's (elastic regime), and the final
meshes near the contact (coarse cells outlined, fine cells filled, the block's equivalent plastic
strain in the plastic regime). SI units; see :mod:`arlequin.demos.ball_impact`.
"""

from __future__ import annotations

import numpy as np

from .result import RESULT_UNITS, BallImpactResult, hertz_force_history

__all__ = ["picture", "write_outputs"]


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


def write_outputs(folder, result: BallImpactResult, bodies, res) -> None:
    """The results with units and the picture, then close the folder."""
    data = result.to_json()
    keys = [k for k in RESULT_UNITS if k in data]
    folder.add_results({k: data[k] for k in keys}, RESULT_UNITS)
    picture(result, bodies, res, str(folder.picture("ball_impact")))
    folder.finish()
