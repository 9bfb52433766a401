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

Four sub-packages, one concept a module in each: ``system`` (what every solver reads off the
coupled system: ``operators`` for masses, forces and tangents, ``rows`` for constraint rows,
``constraints``, ``loads``, ``yield_watch``), ``dynamics`` (``base``: the :class:`Integrator`
class, ``registry``, ``controllers`` for step sizes, ``stability``, ``damping`` for Rayleigh
damping, ``explicit`` with its impulse basis ``row_basis``, ``subcycling``, ``implicit``,
``adaptive_dynamic``), ``statics`` (``static``, ``quasi_static``: load stepping with Newton,
:func:`solve_quasi_static`, its result ``quasi_static_result``, ``condensation`` for its Newton
systems, ``adaptive``) and ``run`` (``driver``: :func:`solve`, ``recorder``, ``result``). The
linear algebra they call (factorisations, the sparse direct solvers, the explicit impulse solve,
the compiled products and vector updates) is the layer below, :mod:`arlequin.linalg`.
"""

from ..contract import ConstraintError, SimulationError, UnilateralConstraint
from .dynamics.base import Integrator, IntegratorSnapshot
from .dynamics.controllers import CriticalFraction, FixedStep, StepController, StepSchedule
from .dynamics.damping import RayleighDamping
from .dynamics.explicit import CentralDifference
from .dynamics.implicit import HHTAlpha, ImplicitIntegrator, Newmark, ThetaScheme
from .dynamics.registry import REGISTRY, get_integrator, register
from .dynamics.stability import DEFAULT_SAFETY, StableStep, check_time_step, stable_time_step
from .dynamics.subcycling import SubcycledCentralDifference
from .run.driver import solve
from .run.recorder import Recorder
from .run.result import DynamicResult
from .statics.quasi_static import (
    NewtonError,
    QuasiStaticResult,
    QuasiStaticSolver,
    solve_quasi_static,
)
from .statics.static import SingularSystemError, StaticResult, solve_static
from .system.constraints import LinearInequality, is_unilateral
from .system.loads import Constant, LoadCurve, Ramp, Sine, SmoothStep, Tabulated
from .system.operators import SystemOperators

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
