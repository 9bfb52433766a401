"""Sets of state arrays reused once nothing outside the pool references them.

A compiled state update writes a new immutable state at every call. Fresh arrays of a few
megabytes are fresh pages (about 1,000 page faults per evaluation of the J2 internal force at
nr = 30, 7 MB), which cost as much as the kernel itself; a set of arrays that no state, copy
holder or view references any more is written over instead. The test is the arrays' reference
counts, calibrated at import against an array held only by its list (the count varies between
Python versions), so a state still held anywhere is never overwritten.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

import numpy as np

__all__ = ["ArrayPool"]


def _max_refs(arrays: Sequence[np.ndarray]) -> int:
    return max(sys.getrefcount(a) for a in arrays)


# the references of an array held only by its list (and by this check)
_FREE_REFS = _max_refs([np.empty(1)])


class ArrayPool:
    """At most ``size`` sets of float arrays of fixed shapes, handed out again once free.

    Parameters
    ----------
    size : int
        Sets kept (an explicit integrator holds two states at once, the committed one and the
        trial; a third for a caller that keeps one more). Beyond it, sets are allocated and
        not kept.
    """

    def __init__(self, size: int = 3) -> None:
        self.size = size
        self._sets: list[list[np.ndarray]] = []

    def take(self, shapes: Sequence[tuple[int, ...]]) -> list[np.ndarray]:
        """A set of arrays of these shapes that nothing else references: a set handed out
        before (holding what its user wrote), or fresh arrays of zeros (``calloc``'s pages,
        zeroed as they are first touched: a writer may leave entries that stay zero unwritten,
        e.g. the out-of-plane shear of planar states)."""
        shapes = [tuple(s) for s in shapes]
        for arrays in self._sets:
            if [a.shape for a in arrays] == shapes and _max_refs(arrays) <= _FREE_REFS:
                return arrays
        arrays = [np.zeros(s) for s in shapes]
        if len(self._sets) < self.size:
            self._sets.append(arrays)
        return arrays
