"""The result of a pressure-vessel run: its JSON keys (the Interface), units and summary."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ...io import JsonResult
from ..adaptive_options import ADAPTATIONS_UNIT
from ..plastic_report import PLASTIC_UNITS

__all__ = ["HISTORY_KEYS", "JSON_KEYS", "UNITS", "PressureVesselResult"]

#: The Interface's keys, in order.
JSON_KEYS = ("first_yield_pressure", "limit_load_reached", "limit_load", "n_elements", "n_dofs",
             "patch_fraction", "wall_time_s", "history")  # fmt: skip
#: The keys of ``history``: one value per converged step (the initial state first).
HISTORY_KEYS = ("pressure", "plastic_radius", "outer_displacement", "inner_displacement",
                "newton_iterations", "residuals", "patch_fraction")  # fmt: skip
UNITS = {
    **PLASTIC_UNITS,
    "first_yield_pressure": "Pa",
    "limit_load": "Pa",
    "n_elements": "1",
    "n_dofs": "1",
    "patch_fraction": "1",
    "wall_time_s": "s",
    "pressure": "Pa",
    "plastic_radius": "m",
    "outer_displacement": "m",
    "inner_displacement": "m",
    "newton_iterations": "1",
    "residuals": "1",
    "reference": "",
    "adaptations": ADAPTATIONS_UNIT,
    "max_coarse_yield_ratio": "1",
    "final": "Pa (pressure), m (radius, displacements)",
    "history": "Pa (pressure), m (radius, displacements), 1 (iterations, residuals)",
}


@dataclass
class PressureVesselResult(JsonResult):
    """What a pressure-vessel run computed (SI units).

    Attributes
    ----------
    first_yield_pressure : float
        The bore pressure at which the first quadrature point of the J2 model yields (Pa),
        from the elastic response (linear up to first yield).
    limit_load_reached : bool
        The load could not increase further (a mechanism).
    limit_load : float or None
        The last converged bore pressure then (Pa).
    n_elements, n_dofs : int
        Cells and dofs of the run (every model's).
    patch_fraction : float
        The patch's share of the wall's area (volume in 3D): the coarse cells it covers
        over the coarse mesh, as in the growths' records (1 for ``mono``).
    wall_time_s : float
    history : dict
        Per converged step (the initial state first): ``pressure`` (Pa; under a prescribed
        bore displacement, the pressure that displacement needs, from the reactions),
        ``plastic_radius`` (m: the largest radius of the region with ε̄p > 0, interpolated
        between quadrature points; ``inner`` before first yield), ``outer_displacement`` and
        ``inner_displacement`` (radial, m), ``newton_iterations`` and ``residuals`` (each
        step's relative residuals; 0 and [] for the initial state).
    reference : dict
        Hill's values at the final pressure (sphere), first yield and the limit load.
    adaptations : list of dict
        With ``adaptive``: each growth of the patch, ``step``, ``time`` (the load factor of
        the fields it started from), ``n_fine_elements``, ``patch_fraction`` (of the wall's
        area), ``energy_jump`` (the relative change of the total stored energy across it),
        ``rejected`` (the step was computed again). ``history["patch_fraction"]`` gives the
        patch's share at every step.
    max_coarse_yield_ratio : float
        The largest von Mises stress / σy of the coarse elastic model outside the patch over
        the run (0 for ``mono``); above 1 the run warns (``CoarseYieldWarning``): the plastic
        zone has outgrown the patch.
    band_plastic_fraction : float or None
        The largest share of the patch's gluing band (its quadrature weight) that was plastic
        after a converged step (None for a single mesh): above 0 the run warns
        (``BandYieldWarning``): the band's fields are the coupling's, not the material's.
    max_plastic_strain : float or None
        The final state's largest equivalent plastic strain of the J2 model (1).
    max_plastic_strain_position : list of float or None
        Its quadrature point (m, reference configuration).
    max_plastic_strain_in_band : bool or None
        Whether it lies in the patch's gluing band (None for a single mesh): if so, it is the
        coupling's, not the material's.
    """

    first_yield_pressure: float
    limit_load_reached: bool
    limit_load: float | None
    n_elements: int
    n_dofs: int
    patch_fraction: float
    wall_time_s: float
    history: dict[str, list[Any]]
    reference: dict[str, float] = field(default_factory=dict)
    max_coarse_yield_ratio: float = 0.0
    config: dict[str, Any] = field(default_factory=dict)
    adaptations: list[dict[str, Any]] = field(default_factory=list)
    band_plastic_fraction: float | None = None
    max_plastic_strain: float | None = None
    max_plastic_strain_position: list[float] | None = None
    max_plastic_strain_in_band: bool | None = None

    json_exclude = ("config",)

    @property
    def final(self) -> dict[str, float]:
        """The last converged state: ``pressure`` (Pa), ``plastic_radius``,
        ``outer_displacement``, ``inner_displacement`` (m) (scalars for tables and studies)."""
        keys = ("pressure", "plastic_radius", "outer_displacement", "inner_displacement")
        return {k: float(self.history[k][-1]) for k in keys}

    def to_json(self) -> dict[str, Any]:
        """The Interface's keys, then ``final`` (the last converged state's scalars, which a
        study's table shows) and the rest."""
        data = super().to_json()
        data["final"] = self.final
        return data

    def summary(self) -> str:
        """One line: first yield, the final state (against Hill's for the sphere), Newton, and
        a warning when the coarse model outside the patch went past yield."""
        h = self.history
        its = h["newton_iterations"][1:]
        end = (f"limit load {self.limit_load / 1e6:.2f} MPa" if self.limit_load_reached
               else f"P = {h['pressure'][-1] / 1e6:.2f} MPa")  # fmt: skip
        return (
            f"{self.config.get('shape', 'vessel')} ({self.config.get('model')}): first yield "
            f"{self.first_yield_pressure / 1e6:.3f} MPa, {end}: plastic radius "
            f"{h['plastic_radius'][-1] * 1e3:.3f} mm, outer displacement "
            f"{h['outer_displacement'][-1] * 1e6:.3f} µm; {len(its)} steps, Newton "
            f"{sum(its)} iterations (max {max(its, default=0)}), {self.wall_time_s:.1f} s"
            + self._against_hill()
            + self._growths()
            + (
                f"; WARNING: the coarse model outside the patch reached "
                f"{self.max_coarse_yield_ratio:.2f} σy (the plastic zone outgrew the patch)"
                if self.max_coarse_yield_ratio > 1.0
                else ""
            )
        )

    def _growths(self) -> str:
        """An adaptive run's growths and the largest coarse σ_vm/σy (as the plate says)."""
        if not self.config.get("adaptive"):
            return ""
        return (f"; the patch grew {len(self.adaptations)} times to {self.patch_fraction:.3f} "
                f"of the wall, coarse σ_vm/σy ≤ {self.max_coarse_yield_ratio:.3f}")  # fmt: skip

    def _against_hill(self) -> str:
        ref, h = self.reference, self.history
        if "outer_displacement" not in ref:
            return ""
        c = h["plastic_radius"][-1] / ref["plastic_radius"] - 1.0
        ub = h["outer_displacement"][-1] / ref["outer_displacement"] - 1.0
        return f"; against Hill: c {100 * c:+.2f}%, u_b {100 * ub:+.2f}%"
