"""What the commands of the ``arlequin`` CLI share: the results check, JSON output, ``--out``,
the progress bar."""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
from collections.abc import Callable, Iterator

__all__ = [
    "NonFiniteResult",
    "ProgressBar",
    "add_out",
    "check_writable",
    "progress_bar",
    "write_json",
]


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


def write_json(path: str | None, data: dict) -> None:
    """Write ``data`` as JSON to ``path`` (if given) after refusing non-finite values."""
    _check_results(data)
    if path:
        with open(path, "w", encoding="utf-8") as fh:
            json.dump(data, fh, indent=2)


def check_writable(path: str | None, option: str) -> None:
    """Refuse, before any computation, an output file whose folder cannot be written."""
    if not path:
        return
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder) or not os.access(folder, os.W_OK):
        raise ValueError(
            f"{option} {path!r}: the folder {folder!r} does not exist or is not writable"
        )


def add_out(p: argparse.ArgumentParser) -> None:
    """The ``--out DIR`` option of the demos."""
    p.add_argument(
        "--out",
        metavar="DIR",
        default=None,
        help="write a results folder: results.json, CSV histories, fields/*.xdmf, pictures",
    )


class ProgressBar:
    """A tqdm bar with ETA on stderr, opened at the first update (so that input errors, raised
    before any work, print no bar); off when stderr is not a terminal.

    Parameters
    ----------
    total : float
        The end of the bar, in ``unit``.
    unit : str
    scale : float
        ``update(x)`` shows ``x * scale`` (e.g. seconds of simulated time shown in µs).
    label : str
    """

    def __init__(self, total: float, unit: str, scale: float = 1.0,
                 label: str = "progress") -> None:  # fmt: skip
        self.total, self.unit, self.scale, self.label = total, unit, scale, label
        self.bar = None

    def update(self, x: float) -> None:
        """Show ``x`` (in the caller's unit, times ``scale``) as done."""
        if self.bar is None:
            from tqdm import tqdm

            self.bar = tqdm(
                total=round(self.total, 3),
                unit=self.unit,
                desc=self.label,
                leave=False,
                disable=None,  # off when stderr is not a terminal (logs, pipes, CI)
                bar_format="{l_bar}{bar}| {n:.1f}/{total:.1f} "
                + self.unit
                + " [{elapsed}<{remaining}]",
            )
        self.bar.n = round(x * self.scale, 3)
        self.bar.refresh()

    def close(self) -> None:
        """Close the bar (if it was opened)."""
        if self.bar is not None:
            self.bar.close()


@contextlib.contextmanager
def progress_bar(total: float, unit: str, quiet: bool, scale: float = 1.0,
                 label: str = "progress") -> Iterator[Callable[[float], None] | None]:  # fmt: skip
    """``with progress_bar(...) as update:`` a lazily opened :class:`ProgressBar` (``update``
    its update; None when ``quiet``), closed on leaving the block, whatever happens in it."""
    if quiet:
        yield None
        return
    bar = ProgressBar(total, unit, scale, label)
    try:
        yield bar.update
    finally:
        bar.close()
