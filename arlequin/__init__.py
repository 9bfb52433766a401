"""arlequin: Arlequin multiscale coupling for computational solid mechanics.

A coarse model of a whole structure and refined patches overlap, share the energy through
partition weights (α_coarse + α_fine = 1 in the overlap) and are glued by Lagrange-multiplier
mediators (L2 or H1 coupling) on a gluing zone. Physics models live in :mod:`arlequin.models`.

Public API (``docs/api.md`` lists every name with the module it lives in)
--------------------------------------------------------------------------
ArlequinProblem, Patch,
PatchCoupling                   set up a coupled problem (:mod:`arlequin.problem.arlequin_problem`,
                                :mod:`arlequin.coupling.gluing`)
MultiBodyProblem                several bodies (problems or models) in one system
                                (:mod:`arlequin.problem.bodies`)
refine_region                   nested patches from coarse cells (:mod:`arlequin.coupling.patches`)
AdaptivePatch, adapt            a nested patch that grows where the material yields
                                (:mod:`arlequin.adapt`)
RampWeights, ConstantWeights,
CallableWeights                 partition weights (:mod:`arlequin.coupling.weights`)
solve_static, solve,
solve_quasi_static              static, dynamic and quasi-static solves (:mod:`arlequin.solvers`)
DofMap                          the dof layout of a coupled system (:mod:`arlequin.dofs`)
ResultsFolder                   results on disk (:mod:`arlequin.io`)
evaluate_field, locate_points   fields at points, bounded point locator
errors                          ``ValueError`` subclasses naming the quantity and its value
"""

import importlib.abc as _abc
import importlib.util as _util
import sys as _sys
from pathlib import Path as _Path


def _map_models_folder() -> None:
    """Make ``arlequin.models`` the sibling ``models/`` folder when this package is the source
    tree (``arlequin/`` next to ``models/``, e.g. run from the repository root after
    ``pip install .``, where the local folder shadows the installed package). Installed
    packages hold ``arlequin/models/`` themselves and are left alone."""
    here = _Path(__file__).resolve().parent
    source = here.parent / "models"
    if (here / "models").is_dir() or not (source / "__init__.py").is_file():
        return

    class _ModelsFinder(_abc.MetaPathFinder):
        def find_spec(self, name, path=None, target=None):
            if name != "arlequin.models":
                return None
            return _util.spec_from_file_location(
                name, source / "__init__.py", submodule_search_locations=[str(source)]
            )

    if not any(type(f).__name__ == "_ModelsFinder" for f in _sys.meta_path):
        _sys.meta_path.insert(0, _ModelsFinder())


_map_models_folder()


def numba_cache_dir() -> str:
    """Where numba keeps the compiled kernels of this package (``cache=True``): the
    ``NUMBA_CACHE_DIR`` environment variable if set, else a per-user cache directory,
    ``$XDG_CACHE_HOME/arlequin/numba`` (``~/.cache/arlequin/numba`` by default), or a folder of
    the temporary directory where that cannot be written.

    Never inside the installed package: a cache there outlives ``pip uninstall`` (the
    leftover folder then shadows ``arlequin.models`` of the next installation) and cannot be
    written in a read-only installation. numba keeps one subfolder per source folder, so
    several installations share the directory without clashing.
    """
    import os

    given = os.environ.get("NUMBA_CACHE_DIR")
    if given:
        return given
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    path = os.path.join(base, "arlequin", "numba")
    try:
        os.makedirs(path, exist_ok=True)
        if os.access(path, os.W_OK):
            return path
    except OSError:
        pass
    # no writable home (a service account): the temporary directory, one folder per user
    import tempfile

    return os.path.join(tempfile.gettempdir(), f"arlequin-numba-{os.getuid()}")


def _cache_kernels_outside_the_package() -> None:
    """Point numba's cache at :func:`numba_cache_dir` before any kernel of the package is
    compiled (the kernels' modules are imported after this package's ``__init__``)."""
    import numba

    if not numba.config.CACHE_DIR:
        numba.config.CACHE_DIR = numba_cache_dir()


_cache_kernels_outside_the_package()

from . import adapt
from .adapt import AdaptivePatch, PatchLimitError
from .contract import (
    BandYieldWarning,
    CapabilityError,
    CoarseYieldWarning,
    ConstraintError,
    ContractError,
    LinearSolverError,
    SimulationError,
    StateError,
)
from .coupling.fields import evaluate_field
from .coupling.gluing import ExactnessWarning, Patch, PatchCoupling
from .coupling.mediators import MediatorError
from .coupling.overlap import Overlap, OverlapError, build_overlap
from .coupling.patches import refine_region
from .coupling.weights import CallableWeights, ConstantWeights, RampWeights, WeightSumError
from .dofs import DofMap
from .geometry.locate import locate_points
from .geometry.meshcheck import MeshError, check_mesh
from .io import ResultsFolder
from .problem.arlequin_problem import ArlequinProblem
from .problem.bodies import MultiBodyProblem
from .solvers import DynamicResult, solve
from .solvers.statics.quasi_static import NewtonError, QuasiStaticResult, solve_quasi_static
from .solvers.statics.static import SingularSystemError, StaticResult, solve_static

__version__ = "0.1.0"

__all__ = [
    "AdaptivePatch",
    "ArlequinProblem",
    "BandYieldWarning",
    "CallableWeights",
    "CapabilityError",
    "CoarseYieldWarning",
    "ConstantWeights",
    "ConstraintError",
    "ContractError",
    "DofMap",
    "DynamicResult",
    "ExactnessWarning",
    "LinearSolverError",
    "MediatorError",
    "MeshError",
    "MultiBodyProblem",
    "NewtonError",
    "Overlap",
    "OverlapError",
    "Patch",
    "PatchCoupling",
    "PatchLimitError",
    "QuasiStaticResult",
    "RampWeights",
    "ResultsFolder",
    "SimulationError",
    "SingularSystemError",
    "StateError",
    "StaticResult",
    "WeightSumError",
    "adapt",
    "build_overlap",
    "check_mesh",
    "evaluate_field",
    "locate_points",
    "refine_region",
    "solve",
    "solve_quasi_static",
    "solve_static",
]


def __getattr__(name: str):
    """``arlequin.study``: the study runner, which lives with the demos it runs
    (:func:`arlequin.demos.study.study`), loaded on first use so that the core does not import
    the demos."""
    if name == "study":
        from importlib import import_module

        return import_module("arlequin.demos.study").study
    raise AttributeError(f"module 'arlequin' has no attribute {name!r}")
