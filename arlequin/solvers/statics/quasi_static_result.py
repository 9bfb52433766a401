"""What a quasi-static run gives back: its converged steps, its result, its failure
(:func:`arlequin.solvers.statics.quasi_static.solve_quasi_static`). SI units.

Each converged step keeps a record of its Newton iterations (:class:`NewtonIteration`): the
relative residuals as the solver measures them and how many quadrature points crossed the
yield surface in the iteration. A point is *plastic* at an iterate when its equivalent
plastic strain ε̄p there exceeds the committed one (the return map flowed over the step),
*elastic* otherwise; a crossing is a change of that status from one iterate to the next. The
consistent tangent is the derivative of the response only while that set stays the same, so
these counts tell which iterations may be expected to converge quadratically. ε̄p is read
duck-typed (the solvers never import the models): the model's
``equivalent_plastic_strain(state)`` where it has one, else the state's ``eqps``; models with
neither (elastic ones) have no point to count.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...contract import CoarseYieldWarning, SimulationError
from ...problem.system import CoupledSystem

__all__ = [
    "STATUSES",
    "CoarseYieldWatch",
    "IterationTracker",
    "NewtonError",
    "NewtonIteration",
    "QuasiStaticResult",
    "QuasiStaticStep",
    "plastic_points",
]

#: How a quasi-static run ends: the target load reached, a limit load, a stop asked by the
#: callback.
STATUSES = ("completed", "limit_load", "stopped")


class NewtonError(SimulationError):
    """Newton's method failed at the smallest load step (or a model's state was invalid there):
    the run stops; ``result`` holds every converged step."""


@dataclass(frozen=True)
class NewtonIteration:
    """One Newton iteration of a converged load step (see the module docstring).

    Attributes
    ----------
    iteration : int
        Its number in the step, from 1.
    residual : float
        The relative residual after it (the one compared with ``tol``: the larger of the two
        below).
    equilibrium_residual : float
        ‖r‖ on the free dofs over the scale of the external forces, reactions and coupling
        forces, after it.
    constraint_residual : float
        ‖B u − g‖ of the multipliers' rows over its own scale, after it (0 without rows).
    line_search : float
        The length s of the accepted update u + s Δu (1 without backtracking).
    crossings : int
        Quadrature points whose status (plastic or elastic over the step) changed from the
        iterate it started from to the one it reached.
    plastic_points : int
        Quadrature points plastic at the iterate it reached.
    """

    iteration: int
    residual: float
    equilibrium_residual: float
    constraint_residual: float
    line_search: float
    crossings: int
    plastic_points: int


def plastic_points(system: CoupledSystem, committed: dict[str, list[Any]],
                   trial: dict[str, list[Any]]) -> np.ndarray:  # fmt: skip
    """Which quadrature points of ``system`` are plastic at a trial state: ε̄p of ``trial``
    above that of ``committed``, over every block term whose model tells ε̄p (module
    docstring), flattened in the order of the blocks and their terms.

    Parameters
    ----------
    system : CoupledSystem
    committed, trial : dict
        Block name -> the states of its terms (None for linear terms).

    Returns
    -------
    ndarray of bool, shape (n_points,)
        Empty if no model tells ε̄p.
    """
    flags = []
    for block in system.blocks:
        for term, old, new in zip(block.terms, committed[block.name], trial[block.name]):
            if old is None or new is None:
                continue
            read = getattr(term.model, "equivalent_plastic_strain", None)
            if callable(read):
                before, after = read(old), read(new)
            elif hasattr(new, "eqps"):
                before, after = old.eqps, new.eqps
            else:
                continue
            flags.append((np.asarray(after) > np.asarray(before)).ravel())
    return np.concatenate(flags) if flags else np.zeros(0, dtype=bool)


class IterationTracker:
    """The :class:`NewtonIteration` records of one Newton solve, from the trial states of its
    iterates (the first: the predictor's)."""

    def __init__(self, system: CoupledSystem, committed: dict[str, list[Any]],
                 trial: dict[str, list[Any]]) -> None:  # fmt: skip
        self.system, self.committed = system, committed
        self.flags = plastic_points(system, committed, trial)
        self.records: list[NewtonIteration] = []

    def add(self, trial: dict[str, list[Any]], residual: float, parts: tuple[float, float],
            line_search: float) -> None:  # fmt: skip
        """Record the iteration that reached ``trial`` with these residuals."""
        flags = plastic_points(self.system, self.committed, trial)
        crossings = int(np.count_nonzero(flags != self.flags))
        self.flags = flags
        self.records.append(NewtonIteration(
            len(self.records) + 1, float(residual), float(parts[0]), float(parts[1]),
            float(line_search), crossings, int(np.count_nonzero(flags)),
        ))  # fmt: skip


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
    newton : tuple of NewtonIteration
        Its Newton iterations, one record each (``iterations`` of them): residuals and the
        quadrature points that crossed the yield surface.
    """

    load_factor: float
    step: float
    iterations: int
    residuals: tuple[float, ...]
    cuts: int
    # a default: the steps of checkpoints written before the records existed still load
    newton: tuple[NewtonIteration, ...] = ()

    @property
    def crossings(self) -> list[int]:
        """The quadrature points that crossed the yield surface in each iteration."""
        return [it.crossings for it in self.newton]


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
        (:attr:`QuasiStaticSolver.timings
        <arlequin.solvers.statics.quasi_static.QuasiStaticSolver>`).
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
    #: largest share of a J2 patch's gluing band that was plastic after a converged step
    #: (None: no J2 patch watched; :class:`~arlequin.solvers.system.yield_watch.BandYieldWatch`)
    band_plastic_fraction: float | None = None
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
