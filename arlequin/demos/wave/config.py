"""The 1D wave demo's configuration (``arlequin wave``): one field a parameter."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

from ...solvers import get_integrator
from ...solvers.dynamics.controllers import check_step
from ..config import DemoConfig, option

__all__ = ["INTEGRATORS", "WaveConfig"]

#: CLI integrator names -> registry names
INTEGRATORS = {"explicit": "explicit", "implicit": "newmark"}


@dataclass(frozen=True)
class WaveConfig(DemoConfig):
    """A smooth pulse through an Arlequin overlap (lengths in coarse elements, h = 1 cm); see
    :mod:`arlequin.demos.wave`."""

    command: ClassVar[str] = "wave"
    title: ClassVar[str] = (
        "1D elastic wave through an Arlequin overlap: reflected and transmitted energy"
    )
    description: ClassVar[str] = (
        "A smooth right-going pulse in a coarse bar meets a refined patch glued at its left end; "
        "the reflection is measured against a single coarse-mesh run with the same integrator "
        "and time step (fractions of the incident energy)."
    )
    switches: ClassVar[tuple[str, ...]] = ("plot", "json", "quiet", "out")

    ratio: int = option(4, "coarse/fine element size ratio", "1")
    pulse_width: float = option(10.0, "pulse support width, in coarse elements",
                                "coarse elements")  # fmt: skip
    gluing_width: float = option(10.0, "gluing band width, in coarse elements (snapped to fine "
                                 "cells)", "coarse elements")  # fmt: skip
    coupling: str = option("H1", "coupling operator", "", choices=("L2", "H1"))
    mediator: str = option("coarse", "mediator space", "", choices=("coarse", "fine"))
    weights: str = option("ramp", "partition weights in the gluing band", "",
                          choices=("constant", "ramp"))  # fmt: skip
    integrator: str = option("explicit", "time scheme (implicit: trapezoidal Newmark, "
                             "consistent mass)", "", choices=tuple(INTEGRATORS))  # fmt: skip
    dt: float | None = option(None, "time step", "s",
                              default_help="the coupled explicit stable step")  # fmt: skip
    epsilon: float = option(1e-3, "floor of alpha_coarse in the patch's free zone", "1")
    length: float | None = option(None, "H1 coupling length, in coarse elements",
                                  "coarse elements",
                                  default_help="one coarse element")  # fmt: skip

    def check(self) -> None:
        """Refuse a ratio below 1, non-positive or non-finite widths, an unknown integrator and
        a non-positive or non-finite time step."""
        ratio = int(self.ratio)
        if ratio < 1:
            raise ValueError(f"mesh ratio must be a positive integer, got ratio={ratio}")
        if not self.pulse_width > 0 or not self.gluing_width > 0:
            raise ValueError(
                f"pulse and gluing widths must be positive, got pulse_width={self.pulse_width}, "
                f"gluing_width={self.gluing_width}"
            )
        get_integrator(self.registry_name)  # an unknown scheme, by name
        if self.dt is not None:
            check_step(self.dt, "time step dt (s)")
        finite = {"pulse_width": self.pulse_width, "gluing_width": self.gluing_width,
                  "epsilon": self.epsilon}  # fmt: skip
        for what, value in finite.items():
            if not math.isfinite(float(value)):
                raise ValueError(f"{what} must be finite, got {what}={value}")

    @property
    def registry_name(self) -> str:
        """The integrator's name in :func:`arlequin.solvers.get_integrator`."""
        return INTEGRATORS.get(self.integrator, self.integrator)

    def progress_scale(self) -> tuple[float, str, float, str]:
        """Percent of the coupled run's steps."""
        return 100.0, "%", 100.0, "coupled run"

    def plot(self, result: Any, path: str) -> None:
        """The snapshot against the single-mesh reference, and the energy (PNG)."""
        from .report import plot_wave

        plot_wave(result, path)
