"""Two-bar impact: level-set contact vs Newmark + Signorini vs the exact solution (docs/contact.md).

``run(**params) -> dict`` returns the figures of the docs' tables; run as a script it prints the
tables as JSON and writes ``two_bars.png`` (the paper's Figure 1 against the exact solution) and
``two_bars_hht.png`` into ``results/two_bars/`` (``--out DIR`` elsewhere; ``--docs`` regenerates
the pictures of ``docs/``). SI units.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from arlequin.demos.block_impact import run_block_impact
from arlequin.demos.two_bars import plot_two_bars, run_two_bars, run_wall

#: The pictures of this example in the documentation's gallery (paths under docs/).
GALLERY_IMAGES = ["two_bars.png", "two_bars_hht.png"]

DOCS = Path(__file__).resolve().parent.parent / "docs"


def _fig(r) -> dict:
    m = r.metrics()
    keys = (
        "velocity_rms_error",
        "pressure_rms_error",
        "duration_error_steps",
        "final_velocity_error",
        "energy_loss",
        "max_energy_gain",
    )
    out = {k: m[k] for k in keys}
    out["final_velocities"] = r.final_velocities
    out["mean_iterations"] = float(r.fixed_point_iterations[1:].mean())
    return out


def run(
    elements: int = 100,
    refinement=(25, 50, 100, 200, 400),
    blocks: bool = True,
    plot: str | None = None,
) -> dict:
    """All the figures of docs/contact.md (fractions, steps, m/s)."""
    out: dict = {}
    both = run_two_bars(method="both", elements=elements)
    hht = run_two_bars(method="newmark", newmark="hht", elements=elements)
    out["bars"] = {
        "levelset-theta": _fig(both),
        "newmark-trapezoidal": _fig(both.newmark),
        "newmark-hht": _fig(hht),
        "levelset-theta1": _fig(run_two_bars(theta=1.0, elements=elements)),
        "levelset-explicit-cfl0.9": _fig(
            run_two_bars(integrator="explicit", cfl=0.9, elements=elements)
        ),
    }
    out["wall"] = {
        "levelset-theta": _fig(run_wall(elements=elements)),
        "levelset-explicit-cfl0.9": _fig(
            run_wall(integrator="explicit", cfl=0.9, elements=elements)
        ),
        "newmark-trapezoidal": _fig(run_wall(method="newmark", elements=elements)),
        "newmark-hht": _fig(run_wall(method="newmark", newmark="hht", elements=elements)),
    }
    out["energy_loss_vs_elements"] = {
        n: run_two_bars(elements=n).metrics()["energy_loss"] for n in refinement
    }
    if blocks:
        rows = {}
        for dim, target, ne in (
            (2, "plane", 20),
            (2, "plane", 40),
            (2, "plane", 80),
            (2, "block", 20),
            (2, "block", 40),
            (3, "plane", 20),
            (3, "plane", 40),
            (3, "block", 20),
            (3, "block", 40),
        ):
            r = run_block_impact(dim, target, ne)
            rows[f"{dim}D-{target}-{ne}"] = {
                "energy_loss": r.energy_loss,
                "max_gap_drift_over_h": r.max_gap_drift / r.h,
                "max_penetration_over_h": r.max_penetration / r.h,
                "penetration_bound_over_h": (r.max_penetration - r.max_penetration_excess) / r.h,
                "mean_iterations": float(r.iterations_contact.mean()),
                "iterations": r.iteration_distribution(),
                "steps_in_contact": int(r.iterations_contact.size),
            }
        out["blocks"] = rows
    if plot:
        plot_two_bars(both, plot)
    return out


if __name__ == "__main__":
    blocks = "--no-blocks" not in sys.argv
    if "--docs" in sys.argv:
        folder = DOCS
    elif "--out" in sys.argv:
        folder = Path(sys.argv[sys.argv.index("--out") + 1])
    else:
        folder = Path("results") / "two_bars"
    folder.mkdir(parents=True, exist_ok=True)
    res = run(blocks=blocks, plot=str(folder / "two_bars.png"))
    r = run_two_bars(method="both", newmark="hht")
    plot_two_bars(r, str(folder / "two_bars_hht.png"))
    print(json.dumps(res, indent=2))
