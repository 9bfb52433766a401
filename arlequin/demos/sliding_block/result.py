"""What a sliding-block run computed: :class:`SlidingBlockResult`, its JSON keys and units."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...io import JsonResult

__all__ = ["JSON_KEYS", "RESULT_UNITS", "SlidingBlockResult"]

#: The keys of the Interface, in order (then the inputs and the other results).
JSON_KEYS = ("t", "mean_velocity", "friction_work", "contact_work", "total_energy", "stop_time",
             "sliding_distance", "fixed_point_iterations")  # fmt: skip

#: The SI units of the scalar results recorded in ``results.json``.
RESULT_UNITS = {"stop_time": "s", "sliding_distance": "m", "acceleration": "m/s^2",
                "expected_acceleration": "m/s^2", "energy_balance_error": "1",
                "max_slip_after_stop": "m/s", "ramp_time": "s", "wall_time_s": "s",
                "expected_stop_time": "s", "negative_dissipation_steps": "1",
                "slipping_steps_after_stop": "1"}  # fmt: skip

#: The histories decimated to at most 2000 points in the JSON.
_HISTORIES = ("t", "mean_velocity", "friction_work", "contact_work", "total_energy",
              "damping_work")  # fmt: skip


@dataclass
class SlidingBlockResult(JsonResult):
    """What a sliding-block run computed (SI units; times counted from the launch or the end of
    the load ramp).

    Attributes
    ----------
    t : list of float
        Record times (s), one per step (decimated to at most 2000 in the JSON).
    mean_velocity : list of float
        Mean velocity along x (m/s): the block's momentum over its mass.
    friction_work, contact_work : list of float
        Works (J) of the tangential and normal contact multipliers since the start (≤ 0: minus
        the energy they removed).
    total_energy : list of float
        Kinetic + strain energy − the work of the loads since the start (J); a launch at the end
        of the gravity ramp counts with the loads' work (the kinetic energy it gave). With the
        works above and ``damping_work``, constant up to the scheme's energy error.
    stop_time : float or None
        When the time-averaged mean velocity (over one shear period 4H/c_s) falls below
        :data:`~arlequin.demos.sliding_block.run.STOP_FRACTION` V after the launch (s; None
        without a launch).
    sliding_distance : float
        Mean displacement along x of the contact nodes at the end, from the start (m): from the
        launch with the pressure loading, from the end of the ramp under gravity.
    fixed_point_iterations : dict
        Fixed-point iterations per step: ``mean``, ``max`` and ``counts`` (iterations -> steps).
    acceleration, expected_acceleration : float
        Fitted mean acceleration along x (m/s², a straight line through the sliding phase) and
        the exact one.
    expected_stop_time : float or None
        The exact stop time V / (deceleration) (s), None when the block does not stop.
    energy_balance_error : float
        ``max |E + D_f + W_c + D_d − W_ext − E(0)|`` over the run, against the largest energy
        (1), D_d the energy the damping dissipated.
    max_slip_after_stop : float or None
        Largest slip velocity (m/s) of a contact node after 1.1 × the exact stop time.
    slipping_steps_after_stop : float or None
        Fraction of the steps after 1.1 × the exact stop time in which a contact node slips
        faster than 1e-6 V.
    negative_dissipation_steps : int
        Steps whose friction work increment is positive beyond round-off (1e-12 of the
        largest energy; a sticking point's work is zero to round-off, of either sign).
    ramp_time : float
        Duration of the gravity ramp (s; 0 with the pressure loading).
    n_steps : int
    wall_time_s : float
        Wall time of the integration (s).
    config : dict
        The inputs (:meth:`SlidingBlockConfig.inputs`).
    damping_work : list of float
        Work of the damping forces since the start (J, ≤ 0), one per record.
    slip_velocity : ndarray, optional
        Largest slip velocity of the contact nodes per record (m/s; not in the JSON).
    """

    t: list[float]
    mean_velocity: list[float]
    friction_work: list[float]
    contact_work: list[float]
    total_energy: list[float]
    stop_time: float | None
    sliding_distance: float
    fixed_point_iterations: dict[str, Any]
    acceleration: float
    expected_acceleration: float
    expected_stop_time: float | None
    energy_balance_error: float
    max_slip_after_stop: float | None
    slipping_steps_after_stop: float | None
    negative_dissipation_steps: int
    ramp_time: float
    n_steps: int
    wall_time_s: float
    config: dict[str, Any] = field(default_factory=dict)
    damping_work: list[float] = field(default_factory=list)
    slip_velocity: np.ndarray | None = None

    json_exclude = ("slip_velocity",)

    def to_json(self) -> dict[str, Any]:
        """The Interface's keys first (histories decimated to ≤ 2000 points), then the rest."""
        data = super().to_json()
        step = max(1, math.ceil(len(self.t) / 2000))
        for k in _HISTORIES:
            data[k] = data[k][::step]
        config = data.pop("config")
        ordered = {k: data.pop(k) for k in JSON_KEYS}
        return {**ordered, **config, **data}

    def summary(self) -> str:
        """One line: acceleration, stop time, energy error, iterations."""
        if self.config.get("gravity") is not None and not self.config.get("velocity"):
            return self._rest_summary()
        stop = "none" if self.stop_time is None else f"{self.stop_time:.6e} s"
        exp = "" if self.expected_stop_time is None else f" (exact {self.expected_stop_time:.6e})"
        where = "" if self.config.get("gravity") is None else (
            f" launched at {self.config.get('velocity')} m/s on a {self.config.get('incline')}° "
            f"incline")  # fmt: skip
        return (f"sliding block{where}: acceleration {self.acceleration:.6e} m/s^2 (exact "
                f"{self.expected_acceleration:.6e}), stop {stop}{exp}, sliding distance "
                f"{self.sliding_distance:.3e} m, energy balance {self.energy_balance_error:.2e}, "
                f"fixed point {self.fixed_point_iterations['mean']:.2f} iterations per step "
                f"(max {self.fixed_point_iterations['max']}), damping ratio "
                f"{self.config.get('damping')}" + (f"; the base still slips after the stop in "
                f"{100 * self.slipping_steps_after_stop:.0f}% of the steps" if
                self.slipping_steps_after_stop else ""))  # fmt: skip

    def _rest_summary(self) -> str:
        """The summary of a block left at rest on the incline: it slides or sticks."""
        moved = abs(self.sliding_distance) > 1e-6 * float(self.config.get("width", 0.02))
        return (f"sliding block on a {self.config.get('incline')}° incline: it "
                f"{'slides' if moved else 'sticks'} (sliding distance "
                f"{self.sliding_distance:.3e} m), acceleration {self.acceleration:.6e} m/s^2 "
                f"(exact {self.expected_acceleration:.6e}), energy balance "
                f"{self.energy_balance_error:.2e}, fixed point "
                f"{self.fixed_point_iterations['mean']:.2f} iterations per step")  # fmt: skip
