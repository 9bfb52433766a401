"""``arlequin sliding-block``: an elastic block on a rigid plane with Coulomb friction."""

from __future__ import annotations

import argparse

from .common import add_out, run_demo

__all__ = ["add_sliding_block", "sliding_options"]


def sliding_options(args: argparse.Namespace) -> dict:
    """The keyword arguments of :func:`~arlequin.demos.sliding_block.run_sliding_block` that the
    command line gives (all but ``out`` and ``progress``)."""
    velocity = args.velocity
    if velocity is None:
        velocity = 0.0 if args.gravity is not None else 1.0
    opts = dict(dim=args.dim, friction=args.friction, velocity=velocity, incline=args.incline,
                pressure=args.pressure, gravity=args.gravity, elements=args.elements,
                t_end=args.t_end, ramp_time=args.ramp_time)  # fmt: skip
    if args.damping is not None:
        opts["damping"] = args.damping
    return opts


def _cmd(args: argparse.Namespace) -> int:
    from ..demos.sliding_block import run_sliding_block

    run_demo(run_sliding_block, sliding_options(args), args, "sliding block")
    return 0


def add_sliding_block(sub) -> None:
    """Register the ``sliding-block`` subcommand."""
    p = sub.add_parser(
        "sliding-block",
        help="elastic block launched along a rigid plane with Coulomb friction",
        description="A block under a top pressure launched at --velocity along a rigid plane "
        "(exact: it decelerates at mu p/(rho H) and stops), or at rest on an incline under "
        "--gravity (exact: it sticks for tan(theta) < mu, else slides at g(sin - mu cos)). "
        "Level-set contact with Coulomb friction; SI units; times from the launch or the end "
        "of the gravity ramp.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--dim", type=int, choices=[2, 3], default=2, help="plane strain or 3D")
    p.add_argument(
        "--friction",
        type=float,
        default=0.3,
        metavar="MU",
        help="Coulomb coefficient (0: frictionless, no tangential rows)",
    )
    p.add_argument(
        "--velocity",
        type=float,
        default=None,
        metavar="V0",
        help="launch velocity (m/s); default 1 with --pressure, 0 with --gravity",
    )
    p.add_argument(
        "--incline",
        type=float,
        default=0.0,
        metavar="DEG",
        help="incline of the plane (degrees; with --gravity)",
    )
    load = p.add_mutually_exclusive_group()
    load.add_argument(
        "--pressure",
        type=float,
        default=None,
        metavar="P",
        help="top pressure (Pa); the default loading, 1e5 Pa",
    )
    load.add_argument(
        "--gravity",
        type=float,
        default=None,
        metavar="G",
        help="gravity (m/s^2), ramped from rest over --ramp-time",
    )
    p.add_argument(
        "--elements",
        type=int,
        default=4,
        metavar="N",
        help="elements across the height (twice as many along the width)",
    )
    p.add_argument(
        "--t-end",
        type=float,
        default=None,
        metavar="T",
        help="simulated time after the launch or the ramp (s); default 1.3 x the "
        "exact stop time, or 200 H/c_d",
    )
    p.add_argument(
        "--damping",
        type=float,
        default=None,
        metavar="ZETA",
        help="damping ratio at the block's first shear mode (stiffness-proportional "
        "Rayleigh damping; 0: undamped, the edges then micro-slip after the stop); "
        "default the demo's DAMPING, 0.005",
    )
    p.add_argument(
        "--ramp-time",
        type=float,
        default=None,
        metavar="T",
        help="duration of the gravity ramp (s); default 300 H/c_d",
    )
    p.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    add_out(p)
    p.set_defaults(func=_cmd)
