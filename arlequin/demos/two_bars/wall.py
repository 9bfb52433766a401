"""A bar against a rigid wall (the bar-on-wall variant of the two-bar impact; SI units)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ...models import ContactSurface, IsotropicElastic, PlaneObstacle, RigidContactPair
from .config import check_common
from .report import UNITS, finish, open_folder
from .result import TwoBarsResult
from .run import run_1d
from .setup import AREA, Impact, Scheme
from .setup import bar as _bar

__all__ = ["run_wall"]


def run_wall(
    method: str = "levelset",
    newmark: str = "trapezoidal",
    length: float = 1.0,
    young: float = 210e9,
    density: float = 7850.0,
    velocity: float = 1.0,
    elements: int = 100,
    cfl: float = 1.0,
    theta: float = 0.5,
    t_end: float | None = None,
    integrator: str = "theta",
    out: str | Path | None = None,
) -> TwoBarsResult:
    """A bar on [−L, 0] at velocity v₀ > 0 against a rigid wall at x = 0 (touching at t = 0).

    Exact: pressure ρ c v₀ during 2L/c, then the bar rebounds at −v₀. The wall is a
    :class:`~arlequin.models.PlaneObstacle` (φ = −x). Parameters as :func:`run_two_bars`; the
    result's ``final_velocities`` has one entry and ``interface_velocity`` is the bar's
    contact-node velocity (exact 0 during contact).
    """
    if method not in ("levelset", "newmark"):
        raise ValueError(f"method must be 'levelset' or 'newmark', got {method!r}")
    check_common(young, density, cfl, elements, t_end, theta, velocity=velocity, length=length)
    if not velocity > 0:
        raise ValueError(f"the bar must approach the wall: velocity={velocity}")
    material = IsotropicElastic(young, 0.3, density)
    c = math.sqrt(young / density)
    L = float(length)
    n = int(elements)
    dt = cfl * L / n / c
    t_end = 3.0 * L / c if t_end is None else float(t_end)
    bar = _bar(-L, 0.0, n, material)
    ex = {
        "interface_velocity": 0.0,
        "pressure": density * c * velocity,
        "duration": 2.0 * L / c,
        "final_velocities": [-velocity],
        "c": c,
        "velocity_scale": velocity,
    }
    config = {
        "length": L,
        "young": young,
        "density": density,
        "velocity": velocity,
        "elements": n,
        "cfl": cfl,
        "theta": theta,
        "t_end": t_end,
        "method": method,
    }

    def pair_factory(dofmap):
        s = ContactSurface(
            bar.mesh, where=lambda x: x[0] > -0.5 * L, offset=dofmap["bar"], area=AREA
        )
        return RigidContactPair(s, PlaneObstacle([0.0], [-1.0]), dofmap)

    def interface_dof(dofmap):
        return int(dofmap["bar"].node_dofs([np.argmax(bar.mesh.p[0])])[0, 0])

    folder = open_folder(out, "arlequin two-bars --wall",
                         dict(config, newmark=newmark, integrator=integrator), UNITS)  # fmt: skip
    setup = Impact(
        [bar], ["bar"], [velocity], pair_factory, interface_dof, ex, config, material, dt, t_end
    )
    res = run_1d(setup, Scheme(method, newmark, integrator, theta), folder)
    finish(folder, res)
    return res
