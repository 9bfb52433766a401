"""The wave demo's results folder and its picture of the snapshot."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...io import ResultsFolder
from .result import RESULT_UNITS

if TYPE_CHECKING:
    from .result import WaveResult

__all__ = ["plot_wave", "write_results"]


def write_results(folder: ResultsFolder, result: WaveResult) -> None:
    """The results (the CLI's JSON keys, the incident energy, the multiplier and coupling
    work maxima) with their units, ``wave.png``, then the folder finished."""
    folder.add_results(
        {**result.to_json(), "incident_energy": result.incident_energy,
         "multiplier_max": result.multiplier_max,
         "coupling_work_max": result.coupling_work_max},
        RESULT_UNITS,
    )  # fmt: skip
    plot_wave(result, str(folder.picture("wave")))
    folder.finish()


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
