"""The 1D impact set-ups: bars, their contact pair and model, the time scheme (SI units).

Methods: the level-set (Signorini–Moreau) contact model (:class:`arlequin.models.LevelSetContact`)
with the θ-scheme (``integrator="theta"``, consistent mass) or central differences
(``integrator="explicit"``, lumped mass); the baseline Newmark + Signorini on displacements
(:class:`arlequin.models.SignoriniContact`): trapezoidal (β = ¼, γ = ½) or HHT-α (α = −0.1).
The time step is ``cfl × h_min / c``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import skfem

from ...models import (
    ContactSurface,
    DeformableContactPair,
    IsotropicElastic,
    LevelSetContact,
    LinearElastic,
    SignoriniContact,
)
from .exact import exact_two_bars

if TYPE_CHECKING:
    from .config import TwoBarsConfig

__all__ = ["AREA", "Impact", "Scheme", "TwoBarsSetup", "bar", "contact", "integrator_options"]

AREA = 1e-4  # bar cross-section (m²); the pressures do not depend on it


def bar(x0: float, x1: float, n: int, material: IsotropicElastic) -> LinearElastic:
    """A bar on [x0, x1] (m) of ``n`` linear elements, cross-section :data:`AREA`."""
    mesh = skfem.MeshLine(np.linspace(x0, x1, n + 1))
    return LinearElastic(mesh, material, kind="1d", area=AREA)


def contact(kind: str, pair, material, name: str = "contact"):
    """The contact model: ``"levelset"`` or the Signorini baseline."""
    if kind == "levelset":
        return LevelSetContact(pair, material=material, name=name)
    return SignoriniContact(pair, name=name)


def integrator_options(
    method: str, newmark: str, integrator: str, theta: float
) -> tuple[str, dict]:
    """The integrator's registry name and options of a method and its scheme."""
    if method == "levelset":
        if integrator == "theta":
            return "theta", {"theta": theta}
        if integrator == "explicit":
            return "explicit", {}
        raise ValueError(f"integrator must be 'theta' or 'explicit', got {integrator!r}")
    if newmark == "trapezoidal":
        return "newmark", {"beta": 0.25, "gamma": 0.5}
    if newmark == "hht":
        return "hht", {"alpha": -0.1}
    raise ValueError(f"newmark must be 'trapezoidal' or 'hht', got {newmark!r}")


@dataclass
class Impact:
    """A 1D impact set-up: the bars, their initial velocities, the contact pair, the step."""

    bodies: list[LinearElastic]
    names: list[str]
    v_init: list[float]
    pair_factory: Any  # DofMap -> ContactPair
    interface_dof: Any  # DofMap -> global dof of the reported interface velocity
    exact: dict[str, Any]
    config: dict[str, Any]
    material: IsotropicElastic
    dt: float
    t_end: float


@dataclass(frozen=True)
class Scheme:
    """The method and time scheme of one run."""

    method: str  # "levelset" or "newmark"
    newmark: str
    integrator: str
    theta: float


class TwoBarsSetup:
    """The two bars of a configuration, their exact solution, step and end time; one
    :class:`Impact` a method (the bars shared by both runs of ``method="both"``).

    Attributes
    ----------
    record : dict
        The resolved inputs of the runs (``lengths`` (m), ``elements``, ``t_end`` (s)...).
    """

    def __init__(self, config: TwoBarsConfig) -> None:
        l1, l2 = (float(x) for x in config.lengths)
        self.l1, self.l2 = l1, l2
        self.material = IsotropicElastic(config.young, 0.3, config.density)
        ex = exact_two_bars((l1, l2), config.young, config.density, config.velocity,
                            config.velocity2)  # fmt: skip
        ex["velocity_scale"] = config.velocity - config.velocity2
        self.exact = ex
        c = ex["c"]
        n = int(config.elements)
        self.dt = config.cfl * min(l1, l2) / n / c
        self.t_end = 3.0 * max(l1, l2) / c if config.t_end is None else float(config.t_end)
        self.bar1 = bar(-l1, 0.0, n, self.material)
        self.bar2 = bar(0.0, l2, n, self.material)
        self.velocities = [config.velocity, config.velocity2]
        self.record = {
            "lengths": [l1, l2],
            "young": config.young,
            "density": config.density,
            "velocity": config.velocity,
            "velocity2": config.velocity2,
            "elements": n,
            "cfl": config.cfl,
            "theta": config.theta,
            "t_end": self.t_end,
        }

    def pair_factory(self, dofmap):
        """The deformable contact pair of the bars' facing ends."""
        l1, l2 = self.l1, self.l2
        s = ContactSurface(
            self.bar1.mesh, where=lambda x: x[0] > -0.5 * l1, offset=dofmap["bar1"], area=AREA
        )
        m = ContactSurface(
            self.bar2.mesh, where=lambda x: x[0] < 0.5 * l2, offset=dofmap["bar2"], area=AREA
        )
        return DeformableContactPair(s, m, dofmap)

    def interface_dof(self, dofmap) -> int:
        """Bar 2's contact-node dof (the reported interface velocity)."""
        return int(dofmap["bar2"].node_dofs([np.argmin(self.bar2.mesh.p[0])])[0, 0])

    def impact(self, method: str) -> Impact:
        """The set-up of one run with ``method`` (``"levelset"`` or ``"newmark"``)."""
        return Impact(
            [self.bar1, self.bar2],
            ["bar1", "bar2"],
            list(self.velocities),
            self.pair_factory,
            self.interface_dof,
            self.exact,
            dict(self.record, method=method),
            self.material,
            self.dt,
            self.t_end,
        )
