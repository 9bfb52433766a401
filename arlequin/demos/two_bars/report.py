"""The two-bar impact's results folder and its picture against the exact solution."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ...io import ResultsFolder
from .result import RESULT_UNITS

if TYPE_CHECKING:
    from .result import TwoBarsResult

__all__ = ["UNITS", "finish", "open_folder", "plot_two_bars"]

#: Units of the inputs of the bar-on-wall runs (the two-bar ones come from its configuration).
UNITS = {"lengths": "m", "length": "m", "young": "Pa", "density": "kg/m^3", "velocity": "m/s",
         "velocity2": "m/s", "elements": "1", "cfl": "1", "theta": "1", "t_end": "s",
         "method": "", "newmark": "", "integrator": ""}  # fmt: skip


def open_folder(out: str | Path | None, command: str, inputs: dict[str, Any],
                units: dict[str, str]) -> ResultsFolder | None:  # fmt: skip
    """The results folder of a run (None without ``out``)."""
    return None if out is None else ResultsFolder(out, command, inputs, units)


def finish(folder: ResultsFolder | None, res: TwoBarsResult) -> None:
    """Results of every run (``newmark-*`` prefixed for the baseline) and the picture."""
    if folder is None:
        return
    for r in [res] + ([res.newmark] if res.newmark is not None else []):
        vals = {**r.metrics(), "contact_duration": r.contact_duration, "dt": r.dt,
                "final_velocities": r.final_velocities}  # fmt: skip
        prefix = "" if r is res else f"{r.method}:"
        folder.add_results(
            {prefix + k: v for k, v in vals.items()},
            {prefix + k: u for k, u in RESULT_UNITS.items()},
        )
    plot_two_bars(res, str(folder.picture("two_bars")))
    folder.finish()


def plot_two_bars(result: TwoBarsResult, path: str) -> None:
    """Interface velocity and contact pressure against time, with the exact solution (PNG).

    With a ``result.newmark`` (the paper's Figure 1) each method gets its own column of panels,
    each scaled to its own curves: the Newmark + Signorini chatter would otherwise set the scale
    and hide the level-set curve.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ex = result.exact
    t_exact = np.array([0.0, 0.0, ex["duration"], ex["duration"], result.t[-1]])
    v_after = ex["final_velocities"][-1]
    v_exact = np.array([ex["interface_velocity"]] * 3 + [v_after, v_after])
    v_exact[0] = result.interface_velocity[0]
    p_exact = np.array([0.0, ex["pressure"], ex["pressure"], 0.0, 0.0])
    runs = [result] + ([result.newmark] if result.newmark is not None else [])
    colours = {"levelset": "C0", "newmark-trapezoidal": "C3", "newmark-hht": "C1"}
    fig, axes = plt.subplots(2, len(runs), figsize=(7 * len(runs), 6.5), sharex=True,
                             squeeze=False)  # fmt: skip
    for col, r in enumerate(runs):
        colour = colours.get(r.method, "C2")
        top, bottom = axes[0, col], axes[1, col]
        top.plot(r.t * 1e6, r.interface_velocity, color=colour, lw=1.0, label=r.method)
        bottom.plot(r.t * 1e6, r.contact_pressure / 1e6, color=colour, lw=1.0, label=r.method)
        top.plot(t_exact * 1e6, v_exact, "k--", lw=1.2, label="exact")
        bottom.plot(t_exact * 1e6, p_exact / 1e6, "k--", lw=1.2, label="exact")
        top.set_title(r.method)
        top.set_ylabel("interface velocity (m/s)")
        bottom.set_ylabel("contact pressure (MPa)")
        bottom.set_xlabel("time (µs)")
        for ax in (top, bottom):
            ax.grid(alpha=0.3)
            ax.legend(loc="best", fontsize=8)
    cfg = result.config
    fig.suptitle(
        f"two-bar impact: {cfg.get('elements')} elements per bar, CFL {cfg.get('cfl')}, "
        f"v0 = {cfg.get('velocity')} m/s"
    )
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
