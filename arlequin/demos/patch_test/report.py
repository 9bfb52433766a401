"""The patch test's results folder and its picture of the error field."""

from __future__ import annotations

import textwrap
from typing import TYPE_CHECKING

import numpy as np

from ...io import ResultsFolder, write_static
from .result import RESULT_UNITS

if TYPE_CHECKING:
    from .result import PatchTestResult

__all__ = ["plot_patch_test_error", "write_folder"]


def write_folder(folder: ResultsFolder, problem, result: PatchTestResult, meshes: dict,
                 u_exact: dict, scale: float, inputs: set[str]) -> None:  # fmt: skip
    """The solution's fields, the results (those not inputs) with their units, and the error
    picture (``patch_test_error.png``), then the folder finished.

    ``u_exact`` holds each model's exact nodal displacement (m), ``scale`` max |u| (m).
    """
    static = result.static
    write_static(folder, static.system, static, problem.field_layout())
    values = {k: v for k, v in result.to_json().items() if k not in inputs}
    folder.add_results(values, RESULT_UNITS)
    errors = {k: np.linalg.norm((static.displacements[k] - u_exact[k]).reshape(
        -1, meshes[k].dim()), axis=1) / scale for k in meshes}  # fmt: skip
    plot_patch_test_error(meshes, errors, str(folder.picture("patch_test_error")),
                          result.summary())  # fmt: skip
    folder.finish()


def plot_patch_test_error(meshes: dict, errors: dict, path: str, title: str = "") -> None:
    """The patch test's error field, one panel per model (PNG): |u_h − u| / max |u| at the
    nodes, on 1D meshes as curves, on 2D meshes coloured (quadrilaterals split in two
    triangles for the drawing). 3D meshes are not drawn (see their XDMF fields)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.tri import Triangulation

    names = [n for n in meshes if meshes[n].dim() <= 2]
    if not names:
        return
    fig, axes = plt.subplots(1, len(names), figsize=(6 * len(names), 4.5), squeeze=False)
    top = max(float(np.max(errors[n])) for n in names) or 1.0
    for ax, name in zip(axes[0], names):
        mesh, err = meshes[name], np.asarray(errors[name])
        if mesh.dim() == 1:
            order = np.argsort(mesh.p[0])
            ax.plot(mesh.p[0, order], err[order], "o-", ms=3)
            ax.set_xlabel("x (m)")
            ax.set_ylabel("|u_h − u| / max |u|")
        else:
            t = mesh.t
            tris = t.T if t.shape[0] == 3 else np.vstack([t[[0, 1, 2]].T, t[[0, 2, 3]].T])
            tri = Triangulation(mesh.p[0], mesh.p[1], tris)
            art = ax.tripcolor(tri, err, shading="gouraud", vmin=0.0, vmax=top, cmap="viridis")
            ax.triplot(tri, color="white", lw=0.2, alpha=0.4)
            ax.set_aspect("equal")
            ax.set_xlabel("x (m)")
            ax.set_ylabel("y (m)")
            fig.colorbar(art, ax=ax, label="|u_h − u| / max |u|")
        ax.set_title(name)

    fig.suptitle(textwrap.fill(title, 110), fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
