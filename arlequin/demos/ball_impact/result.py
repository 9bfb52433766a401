"""The result of a ball-impact run, its keys and units, and Hertz's impact solution.

SI units; see :mod:`arlequin.demos.ball_impact`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...io import JsonResult
from ...models import IsotropicElastic
from ..adaptive_options import ADAPTATIONS_UNIT

__all__ = [
    "HISTORY_KEYS",
    "HISTORY_UNITS",
    "INPUT_UNITS",
    "JSON_KEYS",
    "RESULT_UNITS",
    "BallImpactResult",
    "hertz",
    "hertz_force_history",
]

#: The Interface's keys, in order (then the Hertz values and the inputs).
JSON_KEYS = ("contact_duration", "peak_force", "restitution", "dent_depth",
             "max_plastic_strain", "energy_balance_error", "patch_fraction", "n_elements",
             "wall_time_s", "history")  # fmt: skip
HISTORY_KEYS = ("t", "contact_force", "ball_velocity", "kinetic", "elastic",
                "plastic_dissipation", "contact_work", "coupling_work",
                "friction_work")  # fmt: skip
HISTORY_UNITS = {"t": "s", "contact_force": "N", "ball_velocity": "m/s", "kinetic": "J",
                  "elastic": "J", "plastic_dissipation": "J", "contact_work": "J",
                  "coupling_work": "J", "friction_work": "J", "patch_fraction": "1"}  # fmt: skip
INPUT_UNITS = {"regime": "", "model": "", "velocity": "m/s", "ball_radius": "m",
               "block_radius": "m", "block_height": "m", "patch_size": "m",
               "block_patch_size": "m", "fine_size": "m",
               "coarse_size": "m", "friction": "1", "rigid_wall": "", "coarse_step_ratio": "1",
               "t_end": "s", "ball_material": "", "block_material": "", "adaptive": "",
               "adapt_threshold": "1", "adapt_buffer": "1", "adapt_every": "1",
               "max_patch_fraction": "1"}  # fmt: skip
#: The result's ``patch_fraction`` is a count ratio, unlike the adaptive history's and the
#: growths' ``patch_fraction`` (an area share of the block): the unit says which.
PATCH_FRACTION_UNIT = (
    "1 (the patches' elements over those of the uniformly fine meshes of both bodies; the "
    "references: all their elements over the uniform meshes'. Not the block patch's area "
    "share, which history.csv's and adaptations' patch_fraction give)"
)
RESULT_UNITS = {"contact_duration": "s", "peak_force": "N", "restitution": "1",
                "dent_depth": "m", "max_plastic_strain": "1", "energy_balance_error": "1",
                "patch_fraction": PATCH_FRACTION_UNIT, "n_elements": "1", "wall_time_s": "s",
                "hertz_peak_force": "N", "hertz_contact_duration": "s",
                "hertz_indentation": "m", "hertz_contact_radius": "m", "fine_size": "m",
                "coarse_size": "m", "n_steps": "1", "contact_radius_cells": "1",
                "band_max_plastic_strain": "1", "t_end": "s", "band_plastic_fraction": "1",
                "max_plastic_strain_position": "m",
                "mean_step_ratio": "1", "adaptations": ADAPTATIONS_UNIT,
                "max_coarse_yield_ratio": "1"}  # fmt: skip


def hertz(radius: float, mass: float, velocity: float, ball: IsotropicElastic,
          block: IsotropicElastic | None) -> dict[str, float]:  # fmt: skip
    """Hertz's impact of an elastic sphere (radius m, mass kg, velocity m/s) on an elastic
    half-space of material ``block`` (None: rigid): peak force (N), contact duration (s),
    maximum indentation (m), maximum contact radius (m) (module docstring)."""
    inv = (1 - ball.poisson**2) / ball.young
    if block is not None:
        inv += (1 - block.poisson**2) / block.young
    e_star = 1.0 / inv
    delta = (15 * mass * velocity**2 / (16 * e_star * math.sqrt(radius))) ** 0.4
    return {"hertz_peak_force": 4.0 / 3.0 * e_star * math.sqrt(radius) * delta**1.5,
            "hertz_contact_duration": 2.9432 * delta / velocity, "hertz_indentation": delta,
            "hertz_contact_radius": math.sqrt(radius * delta)}  # fmt: skip


def hertz_force_history(mass: float, velocity: float, peak: float, duration: float,
                        n: int = 400) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Hertz's force against time (s, N): m δ'' = −F, F = k δ^{3/2}, k from the peak force."""
    from scipy.integrate import solve_ivp

    # k from the peak and the energy: F_max = k δ^{3/2}, ½ m v² = 2/5 k δ^{5/2}
    d_max = 2.5 * 0.5 * mass * velocity**2 / peak
    k = peak / d_max**1.5
    sol = solve_ivp(lambda _t, y: [y[1], -k * max(y[0], 0.0) ** 1.5 / mass], (0.0, duration),
                    [0.0, velocity], t_eval=np.linspace(0.0, duration, n), rtol=1e-10,
                    atol=1e-14)  # fmt: skip
    return sol.t, k * np.maximum(sol.y[0], 0.0) ** 1.5


@dataclass
class BallImpactResult(JsonResult):
    """What a ball-impact run computed (SI units; see the module docstring).

    Attributes
    ----------
    contact_duration, peak_force, restitution, dent_depth, max_plastic_strain : float
        s, N, 1, m, 1.
    energy_balance_error : float
        The integrator's balance error over the run against the largest energy (1).
    patch_fraction : float
        p: the patches' elements over those of the uniformly fine (``mono``) meshes of both
        bodies (1); for the references, all their elements over the uniform meshes' (1 for
        ``mono`` and ``mono-zoned``). A ratio of element counts, unlike the area share of
        ``history["patch_fraction"]`` and of the ``adaptations`` (:data:`PATCH_FRACTION_UNIT`).
    n_elements : int
        Elements of the run (every mesh).
    wall_time_s : float
        Wall time of the time loop (s).
    history : dict
        Per sample (the first step after each t_end/1000: about 1000 rows,
        :data:`~arlequin.demos.ball_impact.record.SAMPLES`, or every step of a shorter run):
        ``t`` (s), ``contact_force`` (N), ``ball_velocity`` (m/s, along z), ``kinetic``,
        ``elastic`` (strain energy of the elastic models and stored energy of the J2 one),
        ``plastic_dissipation``, ``contact_work`` (of the normal multipliers),
        ``coupling_work``, ``friction_work`` (of the tangential multipliers, ≤ 0; 0 without
        friction) (J); with ``adaptive``, ``patch_fraction`` (the block patch's share of the
        block's coarse mesh's (r, z) area, 1: not the result's ``patch_fraction``, a ratio of
        element counts over both bodies).
    hertz : dict
        Hertz's values (elastic regime; empty otherwise).
    contact_radius_cells : float
        The largest contact radius in fine cells (1).
    band_max_plastic_strain : float
        The largest ε̄p in the block patch's gluing band (1; the coarse model glued there is
        elastic: a warning above 0.02).
    band_plastic_fraction : float or None
        The largest share of the block patch's gluing band that was plastic at a recorded
        sample (1; None without a J2 patch: a ``BandYieldWarning`` above 0).
    max_plastic_strain_position : list of float or None
        Where the final largest ε̄p lies (m, reference configuration; None: elastic regime).
    t_end : float
        The simulated time (s): the given one, or the default the run chose.
    coarse_step_ratio : int
        The multi-time-step bound M (1: one step for every model).
    mean_step_ratio : float
        The mean ratio m ≤ M the coarse models' macro steps used (1 without multi-time-step).
    adaptations : list of dict
        With ``adaptive``: each growth of the block's patch, ``step`` (the time step it grew
        at), ``time`` (s), ``n_fine_elements``, ``patch_fraction`` (the share of the block's
        coarse mesh's (r, z) area, as in ``history``), ``energy_jump`` (relative change of
        the total energy across it), ``rejected`` (the interval after it was computed again:
        the coarse block yielded outside the patch).
    max_coarse_yield_ratio : float or None
        With ``adaptive``: the largest von Mises / σy of the block's coarse model outside the
        patch at the accepted checks (1).
    """

    contact_duration: float
    peak_force: float
    restitution: float
    dent_depth: float
    max_plastic_strain: float
    energy_balance_error: float
    patch_fraction: float
    n_elements: int
    wall_time_s: float
    history: dict[str, list[float]]
    hertz: dict[str, float] = field(default_factory=dict)
    n_steps: int = 0
    fine_size: float = 0.0
    coarse_size: float = 0.0
    contact_radius_cells: float = 0.0
    band_max_plastic_strain: float = 0.0
    band_plastic_fraction: float | None = None
    max_plastic_strain_position: list[float] | None = None
    t_end: float = 0.0
    coarse_step_ratio: int = 1
    mean_step_ratio: float = 1.0
    config: dict[str, Any] = field(default_factory=dict)
    adaptations: list[dict[str, Any]] = field(default_factory=list)
    max_coarse_yield_ratio: float | None = None

    def to_json(self) -> dict[str, Any]:
        """The Interface's keys first, then Hertz's values, then the inputs and the rest."""
        data = super().to_json()
        n = len(self.history.get("t", ()))
        step = max(1, math.ceil(n / 2000))
        data["history"] = {k: v[::step] for k, v in data["history"].items()}
        ordered = {k: data.pop(k) for k in JSON_KEYS}
        extra = data.pop("hertz")
        config = data.pop("config")
        return {**ordered, **extra, **config, **data}

    def errors(self) -> dict[str, float]:
        """Relative errors of the peak force and the contact duration against Hertz (1)."""
        if not self.hertz:
            return {}
        return {"peak_force": self.peak_force / self.hertz["hertz_peak_force"] - 1.0,
                "contact_duration": (self.contact_duration
                                     / self.hertz["hertz_contact_duration"] - 1.0)}  # fmt: skip

    def summary(self) -> str:
        """One line: the measured quantities (and their errors against Hertz)."""
        err = self.errors()
        against = (f" (Hertz: {100 * err['peak_force']:+.2f}%, "
                   f"{100 * err['contact_duration']:+.2f}%)" if err else "")  # fmt: skip
        return (f"ball impact ({self.config.get('model')}, {self.config.get('regime')}): peak "
                f"force {self.peak_force:.6g} N, contact {self.contact_duration:.6g} s{against}, "
                f"restitution {self.restitution:.4f}, dent {self.dent_depth:.4g} m, max eqps "
                f"{self.max_plastic_strain:.4g}, balance {self.energy_balance_error:.2e}, "
                f"{self.n_elements} elements (p = {self.patch_fraction:.3f}), "
                f"{self.wall_time_s:.1f} s{self._growths()}")  # fmt: skip

    def _growths(self) -> str:
        """An adaptive run's growths, the block patch's last area share and the largest
        coarse σ_vm/σy (as the plate says)."""
        if not self.config.get("adaptive"):
            return ""
        share = (f" to {self.adaptations[-1]['patch_fraction']:.3f} of the block"
                 if self.adaptations else "")  # fmt: skip
        ratio = self.max_coarse_yield_ratio
        return (f"; the block patch grew {len(self.adaptations)} times{share}, coarse "
                f"σ_vm/σy ≤ {float('nan') if ratio is None else ratio:.3f}")  # fmt: skip
