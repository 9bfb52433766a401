"""The sliding block (:mod:`arlequin.demos.sliding_block.run`), a package from now on."""

from .run import DAMPING, JSON_KEYS, RAMP_TRANSITS, SlidingBlockResult, run_sliding_block

__all__ = ["DAMPING", "JSON_KEYS", "RAMP_TRANSITS", "SlidingBlockResult", "run_sliding_block"]
