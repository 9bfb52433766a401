"""arlequin: Arlequin multiscale coupling for computational solid mechanics.

A coarse model of a whole structure and refined patches overlap, share the energy through
partition weights (α_coarse + α_fine = 1 in the overlap) and are glued by Lagrange-multiplier
mediators (L2 or H1 coupling) on a gluing zone. Physics models live in :mod:`arlequin.models`.

Public API
----------
ArlequinProblem, Patch          set up a coupled problem (:mod:`arlequin.problem`)
refine_region                   nested patches from coarse cells (:mod:`arlequin.patches`)
RampWeights, ConstantWeights,
CallableWeights                 partition weights (:mod:`arlequin.weights`)
solve_static                    static saddle-point solve (:mod:`arlequin.integrators.static`)
evaluate_field, locate_points   fields at points, bounded point locator
"""

from .fields import evaluate_field
from .integrators.static import StaticResult, solve_static
from .locate import locate_points
from .overlap import Overlap, OverlapError, build_overlap
from .patches import refine_region
from .problem import ArlequinProblem, Patch
from .weights import CallableWeights, ConstantWeights, RampWeights, WeightSumError

__version__ = "0.1.0"

__all__ = [
    "ArlequinProblem",
    "CallableWeights",
    "ConstantWeights",
    "Overlap",
    "OverlapError",
    "Patch",
    "RampWeights",
    "StaticResult",
    "WeightSumError",
    "build_overlap",
    "evaluate_field",
    "locate_points",
    "refine_region",
    "solve_static",
]
