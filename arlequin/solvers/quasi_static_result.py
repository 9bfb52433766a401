"""What a quasi-static run gives back: its converged steps, its result, its failure
(:func:`arlequin.solvers.quasi_static.solve_quasi_static`). SI units."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..contract import CoarseYieldWarning, SimulationError
from ..problem.system import CoupledSystem

__all__ = ["STATUSES", "CoarseYieldWatch", "NewtonError", "QuasiStaticResult", "QuasiStaticStep"]

#: How a quasi-static run ends: the target load reached, a limit load, a stop asked by the
#: callback.
STATUSES = ("completed", "limit_load", "stopped")


class NewtonError(SimulationError):
    """Newton's method failed at the smallest load step (or a model's state was invalid there):
    the run stops; ``result`` holds every converged step."""


@dataclass(frozen=True)
class QuasiStaticStep:
    """One converged load step.

    Attributes
    ----------
    load_factor : float
        λ at the end of the step.
    step : float
        Δλ of the step (after any cut).
    iterations : int
        Newton iterations.
    residuals : tuple of float
        The relative residual before each iteration and after the last.
    cuts : int
        How many times the step was cut before it converged.
    """

    load_factor: float
    step: float
    iterations: int
    residuals: tuple[float, ...]
    cuts: int


@dataclass
class QuasiStaticResult:
    """What :func:`solve_quasi_static` computed.

    Attributes
    ----------
    status : {"completed", "limit_load", "stopped"}
    message : str
    load_factors : list of float
        λ of the initial state and of every converged step.
    steps : list of QuasiStaticStep
    u : ndarray, shape (n,)
        Final displacement (m).
    displacements : dict
        Block name -> final displacement (m).
    multipliers : dict
        Constraint name -> final multipliers (the constraint's dual unit: N for L2 rows on
        displacements in m... see the constraint).
    reactions : ndarray, shape (n,)
        Reaction forces at the Dirichlet dofs (N), zero elsewhere: f_int − f_ext there.
    states : dict
        Block name -> the committed model states of its terms.
    limit_load : float or None
        The last converged λ when the run ended at a limit load.
    linear_solver : str
        The sparse direct solver of the Newton systems (``"superlu"`` or ``"pardiso"``).
    timings : dict
        Seconds (wall time) of the load steps: ``"constitutive_and_tangent_s"``,
        ``"factorisation_s"``, ``"solve_s"``, ``"other_s"``
        (:attr:`QuasiStaticSolver.timings <arlequin.solvers.quasi_static.QuasiStaticSolver>`).
    """

    status: str
    message: str
    load_factors: list[float]
    steps: list[QuasiStaticStep]
    u: np.ndarray
    displacements: dict[str, np.ndarray]
    multipliers: dict[str, np.ndarray]
    reactions: np.ndarray
    states: dict[str, list[Any]]
    limit_load: float | None = None
    system: CoupledSystem | None = field(default=None, repr=False)
    #: with ``adapt=``: the patch's growths (:class:`arlequin.problem.adapt.Adaptation`), the
    #: largest σ_vm/σy of the coarse model outside the patch over the accepted steps, the
    #: final problem
    adaptations: list[Any] = field(default_factory=list)
    max_coarse_yield_ratio: float | None = None
    problem: Any = field(default=None, repr=False)
    linear_solver: str = "superlu"
    timings: dict[str, float] = field(default_factory=dict)

    @property
    def newton_iterations(self) -> list[int]:
        """Newton iterations of every converged step."""
        return [s.iterations for s in self.steps]

    @property
    def residuals(self) -> list[list[float]]:
        """Relative residuals of every converged step's iterations."""
        return [list(s.residuals) for s in self.steps]


class CoarseYieldWatch:
    """The largest coarse von Mises / σy outside the patches over the steps, for a problem that
    can tell it (``coarse_yield_ratio``, an ``ArlequinProblem`` with J2 patches); a
    :class:`~arlequin.contract.CoarseYieldWarning` once it passes 1."""

    def __init__(self, problem: Any) -> None:
        self.ratio_of = getattr(problem, "coarse_yield_ratio", None)
        self.worst: float | None = None
        self.warned = False

    def __call__(self, solver: Any) -> None:
        if self.ratio_of is None:
            return
        ratio = self.ratio_of(solver.u)
        if ratio is None:
            self.ratio_of = None
            return
        self.worst = ratio if self.worst is None else max(self.worst, ratio)
        if ratio > 1.0 and not self.warned:
            self.warned = True
            warnings.warn(
                f"at λ = {solver.t:.6g} the coarse model outside the patches carries von Mises "
                f"stresses {ratio:.3f} times the patches' yield stress: the plastic zone has "
                "outgrown the patches (the results past this load are not those of the "
                "elastoplastic material: widen the patches, or use an AdaptivePatch)",
                CoarseYieldWarning,
                stacklevel=3,
            )

    def finish(self, result: QuasiStaticResult) -> QuasiStaticResult:
        """``result`` with the largest ratio seen (``max_coarse_yield_ratio``; None if the
        problem has no coarse yield check)."""
        result.max_coarse_yield_ratio = self.worst
        return result
