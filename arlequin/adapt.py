"""``arlequin.adapt``: adaptive patches, one concept (issue 31) under the name the issue gives it.

The patch that grows (:class:`AdaptivePatch`, its records and errors) lives in
:mod:`arlequin.problem.adapt`, with the problem it rebuilds; the load stepping that drives it in
:mod:`arlequin.solvers.statics.adaptive` (``solve_quasi_static(problem, ...,
adapt=AdaptivePatch())``) and, in explicit runs, in
:mod:`arlequin.solvers.dynamics.adaptive_dynamic` (``solve(problem, "explicit", ...,
adapt=AdaptivePatch())``); :class:`BodyAdaptation` adapts the patch of one body of a
multi-body problem (the ball impact's block).
"""

from .problem.adapt import (
    Adaptation,
    AdaptivePatch,
    AdaptView,
    Growth,
    IndicatorError,
    NonNestedPatchError,
    PatchLimitError,
)
from .problem.adapt_bodies import BodyAdaptation
from .solvers.statics.adaptive import run_adaptive

__all__ = [
    "AdaptView",
    "Adaptation",
    "AdaptivePatch",
    "BodyAdaptation",
    "Growth",
    "IndicatorError",
    "NonNestedPatchError",
    "PatchLimitError",
    "run_adaptive",
]
