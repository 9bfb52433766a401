"""The result of a plate-with-hole run: its JSON keys (the Interface), units and summary."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ...io import JsonResult
from ..adaptive_options import ADAPTATIONS_UNIT
from ..plastic_report import PLASTIC_UNITS

__all__ = ["HISTORY_KEYS", "JSON_KEYS", "UNITS", "PlateWithHoleResult"]

#: The Interface's keys, in order.
JSON_KEYS = ("history", "wall_time_s", "n_elements", "patch_fraction")
#: The keys of ``history``: one value per converged state (the initial state first, then
#: first yield, then every load step). The Interface's three first.
HISTORY_KEYS = ("load", "displacement", "plastic_area", "plastic_extent", "newton_iterations",
                "residuals", "patch_fraction")  # fmt: skip
UNITS = {
    **PLASTIC_UNITS,
    "load": "Pa",
    "displacement": "m",
    "plastic_area": "m^2",
    "plastic_extent": "m",
    "newton_iterations": "1",
    "residuals": "1",
    "wall_time_s": "s",
    "n_elements": "1",
    "n_dofs": "1",
    "patch_fraction": "1",
    "first_yield_load": "Pa",
    "max_coarse_yield_ratio": "1",
    "plastic_cover_fraction": "1",
    "band_fraction": "1",
    "adaptations": ADAPTATIONS_UNIT,
}


@dataclass
class PlateWithHoleResult(JsonResult):
    """What a plate-with-hole run computed (SI units).

    Attributes
    ----------
    history : dict
        Per converged state (the unloaded plate first, then first yield, then each load step):
        ``load`` S (Pa); ``displacement`` the mean x-displacement of the loaded edge x = W (m);
        ``plastic_area`` the area of the quadrature-point weights with ε̄p > 0 over the quarter
        plate (m²); ``plastic_extent`` the largest distance from the hole's centre of a
        quadrature point with ε̄p > 0 (m, 0 before yield); ``newton_iterations`` and
        ``residuals`` (each step's relative residuals; 0 and [] for the first two states);
        ``patch_fraction`` the J2 region's share of the plate's area (the adaptive patch's
        after the step).
    wall_time_s : float
        The run's wall time (s): meshes, models, the elastic solve, the load steps.
    n_elements : int
        Cells of the run (every model's).
    patch_fraction : float
        The J2 region's share of the quarter plate's area (1 for ``mono``).
    n_dofs : int
    first_yield_load : float
        The remote traction S at which the first quadrature point yields (Pa).
    status : str
        The quasi-static solver's end: ``completed`` or ``limit_load``.
    adaptations : list of dict
        With ``adaptive``: one entry per growth of the patch, ``step`` (the load step after
        which it grew, counted from the first after first yield), ``time`` (the load factor λ
        of the fields it started from, S = λ load), ``n_fine_elements``, ``patch_fraction``
        (of the plate's area), ``energy_jump`` (relative change of the stored energy across
        it), ``rejected`` (the step computed again after it), ``newton_iterations``.
    max_coarse_yield_ratio : float or None
        The largest von Mises stress / σy of the coarse elastic model outside the patch over
        the converged steps (0 for mono, None for the graded mesh).
    plastic_cover_fraction : float or None
        The share of the plate's area of the smallest nested patch that holds the final
        plastic zone and its gluing band: the coarse cells over a plastic fine cell plus
        ``gluing_rings`` layers around them (:func:`~.run.plastic_cover_fraction`; None for
        mono and graded). The adaptive patch's ``patch_fraction`` over it measures how tight
        the patch is.
    band_fraction : float or None
        The final patch's gluing band's share of the plate's area (its fine cells within
        ``gluing_rings`` coarse cells of the patch's interior boundary; None for mono and
        graded). Criterion 4 of issue 31 (the adaptive patch at most 1.5 times the plastic
        zone and its band) reads ``patch_fraction ≤ 1.5 (plastic_area / plate + band_fraction)``.
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

    history: dict[str, list[Any]]
    wall_time_s: float
    n_elements: int
    patch_fraction: float
    n_dofs: int = 0
    first_yield_load: float = 0.0
    status: str = "completed"
    config: dict[str, Any] = field(default_factory=dict)
    adaptations: list[dict[str, Any]] = field(default_factory=list)
    max_coarse_yield_ratio: float | None = None
    plastic_cover_fraction: float | None = None
    band_fraction: float | None = None
    band_plastic_fraction: float | None = None
    max_plastic_strain: float | None = None
    max_plastic_strain_position: list[float] | None = None
    max_plastic_strain_in_band: bool | None = None

    json_exclude = ("config",)

    def summary(self) -> str:
        """One line: the final state and Newton."""
        h = self.history
        its = h["newton_iterations"][2:]
        a = self.config.get("radius") or 1.0
        return (
            f"plate with a hole ({self.config.get('model')}): first yield "
            f"{self.first_yield_load / 1e6:.2f} MPa, S = {h['load'][-1] / 1e6:.2f} MPa: edge "
            f"displacement {h['displacement'][-1] * 1e6:.4f} µm, plastic area "
            f"{h['plastic_area'][-1] * 1e6:.4f} mm^2, extent {h['plastic_extent'][-1] / a:.3f} a; "
            f"{len(its)} steps, Newton {sum(its)} iterations (max {max(its, default=0)}), "
            f"{self.n_elements} cells, {self.wall_time_s:.1f} s ({self.status})"
            + (
                f"; the patch grew {len(self.adaptations)} times to {self.patch_fraction:.3f} "
                f"of the plate, coarse σ_vm/σy ≤ {self.max_coarse_yield_ratio:.3f}"
                if self.adaptations
                else ""
            )
        )
