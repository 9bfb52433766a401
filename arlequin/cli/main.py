"""The ``arlequin`` command: a thin layer over :mod:`arlequin.demos`.

Each subcommand runs one demo, prints a one-line summary and optionally writes JSON (SI units;
``*_error`` and ``*_fraction`` values are dimensionless fractions, not percent) and a results
folder (``--out DIR``: results.json with the inputs and their units, history.csv, XDMF field
series that ParaView opens, pictures; see :mod:`arlequin.io`).
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import warnings
from collections.abc import Sequence

from .. import __version__
from ..contract import SimulationError
from .common import NonFiniteResult
from .common import check_writable as _check_writable
from .demos import add_demos
from .info import add_info
from .study import add_study

__all__ = ["main"]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="arlequin", description="Arlequin multiscale coupling: demos and verification."
    )
    parser.add_argument(
        "-v",
        "--verbose",
        action="store_true",
        help="log the library's progress (INFO; other libraries stay at WARNING)",
    )
    parser.add_argument("--version", action="version", version=f"arlequin {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    add_demos(sub)
    add_study(sub)
    add_info(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``arlequin`` command with ``argv`` (default ``sys.argv[1:]``); return its exit status
    (0 success, 1 failed run, 2 bad input)."""
    # OpenMP threads (numba's kernels) sleep between parallel regions instead of spinning: on
    # a small machine a spinning worker slows the serial part of each step (the plastic ball
    # impact, 2,000 steps: 10.1-13.8 s spinning, 10.1-10.3 s passive); read by libgomp when
    # the first kernel runs, so a user's own setting wins
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    # a warning as one line naming its kind (Python's default shows a source line, which reads
    # like a crash)
    warnings.formatwarning = lambda message, category, *_, **__: (
        f"warning ({category.__name__}): {message}\n"
    )
    if args.verbose:  # the library's own messages, not scikit-fem's or numba's internals
        logging.getLogger("arlequin").setLevel(logging.INFO)
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
    except KeyboardInterrupt:  # Ctrl-C: what was written stays (resumable demos: --resume)
        print(f"arlequin {args.command}: interrupted", file=sys.stderr)
        return 130
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
