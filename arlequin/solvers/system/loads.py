"""Load curves: time factors a(t) for loads and boundary data (dimensionless unless stated).

Use them as the ``amplitude`` of
:meth:`arlequin.problem.arlequin_problem.ArlequinProblem.add_body_force`, ``add_traction`` and
``add_dirichlet`` (``level="velocity"`` for prescribed velocities), or as the right-hand side of a
:class:`arlequin.problem.system.LinearConstraint` (``rhs=lambda t: curve(t) * g``). Every curve is a
plain callable of the time t (s), vectorised over numpy arrays.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["Constant", "LoadCurve", "Ramp", "Sine", "SmoothStep", "Tabulated"]


class LoadCurve:
    """Base class: ``curve(t)`` returns the factor at time t (s)."""

    def __call__(self, t):
        raise NotImplementedError

    def __mul__(self, other: float) -> LoadCurve:
        return _Scaled(self, float(other))

    __rmul__ = __mul__


@dataclass(frozen=True)
class _Scaled(LoadCurve):
    curve: LoadCurve
    factor: float

    def __call__(self, t):
        return self.factor * self.curve(t)


@dataclass(frozen=True)
class Constant(LoadCurve):
    """a(t) = value."""

    value: float = 1.0

    def __call__(self, t):
        return self.value + 0.0 * np.asarray(t, dtype=float)


@dataclass(frozen=True)
class Ramp(LoadCurve):
    """Linear rise from 0 at ``t_start`` to 1 at ``t_start + duration`` (s), then constant."""

    duration: float
    t_start: float = 0.0

    def __post_init__(self) -> None:
        if not self.duration > 0.0:
            raise ValueError(f"ramp duration must be positive, got duration={self.duration}")

    def __call__(self, t):
        return np.clip((np.asarray(t, dtype=float) - self.t_start) / self.duration, 0.0, 1.0)


@dataclass(frozen=True)
class SmoothStep(LoadCurve):
    """C¹ rise 3s² − 2s³ (s = (t − t_start)/duration clipped to [0, 1])."""

    duration: float
    t_start: float = 0.0

    def __post_init__(self) -> None:
        if not self.duration > 0.0:
            raise ValueError(f"step duration must be positive, got duration={self.duration}")

    def __call__(self, t):
        s = np.clip((np.asarray(t, dtype=float) - self.t_start) / self.duration, 0.0, 1.0)
        return s * s * (3.0 - 2.0 * s)


@dataclass(frozen=True)
class Sine(LoadCurve):
    """a(t) = sin(2π frequency t + phase); frequency in Hz."""

    frequency: float
    phase: float = 0.0

    def __call__(self, t):
        return np.sin(2.0 * np.pi * self.frequency * np.asarray(t, dtype=float) + self.phase)


class Tabulated(LoadCurve):
    """Piecewise-linear interpolation of (times (s), values); constant outside the table."""

    def __init__(self, times: Sequence[float], values: Sequence[float]) -> None:
        self.times = np.asarray(times, dtype=float)
        self.values = np.asarray(values, dtype=float)
        if self.times.ndim != 1 or self.times.shape != self.values.shape or self.times.size < 1:
            raise ValueError(
                f"times and values must be 1D arrays of the same length, got shapes "
                f"{self.times.shape} and {self.values.shape}"
            )
        if np.any(np.diff(self.times) <= 0.0):
            raise ValueError("tabulated load curve times must be strictly increasing")

    def __call__(self, t):
        return np.interp(np.asarray(t, dtype=float), self.times, self.values)
