"""The plate with a hole: a coarse elastic plate and a J2 patch around the hole, pulled past
first yield, quasi-static (``arlequin plate-with-hole``).

A quarter of a plane-strain plate [0, W]² (W = 10a by default: 20 hole radii across, so that
the far field is uniform) with a hole of radius a is pulled by a uniform traction S on x = W
(symmetry on x = 0 and y = 0). The elastic response is computed up to first yield (linear:
from one probing step), then S is raised in N equal steps, each solved by Newton with the
consistent tangents (:func:`arlequin.solve_quasi_static`; J2 at small strain with B-bar,
:class:`~arlequin.models.SmallStrainJ2`). Models: see :mod:`.setup`.

Outputs (``out``): results.json (inputs and results with units), ``newton.csv`` (per step:
load factor, Newton iterations, residuals, cuts), the field series of each block
(``fields/coarse.xdmf``, ``fields/patch0.xdmf``: displacement, α, the mediator's multipliers,
ε̄p and the von Mises stress per cell, one frame a step), ``load_displacement.png`` and
``plastic_zone.png``.
"""

from .config import DEFAULT_LOAD, PlateWithHoleConfig
from .result import HISTORY_KEYS, JSON_KEYS, PlateWithHoleResult

__all__ = [
    "DEFAULT_LOAD",
    "HISTORY_KEYS",
    "JSON_KEYS",
    "PlateWithHoleConfig",
    "PlateWithHoleResult",
    "run_plate_with_hole",
]


def run_plate_with_hole(out=None, progress=None, **options) -> PlateWithHoleResult:
    """Run the plate with a hole with the options of :class:`PlateWithHoleConfig` (SI units);
    ``out`` a results folder, ``progress(fraction)`` of the load."""
    return PlateWithHoleConfig(**options).run(out=out, progress=progress)
