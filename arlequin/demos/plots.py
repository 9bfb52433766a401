"""Pictures of the demos (matplotlib, PNG): time histories and snapshots against references."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .sliding_block import SlidingBlockResult
    from .two_bars import TwoBarsResult
    from .wave import WaveResult

__all__ = ["plot_sliding_block", "plot_two_bars", "plot_wave"]


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


def plot_wave(result: WaveResult, path: str) -> None:
    """PNG of the snapshot: coupled coarse and fine fields, the single-mesh reference, and the
    reflected wave (their difference in the coarse-only region, magnified)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    f = result.fields
    fig, (ax1, ax2, ax3) = plt.subplots(3, 1, figsize=(8, 7.5))
    for ax in (ax1, ax2):
        ax.axvspan(f["x_patch"], f["band_end"], color="0.9", label="gluing band")
    ax1.plot(f["x_coarse"], f["u0_coarse"], "k:", lw=1, label="initial pulse")
    ax1.plot(f["x_coarse"], f["u_reference"], "C2-", lw=1, label="single coarse mesh")
    ax1.plot(f["x_coarse"], f["u_coarse"], "C0o-", ms=2, lw=1, label="coupled: coarse")
    ax1.plot(f["x_fine"], f["u_fine"], "C1-", lw=1, label="coupled: fine patch")
    ax1.set_ylabel("u (m)")
    ax1.legend(fontsize=7)
    c = result.config
    ax1.set_title(
        f"ratio {c['ratio']}, W = {c['pulse_width']}, G = {c['gluing_width']}, "
        f"{c['coupling']}, {c['mediator']} mediator, {c['weights']}, {c['integrator']}"
    )
    only = f["x_coarse"] <= f["x_patch"] + 1e-12
    diff = f["u_coarse"] - f["u_reference"]
    ax2.plot(
        f["x_coarse"][only],
        diff[only],
        "C3o-",
        ms=2,
        lw=1,
        label=f"reflected wave (reflected energy fraction {result.reflected_energy_fraction:.2e})",
    )
    ax2.set_ylabel("Δu (m)")
    ax2.legend(fontsize=7)
    ax2.set_xlim(ax1.get_xlim())
    e = f["energy"]
    ax3.plot(f["times"] * 1e3, e / e[0] - 1.0, "C0-", lw=1)
    ax3.set_xlabel("t (ms)")
    ax3.set_ylabel("E(t)/E(0) − 1")
    ax2.set_xlabel("x (m)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


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
    import textwrap

    fig.suptitle(textwrap.fill(title, 110), fontsize=9)
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
