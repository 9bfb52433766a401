"""The two-bar impact's configuration (``arlequin two-bars``) and the input checks it shares
with the bar on a rigid wall."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ..config import DemoConfig, option

__all__ = ["METHODS", "TwoBarsConfig", "check_common"]

#: Methods of :func:`~arlequin.demos.two_bars.run_two_bars` (``"both"``: level set, then Newmark).
METHODS = ("levelset", "newmark", "both")


def check_common(young, density, cfl, elements, t_end, theta, **finite) -> None:
    """Refuse, before any work, the inputs that would end in a division by zero, a NaN or a
    meaningless run, naming the quantity and its value."""
    for name, value in {"young": young, "density": density, "cfl": cfl, **finite}.items():
        if isinstance(value, bool) or not isinstance(value, (int, float, np.number)):
            raise ValueError(f"{name} must be a number, got {value!r}")
        if not math.isfinite(value):
            raise ValueError(f"{name} must be finite, got {name}={value}")
    for name, value in {"young": young, "density": density, "cfl": cfl}.items():
        if not value > 0.0:
            raise ValueError(f"{name} must be positive, got {name}={value}")
    for name in ("length", "length1", "length2"):
        if name in finite and not finite[name] > 0.0:
            raise ValueError(f"bar lengths must be positive, got {name}={finite[name]}")
    if isinstance(elements, bool) or int(elements) != elements or elements < 1:
        raise ValueError(f"elements must be a positive integer, got elements={elements}")
    if t_end is not None and not (math.isfinite(t_end) and t_end > 0.0):
        raise ValueError(f"t_end must be positive and finite (s), got t_end={t_end}")
    if not 0.5 <= theta <= 1.0:
        raise ValueError(f"theta must lie in [1/2, 1], got theta={theta}")


def check_schemes(method: str, newmark: str, integrator: str) -> None:
    """Refuse a time scheme the method would use and does not know (the level-set method's
    ``integrator``, the baseline's ``newmark``)."""
    if method in ("levelset", "both") and integrator not in ("theta", "explicit"):
        raise ValueError(f"integrator must be 'theta' or 'explicit', got {integrator!r}")
    if method in ("newmark", "both") and newmark not in ("trapezoidal", "hht"):
        raise ValueError(f"newmark must be 'trapezoidal' or 'hht', got {newmark!r}")


@dataclass(frozen=True)
class TwoBarsConfig(DemoConfig):
    """Two elastic bars touching at t = 0, bar 1 approaching (SI units); see
    :mod:`arlequin.demos.two_bars`."""

    command: ClassVar[str] = "two-bars"
    title: ClassVar[str] = (
        "impact of two elastic bars: level-set contact vs Newmark + Signorini vs exact"
    )
    description: ClassVar[str] = (
        "Bar 1 at --velocity hits bar 2 (touching at t = 0); SI units. Reports the interface "
        "velocity, contact pressure (-lambda_v), energies and contact work."
    )
    switches: ClassVar[tuple[str, ...]] = ("plot", "json", "quiet", "out")

    method: str = option("levelset", "contact method (both: level set, then the Newmark "
                         "baseline)", "", choices=METHODS)  # fmt: skip
    newmark: str = option("trapezoidal", "Newmark variant of the baseline (beta = 1/4, "
                          "gamma = 1/2, or HHT-alpha = -0.1)", "",
                          choices=("trapezoidal", "hht"))  # fmt: skip
    lengths: tuple[float, float] = option((1.0, 1.0), "bar lengths", "m", nargs=2,
                                          metavar=("L1", "L2"))  # fmt: skip
    young: float = option(210e9, "Young's modulus", "Pa", metavar="E")
    density: float = option(7850.0, "density", "kg/m^3", metavar="RHO")
    velocity: float = option(1.0, "bar 1 velocity", "m/s", metavar="V0")
    velocity2: float = option(0.0, "bar 2 velocity", "m/s", metavar="V2")
    elements: int = option(100, "elements per bar", "1", metavar="N")
    cfl: float = option(1.0, "dt = C h_min / c", "1", metavar="C")
    theta: float = option(0.5, "theta of the theta-scheme", "1", metavar="T")
    t_end: float | None = option(None, "end time", "s", metavar="T",
                                 default_help="3 max(L1, L2)/c")  # fmt: skip
    integrator: str = option("theta", "time scheme of the level-set method (the theta-scheme, "
                             "consistent mass, or central differences, lumped mass)", "",
                             choices=("theta", "explicit"))  # fmt: skip

    def __post_init__(self) -> None:
        if isinstance(self.lengths, list):  # [L1, L2] from Python or a study
            object.__setattr__(self, "lengths", tuple(self.lengths))
        super().__post_init__()

    def check(self) -> None:
        """Refuse an unknown method or scheme, a non-positive or non-finite material, step or
        length, theta outside [1/2, 1], and bars that do not approach."""
        if self.method not in METHODS:
            raise ValueError(f"method must be 'levelset', 'newmark' or 'both', got {self.method!r}")
        if len(self.lengths) != 2:
            raise ValueError(f"lengths must be two bar lengths (m), got lengths={self.lengths!r}")
        check_common(self.young, self.density, self.cfl, self.elements, self.t_end, self.theta,
                     velocity=self.velocity, velocity2=self.velocity2, length1=self.lengths[0],
                     length2=self.lengths[1])  # fmt: skip
        if not self.velocity > self.velocity2:
            raise ValueError(
                f"bar 1 must approach bar 2: velocity={self.velocity} <= velocity2={self.velocity2}"
            )
        check_schemes(self.method, self.newmark, self.integrator)

    def progress_scale(self) -> tuple[float, str, float, str]:
        """Percent of the simulated time (both runs of ``method="both"`` together)."""
        return 100.0, "%", 100.0, "two bars"

    def plot(self, result: Any, path: str) -> None:
        """Interface velocity and contact pressure against the exact solution (PNG)."""
        from .report import plot_two_bars

        plot_two_bars(result, path)
