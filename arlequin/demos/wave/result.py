"""The wave demo's result: the reflected and transmitted energy fractions (dimensionless), the
energy drift, the step (s), and the snapshot's fields for the picture."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ...io import JsonResult

__all__ = ["RESULT_UNITS", "WaveResult"]

#: Units of the results written to results.json.
RESULT_UNITS = {"reflected_energy_fraction": "1", "transmitted_energy_fraction": "1",
                "energy_drift": "1", "dt": "s", "n_steps": "1", "incident_energy": "J",
                "multiplier_max": "N/m", "coupling_work_max": "J"}  # fmt: skip


@dataclass
class WaveResult(JsonResult):
    """Result of :func:`run_wave` (fractions are dimensionless, dt in s).

    ``to_json()`` gives the five keys of the CLI's JSON output.
    """

    reflected_energy_fraction: float
    transmitted_energy_fraction: float
    energy_drift: float
    dt: float
    n_steps: int
    incident_energy: float = 0.0
    config: dict = field(default_factory=dict)
    multiplier_max: float = 0.0
    coupling_work_max: float = 0.0
    fields: dict = field(default_factory=dict, repr=False)
    dynamic: Any = field(default=None, repr=False)

    json_keys = (
        "reflected_energy_fraction",
        "transmitted_energy_fraction",
        "energy_drift",
        "dt",
        "n_steps",
    )

    def summary(self) -> str:
        """One line: the reflected and transmitted energy fractions."""
        c = self.config
        return (
            f"wave ratio {c.get('ratio')} W={c.get('pulse_width')} G={c.get('gluing_width')} "
            f"{c.get('coupling')} {c.get('mediator')} mediator {c.get('weights')} weights "
            f"{c.get('integrator')}: reflected {self.reflected_energy_fraction:.3e}, transmitted "
            f"{self.transmitted_energy_fraction:.6f}, drift {self.energy_drift:.3e}, "
            f"dt {self.dt:.4e} s, {self.n_steps} steps"
        )
