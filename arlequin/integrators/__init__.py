"""Time integrators of coupled systems and the static solver.

Dynamic integrators (see ``docs/dynamics.md``), selected by name or class through
:func:`get_integrator` / :func:`solve`:

==========================  ===============================================================
``"explicit"``              :class:`CentralDifference`: lumped weighted masses, constraint
                            impulses at velocity level, critical step computed
``"newmark"``               :class:`Newmark` (β, γ) on the monolithic saddle point
``"hht"``                   :class:`HHTAlpha`: Newmark with numerical damping
``"theta"``                 :class:`ThetaScheme`: θ-scheme on (u, v)
==========================  ===============================================================

Constraints: equality rows are :class:`arlequin.system.LinearConstraint`; unilateral rows
(contact) follow :class:`UnilateralConstraint`.
"""

from .base import (
    REGISTRY,
    ConstraintError,
    DynamicResult,
    Integrator,
    SimulationError,
    SystemOperators,
    get_integrator,
    register,
    solve,
)
from .constraints import LinearInequality, UnilateralConstraint, is_unilateral
from .explicit import DEFAULT_SAFETY, CentralDifference
from .implicit import HHTAlpha, ImplicitIntegrator, Newmark, ThetaScheme
from .loads import Constant, LoadCurve, Ramp, Sine, SmoothStep, Tabulated
from .stability import StableStep, stable_time_step
from .static import SingularSystemError, StaticResult, solve_static

__all__ = [
    "DEFAULT_SAFETY",
    "REGISTRY",
    "CentralDifference",
    "Constant",
    "ConstraintError",
    "DynamicResult",
    "HHTAlpha",
    "ImplicitIntegrator",
    "Integrator",
    "LinearInequality",
    "LoadCurve",
    "Newmark",
    "Ramp",
    "SimulationError",
    "Sine",
    "SingularSystemError",
    "SmoothStep",
    "StableStep",
    "StaticResult",
    "SystemOperators",
    "Tabulated",
    "ThetaScheme",
    "UnilateralConstraint",
    "get_integrator",
    "is_unilateral",
    "register",
    "solve",
    "solve_static",
    "stable_time_step",
]
