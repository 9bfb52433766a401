"""The plate with a hole: a coarse elastic plate and a J2 patch around the hole, pulled past
first yield, quasi-static (``arlequin plate-with-hole``).

A quarter of a plane-strain plate [0, W]² (W = 10a by default: 20 hole radii across, so that
the far field is uniform) with a hole of radius a is pulled by a uniform traction S on x = W
(symmetry on x = 0 and y = 0). The elastic response is computed up to first yield (linear:
from one probing step), then S is raised in N equal steps, each solved by Newton with the
consistent tangents (:func:`arlequin.solve_quasi_static`; J2 at small strain with B-bar,
:class:`~arlequin.models.SmallStrainJ2`). Models: see :mod:`.setup`; the page
``docs/plate_with_hole.md`` gives the measurements in full.

Defaults (E = 210 GPa, ν = 0.3, σy = 240 MPa, perfectly plastic, a = 10 mm, W = 10a, 16 coarse
cells along the quarter hole, 24 rings, the patch the 16 rings within 5a refined twice, L2
coupling): first yield at S = 89.6 MPa; the default S = 195 MPa is where the plastic zone's
extent from the hole's centre, growing fast as shear bands form, reaches 2.3a (mono: 1.97a at
190 MPa, 2.69a at 200 MPa). Against ``mono``: the loaded edge's mean displacement within 0.090%
(``arlequin``) and 0.018% (``graded``) at every state, the final plastic area −1.97% and
−0.33%. Cost (``benchmarks/plate_with_hole.py``, one process): mono 26.8 s, arlequin 13.9 s,
graded 13.3 s: T_arlequin / T_graded = 1.04 (target ≤ 1.5, met), T_mono / T_arlequin = 1.93
(target ≥ 10, not met: every ring of this polar mesh has the same number of cells, so the patch
holds two thirds of mono's cells); 63% of the Arlequin run is the SuperLU factorisation of the
patch at each Newton iteration.

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
