"""Pictures of the demos (matplotlib, PNG): time histories and snapshots against references."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .taylor_bar import TaylorBarResult

__all__ = ["plot_taylor_bar"]


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
