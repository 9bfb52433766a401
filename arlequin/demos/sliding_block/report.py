"""The sliding block's results folder: ``sliding.csv`` (per step), the scalar results in
``results.json`` and the picture ``sliding_block.png`` (:func:`plot_sliding_block`)."""

from __future__ import annotations

import numpy as np

from ...io import ResultsFolder
from .result import RESULT_UNITS, SlidingBlockResult

__all__ = ["plot_sliding_block", "write_results"]

#: The columns of sliding.csv and their units.
_COLUMNS = {"t": "s", "mean_velocity": "m/s", "slip_velocity": "m/s", "friction_work": "J",
            "contact_work": "J", "damping_work": "J", "total_energy": "J",
            "fixed_point_iterations": "1"}  # fmt: skip
#: Where each column comes from in the run's per-step histories.
_SOURCES = {"t": "t", "mean_velocity": "v", "slip_velocity": "slip", "friction_work": "fw",
            "contact_work": "cw", "damping_work": "dw", "total_energy": "e",
            "fixed_point_iterations": "it"}  # fmt: skip


def write_results(folder: ResultsFolder, result: SlidingBlockResult,
                  arr: dict[str, np.ndarray]) -> None:  # fmt: skip
    """Write sliding.csv (one row per step), the results and the picture, and close the folder.

    Parameters
    ----------
    folder : ResultsFolder
    result : SlidingBlockResult
    arr : dict
        The run's per-step histories (:mod:`arlequin.demos.sliding_block.run`), shape (n,)
        each.
    """
    hist = folder.history(list(_COLUMNS), _COLUMNS, name="sliding")
    for i in range(arr["t"].size):
        hist.append({col: arr[src][i] for col, src in _SOURCES.items()})
    data = result.to_json()
    keys = [k for k in RESULT_UNITS if k in data] + ["fixed_point_iterations"]
    folder.add_results({k: data[k] for k in keys}, RESULT_UNITS)
    plot_sliding_block(result, str(folder.picture("sliding_block")))
    folder.finish()


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
    if result.config.get("gravity") is not None and result.config.get("velocity"):
        v0 = float(result.config["velocity"])  # launched at the end of the ramp (t = 0)
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
