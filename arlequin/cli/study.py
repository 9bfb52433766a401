"""``arlequin study SPEC``: a parameter study of a demo on Dask (:mod:`arlequin.demos.study`)."""

from __future__ import annotations

import argparse
import sys

__all__ = ["add_study"]


def _cmd(args: argparse.Namespace) -> int:
    from ..demos.study import study

    quiet = args.quiet or not sys.stderr.isatty()

    def progress(done: int, running: int, failed: int, total: int, eta: float | None) -> None:
        if quiet:
            return
        left = "" if eta is None else f", ETA {eta:.0f} s"
        print(f"\rcases: {done}/{total} done, {running} to go, {failed} failed{left}   ",
              end="", file=sys.stderr, flush=True)  # fmt: skip

    def announce(link: str | None) -> None:
        if link and not args.quiet:
            print(f"Dask dashboard: {link}", flush=True)

    run = study(args.spec, out=args.out, scheduler=args.scheduler, workers=args.workers,
                resume=args.resume, progress=progress, on_cluster=announce)  # fmt: skip
    if not quiet:
        print(file=sys.stderr)
    print(f"study {run.out}: {len(run.ran)} cases run, {len(run.skipped)} already complete, "
          f"{len(run.failed)} failed; table in {run.out / 'results.csv'}")  # fmt: skip
    for case, reason in run.failed.items():
        print(f"  {case} failed: {reason}")
    return 1 if run.failed else 0


def add_study(sub) -> None:
    """Register the ``study`` subcommand."""
    p = sub.add_parser(
        "study",
        help="a parameter study of a demo, each case a task on Dask",
        description='Run the cases of a study file (TOML: demo = "two-bars", [parameters] with '
        "lists as grid axes) on a local Dask cluster or the scheduler at --scheduler; each case "
        "writes its results folder under --out/cases/, the study an index and results.csv. "
        "Completed cases are skipped on a rerun.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("spec", metavar="SPEC", help="the study file (TOML)")
    p.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        default=None,
        help="a running Dask scheduler; without it, a local cluster",
    )
    p.add_argument(
        "--workers",
        type=int,
        default=None,
        metavar="N",
        help="workers of the local cluster; without it, one per core",
    )
    p.add_argument("--out", metavar="DIR", default="study", help="the study folder")
    p.add_argument(
        "--resume",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="skip the cases already complete in --out",
    )
    p.add_argument("--quiet", action="store_true", help="no progress line, no dashboard link")
    p.set_defaults(func=_cmd)
