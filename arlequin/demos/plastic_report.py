"""What the quasi-static J2 demos report of their plastic zone's peak and gluing band.

A J2 patch's largest plastic strain is the quantity a plasticity study reports first; it means
something only outside the gluing band, where the patch's fields are the material's. The demos
record it with its place and whether it lies in the band (``max_plastic_strain``,
``max_plastic_strain_position``, ``max_plastic_strain_in_band``), and the band's plastic share
over the run (``band_plastic_fraction``,
:class:`~arlequin.solvers.system.yield_watch.BandYieldWatch`).
"""

from __future__ import annotations

from typing import Any

from ..coupling.band_plasticity import band_cells, plastic_peak

__all__ = ["PLASTIC_UNITS", "mark_peak", "plastic_report"]

#: The units of :func:`plastic_report`'s keys.
PLASTIC_UNITS = {
    "band_plastic_fraction": "1",
    "max_plastic_strain": "1",
    "max_plastic_strain_position": "m",
    "max_plastic_strain_in_band": "",
}


def plastic_report(problem: Any, block: str, model: Any, state: Any,
                   band_fraction: float | None) -> dict[str, Any]:  # fmt: skip
    """The JSON keys of :data:`PLASTIC_UNITS` for the J2 ``model`` (of ``block``) in its final
    ``state`` and the band's largest plastic share over the run (None without a patch: a
    single mesh, or a graded one with a J2 zone)."""
    pc = next((pc for pc in getattr(problem, "couplings", ()) if pc.name == block), None)
    peak = plastic_peak(model, state, None if pc is None else band_cells(pc))
    return {
        "band_plastic_fraction": band_fraction if pc is not None else None,
        "max_plastic_strain": None if peak is None else peak.value,
        "max_plastic_strain_position": None if peak is None else peak.position.tolist(),
        "max_plastic_strain_in_band": peak.in_band if (peak is not None and pc) else None,
    }


def mark_peak(ax: Any, report: dict[str, Any]) -> None:
    """Mark a picture's largest plastic strain (a :func:`plastic_report`): a cross at its
    place (its first two coordinates: a 3D point shown on its plane's picture) and a line
    under the title saying its value and whether it lies in the gluing band."""
    where, value = report.get("max_plastic_strain_position"), report.get("max_plastic_strain")
    if where is None or not value:
        return
    band = report.get("max_plastic_strain_in_band")
    ax.plot(where[0], where[1], marker="x", color="red", markersize=9, mew=2)
    note = {True: ", IN THE GLUING BAND (the coupling's)", False: ", outside the band",
            None: ""}[band]  # fmt: skip
    ax.set_xlabel(f"x: largest ε̄p {value:.3g}{note}", fontsize=8)
