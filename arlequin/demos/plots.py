"""Pictures of the demos (matplotlib, PNG): time histories and snapshots against references."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .sliding_block import SlidingBlockResult
    from .taylor_bar import TaylorBarResult

__all__ = ["plot_sliding_block", "plot_taylor_bar"]


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


def plot_sliding_block(result: SlidingBlockResult, path: str) -> None:
    """Mean velocity against the exact straight line, and the energies, against time (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.asarray(result.t) * 1e6
    v = np.asarray(result.mean_velocity)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.5))
    ax1.plot(t, v, lw=1.0, label="mean velocity (momentum / mass)")
    v0 = v[np.searchsorted(t, 0.0)] if t.size else 0.0
    a = result.expected_acceleration
    ts = np.linspace(0.0, t[-1], 200) if t.size else np.zeros(1)
    line = v0 + a * ts * 1e-6 if result.expected_stop_time is None else np.maximum(
        v0 + a * ts * 1e-6, 0.0)  # fmt: skip
    ax1.plot(ts, line, "k--", lw=1.0, label="exact (rigid block)")
    ax1.set_xlabel("t (µs)")
    ax1.set_ylabel("m/s")
    ax1.legend()
    ax1.set_title(f"μ = {result.config.get('friction')}")
    e = np.asarray(result.total_energy)
    fw = -np.asarray(result.friction_work)
    cw = -np.asarray(result.contact_work)
    ax2.plot(t, e, label="kinetic + strain − W_ext")
    ax2.plot(t, fw, label="friction dissipation D_f")
    ax2.plot(t, cw, label="normal contact loss W_c")
    dd = -np.asarray(result.damping_work) if result.damping_work else np.zeros_like(e)
    if dd.any():
        ax2.plot(t, dd, label="damping dissipation D_d")
    ax2.plot(t, e + fw + cw + dd, "k", lw=1.0, label="sum (constant)")
    ax2.set_xlabel("t (µs)")
    ax2.set_ylabel("J")
    ax2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
