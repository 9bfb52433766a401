"""The configuration of the pressure-vessel demo: the single source of its options."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

from ..adaptive_options import (
    adapt_buffer_option,
    adapt_every_option,
    adapt_threshold_option,
    adaptive_option,
    check_adaptive_options,
    max_patch_fraction_option,
)
from ..config import DemoConfig, check_choice, check_positive, check_range, option

__all__ = ["MATERIALS", "MODELS", "SHAPES", "PressureVesselConfig"]

SHAPES = ("sphere", "cylinder")
MODELS = ("arlequin", "mono")
MATERIALS = ("small-strain", "finite-strain")

#: Default sizes: 8 coarse cells across the wall b − a; fine cells of at most 1/64 of the
#: smaller of the wall and the bore radius a (the stress falls as 1/r³ from the bore, over a
#: length of a: with 1/64 of b − a the bore's stress reads +1.3% high at b/a = 5, +0.1% with
#: 1/64 of a), the coarse size halved a whole number of times (3 levels at b/a = 2, 5 at
#: b/a = 5); the patch from the bore to 85% of the wall.
COARSE_CELLS, FINE_CELLS, PATCH_FRACTION = 8, 64, 0.85


@dataclass(frozen=True)
class PressureVesselConfig(DemoConfig):
    """A thick sphere (axisymmetric) or cylinder (plane strain, a quarter) under internal
    pressure, J2 plasticity (see :mod:`arlequin.demos.pressure_vessel`)."""

    command: ClassVar[str] = "pressure-vessel"
    switches: ClassVar[tuple[str, ...]] = ("json", "quiet", "resume", "out")
    title: ClassVar[str] = (
        "thick sphere or cylinder under internal pressure, J2 plasticity, against Hill's "
        "solutions (quasi-static, Newton)"
    )
    description: ClassVar[str] = (
        "A thick sphere (axisymmetric, or its eighth in hexahedra with --dim 3) or cylinder "
        "(plane strain, a quarter) of inner radius "
        "A and outer radius B, pressurised at the bore (--pressure) or driven by the bore's "
        "radial displacement (--inner-displacement), loaded in --steps equal steps solved by "
        "Newton with consistent tangents. --model arlequin: a coarse linear-elastic model of "
        "the whole wall and a refined J2 patch from the bore to --patch-outer; --model mono: "
        "one fine J2 mesh. Against Hill's exact solutions (sphere) and the limit loads. SI "
        "units."
    )

    shape: str = option("sphere", "the vessel", "", choices=SHAPES)
    dim: int = option(
        2, "2: the axisymmetric sphere or plane-strain cylinder; 3: the sphere's eighth in "
        "hexahedra", "1", choices=(2, 3),
    )  # fmt: skip
    model: str = option("arlequin", "coarse elastic + J2 patch, or one fine mesh", "",
                        choices=MODELS)  # fmt: skip
    inner: float = option(0.1, "inner radius a", "m", metavar="A")
    outer: float = option(0.2, "outer radius b", "m", metavar="B")
    young: float = option(210e9, "Young's modulus E", "Pa", metavar="E")
    poisson: float = option(0.3, "Poisson's ratio", "1", metavar="NU")
    yield_stress: float = option(240e6, "yield stress", "Pa", flag="--yield", metavar="SY")
    hardening: float = option(0.0, "linear isotropic hardening modulus (0: perfectly plastic)",
                              "Pa", metavar="H")  # fmt: skip
    material: str = option("small-strain", "J2 at small strain or at finite strain", "",
                           choices=MATERIALS)  # fmt: skip
    pressure: float | None = option(
        None, "final internal pressure", "Pa", metavar="P", exclusive="load",
        default_help="3e8 Pa for the sphere, 1.8e8 Pa for the cylinder, unless "
        "--inner-displacement",
    )  # fmt: skip
    inner_displacement: float | None = option(
        None, "final radial displacement of the bore, instead of a pressure", "m", metavar="U",
        exclusive="load",
    )  # fmt: skip
    steps: int = option(10, "equal load steps (cut and grown back where Newton needs)", "1",
                        metavar="N")  # fmt: skip
    patch_outer: float | None = option(
        None, "outer radius of the patch (rounded to a coarse ring)", "m", metavar="RP",
        default_help="a + 0.85 (b - a)",
    )  # fmt: skip
    fine_size: float | None = option(None, "radial size of the fine cells", "m", metavar="H",
                                     default_help="min(a, b - a)/64 (coarse/2^k)")  # fmt: skip
    coarse_size: float | None = option(None, "radial size of the coarse cells", "m",
                                       metavar="H", default_help="(b - a)/8")  # fmt: skip
    adaptive: bool = adaptive_option(
        "a seed of one coarse ring at the bore that grows where the material nears yield "
        "(--model arlequin)"
    )
    adapt_threshold: float = adapt_threshold_option(0.8)
    adapt_buffer: int = adapt_buffer_option()
    adapt_every: int = adapt_every_option(1, "every N load steps (the yield check every step)")
    max_patch_fraction: float = max_patch_fraction_option(0.95, "wall")

    # -- resolved values ---------------------------------------------------------------------
    @property
    def load_pressure(self) -> float | None:
        """The final pressure (Pa), None under a prescribed bore displacement."""
        if self.inner_displacement is not None:
            return None
        if self.pressure is not None:
            return self.pressure
        # the sphere's default (Hill's 300 MPa state); the cylinder's limit load is 192 MPa at
        # the default radii, so its default stays below it
        return 3e8 if self.shape == "sphere" else 1.8e8

    @property
    def thickness(self) -> float:
        return self.outer - self.inner

    @property
    def coarse(self) -> float:
        """The coarse cells' radial size (m)."""
        return self.coarse_size if self.coarse_size is not None else self.thickness / COARSE_CELLS

    @property
    def fine(self) -> float:
        """The fine cells' radial size (m)."""
        if self.fine_size is not None:
            return self.fine_size
        target = min(self.thickness, self.inner) / FINE_CELLS
        return self.coarse / 2.0 ** math.ceil(math.log2(self.coarse / target) - 1e-9)

    @property
    def patch_radius(self) -> float:
        """The requested outer radius of the patch (m): one coarse ring when adaptive."""
        if self.adaptive:
            return self.inner + self.coarse
        if self.patch_outer is not None:
            return self.patch_outer
        return self.inner + PATCH_FRACTION * self.thickness

    # -- checks ------------------------------------------------------------------------------
    def check(self) -> None:
        check_choice("shape", self.shape, SHAPES)
        check_choice("model", self.model, MODELS)
        check_choice("material", self.material, MATERIALS)
        check_choice("dim", self.dim, (2, 3))
        if self.dim == 3 and self.shape != "sphere":
            raise ValueError(f"dim=3 models the sphere's eighth only, got shape={self.shape!r}")
        check_positive("inner", self.inner, "m")
        check_positive("outer", self.outer, "m")
        if not self.inner < self.outer:
            raise ValueError(
                f"the inner radius must be below the outer one, got inner={self.inner} m >= "
                f"outer={self.outer} m"
            )
        check_positive("young", self.young, "Pa")
        check_range("poisson", self.poisson, -1.0, 0.5, closed="()")
        check_positive("yield_stress", self.yield_stress, "Pa")
        check_positive("hardening", self.hardening, "Pa", allow_zero=True)
        if self.pressure is not None and self.inner_displacement is not None:
            raise ValueError("give one of pressure and inner_displacement, got both")
        check_positive("pressure", self.load_pressure, "Pa", allow_none=True)
        check_positive("inner_displacement", self.inner_displacement, "m", allow_none=True)
        if isinstance(self.steps, bool) or int(self.steps) != self.steps or self.steps < 1:
            raise ValueError(f"steps must be an integer >= 1, got steps={self.steps!r}")
        check_positive("coarse_size", self.coarse_size, "m", allow_none=True)
        check_positive("fine_size", self.fine_size, "m", allow_none=True)
        if self.fine > self.coarse:
            raise ValueError(f"fine_size={self.fine} m must not exceed coarse_size={self.coarse} m")
        if self.coarse > self.thickness:
            raise ValueError(f"coarse_size={self.coarse} m exceeds the wall b - a = "
                             f"{self.thickness} m")  # fmt: skip
        if self.model == "arlequin" and not (
            self.inner < self.patch_radius < self.outer - 0.5 * self.coarse
        ):
            raise ValueError(
                f"patch_outer={self.patch_radius} m must lie inside the wall, between the bore "
                f"a={self.inner} m and b - coarse_size/2 = {self.outer - 0.5 * self.coarse} m "
                "(a coarse ring must stay outside the patch)"
            )
        if not math.isclose(math.log2(self.coarse / self.fine) % 1.0, 0.0, abs_tol=1e-6) and not (
            math.isclose(math.log2(self.coarse / self.fine) % 1.0, 1.0, abs_tol=1e-6)
        ):
            raise ValueError(
                f"coarse_size/fine_size = {self.coarse / self.fine:.6g} must be a power of 2 "
                "(the patch is a nested refinement of the coarse cells)"
            )

        self._check_adaptive()

    def _check_adaptive(self) -> None:
        check_adaptive_options(self)
        if self.adaptive and self.model != "arlequin":
            raise ValueError(f"adaptive needs model='arlequin', got model={self.model!r}")
        if self.adaptive and self.patch_outer is not None:
            raise ValueError("adaptive starts from one ring at the bore: give no patch_outer, got "
                             f"patch_outer={self.patch_outer}")  # fmt: skip

    def inputs(self) -> dict[str, Any]:
        """The parameters as recorded, the defaults the run resolved filled in (the pressure,
        the patch's radius, the cell sizes)."""
        out = super().inputs()
        out.update(pressure=self.load_pressure, patch_outer=self.patch_radius,
                   fine_size=self.fine, coarse_size=self.coarse)  # fmt: skip
        return out

    # -- running -----------------------------------------------------------------------------
    def progress_scale(self) -> tuple[float, str, float, str]:
        """The bar shows the load factor in percent."""
        return 100.0, "% load", 100.0, self.command

    @classmethod
    def resume_progress_scale(cls, out: str) -> tuple[float, str, float, str]:
        """The bar of a resumed run (as the run's)."""
        return 100.0, "% load", 100.0, cls.command
