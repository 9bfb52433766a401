"""The Taylor bar's report: the results written at the end of a run (scalars with their units,
the final results.json) and its pictures (the history plot; the final shape, drawn by the bar's
own ``render``: :mod:`~arlequin.demos.taylor_bar.render`, :mod:`~arlequin.demos.taylor_bar.
render_3d`). SI units.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ...io import ResultsFolder

if TYPE_CHECKING:
    from .result import TaylorBarResult

__all__ = ["plot_taylor_bar", "write_results"]


def write_results(folder: ResultsFolder, result: Any, units: dict[str, str]) -> None:
    """The scalar results (with ``units``), the pictures and the final results.json."""
    values = {k: v for k, v in result.to_json().items()
              if k not in ("history", "config", "reference")}  # fmt: skip
    hist = result.history
    values["final_energies"] = {
        k: hist[k][-1]
        for k in (
            "kinetic",
            "elastic",
            "plastic_dissipation",
            "viscous_dissipation",
            "coupling_work",
            "contact_work",
        )
        if k in hist
    }
    folder.add_results(values, units)
    plot_taylor_bar(result, str(folder.picture("taylor_bar_history")))
    title = (f"t = {result.history['t'][-1] * 1e6:.1f} us: length {result.final_length * 1e3:.2f} "
             f"mm, footprint radius {result.mushroom_radius * 1e3:.2f} mm"
             + ("" if result.arlequin or result.config.get("geometry") == "3d"
                else " (grey: initial shape)"))  # fmt: skip
    result.setup.render(result.u, result.state, str(folder.picture("taylor_bar")), title)
    folder.finish()


def plot_taylor_bar(result: TaylorBarResult, path: str) -> None:
    """Length, footprint radius and the energies of a Taylor bar run against time (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    h = {k: np.asarray(v) for k, v in result.history.items()}
    t = h["t"] * 1e6
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    ax1.plot(t, h["length"] * 1e3, "C0-", label="length")
    ax1.plot(t, h["radius"] * 1e3, "C1-", label="footprint radius")
    for key, col in (("final_length", "C0"), ("mushroom_radius", "C1")):
        ax1.axhline(result.reference[key] * 1e3, color=col, ls=":", lw=1)
    ax1.set_ylabel("mm")
    ax1.legend(fontsize=8, title="dotted: published values at 80 µs", title_fontsize=8)
    parts = [("kinetic", "kinetic"), ("elastic", "elastic"),
             ("plastic_dissipation", "plastic dissipation"),
             ("viscous_dissipation", "bulk-viscosity dissipation"),
             ("contact_work", "removed by the wall")]  # fmt: skip
    total = sum(h[k] for k, _ in parts)
    if "coupling_work" in h:  # Arlequin: the net work of the mediator's forces (zero if exact)
        total = total - h["coupling_work"]
        parts.append(("coupling_work", "coupling work"))
    for k, label in parts:
        if k == "viscous_dissipation" and not np.any(h[k]):
            continue
        ax2.plot(t, h[k], lw=1.2, label=label)
    ax2.plot(t, total, "k--", lw=1, label=f"sum (balance error {result.energy_balance_error:.1e})")
    ax2.set_ylabel("J")
    ax2.set_xlabel("time (µs)")
    ax2.legend(fontsize=8)
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
    model = result.config.get("model", "mono")
    fig.suptitle(
        f"Taylor bar ({model}), {result.elements_radial} x {result.elements_axial} cells: L = "
        f"{result.final_length * 1e3:.2f} mm, R = {result.mushroom_radius * 1e3:.2f} mm, "
        f"max ε̄p = {result.max_plastic_strain:.2f}"
    )
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
