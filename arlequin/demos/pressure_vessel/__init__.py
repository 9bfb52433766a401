"""The pressure vessels: a thick sphere or cylinder under internal pressure, J2 plasticity,
quasi-static (``arlequin pressure-vessel``).

A sphere (axisymmetric: the meridional quarter) or a cylinder (plane strain: a quarter of the
section), inner radius a and outer radius b, is pressurised at the bore (or its bore is moved
radially) in equal load steps, each solved by Newton with the consistent tangents
(:func:`arlequin.solve_quasi_static`). Model ``arlequin``: a coarse linear-elastic model of the
whole wall and a refined J2 patch (small-strain :class:`~arlequin.models.SmallStrainJ2` or
finite-strain :class:`~arlequin.models.FiniteStrainJ2`) from the bore to a chosen radius,
glued by a coarse mediator in its outermost coarse ring; model ``mono``: one fine J2 mesh.

Exact references (:mod:`arlequin.demos.pressure_vessel.hill`): for the sphere Hill's solution
(first yield, the plastic front c, the outer displacement u_b, the limit load), for the
cylinder first yield and the limit load.

Outputs (``out``): results.json (inputs and results with units), ``history.csv`` (per
converged step: load factor, pressure, plastic front, displacements, Newton iterations,
residuals, cuts, the quadrature points that crossed the yield surface in each iteration),
``newton.csv`` (per Newton iteration: residuals, crossings), the field series
``fields/coarse.xdmf`` and ``fields/patch0.xdmf`` (displacement, α, the mediator's multipliers,
ε̄p and the von Mises stress per cell, the coarse model's von Mises stress, one frame a
step), ``pressure_displacement.png`` and
``plastic_zone.png``.
"""

from ..config import register_runner
from . import run as _run
from .config import PressureVesselConfig
from .hill import sphere_outer_displacement, sphere_plastic_radius
from .result import JSON_KEYS, PressureVesselResult

__all__ = [
    "JSON_KEYS",
    "PressureVesselConfig",
    "PressureVesselResult",
    "run_pressure_vessel",
    "sphere_outer_displacement",
    "sphere_plastic_radius",
]

# the configuration runs through its package's runner (it does not import its run module)
register_runner(PressureVesselConfig, _run.run, resume=_run.resume)


def run_pressure_vessel(out=None, progress=None, **options) -> PressureVesselResult:
    """Run the pressure vessel with the options of :class:`PressureVesselConfig` (SI units);
    ``out`` a results folder, ``progress(fraction)`` of the load."""
    return PressureVesselConfig(**options).run(out=out, progress=progress)
