"""An adaptive patch on one body of a :class:`~arlequin.problem.bodies.MultiBodyProblem`.

:class:`BodyAdaptation` wraps an :class:`~arlequin.problem.adapt.AdaptivePatch` so that it adapts
the patch of one body (an :class:`~arlequin.ArlequinProblem`) of a multi-body run (the ball
impact's block): the indicator sees that body's blocks (``"block.coarse"`` as ``"coarse"``), a
growth rebuilds the body and the multi-body problem around it (the other bodies, their dofs and
states unchanged: a body's dofs are contiguous in the assembled vector), and the constraints
between the bodies (contact) are rebuilt on the new dof map by ``constraints(problem)``. It has
the members the solvers call duck-typed (``bind``, ``assess``, ``grow``,
``transfer_displacement``, ``constraints_for``, ``records``, ...). SI units.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .adapt import AdaptivePatch, Growth
from .bodies import SEPARATOR, MultiBodyProblem

__all__ = ["BodyAdaptation"]


class _BodyFields:
    """What :meth:`AdaptivePatch.assess` reads of a solver, for one body: its system, its
    fields (the body's slice of the assembled vector), its states (the body's blocks, named as
    in the body) and the time."""

    def __init__(self, system: Any, u: np.ndarray, states: dict[str, Any], t: float) -> None:
        self.system, self.u, self.states, self.t = system, u, states, t


class BodyAdaptation:
    """An adaptive patch on body ``body`` of a multi-body problem (module docstring).

    Parameters
    ----------
    adapt : AdaptivePatch
        The adaptation of the body's patch (its options: threshold, buffer, every, cap...).
    body : str
        The body's name in the :class:`~arlequin.problem.bodies.MultiBodyProblem`.
    constraints : callable, optional
        ``constraints(problem) -> list``: the run's extra constraints (contact pairs) on a
        grown multi-body problem (its ``system().dofmap``); needed when the run has any.
    """

    def __init__(
        self,
        adapt: AdaptivePatch,
        body: str,
        constraints: Callable[[MultiBodyProblem], Sequence[Any]] | None = None,
    ) -> None:
        if not isinstance(adapt, AdaptivePatch):
            raise ValueError(f"adapt must be an AdaptivePatch, got {type(adapt).__name__}")
        if constraints is not None and not callable(constraints):
            raise ValueError(f"constraints must be callable, got {type(constraints).__name__}")
        self.adapt, self.body, self._constraints = adapt, str(body), constraints
        self.outer: MultiBodyProblem | None = None
        self._systems: dict[int, Any] = {}

    # -- delegated ----------------------------------------------------------------------------
    records = property(lambda self: self.adapt.records)
    max_coarse_yield_ratio = property(lambda self: self.adapt.max_coarse_yield_ratio)
    every = property(lambda self: self.adapt.every)
    interval = property(lambda self: self.adapt.interval)
    patch_fraction = property(lambda self: self.adapt.patch_fraction)

    @property
    def problem(self) -> MultiBodyProblem:
        """The current multi-body problem."""
        return self.outer

    @property
    def body_problem(self) -> Any:
        """The adapted body's current problem."""
        return self.adapt.problem

    def bind(self, problem: Any) -> MultiBodyProblem:
        """Check ``problem`` (a multi-body problem with body ``body``, whose patch the
        :class:`AdaptivePatch` accepts) and keep it."""
        if not isinstance(problem, MultiBodyProblem):
            raise ValueError(f"BodyAdaptation adapts a body of a MultiBodyProblem, got "
                             f"{type(problem).__name__}")  # fmt: skip
        if self.body not in problem.bodies:
            raise ValueError(f"unknown body {self.body!r}; bodies are {list(problem.bodies)}")
        self.adapt.bind(problem.bodies[self.body])
        self.outer = problem
        return problem

    def constraints_for(self, problem: MultiBodyProblem) -> list[Any]:
        """The run's extra constraints on a grown problem (``constraints``)."""
        if self._constraints is None:
            raise ValueError("the run has extra constraints: give BodyAdaptation(..., "
                             "constraints=) to rebuild them on the grown problem")  # fmt: skip
        return list(self._constraints(problem))

    # -- the body's part of the assembled fields ----------------------------------------------
    def _slice(self, outer: MultiBodyProblem) -> slice:
        systems = outer.body_systems()
        start = 0
        for name, system in systems.items():
            if name == self.body:
                return slice(start, start + system.n_dofs)
            start += system.n_dofs
        raise KeyError(self.body)  # bind checked the name

    def _key(self, block: str) -> str:
        return f"{self.body}{SEPARATOR}{block}"

    def _body_states(self, states: dict[str, Any]) -> dict[str, Any]:
        head = self._key("")
        return {k[len(head) :]: v for k, v in states.items() if k.startswith(head)}

    def assess(self, solver: Any, step: int, due: bool | None = None) -> Growth | None:
        """:meth:`AdaptivePatch.assess` on the body's fields."""
        inner = self.adapt.problem
        system = self._systems.get(id(inner))
        if system is None:
            self._systems = {id(inner): inner.system()}
            system = self._systems[id(inner)]
        fields = _BodyFields(system, solver.u[self._slice(self.outer)],
                             self._body_states(solver.states), solver.t)  # fmt: skip
        return self.adapt.assess(fields, step, due)

    def grow(
        self, growth: Growth, u: np.ndarray, states: dict[str, list[Any]], step: int, time_: float
    ) -> tuple[MultiBodyProblem, np.ndarray, dict[str, list[Any]]]:
        """The grown multi-body problem, ``u`` (m) moved onto it and the body's patch state
        (:meth:`AdaptivePatch.grow` on the body; the other bodies unchanged)."""
        old = self.outer
        part = self._slice(old)
        inner, u_body, moved = self.adapt.grow(growth, u[part], self._body_states(states), step,
                                               time_)  # fmt: skip
        new = old.with_body(self.body, inner)  # the other bodies' systems kept
        self._last = part
        self.outer = new
        return new, self._splice(u, part, u_body), {self._key(k): v for k, v in moved.items()}

    def transfer_displacement(self, u: np.ndarray) -> np.ndarray:
        """A vector of the problem before the last growth moved onto the grown one."""
        part = self._last
        return self._splice(u, part, self.adapt.transfer_displacement(u[part]))

    @staticmethod
    def _splice(u: np.ndarray, part: slice, body: np.ndarray) -> np.ndarray:
        return np.concatenate([u[: part.start], body, u[part.stop :]])
