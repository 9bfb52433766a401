"""The demos' subcommands (patch-test, two-bars, wave, taylor-bar, sliding-block,
ball-impact): their
options and their runs, shared by ``arlequin`` and the study runner (:mod:`arlequin.demos.study`),
which parses and runs a case exactly as the command line would."""

from __future__ import annotations

import argparse

from .ball import add_ball_impact
from .common import add_out as _add_out
from .common import run_demo
from .common import write_json as _write_json
from .generate import add_demo, config_from_args
from .sliding import add_sliding_block

__all__ = ["add_demos", "check_case", "demo_parser", "two_bars_options", "wave_options"]


def add_demos(sub) -> None:
    """Register the demos' subcommands on an ``add_subparsers`` object."""
    _add_patch_test(sub)
    _add_two_bars(sub)
    _add_wave(sub)
    _add_generated(sub, _taylor_bar_config())
    add_sliding_block(sub)
    add_ball_impact(sub)


def check_case(demo: str, args: argparse.Namespace) -> None:
    """The demo's own input checks on a parsed command line, nothing run or written (its
    configuration made from the options, or its run function with ``check_only=True``; the
    patch test's options are all choices and integers, which the parser has checked). Raises
    the demo's ``ValueError``."""
    if demo == "two-bars":
        from ..demos.two_bars import run_two_bars

        run_two_bars(**two_bars_options(args), check_only=True)
    elif demo == "wave":
        from ..demos.wave import run_wave

        run_wave(**wave_options(args), check_only=True)
    elif demo == "taylor-bar":
        config_from_args(_taylor_bar_config(), args)
    elif demo == "sliding-block":
        from ..demos.sliding_block import run_sliding_block
        from .sliding import sliding_options

        run_sliding_block(**sliding_options(args), check_only=True)
    elif demo == "ball-impact":
        from ..demos.ball_impact import run_ball_impact
        from .ball import ball_options

        run_ball_impact(**ball_options(args), check_only=True)


def _taylor_bar_config():
    from ..demos.taylor_bar import TaylorBarConfig

    return TaylorBarConfig


def _add_generated(sub, config) -> argparse.ArgumentParser:
    """A demo's subcommand generated from its configuration (:func:`add_demo`). The options
    whose field says ``parse=str`` take the word as text: the generator would parse a ``None``
    default as a number, and the record of the options has them untyped."""
    p = add_demo(sub, config)
    text = {f.name for f, opt in config.fields() if opt.cli and opt.parse is str}
    for action in p._actions:
        if action.dest in text:
            action.type = None
    return p


def demo_parser() -> tuple[argparse.ArgumentParser, dict[str, argparse.ArgumentParser]]:
    """A parser of the demos' subcommands, and each subcommand's own parser by name."""
    parser = argparse.ArgumentParser(prog="arlequin")
    sub = parser.add_subparsers(dest="command", required=True)
    add_demos(sub)
    return parser, dict(sub.choices)


def _cmd_patch_test(args: argparse.Namespace) -> int:
    from ..demos.patch_test import run_patch_test

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
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
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
    from ..demos.two_bars import plot_two_bars, run_two_bars

    result = run_demo(run_two_bars, two_bars_options(args), args, "two bars")
    if args.plot:
        plot_two_bars(result, args.plot)
    return 0


def two_bars_options(args: argparse.Namespace) -> dict:
    """The keyword arguments of :func:`~arlequin.demos.two_bars.run_two_bars` that the command
    line gives (all but ``out`` and ``progress``)."""
    return dict(method=args.method, newmark=args.newmark, lengths=tuple(args.lengths),
                young=args.young, density=args.density, velocity=args.velocity,
                velocity2=args.velocity2, elements=args.elements, cfl=args.cfl,
                theta=args.theta, t_end=args.t_end)  # fmt: skip


def _add_two_bars(sub) -> None:
    p = sub.add_parser(
        "two-bars",
        help="impact of two elastic bars: level-set contact vs Newmark + Signorini vs exact",
        description="Bar 1 at --velocity hits bar 2 (touching at t = 0); SI units. Reports the "
        "interface velocity, contact pressure (-lambda_v), energies and contact work.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
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
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    _add_out(p)
    p.set_defaults(func=_cmd_two_bars)


def wave_options(args: argparse.Namespace) -> dict:
    """The keyword arguments of :func:`~arlequin.demos.wave.run_wave` that the command line
    gives (all but ``out`` and ``progress``)."""
    return dict(ratio=args.ratio, pulse_width=args.pulse_width, gluing_width=args.gluing_width,
                coupling=args.coupling, mediator=args.mediator, weights=args.weights,
                integrator=args.integrator, dt=args.dt)  # fmt: skip


def _cmd_wave(args: argparse.Namespace) -> int:
    from ..demos.wave import plot_wave, run_wave

    result = run_demo(run_wave, wave_options(args), args, "coupled run")
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
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
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
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    _add_out(p)
    p.set_defaults(func=_cmd_wave)
