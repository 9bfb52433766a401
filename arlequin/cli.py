"""The ``arlequin`` command: a thin layer over :mod:`arlequin.demos`.

Each subcommand runs one demo, prints a one-line summary and optionally writes JSON (SI units;
``*_error`` and ``*_fraction`` values are dimensionless fractions, not percent) and a results
folder (``--out DIR``: results.json with the inputs and their units, history.csv, XDMF field
series that ParaView opens, pictures; see :mod:`arlequin.io`).
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import os
import sys
from collections.abc import Sequence

from .contract import SimulationError

__all__ = ["main"]


class NonFiniteResult(RuntimeError):
    """A command computed a NaN or an infinite value (the run is reported as failed)."""


def _non_finite(data, prefix: str = "") -> list[str]:
    """Keys of non-finite numbers in a JSON-like document."""
    out: list[str] = []
    if isinstance(data, dict):
        for k, v in data.items():
            out += _non_finite(v, f"{prefix}{k}.")
    elif isinstance(data, (list, tuple)):
        for i, v in enumerate(data):
            out += _non_finite(v, f"{prefix}{i}.")
    elif isinstance(data, float) and not math.isfinite(data):
        out.append(f"{prefix[:-1]}={data}")
    elif isinstance(data, str) and data in ("nan", "inf", "-inf"):
        out.append(f"{prefix[:-1]}={data}")
    return out


def _check_results(data: dict) -> None:
    bad = _non_finite(data)
    if bad:
        shown = ", ".join(bad[:5]) + (f" and {len(bad) - 5} more" if len(bad) > 5 else "")
        raise NonFiniteResult(f"the run produced non-finite results: {shown}")


def _write_json(path: str | None, data: dict) -> None:
    _check_results(data)
    if path:
        with open(path, "w", encoding="utf-8") as fh:
            json.dump(data, fh, indent=2)


def _check_writable(path: str | None, option: str) -> None:
    """Refuse, before any computation, an output file whose folder cannot be written."""
    if not path:
        return
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder) or not os.access(folder, os.W_OK):
        raise ValueError(
            f"{option} {path!r}: the folder {folder!r} does not exist or is not writable"
        )


def _add_out(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--out",
        metavar="DIR",
        default=None,
        help="write a results folder: results.json, history.csv, fields/*.xdmf, pictures",
    )


def _cmd_patch_test(args: argparse.Namespace) -> int:
    from .demos.patch_test import run_patch_test

    result = run_patch_test(
        dim=args.dim,
        coupling=args.coupling,
        weights=args.weights,
        mediator=args.mediator,
        mesh=args.mesh,
        seed=args.seed,
        out=args.out,
        layout=args.layout,
        ratio=args.ratio,
        band_cells=args.band_cells,
    )
    print(result.summary())
    keys = ("max_error", "exact_residual", "n_coarse_dofs", "n_fine_dofs", "n_multipliers")
    data = {k: getattr(result, k) for k in keys}
    data.update({k: v for k, v in result.to_json().items() if k not in data})
    _write_json(args.json, data)
    return 0


def _add_patch_test(sub) -> None:
    p = sub.add_parser(
        "patch-test",
        help="uniform-stress patch test of a random coarse + patch configuration",
        description="Build a random configuration from the seed, solve the uniform-stress "
        "problem and report max_error and exact_residual (fractions).",
    )
    p.add_argument("--dim", choices=["1", "2", "3", "axi"], default="2")
    p.add_argument("--coupling", choices=["L2", "H1"], default="H1")
    p.add_argument("--weights", choices=["constant", "ramp"], default="ramp")
    p.add_argument("--mediator", choices=["coarse", "fine"], default="coarse")
    p.add_argument("--mesh", choices=["nested", "nonnested"], default="nested")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--layout",
        choices=["random", "strip", "square"],
        default="random",
        help="random configuration, a strip spanning the domain, or an interior square (2D)",
    )
    p.add_argument("--ratio", type=int, default=4, help="coarse/fine size ratio (strip, square)")
    p.add_argument(
        "--band-cells", type=int, default=1, help="gluing band in coarse cells (strip, square)"
    )
    p.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON")
    _add_out(p)
    p.set_defaults(func=_cmd_patch_test)


def _cmd_two_bars(args: argparse.Namespace) -> int:
    from .demos.two_bars import plot_two_bars, run_two_bars

    result = run_two_bars(
        method=args.method,
        newmark=args.newmark,
        lengths=tuple(args.lengths),
        young=args.young,
        density=args.density,
        velocity=args.velocity,
        velocity2=args.velocity2,
        elements=args.elements,
        cfl=args.cfl,
        theta=args.theta,
        t_end=args.t_end,
        out=args.out,
    )
    print(result.summary())
    _write_json(args.json, result.to_json())
    if args.plot:
        plot_two_bars(result, args.plot)
    return 0


def _add_two_bars(sub) -> None:
    p = sub.add_parser(
        "two-bars",
        help="impact of two elastic bars: level-set contact vs Newmark + Signorini vs exact",
        description="Bar 1 at --velocity hits bar 2 (touching at t = 0); SI units. Reports the "
        "interface velocity, contact pressure (-lambda_v), energies and contact work.",
    )
    p.add_argument("--method", choices=["levelset", "newmark", "both"], default="levelset")
    p.add_argument("--newmark", choices=["trapezoidal", "hht"], default="trapezoidal")
    p.add_argument(
        "--lengths",
        nargs=2,
        type=float,
        default=[1.0, 1.0],
        metavar=("L1", "L2"),
        help="bar lengths (m)",
    )
    p.add_argument("--young", type=float, default=210e9, metavar="E", help="Young's modulus (Pa)")
    p.add_argument("--density", type=float, default=7850.0, metavar="RHO", help="density (kg/m^3)")
    p.add_argument("--velocity", type=float, default=1.0, metavar="V0", help="bar 1 velocity (m/s)")
    p.add_argument(
        "--velocity2", type=float, default=0.0, metavar="V2", help="bar 2 velocity (m/s)"
    )
    p.add_argument("--elements", type=int, default=100, metavar="N", help="elements per bar")
    p.add_argument("--cfl", type=float, default=1.0, metavar="C", help="dt = C h_min / c")
    p.add_argument(
        "--theta", type=float, default=0.5, metavar="T", help="theta of the theta-scheme"
    )
    p.add_argument(
        "--t-end",
        type=float,
        default=None,
        metavar="T",
        help="end time (s), default 3 max(L1, L2)/c",
    )
    p.add_argument("--json", metavar="PATH", default=None, help="write the histories as JSON")
    p.add_argument("--plot", metavar="PNG", default=None, help="plot against the exact solution")
    _add_out(p)
    p.set_defaults(func=_cmd_two_bars)


def _cmd_wave(args: argparse.Namespace) -> int:
    from .demos.wave import plot_wave, run_wave

    result = run_wave(
        ratio=args.ratio,
        pulse_width=args.pulse_width,
        gluing_width=args.gluing_width,
        coupling=args.coupling,
        mediator=args.mediator,
        weights=args.weights,
        integrator=args.integrator,
        dt=args.dt,
        out=args.out,
    )
    print(result.summary())
    _write_json(args.json, result.to_json())
    if args.plot:
        plot_wave(result, args.plot)
    return 0


def _add_wave(sub) -> None:
    p = sub.add_parser(
        "wave",
        help="1D elastic wave through an Arlequin overlap: reflected and transmitted energy",
        description="A smooth right-going pulse in a coarse bar meets a refined patch glued at "
        "its left end; the reflection is measured against a single coarse-mesh run with the same "
        "integrator and time step (fractions of the incident energy).",
    )
    p.add_argument("--ratio", type=int, default=4, help="coarse/fine element size ratio")
    p.add_argument("--pulse-width", type=float, default=10.0, help="in coarse elements")
    p.add_argument("--gluing-width", type=float, default=10.0, help="in coarse elements")
    p.add_argument("--coupling", choices=["L2", "H1"], default="H1")
    p.add_argument("--mediator", choices=["coarse", "fine"], default="coarse")
    p.add_argument("--weights", choices=["constant", "ramp"], default="ramp")
    p.add_argument("--integrator", choices=["explicit", "implicit"], default="explicit")
    p.add_argument(
        "--dt",
        type=float,
        default=None,
        help="time step (s); default: the coupled explicit stable step",
    )
    p.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON")
    p.add_argument("--plot", metavar="PNG", default=None, help="write a picture of the snapshot")
    _add_out(p)
    p.set_defaults(func=_cmd_wave)


def _progress_bar(total: float, quiet: bool):
    """A tqdm bar over the simulated time (µs) with ETA on stderr, or None when quiet."""
    if quiet:
        return None, None
    from tqdm import tqdm

    bar = tqdm(
        total=round(total * 1e6, 3),
        unit="µs",
        desc="simulated time",
        leave=False,
        bar_format="{l_bar}{bar}| {n:.1f}/{total:.1f} µs [{elapsed}<{remaining}]",
    )

    def update(t: float) -> None:
        bar.n = round(t * 1e6, 3)
        bar.refresh()

    return bar, update


def _cmd_taylor_bar(args: argparse.Namespace) -> int:
    from .demos.taylor_bar import run_taylor_bar

    law_params = {
        k: getattr(args, k)
        for k in ("voce_saturation", "voce_rate", "jc_b", "jc_n", "jc_c", "jc_reference_rate")
    }
    law_params = {k: v for k, v in law_params.items() if v is not None}
    bar, update = _progress_bar(args.t_end, args.quiet)
    try:
        result = run_taylor_bar(
            model=args.model,
            elements_radial=args.elements_radial,
            mesh_size=args.mesh_size,
            t_end=args.t_end,
            velocity=args.velocity,
            young=args.young,
            poisson=args.poisson,
            density=args.density,
            yield_stress=args.yield_stress,
            hardening=args.hardening,
            hardening_law=args.hardening_law,
            length=args.length,
            radius=args.radius,
            bulk_viscosity=args.bulk_viscosity,
            fbar=not args.no_fbar,
            backend=args.backend,
            out=args.out,
            progress=update,
            **law_params,
        )
    finally:
        if bar is not None:
            bar.close()
    print(result.summary())
    _write_json(args.json, result.to_json())
    return 0


def _add_taylor_bar(sub) -> None:
    p = sub.add_parser(
        "taylor-bar",
        help="Taylor bar impact: a copper bar hits a rigid wall (finite-strain J2, axisymmetric)",
        description="A bar (length L, radius R) moving at V hits a rigid frictionless wall at "
        "t = 0; axisymmetric Q1 F-bar cells, central differences with the step re-estimated "
        "in the current configuration, the level-set contact model at the wall. SI units. "
        "Reports the final length, the footprint (mushroom) radius, the maximum equivalent "
        "plastic strain and the energy balance error (a fraction).",
    )
    p.add_argument(
        "--model",
        choices=["mono"],
        default="mono",
        help="mono: one finite-strain mesh over the whole bar",
    )
    size = p.add_mutually_exclusive_group()
    size.add_argument(
        "--elements-radial",
        type=int,
        default=None,
        metavar="N",
        help="cells across the radius (default 10); the axial count is round(L/h)",
    )
    size.add_argument(
        "--mesh-size", type=float, default=None, metavar="H", help="cell edge across the radius (m)"
    )
    p.add_argument("--t-end", type=float, default=80e-6, metavar="T", help="end time (s)")
    p.add_argument("--velocity", type=float, default=227.0, metavar="V", help="impact speed (m/s)")
    p.add_argument("--young", type=float, default=117e9, metavar="E", help="Young's modulus (Pa)")
    p.add_argument("--poisson", type=float, default=0.35, metavar="NU", help="Poisson's ratio")
    p.add_argument("--density", type=float, default=8930.0, metavar="RHO", help="density (kg/m^3)")
    p.add_argument(
        "--yield-stress", type=float, default=0.4e9, metavar="S", help="initial yield stress (Pa)"
    )
    p.add_argument(
        "--hardening",
        type=float,
        default=0.1e9,
        metavar="H",
        help="linear hardening modulus (Pa; the linear term of the Voce law)",
    )
    p.add_argument("--hardening-law", choices=["linear", "voce", "johnson-cook"], default="linear")
    p.add_argument(
        "--voce-saturation",
        type=float,
        default=None,
        metavar="Q",
        help="Voce: saturation stress Q (Pa, default 0.1e9)",
    )
    p.add_argument(
        "--voce-rate",
        type=float,
        default=None,
        metavar="B",
        help="Voce: saturation rate b (default 10)",
    )
    p.add_argument(
        "--jc-b",
        type=float,
        default=None,
        metavar="B",
        help="Johnson-Cook: B (Pa, default 0.292e9; A is --yield-stress)",
    )
    p.add_argument(
        "--jc-n",
        type=float,
        default=None,
        metavar="N",
        help="Johnson-Cook: exponent n (default 0.31)",
    )
    p.add_argument(
        "--jc-c",
        type=float,
        default=None,
        metavar="C",
        help="Johnson-Cook: strain-rate coefficient C (default 0: off)",
    )
    p.add_argument(
        "--jc-reference-rate",
        type=float,
        default=None,
        metavar="R",
        help="Johnson-Cook: reference strain rate (1/s, default 1)",
    )
    p.add_argument("--length", type=float, default=32.4e-3, metavar="L", help="bar length (m)")
    p.add_argument("--radius", type=float, default=3.2e-3, metavar="R", help="bar radius (m)")
    p.add_argument(
        "--bulk-viscosity",
        action="store_true",
        help="artificial bulk viscosity (linear 0.06, quadratic 1.5)",
    )
    p.add_argument(
        "--no-fbar",
        action="store_true",
        help="plain Q1 cells (they lock under plastic flow; for comparison)",
    )
    p.add_argument(
        "--backend",
        choices=["auto", "numba", "numpy"],
        default="auto",
        help="internal-force path (auto: the compiled kernel)",
    )
    p.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    _add_out(p)
    p.set_defaults(func=_cmd_taylor_bar)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="arlequin", description="Arlequin multiscale coupling: demos and verification."
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress (INFO)")
    sub = parser.add_subparsers(dest="command", required=True)
    _add_patch_test(sub)
    _add_two_bars(sub)
    _add_wave(sub)
    _add_taylor_bar(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
    )
    try:
        for attr in ("json", "plot"):
            _check_writable(getattr(args, attr, None), f"--{attr}")
        return int(args.func(args) or 0)
    except SimulationError as exc:  # the run failed (an inverted cell, a NaN...): not bad input
        print(f"arlequin {args.command}: failed: {exc}", file=sys.stderr)
        return 1
    except ValueError as exc:  # bad input (every input error of the library is a ValueError)
        print(f"arlequin {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except NonFiniteResult as exc:
        print(f"arlequin {args.command}: failed: {exc}", file=sys.stderr)
        return 1
    except Exception as exc:  # a bug: say so in one line, the traceback with -v
        if args.verbose:
            raise
        print(
            f"arlequin {args.command}: internal error ({type(exc).__name__}: {exc}); rerun with "
            "-v for the traceback and report it",
            file=sys.stderr,
        )
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
