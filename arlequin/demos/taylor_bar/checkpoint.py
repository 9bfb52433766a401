"""Checkpoints of a Taylor bar run, and resuming one.

Every ``interval`` of simulated time (at the first record at or after it) the run writes
``checkpoint.pkl`` into its results folder, atomically (a temporary file renamed over the last
one): the integrator's snapshot, what the integrator's recorder and the Taylor recorder have
recorded, the per-step multipliers, the inputs and the call's keywords. A resumed run rebuilds
the same set-up from those keywords, writes again the history rows and field frames recorded
until the checkpoint (read back from the interrupted run's files), restores the integrator and
continues: the same steps, and the same values bit for bit (wall times, timestamps and the
command line aside). The checkpoint is removed when the run completes.
"""

from __future__ import annotations

import logging
import os
import pickle
from pathlib import Path
from typing import Any

from ...io import read_checkpoint, read_series, write_checkpoint

__all__ = ["CHECKPOINT", "CheckpointWriter", "load_checkpoint", "read_frames"]

logger = logging.getLogger(__name__)

#: The checkpoint's file name in the results folder.
CHECKPOINT = "checkpoint.pkl"

# 2: the multi-time-step integrator's snapshot keeps its slow force by dof ranges
_FORMAT = 2


class CheckpointWriter:
    """The ``on_checkpoint`` listener of :func:`arlequin.solvers.solve` for a Taylor run.

    Parameters
    ----------
    folder : Path
        The results folder.
    interval : float
        Simulated time between checkpoints (s).
    config : dict
        The run's inputs (checked on resume).
    call : dict
        The keywords of ``run_taylor_bar`` that rebuild the run.
    taylor : TaylorRecorder
    multipliers : MultiplierHistory or None
    """

    def __init__(self, folder: Path, interval: float, config: dict, call: dict, taylor,
                 multipliers) -> None:  # fmt: skip
        self.path = Path(folder) / CHECKPOINT
        self.interval = float(interval)
        self.config, self.call = config, call
        self.taylor, self.multipliers = taylor, multipliers
        self.next_time = 0.0
        self.enabled = True
        self.written = 0

    def __call__(self, integ, recorder) -> None:
        t = float(integ.t)
        if not self.enabled or t < self.next_time * (1.0 - 1e-12):
            return
        # the next checkpoint time depends on t only: the same in a resumed run
        self.next_time = (int(t / self.interval + 1e-9) + 1) * self.interval
        data = {
            "format": _FORMAT, "t": t, "config": self.config, "call": self.call,
            "snapshot": integ.snapshot(), "recorder": recorder.state(),
            "taylor": self.taylor.state(),
            "multipliers": None if self.multipliers is None else self.multipliers.state(),
        }  # fmt: skip
        try:
            write_checkpoint(self.path, data)
        except (pickle.PicklingError, TypeError, AttributeError) as exc:
            self.enabled = False  # e.g. user weights given as lambdas: no resume
            logger.warning("checkpoints disabled: the run's inputs cannot be saved (%s)", exc)
            return
        self.written += 1

    def resume_from(self, ckpt: dict[str, Any], frames: dict[str, list]) -> None:
        """Continue from a checkpoint: the Taylor recorder and the multipliers get back what
        they had recorded (the history rows and the field ``frames`` written until then,
        :func:`read_frames` of the folder before it reopened, are written again) and the next
        checkpoint is the one after it."""
        self.taylor.restore(ckpt["taylor"], frames)
        if self.multipliers is not None:
            self.multipliers.restore(ckpt["multipliers"])
        self.next_time = (int(ckpt["t"] / self.interval + 1e-9) + 1) * self.interval

    def remove(self) -> None:
        """Delete the checkpoint (the run completed)."""
        self.path.unlink(missing_ok=True)


def load_checkpoint(out: str | os.PathLike | None, config: dict | None) -> dict[str, Any]:
    """The checkpoint of the results folder ``out``, written by a run with inputs ``config``
    (None: any).

    Raises
    ------
    ValueError
        If ``out`` is None, has no (readable) checkpoint (nothing to resume: the run completed
        or never reached its first checkpoint), or one written by a run with other inputs.
    """
    if out is None:
        raise ValueError("resume=True needs out=DIR, the results folder of the interrupted run")
    path = Path(out) / CHECKPOINT
    data = read_checkpoint(path)  # CheckpointError (a ValueError): none, or unreadable
    if not isinstance(data, dict) or data.get("format") != _FORMAT:
        raise ValueError(f"{str(path)!r} is not a Taylor bar checkpoint of this version")
    if config is not None and data["config"] != config:
        diff = sorted(k for k in set(config) | set(data["config"])
                      if config.get(k) != data["config"].get(k))  # fmt: skip
        raise ValueError(
            f"the checkpoint in {str(out)!r} belongs to a run with other inputs ({diff}); "
            f"resume it with resume_taylor_bar({str(out)!r}) or `arlequin taylor-bar --resume "
            f"--out {out}`"
        )
    return data


def read_frames(out: str | os.PathLike, names) -> dict[str, list]:
    """The field frames already written in ``out`` (series name -> [(t, point, cell)])."""
    frames = {}
    for name in names:
        path = Path(out) / "fields" / f"{name}.xdmf"
        frames[name] = read_series(path)[1] if path.is_file() else []
    return frames
