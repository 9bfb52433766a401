"""Reflected energy fraction of the 1D wave demo against pulse width, for every configuration.

Prints JSON (one record per run) and writes the plots ``docs/wave_reflection_<integrator>.png``.

    python benchmarks/wave_reflection.py [--quick] [--json PATH] [--plot-dir docs]
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from pathlib import Path

from arlequin.demos.wave import run_wave

logger = logging.getLogger("wave_reflection")

WIDTHS = [2, 3, 4, 5, 6, 8, 10, 12, 15, 20, 25, 30, 40]
CONFIGS = [
    # (weights, mediator, coupling)
    ("ramp", "coarse", "L2"),
    ("ramp", "coarse", "H1"),
    ("ramp", "fine", "L2"),
    ("ramp", "fine", "H1"),
    ("constant", "coarse", "L2"),
    ("constant", "coarse", "H1"),
    ("constant", "fine", "H1"),
]
RATIOS = [2, 4, 8]
INTEGRATORS = ["explicit", "implicit"]


def sweep(widths, ratios, configs, integrators):
    out = []
    for integrator in integrators:
        for ratio in ratios:
            for weights, mediator, coupling in configs:
                for w in widths:
                    t0 = time.perf_counter()
                    r = run_wave(
                        ratio=ratio,
                        pulse_width=w,
                        coupling=coupling,
                        mediator=mediator,
                        weights=weights,
                        integrator=integrator,
                    )
                    rec = {
                        "integrator": integrator,
                        "ratio": ratio,
                        "weights": weights,
                        "mediator": mediator,
                        "coupling": coupling,
                        "pulse_width": w,
                        **r.to_json(),
                        "seconds": time.perf_counter() - t0,
                    }
                    logger.info("%s", rec)
                    out.append(rec)
    return out


def plot(records, plot_dir: Path) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    files = []
    for integrator in sorted({r["integrator"] for r in records}):
        ratios = sorted({r["ratio"] for r in records})
        fig, axes = plt.subplots(1, len(ratios), figsize=(5.2 * len(ratios), 4.4), sharey=True)
        axes = [axes] if len(ratios) == 1 else axes
        for ax, ratio in zip(axes, ratios):
            keys = []
            for r in records:
                k = (r["weights"], r["mediator"], r["coupling"])
                if k not in keys:
                    keys.append(k)
            for k in keys:
                rs = [
                    r
                    for r in records
                    if r["integrator"] == integrator
                    and r["ratio"] == ratio
                    and (r["weights"], r["mediator"], r["coupling"]) == k
                ]
                if not rs:
                    continue
                rs.sort(key=lambda r: r["pulse_width"])
                ls = "-" if k[0] == "ramp" else ":"
                ax.semilogy(
                    [r["pulse_width"] for r in rs],
                    [max(r["reflected_energy_fraction"], 1e-18) for r in rs],
                    ls,
                    marker="o",
                    ms=3,
                    label=f"{k[0]}, {k[1]} mediator, {k[2]}",
                )
            ax.axhline(1e-4, color="k", lw=0.8, ls="--")
            ax.axvline(10, color="grey", lw=0.5)
            ax.axvline(15, color="grey", lw=0.5)
            ax.set_title(f"{integrator}, fine/coarse ratio {ratio}")
            ax.set_xlabel("pulse width (coarse elements)")
            ax.grid(True, which="both", alpha=0.3)
        axes[0].set_ylabel("reflected energy / incident energy")
        axes[-1].legend(fontsize=7, loc="upper right")
        fig.tight_layout()
        path = plot_dir / f"wave_reflection_{integrator}.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        files.append(str(path))
    return files


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("--quick", action="store_true", help="few widths, explicit only")
    p.add_argument("--json", default=None)
    p.add_argument("--plot-dir", default="docs")
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s", stream=sys.stderr)
    logging.getLogger("skfem").setLevel(logging.WARNING)
    widths = [2, 10, 40] if args.quick else WIDTHS
    integrators = ["explicit"] if args.quick else INTEGRATORS
    records = sweep(widths, RATIOS, CONFIGS, integrators)
    files = plot(records, Path(args.plot_dir))
    text = json.dumps({"records": records, "plots": files}, indent=1)
    if args.json:
        Path(args.json).write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
