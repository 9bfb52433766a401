"""Step controllers: who chooses the size of the next time step.

An integrator asks its controller for the size of each step; the driver then shortens it, if
needed, to land exactly on the next requested output time (``t_eval``) or the end time. The
caller can also impose the next step with ``integrator.step(dt)``. Three controllers:

:class:`FixedStep`
    a constant step (s).
:class:`CriticalFraction`
    a fraction (``safety``) of the integrator's estimate of the critical step, re-estimated every
    ``every`` steps from the current configuration (see
    :meth:`arlequin.solvers.CentralDifference.critical_time_step`).
:class:`StepSchedule`
    any function of the integrator (its step count, time, state) returning the next step (s).

A plain callable ``f(integrator) -> dt`` is accepted wherever a controller is, and a number is a
:class:`FixedStep`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

__all__ = [
    "CriticalFraction",
    "FixedStep",
    "StepController",
    "StepSchedule",
    "as_controller",
    "check_step",
]


def check_step(dt: float, what: str = "time step") -> float:
    """``dt`` as a float, or ``ValueError`` naming it unless it is positive and finite."""
    if type(dt) is float and 0.0 < dt < math.inf:  # the common case, at every step
        return dt
    if isinstance(dt, (str, bool)):
        raise ValueError(f"{what} must be a positive number of seconds, got {dt!r}")
    try:
        value = float(dt)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be a positive number of seconds, got {dt!r}") from None
    if not (value > 0.0 and math.isfinite(value)):
        raise ValueError(f"{what} must be positive and finite, got dt={dt}")
    return value


@runtime_checkable
class StepController(Protocol):
    """Chooses the size (s) of the next step of an integrator."""

    def propose(self, integrator: Any) -> float:
        """The next step size (s), given the integrator at the start of that step."""


@dataclass(frozen=True)
class FixedStep:
    """A constant step ``dt`` (s)."""

    dt: float

    def __post_init__(self) -> None:
        check_step(self.dt)

    def propose(self, integrator: Any) -> float:
        """The next step size (s) for ``integrator``."""
        return float(self.dt)


@dataclass(frozen=True)
class CriticalFraction:
    """``safety`` × the critical step, re-estimated every ``every`` steps.

    Parameters
    ----------
    safety : float
        In (0, 1].
    every : int
        Steps between two estimates (≥ 1).

    Notes
    -----
    The estimate is the integrator's ``critical_time_step(max_age=every)`` (central differences:
    the computed critical step of the coupled system at the start, scaled by the models' own
    estimates in the current configuration when they declare the ``"critical_time_step"``
    capability). The integrator keeps the estimate and its age, so one controller can serve
    several integrators.
    """

    safety: float = 0.9
    every: int = 20

    def __post_init__(self) -> None:
        if not 0.0 < self.safety <= 1.0:
            raise ValueError(f"safety factor must lie in (0, 1], got safety={self.safety}")
        if int(self.every) != self.every or self.every < 1:
            raise ValueError(f"every must be a positive integer, got every={self.every}")

    def propose(self, integrator: Any) -> float:
        """The next step size (s) for ``integrator``."""
        return self.safety * float(integrator.critical_time_step(max_age=int(self.every)))


@dataclass(frozen=True)
class StepSchedule:
    """The next step from a function of the integrator, ``schedule(integrator) -> dt`` (s).

    Examples
    --------
    A step that varies smoothly with the step count n:

    >>> import math
    >>> def dt_n(integ):
    ...     return 1e-6 * (1 + 0.3 * math.sin(2 * math.pi * integ.step_count / 7.3))
    >>> schedule = StepSchedule(dt_n)
    """

    schedule: Callable[[Any], float]

    def __post_init__(self) -> None:
        if not callable(self.schedule):
            raise ValueError(
                f"StepSchedule needs a function integrator -> dt (s), got "
                f"{type(self.schedule).__name__} (for a list of steps: "
                f"lambda integ: steps[min(integ.step_count, len(steps) - 1)])"
            )

    def propose(self, integrator: Any) -> float:
        """The next step size (s) for ``integrator``."""
        return check_step(self.schedule(integrator), "scheduled time step")


def as_controller(spec: Any) -> StepController | None:
    """A controller from a controller, a number (a fixed step, s), a callable, or None."""
    if spec is None or isinstance(spec, StepController):
        return spec
    if isinstance(spec, (int, float)) and not isinstance(spec, bool):
        return FixedStep(float(spec))
    if isinstance(spec, str):
        raise ValueError(f"the time step dt must be a number of seconds, got the string {spec!r}")
    if callable(spec):
        return StepSchedule(spec)
    raise TypeError(
        f"a step controller must be a StepController, a step size (s) or a callable of the "
        f"integrator, got {type(spec).__name__}"
    )
