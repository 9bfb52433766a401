"""The ``arlequin`` command: a thin layer over :mod:`arlequin.demos`.

Each subcommand runs one demo, prints a one-line summary and optionally writes JSON (SI units;
``*_error`` and ``*_fraction`` values are dimensionless fractions, not percent).
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
from collections.abc import Sequence

__all__ = ["main"]


def _write_json(path: str | None, data: dict) -> None:
    if path:
        with open(path, "w", encoding="utf-8") as fh:
            json.dump(data, fh, indent=2)


def _cmd_patch_test(args: argparse.Namespace) -> int:
    from .demos.patch_test import run_patch_test

    result = run_patch_test(
        dim=args.dim,
        coupling=args.coupling,
        weights=args.weights,
        mediator=args.mediator,
        mesh=args.mesh,
        seed=args.seed,
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
    p.add_argument("--json", metavar="PATH", default=None, help="write the results as JSON")
    p.set_defaults(func=_cmd_patch_test)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="arlequin", description="Arlequin multiscale coupling: demos and verification."
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress (INFO)")
    sub = parser.add_subparsers(dest="command", required=True)
    _add_patch_test(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
    )
    try:
        return int(args.func(args) or 0)
    except ValueError as exc:
        print(f"arlequin {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
