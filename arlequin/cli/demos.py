"""The demos' subcommands, registered in one place (:func:`add_demos`), shared by ``arlequin``
and the study runner (:mod:`arlequin.demos.study`), which parses and runs a case exactly as
the command line would. Every subcommand is generated from its demo's configuration
(:mod:`arlequin.cli.generate`)."""

from __future__ import annotations

import argparse

from ..demos.ball_impact.config import BallImpactConfig
from ..demos.patch_test.config import PatchTestConfig
from ..demos.plate_with_hole.config import PlateWithHoleConfig
from ..demos.pressure_vessel.config import PressureVesselConfig
from ..demos.sliding_block.config import SlidingBlockConfig
from ..demos.taylor_bar.config import TaylorBarConfig
from ..demos.two_bars.config import TwoBarsConfig
from ..demos.wave.config import WaveConfig
from .generate import add_demo, config_from_args

__all__ = ["add_demos", "check_case", "demo_parser"]


def add_demos(sub) -> None:
    """Register the demos' subcommands on an ``add_subparsers`` object."""
    add_demo(sub, PatchTestConfig)
    add_demo(sub, TwoBarsConfig)
    add_demo(sub, WaveConfig)
    add_demo(sub, TaylorBarConfig)
    add_demo(sub, SlidingBlockConfig)
    add_demo(sub, BallImpactConfig)
    add_demo(sub, PressureVesselConfig)
    add_demo(sub, PlateWithHoleConfig)


def check_case(demo: str, args: argparse.Namespace) -> None:
    """The demo's own input checks on a parsed command line, nothing run or written: its
    configuration made from the options (its checks run then). Raises the demo's
    ``ValueError``."""
    config = getattr(args, "config", None)
    if config is None:
        raise ValueError(f"{demo!r} is not a demo of the arlequin command")
    config_from_args(config, args)


def demo_parser() -> tuple[argparse.ArgumentParser, dict[str, argparse.ArgumentParser]]:
    """A parser of the demos' subcommands, and each subcommand's own parser by name."""
    parser = argparse.ArgumentParser(prog="arlequin")
    sub = parser.add_subparsers(dest="command", required=True)
    add_demos(sub)
    return parser, dict(sub.choices)
