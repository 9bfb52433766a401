"""Solvers of coupled systems: time integrators, the static and the quasi-static solvers.

Dynamic integrators (see ``docs/dynamics.md``), selected by name or class through
:func:`get_integrator` / :func:`solve`:

==========================  ===============================================================
``"explicit"``              :class:`CentralDifference`: lumped weighted masses, constraint
                            impulses at velocity level, critical step computed, variable steps
``"newmark"``               :class:`Newmark` (β, γ) on the monolithic saddle point
``"hht"``                   :class:`HHTAlpha`: Newmark with numerical damping
``"theta"``                 :class:`ThetaScheme`: θ-scheme on (u, v)
``"explicit-mts"``          :class:`SubcycledCentralDifference`: multi-time-step central
                            differences, slow blocks with a macro step of m fine steps
==========================  ===============================================================

Step sizes come from a step controller (:class:`FixedStep`, :class:`CriticalFraction`,
:class:`StepSchedule`) or from the caller (``integrator.step(dt)``). Constraints: equality rows
are :class:`arlequin.problem.system.LinearConstraint`; unilateral rows (contact) follow
:class:`arlequin.contract.UnilateralConstraint` (:class:`LinearInequality` is the minimal one).

One concept a module: ``operators`` (mass, forces, tangents), ``rows`` (constraint rows),
``linalg`` (factorisations), ``impulses`` (the explicit impulse solve), ``damping`` (Rayleigh
damping), ``controllers`` (step sizes), ``base`` (the :class:`Integrator` class), ``registry``,
``explicit``, ``subcycling``, ``implicit``, ``stability``, ``recorder``, ``result``, ``driver``
(:func:`solve`), ``static``, ``quasi_static`` (load stepping with Newton,
:func:`solve_quasi_static`), ``condensation`` (its Newton systems), ``direct`` (their sparse
direct solvers: SuperLU, or PARDISO where pypardiso is installed), ``loads``.
"""

from ..contract import ConstraintError, SimulationError, UnilateralConstraint
from .base import Integrator, IntegratorSnapshot
from .constraints import LinearInequality, is_unilateral
from .controllers import CriticalFraction, FixedStep, StepController, StepSchedule
from .damping import RayleighDamping
from .driver import solve
from .explicit import CentralDifference
from .implicit import HHTAlpha, ImplicitIntegrator, Newmark, ThetaScheme
from .loads import Constant, LoadCurve, Ramp, Sine, SmoothStep, Tabulated
from .operators import SystemOperators
from .quasi_static import NewtonError, QuasiStaticResult, QuasiStaticSolver, solve_quasi_static
from .recorder import Recorder
from .registry import REGISTRY, get_integrator, register
from .result import DynamicResult
from .stability import DEFAULT_SAFETY, StableStep, check_time_step, stable_time_step
from .static import SingularSystemError, StaticResult, solve_static
from .subcycling import SubcycledCentralDifference

__all__ = [
    "DEFAULT_SAFETY",
    "REGISTRY",
    "CentralDifference",
    "Constant",
    "ConstraintError",
    "CriticalFraction",
    "DynamicResult",
    "FixedStep",
    "HHTAlpha",
    "ImplicitIntegrator",
    "Integrator",
    "IntegratorSnapshot",
    "LinearInequality",
    "LoadCurve",
    "Newmark",
    "NewtonError",
    "QuasiStaticResult",
    "QuasiStaticSolver",
    "Ramp",
    "RayleighDamping",
    "Recorder",
    "SimulationError",
    "Sine",
    "SingularSystemError",
    "SmoothStep",
    "StableStep",
    "StaticResult",
    "StepController",
    "StepSchedule",
    "SubcycledCentralDifference",
    "SystemOperators",
    "Tabulated",
    "ThetaScheme",
    "UnilateralConstraint",
    "check_time_step",
    "get_integrator",
    "is_unilateral",
    "register",
    "solve",
    "solve_quasi_static",
    "solve_static",
    "stable_time_step",
]
