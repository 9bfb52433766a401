"""The result of a two-bar (or bar-on-wall) impact run: its histories, its JSON document and
the units of the figures written to results.json (SI units)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...io import JsonResult
from .exact import impact_metrics

__all__ = ["JSON_KEYS", "RESULT_UNITS", "TwoBarsResult"]

JSON_KEYS = (
    "t",
    "interface_velocity",
    "contact_pressure",
    "kinetic",
    "internal",
    "total_energy",
    "contact_work",
    "final_velocities",
    "contact_duration",
    "dt",
    "fixed_point_iterations",
)

#: Units of the figures of a run written to results.json (the baseline's prefixed).
RESULT_UNITS = {"velocity_rms_error": "1", "pressure_rms_error": "1", "duration_error_steps": "1",
                "final_velocity_error": "1", "energy_loss": "1", "max_energy_gain": "1",
                "contact_work": "J", "balance_error": "1", "contact_duration": "s", "dt": "s",
                "final_velocities": "m/s"}  # fmt: skip


@dataclass
class TwoBarsResult(JsonResult):
    """Time histories of one impact run (SI units).

    Attributes
    ----------
    t : ndarray, shape (n_rec,)
        Times (s), from 0.
    interface_velocity : ndarray, shape (n_rec,)
        Velocity of bar 2's contact node (m/s) (the bar's for the wall).
    contact_pressure : ndarray, shape (n_rec,)
        −λ_v (Pa).
    kinetic, internal, total_energy : ndarray, shape (n_rec,)
        Kinetic, strain and their sum (J).
    contact_work : ndarray, shape (n_rec,)
        Accumulated work of the contact forces (J), from the multipliers (≤ 0: dissipated).
    final_velocities : list of float
        Mass-weighted mean velocities of the bars at the end (m/s).
    contact_duration : float
        (last − first record with λ_v ≠ 0) + Δt (s).
    dt : float
        Time step (s).
    fixed_point_iterations : ndarray of int, shape (n_rec,)
        Status iterations of the step ending at each record (0 at t = 0 for implicit schemes).
    method : str
        ``"levelset"``, ``"newmark-trapezoidal"`` or ``"newmark-hht"``.
    exact : dict
        Exact interface velocity (m/s), pressure (Pa), duration (s), final velocities (m/s).
    newmark : TwoBarsResult or None
        The baseline run of ``method="both"``.
    dynamic : DynamicResult
        The integrator's result (with the fields u, v at every step).
    """

    t: np.ndarray
    interface_velocity: np.ndarray
    contact_pressure: np.ndarray
    kinetic: np.ndarray
    internal: np.ndarray
    total_energy: np.ndarray
    contact_work: np.ndarray
    final_velocities: list[float]
    contact_duration: float
    dt: float
    fixed_point_iterations: np.ndarray
    method: str = "levelset"
    integrator: str = "theta"
    exact: dict[str, Any] = field(default_factory=dict)
    config: dict[str, Any] = field(default_factory=dict)
    n_status_failures: int = 0
    newmark: TwoBarsResult | None = None
    dynamic: Any = field(default=None, repr=False)

    json_keys = JSON_KEYS

    def to_json(self) -> dict[str, Any]:
        """The JSON document of the CLI: exactly :data:`JSON_KEYS` (+ ``"newmark"``)."""
        out = super().to_json()
        if self.newmark is not None:
            out["newmark"] = self.newmark.to_json()
        return out

    def metrics(self) -> dict[str, float]:
        """The Must-show figures against :attr:`exact` (see :func:`impact_metrics`)."""
        return impact_metrics(self)

    def summary(self) -> str:
        """One line: the errors against the exact solution."""
        m = self.metrics()
        text = (
            f"{self.method} ({self.integrator}), dt = {self.dt:.4e} s: interface velocity rms "
            f"error {m['velocity_rms_error']:.3e}, pressure rms error "
            f"{m['pressure_rms_error']:.3e}, "
            f"duration {self.contact_duration:.6e} s (exact {self.exact['duration']:.6e} s, "
            f"{m['duration_error_steps']:+.2f} steps), final velocities "
            f"{[round(v, 6) for v in self.final_velocities]}, energy lost {m['energy_loss']:.3e}"
        )
        if self.newmark is not None:
            text += "\n" + self.newmark.summary()
        return text
