"""The Arlequin patch test: a uniform stress state reproduced by a coarse model plus a patch.

A random configuration is built from a seed (:mod:`.meshes`): a coarse mesh with random
spacing and a patch band spanning the domain in all directions but one, glued along straight
bands at both of its ends; or, with ``layout="strip"`` or ``"square"``, uniform 2D grids. The
exact field is a linear displacement u(x) = A x (uniform strain and stress), its tractions on
the physical boundary and a few exact Dirichlet values removing the rigid motions
(:mod:`.setup`). Reported (:mod:`.result`, fractions): ``max_error`` (max |u_h − u| / max |u|
over the nodes of both models) and ``exact_residual`` (the relative residual of the exact fields
with the best multipliers in the discrete equations).

Modules: :mod:`.config` (``PatchTestConfig``, the ``arlequin patch-test`` options),
:mod:`.meshes`, :mod:`.setup`, :mod:`.run` (``run_patch_test``), :mod:`.result` and
:mod:`.report` (the results folder and the error picture).
"""

from ..config import register_runner
from . import run as _run
from .api import build_patch_test_problem, run_patch_test
from .config import DIMS, LAYOUTS, PatchTestConfig
from .report import plot_patch_test_error
from .result import PatchTestResult

__all__ = [
    "DIMS",
    "LAYOUTS",
    "PatchTestConfig",
    "PatchTestResult",
    "build_patch_test_problem",
    "plot_patch_test_error",
    "run_patch_test",
]

# the configuration runs through its package's runner (it does not import its run module);
# one static solve, no progress
register_runner(
    PatchTestConfig, lambda config, out=None, progress=None: _run.run_config(config, out)
)
