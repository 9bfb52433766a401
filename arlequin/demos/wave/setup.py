"""The wave demo's set-up: the layout in coarse elements, the two bars, the Arlequin problem
and the initial pulse (SI: h = 1 cm, E = 200 GPa, ρ = 7800 kg/m³, A = 1 cm², so
c = √(E/ρ) ≈ 5064 m/s).

::

    0      a            a+W     X_p        X_p+G                                   L
    |------[== pulse ==>]-------|~~ band ~~|---------- patch free zone ----------|
    coarse everywhere;          refined patch on [X_p, L], gluing band [X_p, X_p+G]

with a = max(5, G), X_p = a + W + 5 and L = X_p + W + G + 15. The pulse is the right-going wave
u(x, 0) = A₀ sin⁴(π (x − a)/W) on [a, a + W], v(x, 0) = −c ∂u/∂x, on the coarse model only (the
patch starts at rest: the initial condition is coupling-consistent).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import skfem

from ...models import IsotropicElastic, LinearElastic
from ...problem.arlequin_problem import ArlequinProblem, Patch

if TYPE_CHECKING:
    from .config import WaveConfig

__all__ = ["AMPLITUDE", "AREA", "DENSITY", "YOUNG", "H", "WaveSetup", "build_wave", "wave_layout"]

H = 0.01  # coarse element size (m)
YOUNG = 200e9  # Pa
DENSITY = 7800.0  # kg/m³
AREA = 1e-4  # m²
AMPLITUDE = 1e-6  # m


def wave_layout(pulse_width: float, gluing_width: float) -> dict[str, float]:
    """Positions in coarse elements: a (pulse start), x_patch, band end, length, travel."""
    w, g = float(pulse_width), float(gluing_width)
    a = max(5.0, math.ceil(g))
    x_patch = a + math.ceil(w) + 5.0
    length = x_patch + math.ceil(w) + math.ceil(g) + 15.0
    return {
        "a": a,
        "x_patch": x_patch,
        "band_end": x_patch + g,
        "length": length,
        "travel": w + g + 10.0,
    }


def _pulse(x: np.ndarray, a: float, w: float) -> tuple[np.ndarray, np.ndarray]:
    s = np.clip((x - a) / w, 0.0, 1.0)
    u = np.sin(np.pi * s) ** 4
    du = 4.0 * np.sin(np.pi * s) ** 3 * np.cos(np.pi * s) * np.pi / w
    return u, du


@dataclass
class WaveSetup:
    """The built wave problem.

    Attributes
    ----------
    layout : dict
        :func:`wave_layout` (coarse elements).
    coarse_mesh, fine_mesh : skfem.MeshLine
    coarse, fine : LinearElastic
    problem : ArlequinProblem
    system : CoupledSystem
        The coupled system of ``problem``.
    u0c, v0c : ndarray, shape (n_coarse_nodes,)
        The pulse's initial displacement (m) and velocity (m/s) on the coarse model.
    c : float
        Wave speed (m/s).
    """

    layout: dict[str, float]
    coarse_mesh: Any
    fine_mesh: Any
    coarse: LinearElastic
    fine: LinearElastic
    problem: ArlequinProblem
    system: Any
    u0c: np.ndarray
    v0c: np.ndarray
    c: float


def build_wave(config: WaveConfig) -> WaveSetup:
    """The meshes, models, problem and initial pulse of a (checked) configuration."""
    ratio = int(config.ratio)
    lay = wave_layout(config.pulse_width, config.gluing_width)
    n_c = round(lay["length"])
    n_patch = round(lay["length"] - lay["x_patch"])
    mat = IsotropicElastic(YOUNG, 0.0, DENSITY)
    c = math.sqrt(YOUNG / DENSITY)
    coarse_mesh = skfem.MeshLine(np.linspace(0.0, n_c * H, n_c + 1))
    fine_mesh = skfem.MeshLine(np.linspace(lay["x_patch"] * H, n_c * H, n_patch * ratio + 1))
    cm = LinearElastic(coarse_mesh, mat, area=AREA)
    fm = LinearElastic(fine_mesh, mat, area=AREA)
    length = config.length
    patch = Patch(
        fm,
        gluing_width=config.gluing_width * H,
        weights=config.weights,
        coupling=config.coupling,
        mediator=config.mediator,
        epsilon=config.epsilon,
        length=None if length is None else float(length) * H,
    )
    problem = ArlequinProblem(cm, [patch])
    system = problem.system()
    xc = coarse_mesh.p[0]
    f, df = _pulse(xc / H, lay["a"], float(config.pulse_width))
    u0c = AMPLITUDE * f
    v0c = -c * AMPLITUDE * df / H
    return WaveSetup(lay, coarse_mesh, fine_mesh, cm, fm, problem, system, u0c, v0c, c)
