"""The record of an adaptive patch's growth (:class:`Adaptation`) and the checks of an
:class:`~arlequin.problem.adapt.AdaptivePatch`'s settings, before any work (each wrong one
named with its value)."""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Any

__all__ = ["Adaptation", "check_bounds", "check_settings"]


@dataclass
class Adaptation:
    """One growth of the patch.

    Attributes
    ----------
    step : int
        The load step after which it grew (1 for the first).
    time : float
        The load factor of the fields it started from (the committed one).
    n_fine_elements, n_coarse_cells : int
        Cells of the new patch (fine) and coarse cells it covers.
    patch_fraction : float
        The new patch's share of the coarse mesh's area (plane measure).
    rejected : bool
        The step was not accepted (the coarse model yielded outside the patch) and was
        computed again after the growth.
    energy_jump : float or None
        (E_after − E_before) / |E_before| of the total stored energy across the growth (set
        by the solver after the multipliers are re-solved).
    newton_iterations : int
        Iterations of that re-solve.
    energy_change : float or None
        E_after − E_before (J) (explicit runs: the listeners' energy balances move by it).
    wall_time_s : float
        Time spent rebuilding the patch (its mesh, model, overlap, weights, gluing band,
        coupling rows) and transferring the fields (s).
    system_time_s : float
        Time the solver spent on the new system's operators and saddle-point solver (s;
        explicit runs: the new integrator, its stable step and impulse factorisation, and the
        rebuilt constraints).
    resolve_time_s : float
        Time of the re-solve of the multipliers and fields at the same load (s; explicit
        runs: the new integrator's first impulse and the energies across the growth).
    discarded_time_s : float
        Time of the rejected step (explicit runs: interval) computed again after the growth
        (s; 0 if accepted).
    """

    step: int
    time: float
    n_fine_elements: int
    n_coarse_cells: int
    patch_fraction: float
    rejected: bool
    energy_jump: float | None = None
    newton_iterations: int = 0
    wall_time_s: float = 0.0
    system_time_s: float = 0.0
    resolve_time_s: float = 0.0
    discarded_time_s: float = 0.0
    energy_change: float | None = None

    @property
    def adapt_time_s(self) -> float:
        """The growth's whole cost (s): rebuild, transfer, new operators, re-solve and the
        rejected step's time."""
        return self.wall_time_s + self.system_time_s + self.resolve_time_s + self.discarded_time_s

    def to_json(self) -> dict[str, Any]:
        """The adaptation as plain JSON (an entry of the demos' ``adaptations``)."""
        return {
            "step": self.step,
            "time": self.time,
            "n_fine_elements": self.n_fine_elements,
            "patch_fraction": self.patch_fraction,
            "energy_jump": self.energy_jump,
            "rejected": self.rejected,
            "newton_iterations": self.newton_iterations,
            "rebuild_time_s": self.wall_time_s,
            "system_time_s": self.system_time_s,
            "resolve_time_s": self.resolve_time_s,
            "discarded_time_s": self.discarded_time_s,
        }


def _is_real(value: Any) -> bool:
    """A real number (numpy scalars included), not a bool."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def check_settings(
    threshold: Any, buffer: Any, band_cells: Any, every: Any, patch: Any, interval: Any
) -> None:
    """:class:`AdaptivePatch`'s threshold, counts and check interval, each named if wrong."""
    if not (_is_real(threshold) and 0.0 < threshold <= 1.0):
        raise ValueError(f"threshold β must lie in (0, 1], got threshold={threshold!r}")
    for name, value, low in (("buffer", buffer, 0), ("band_cells", band_cells, 0),
                             ("every", every, 1), ("patch", patch, 0)):  # fmt: skip
        if isinstance(value, bool) or int(value) != value or value < low:
            raise ValueError(f"{name} must be an integer >= {low}, got {name}={value!r}")
    if interval is not None and not (
        _is_real(interval) and math.isfinite(interval) and interval > 0.0
    ):
        raise ValueError(f"interval must be a positive time (s), got interval={interval!r}")


def check_bounds(max_fraction: Any, band_weight: Any, levels: Any, indicator: Any) -> None:
    """:class:`AdaptivePatch`'s fraction, band weight, levels and indicator, each named if
    wrong."""
    if not (_is_real(max_fraction) and 0.0 < max_fraction <= 1.0):
        raise ValueError(f"max_fraction must lie in (0, 1], got max_fraction={max_fraction!r}")
    if not (_is_real(band_weight) and 0.0 <= band_weight < 1.0):
        raise ValueError(f"band_weight must lie in [0, 1), got band_weight={band_weight!r}")
    if levels is not None and (int(levels) != levels or levels < 0):
        raise ValueError(f"levels must be a non-negative integer, got levels={levels}")
    if indicator is not None and not callable(indicator):
        raise ValueError(f"indicator must be callable, got {type(indicator).__name__}")
