"""``arlequin ball-impact``: an elastic ball striking a thick block, each with a refined patch."""

from __future__ import annotations

import argparse

from .common import add_out, run_demo

__all__ = ["add_ball_impact", "ball_options"]


def _materials(args: argparse.Namespace) -> tuple:
    """The ball's and the block's materials: the demo's defaults with the given options."""
    from dataclasses import replace

    from ..demos.ball_impact import COPPER, STEEL

    names = {
        "young": "young",
        "poisson": "poisson",
        "density": "density",
        "yield_stress": "yield_stress",
        "hardening_modulus": "hardening",
    }
    ball = {k: getattr(args, f"ball_{k}") for k in ("young", "poisson", "density")
            if getattr(args, f"ball_{k}") is not None}  # fmt: skip
    block = {k: getattr(args, f"block_{o}") for k, o in names.items()
             if getattr(args, f"block_{o}") is not None}  # fmt: skip
    plastic = args.regime == "plastic"
    if not plastic and ({"yield_stress", "hardening_modulus"} & set(block)):
        raise ValueError("--block-yield-stress and --block-hardening are for --regime plastic")
    return (
        replace(STEEL, **ball) if ball else None,
        replace(COPPER if plastic else STEEL, **block) if block else None,
    )


def ball_options(args: argparse.Namespace) -> dict:
    """The keyword arguments of :func:`~arlequin.demos.ball_impact.run_ball_impact` that the
    command line gives (all but ``out`` and ``progress``)."""
    ball, block = _materials(args)
    return dict(regime=args.regime, model=args.model, velocity=args.velocity,
                ball_radius=args.ball_radius, block_radius=args.block_radius,
                block_height=args.block_height, ball_material=ball, block_material=block,
                patch_size=args.patch_size, block_patch_size=args.block_patch_size,
                fine_size=args.fine_size,
                coarse_size=args.coarse_size, friction=args.friction,
                rigid_wall=args.rigid_wall, coarse_step_ratio=args.coarse_step_ratio,
                t_end=args.t_end)  # fmt: skip


def _cmd(args: argparse.Namespace) -> int:
    from ..demos.ball_impact import run_ball_impact

    opts = ball_options(args)
    run_ball_impact(**opts, check_only=True)  # every input checked before the progress bar
    run_demo(run_ball_impact, opts, args, "ball impact")
    return 0


def add_ball_impact(sub) -> None:
    """Register the ``ball-impact`` subcommand."""
    p = sub.add_parser(
        "ball-impact",
        help="elastic ball striking a thick block, each body a coarse model plus a patch",
        description="An elastic ball (radius R) moving at -V along the axis strikes a thick "
        "block (or --rigid-wall), axisymmetric; level-set contact between the bodies' refined "
        "patches. Elastic regime: against Hertz's impact (peak force, contact duration); "
        "plastic regime: finite-strain J2 in the block's patch (dent, restitution). SI units.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--regime", choices=["elastic", "plastic"], default="elastic")
    p.add_argument("--model", choices=["arlequin", "mono", "mono-zoned", "graded"],
                   default="arlequin", help="arlequin: coarse models plus patches; mono: one "
                   "uniformly fine mesh per body (J2 in the whole block); mono-zoned: the same, "
                   "J2 in the patch region only; graded: conforming meshes graded from the "
                   "contact")  # fmt: skip
    p.add_argument(
        "--velocity",
        type=float,
        default=None,
        metavar="V",
        help="impact velocity (m/s); default 1 (elastic) or 10 (plastic)",
    )
    p.add_argument("--ball-radius", type=float, default=0.01, metavar="R", help="ball radius (m)")
    p.add_argument("--block-radius", type=float, default=0.1, metavar="RB", help="block radius (m)")
    p.add_argument("--block-height", type=float, default=0.1, metavar="HB", help="block height (m)")
    for body, plastic in (("ball", ""), ("block", " (plastic regime: copper, ")):
        p.add_argument(f"--{body}-young", type=float, default=None, metavar="E",
                       help=f"{body} Young's modulus (Pa); default steel, 210e9"
                       + (f"{plastic}117e9)" if plastic else ""))  # fmt: skip
        p.add_argument(f"--{body}-poisson", type=float, default=None, metavar="NU",
                       help=f"{body} Poisson's ratio; default 0.3"
                       + (f"{plastic}0.35)" if plastic else ""))  # fmt: skip
        p.add_argument(f"--{body}-density", type=float, default=None, metavar="RHO",
                       help=f"{body} density (kg/m^3); default 7850"
                       + (f"{plastic}8930)" if plastic else ""))  # fmt: skip
    p.add_argument(
        "--block-yield-stress",
        type=float,
        default=None,
        metavar="S",
        help="block yield stress (Pa; plastic regime); default 0.4e9",
    )
    p.add_argument(
        "--block-hardening",
        type=float,
        default=None,
        metavar="H",
        help="block linear hardening modulus (Pa; plastic regime); default 0.1e9",
    )
    p.add_argument("--patch-size", type=float, default=None, metavar="RP",
                   help="radius of the patches around the contact point (m); default 0.2 R "
                   "(elastic), 0.4 R (plastic)")  # fmt: skip
    p.add_argument("--block-patch-size", type=float, default=None, metavar="RP",
                   help="radius of the block's patch (m), if larger; default --patch-size "
                   "(elastic), 0.8 R (plastic)")  # fmt: skip
    p.add_argument("--fine-size", type=float, default=None, metavar="H",
                   help="cell size of the patches (m); default 10 cells across Hertz's contact "
                   "radius (elastic), half the coarse size (plastic)")  # fmt: skip
    p.add_argument(
        "--coarse-size",
        type=float,
        default=None,
        metavar="H",
        help="cell size of the coarse models at the contact (m); default pi R/120",
    )
    p.add_argument(
        "--friction",
        type=float,
        default=0.0,
        metavar="MU",
        help="Coulomb coefficient between the bodies (0: frictionless)",
    )
    p.add_argument(
        "--rigid-wall",
        action="store_true",
        help="the ball against a rigid plane instead of the block",
    )
    p.add_argument("--coarse-step-ratio", type=int, default=None, metavar="M",
                   help="multi-time-step: the coarse models' forces once every m <= M steps, "
                   "the largest stable m (1: off; default 2 with --model arlequin)")  # fmt: skip
    p.add_argument(
        "--t-end",
        type=float,
        default=None,
        metavar="T",
        help="simulated time (s); default 1.4 x Hertz's contact duration (elastic)",
    )
    p.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    add_out(p)
    p.set_defaults(func=_cmd)
