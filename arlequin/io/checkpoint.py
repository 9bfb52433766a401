"""Checkpoints of a run: one pickle file, rewritten atomically after every converged step, so
that an interrupted run continues from its last one (``--resume``).

The payload is whatever the demo needs to continue: its configuration, the solver's snapshot
(arrays and immutable states), its recorder's history. A checkpoint is read back only by the
same version of the library that wrote it (pickles are not an exchange format): results go to
``results.json``, CSV and XDMF.
"""

from __future__ import annotations

import os
import pickle
from pathlib import Path
from typing import Any

__all__ = ["CheckpointError", "read_checkpoint", "write_checkpoint"]


class CheckpointError(ValueError):
    """No usable checkpoint where one was expected (the path named)."""


def write_checkpoint(path: str | os.PathLike, payload: dict[str, Any]) -> None:
    """Write ``payload`` to ``path`` (write a temporary file, then rename: an interruption
    leaves the previous checkpoint whole)."""
    path = Path(path)
    tmp = path.with_suffix(path.suffix + ".tmp")
    try:
        with open(tmp, "wb") as fh:
            pickle.dump(payload, fh, protocol=pickle.HIGHEST_PROTOCOL)
    except BaseException:  # an unpicklable payload or an interruption: no partial file left
        tmp.unlink(missing_ok=True)
        raise
    os.replace(tmp, path)


def read_checkpoint(path: str | os.PathLike) -> dict[str, Any]:
    """The payload written at ``path``.

    Raises
    ------
    CheckpointError
        No checkpoint there (the run finished before its first step, or another folder), or an
        unreadable one.
    """
    path = Path(path)
    if not path.is_file():
        raise CheckpointError(
            f"no checkpoint {str(path)!r}: nothing to resume (the run completed, or it stopped "
            "before its first step); --resume needs the results folder of an interrupted run "
            "(--out DIR of that run)"
        )
    try:
        with open(path, "rb") as fh:
            return pickle.load(fh)
    except Exception as exc:  # a truncated or foreign file
        raise CheckpointError(f"cannot read the checkpoint {str(path)!r}: {exc}") from exc
