"""arlequin.io.checkpoint: atomic writes, named errors (the pressure vessel's and the Taylor
bar's --resume read through it)."""

from __future__ import annotations

import pickle

import pytest

from arlequin.io import CheckpointError, read_checkpoint, write_checkpoint


def test_a_checkpoint_round_trips_and_a_failed_write_keeps_the_previous_one(tmp_path):
    path = tmp_path / "checkpoint.pkl"
    write_checkpoint(path, {"step": 1})
    with pytest.raises((TypeError, AttributeError, pickle.PicklingError)):
        write_checkpoint(path, {"step": 2, "user_weight": lambda x: x})  # not picklable
    assert read_checkpoint(path) == {"step": 1}
    assert [p.name for p in tmp_path.iterdir()] == ["checkpoint.pkl"]  # no partial file left


def test_a_missing_or_unreadable_checkpoint_is_named(tmp_path):
    with pytest.raises(CheckpointError, match="nothing to resume"):
        read_checkpoint(tmp_path / "checkpoint.pkl")
    (tmp_path / "checkpoint.pkl").write_bytes(b"not a pickle")
    with pytest.raises(CheckpointError, match="cannot read the checkpoint"):
        read_checkpoint(tmp_path / "checkpoint.pkl")
