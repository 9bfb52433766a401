"""Exact solutions of thick pressure vessels in small-strain perfect plasticity (Hill 1950).

Sphere a < r < b under internal pressure P, von Mises (exact: in spherical symmetry von Mises
and Tresca coincide):

* first yield at the bore: P0 = (2σy/3)(1 − a³/b³);
* elastic-plastic (a < c < b): P = 2σy ln(c/a) + (2σy/3)(1 − c³/b³);
* outer displacement u_b = (1 − ν) σy c³ / (E b²) (the elastic shell c < r < b);
* limit load 2σy ln(b/a) (c = b).

Cylinder in plane strain (ε_z = 0), von Mises with compressible elasticity: first yield from
Lamé's elastic solution with σz = ν(σr + σθ), the largest von Mises stress (at the bore)
reaching σy; limit load (2/√3) σy ln(b/a). In between, Hill's Tresca-like formulas are only
approximate for ν < 1/2 (compare with a fine single-mesh run).

SI units (Pa, m).
"""

from __future__ import annotations

import math

from scipy.optimize import brentq

__all__ = [
    "cylinder_first_yield",
    "cylinder_limit_load",
    "sphere_first_yield",
    "sphere_limit_load",
    "sphere_outer_displacement",
    "sphere_plastic_radius",
    "sphere_pressure",
]


def sphere_first_yield(a: float, b: float, yield_stress: float) -> float:
    """P0 (Pa): the pressure at which the bore of the sphere yields."""
    return 2.0 * yield_stress / 3.0 * (1.0 - (a / b) ** 3)


def sphere_pressure(c: float, a: float, b: float, yield_stress: float) -> float:
    """P (Pa) that takes the plastic front of the sphere to radius c (a ≤ c ≤ b)."""
    return 2.0 * yield_stress * math.log(c / a) + 2.0 * yield_stress / 3.0 * (1.0 - (c / b) ** 3)


def sphere_plastic_radius(pressure: float, a: float, b: float, yield_stress: float) -> float:
    """The plastic front c (m) of the sphere at ``pressure`` (Pa): a below first yield."""
    if pressure <= sphere_first_yield(a, b, yield_stress):
        return a
    if pressure >= sphere_limit_load(a, b, yield_stress):
        return b
    return brentq(lambda c: sphere_pressure(c, a, b, yield_stress) - pressure, a, b, xtol=1e-15)


def sphere_outer_displacement(pressure: float, a: float, b: float, young: float,
                              poisson: float, yield_stress: float) -> float:  # fmt: skip
    """u(b) (m) of the sphere at ``pressure``: elastic (Lamé) below first yield, Hill's
    (1 − ν) σy c³/(E b²) above."""
    if pressure <= sphere_first_yield(a, b, yield_stress):
        # Lamé: u(r) = P a³ [(1 − 2ν) r + (1 + ν) b³/(2 r²)] / (E (b³ − a³)), at r = b
        return 3.0 * (1.0 - poisson) * pressure * a**3 * b / (2.0 * young * (b**3 - a**3))
    c = sphere_plastic_radius(pressure, a, b, yield_stress)
    return (1.0 - poisson) * yield_stress * c**3 / (young * b**2)


def sphere_limit_load(a: float, b: float, yield_stress: float) -> float:
    """2σy ln(b/a) (Pa)."""
    return 2.0 * yield_stress * math.log(b / a)


def cylinder_first_yield(a: float, b: float, poisson: float, yield_stress: float) -> float:
    """P0 (Pa) of the plane-strain cylinder: von Mises of Lamé's stresses at the bore = σy.

    At r = a: σr = −P, σθ = P (b² + a²)/(b² − a²), σz = ν(σr + σθ) = 2νP a²/(b² − a²); the
    von Mises stress is linear in P, so P0 = σy / σ_vm(P = 1).
    """
    k = a**2 / (b**2 - a**2)
    sr, st = -1.0, (b**2 + a**2) / (b**2 - a**2)
    sz = poisson * (sr + st)
    assert abs(sz - 2.0 * poisson * k) < 1e-12
    vm = math.sqrt(0.5 * ((sr - st) ** 2 + (st - sz) ** 2 + (sz - sr) ** 2))
    return yield_stress / vm


def cylinder_limit_load(a: float, b: float, yield_stress: float) -> float:
    """(2/√3) σy ln(b/a) (Pa)."""
    return 2.0 / math.sqrt(3.0) * yield_stress * math.log(b / a)
