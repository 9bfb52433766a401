"""The plate with a hole: a coarse elastic plate and a J2 patch around the hole, pulled past
first yield, quasi-static (``arlequin plate-with-hole``).

A quarter of a plane-strain plate [0, W]² (W = 10a by default: 20 hole radii across, so that
the far field is uniform) with a hole of radius a is pulled by a uniform traction S on x = W
(symmetry on x = 0 and y = 0). The elastic response is computed up to first yield (linear:
from one probing step), then S is raised in N equal steps, each solved by Newton with the
consistent tangents (:func:`arlequin.solve_quasi_static`; J2 at small strain with B-bar,
:class:`~arlequin.models.SmallStrainJ2`). Models: see :mod:`.setup`; the page
``docs/plate_with_hole.md`` gives the measurements in full.

Defaults (E = 210 GPa, ν = 0.3, σy = 240 MPa, perfectly plastic, a = 10 mm, W = 10a; the
coarse mesh quasi-uniform: 4 rings of 8 cells along the quarter hole in [0, 2a]², a grid of a/2
cells beyond, 416 cells; the patch the coarse cells of [0, 3.5a]² refined 3 times, 64 fine cells
along the quarter hole, glued in its outer layer of coarse cells with α_coarse 0.75 on its edge,
L2 coupling; mono that whole mesh refined 3 times, 26624 cells): first yield at S = 89.6 MPa;
the default S = 195 MPa is where the plastic zone's extent from the hole's centre, growing fast
as shear bands form, reaches 2.32a. Against ``mono``: the loaded edge's mean displacement within
0.143% (``arlequin``) and 0.023% (``graded``) at every state, the final plastic area −1.11% and
−0.36%, the same extent. Cost (``benchmarks/plate_with_hole.py --repeat 2``, one process, 2
shared cores): mono 61.7 s, arlequin 5.2 s, graded 9.1 s: T_mono / T_arlequin = 11.8 (target
≥ 10, met), T_arlequin / T_graded = 0.57 (target ≤ 1.5, met); 51% of the Arlequin run is the
SuperLU factorisation of its Newton systems (the coarse plate, 880 dofs for the patch's 8496,
is not condensed: forcing it changes nothing measurable).

``adaptive``: the patch starts from the coarse ring on the hole and grows where the plastic
zone nears its gluing band or the coarse stress reaches β σy (default β 0.9), the plastic
points of the band's outer half (α_f < 1/2) disregarded, each growth closed over one-cell
slots and notches (:func:`.setup.fill_notches`); see ``docs/plate_with_hole.md``.

Outputs (``out``): results.json (inputs and results with units), ``history.csv`` (per
converged step, first yield included: load factor, nominal stress, the measures of the
history, Newton iterations, residuals, cuts, the quadrature points that crossed the yield
surface in each iteration), ``newton.csv`` (per Newton iteration: residuals, crossings), the
field series of each block
(``fields/coarse.xdmf``, ``fields/patch0.xdmf``: displacement, α, the mediator's multipliers,
ε̄p and the von Mises stress per cell, the coarse model's von Mises stress, one frame a
step), ``load_displacement.png`` and
``plastic_zone.png``.
"""

from ..config import register_runner
from . import run as _run
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

# the configuration runs through its package's runner (it does not import its run module)
register_runner(PlateWithHoleConfig, _run.run)


def run_plate_with_hole(out=None, progress=None, **options) -> PlateWithHoleResult:
    """Run the plate with a hole with the options of :class:`PlateWithHoleConfig` (SI units);
    ``out`` a results folder, ``progress(fraction)`` of the load."""
    return PlateWithHoleConfig(**options).run(out=out, progress=progress)
