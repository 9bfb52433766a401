"""The configuration of the plate-with-hole demo: the single source of its options."""

from __future__ import annotations

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

__all__ = ["BLOCK", "DEFAULT_LOAD", "MATERIALS", "MAX_LEVELS", "MODELS", "PlateWithHoleConfig"]

MODELS = ("arlequin", "mono", "graded")
MATERIALS = ("small-strain", "finite-strain")
#: More levels than this would make the fine meshes of millions of cells.
MAX_LEVELS = 5
#: The side of the square around the hole that holds its rings, in hole radii.
BLOCK = 2.0
#: The default remote traction S (Pa): the plastic zone then reaches about 2.3 hole radii
#: from the hole's centre (see :mod:`arlequin.demos.plate_with_hole`).
DEFAULT_LOAD = 195e6


def _count(name: str, value: Any, low: int, high: int | None = None) -> None:
    ok = not isinstance(value, bool) and isinstance(value, (int, float)) and int(value) == value
    ok = ok and value >= low and (high is None or value <= high)
    if not ok:
        span = f">= {low}" if high is None else f"in [{low}, {high}]"
        raise ValueError(f"{name} must be an integer {span}, got {name}={value!r}")


@dataclass(frozen=True)
class PlateWithHoleConfig(DemoConfig):
    """A quarter of a plane-strain plate with a hole pulled past first yield, J2 plasticity
    (see :mod:`arlequin.demos.plate_with_hole`)."""

    command: ClassVar[str] = "plate-with-hole"
    title: ClassVar[str] = (
        "plate with a hole pulled past first yield: coarse elastic plate + J2 patch around the "
        "hole, against one fine mesh and a graded mesh (quasi-static, Newton)"
    )
    description: ClassVar[str] = (
        "A quarter of a plane-strain plate 2W x 2W with a hole of radius A (symmetry on x = 0 "
        "and y = 0) pulled by a uniform traction --load on x = W, loaded to first yield and "
        "then in --steps equal steps solved by Newton with consistent tangents. --model "
        "arlequin: a coarse linear-elastic model of the plate (rings around the hole in "
        "[0, 2a]^2, a grid of 2a / n_theta cells beyond) and a J2 patch of the coarse cells in "
        "[0, RP]^2 refined --levels times; --model mono: the whole coarse mesh refined "
        "--levels times, J2 everywhere; --model graded: one conforming mesh, the patch's cells "
        "(J2) and beyond them the grid refined along the patch only (elastic). SI units."
    )

    model: str = option("arlequin", "coarse elastic + J2 patch, one fine mesh, or a graded mesh",
                        "", choices=MODELS)  # fmt: skip
    material: str = option("small-strain", "J2 at small strain or at finite strain", "",
                           choices=MATERIALS)  # fmt: skip
    load: float = option(DEFAULT_LOAD, "final remote traction S on x = W", "Pa", metavar="S")
    steps: int = option(10, "equal load steps from first yield to S (cut where Newton needs)",
                        "1", metavar="N")  # fmt: skip
    levels: int = option(3, "refinement levels of the patch (and of the fine meshes)", "1",
                         metavar="L")  # fmt: skip
    radius: float = option(0.01, "hole radius a", "m", metavar="A")
    half_width: float | None = option(None, "the plate's half width W (>= 10a)", "m",
                                      metavar="W", default_help="10a")  # fmt: skip
    young: float = option(210e9, "Young's modulus E", "Pa", metavar="E")
    poisson: float = option(0.3, "Poisson's ratio", "1", metavar="NU")
    yield_stress: float = option(240e6, "yield stress", "Pa", flag="--yield", metavar="SY")
    hardening: float = option(0.0, "linear isotropic hardening modulus (0: perfectly plastic)",
                              "Pa", metavar="H")  # fmt: skip
    n_theta: int = option(4, "coarse cells along each 45 degrees of the hole (and along each "
                          "side of the square [0, 2a]^2 around it: cells of 2a / N beyond)", "1",
                          metavar="N")  # fmt: skip
    n_radial: int = option(4, "coarse rings from the hole to the square [0, 2a]^2 (geometric)",
                           "1", metavar="N")  # fmt: skip
    gluing_rings: int = option(1, "the gluing band: the patch's outermost coarse cell layers",
                               "1", metavar="N")  # fmt: skip
    edge_weight: float = option(
        0.75, "alpha_coarse on the patch's outer edge, the ramp's start (1: the patch carries "
        "nothing there and its free edge yields spuriously at the square's corners)", "1",
        metavar="W0",
    )  # fmt: skip
    coupling: str = option("L2", "the mediator's coupling (H1 glues the band's gradients too)",
                           "", choices=("L2", "H1"))  # fmt: skip
    patch_radius: float | None = option(
        None, "the patch: the coarse cells within the square [0, RP]^2 (RP snapped down to a "
        "grid line)", "m", metavar="RP", default_help="3.5a",
    )  # fmt: skip
    adaptive: bool = adaptive_option(
        "a seed of the coarse ring at the hole that grows where the material nears yield "
        "(--model arlequin)"
    )
    # 0.9, not the library's 0.8: at the default load the elastic ligament above the hole
    # carries 0.8 σy (net section, plane strain), and β = 0.8 grows the patch along all of it
    adapt_threshold: float = adapt_threshold_option(0.9)
    adapt_buffer: int = adapt_buffer_option()
    adapt_every: int = adapt_every_option(1, "every N load steps (the yield check every step)")
    max_patch_fraction: float = max_patch_fraction_option(0.5, "plate")

    # -- resolved values ---------------------------------------------------------------------
    @property
    def width(self) -> float:
        """W (m): the quarter plate is [0, W]²."""
        return 10.0 * self.radius if self.half_width is None else self.half_width

    @property
    def patch_extent(self) -> float:
        """The requested patch half side (m): the patch holds the coarse cells in [0, RP]²."""
        return 3.5 * self.radius if self.patch_radius is None else self.patch_radius

    # -- checks ------------------------------------------------------------------------------
    def check(self) -> None:
        check_choice("model", self.model, MODELS)
        check_choice("material", self.material, MATERIALS)
        check_choice("coupling", self.coupling, ("L2", "H1"))
        check_positive("load", self.load, "Pa")
        _count("steps", self.steps, 1)
        _count("levels", self.levels, 0, MAX_LEVELS)
        check_positive("radius", self.radius, "m")
        check_positive("half_width", self.half_width, "m", allow_none=True)
        if self.width < 10.0 * self.radius * (1.0 - 1e-12):
            raise ValueError(
                f"half_width={self.width} m must be at least 10 hole radii ({10 * self.radius} "
                "m): the plate is at least 20 hole radii across, its far field uniform"
            )
        check_positive("young", self.young, "Pa")
        check_range("poisson", self.poisson, -1.0, 0.5, closed="()")
        check_positive("yield_stress", self.yield_stress, "Pa")
        check_positive("hardening", self.hardening, "Pa", allow_zero=True)
        _count("n_theta", self.n_theta, 1)
        _count("n_radial", self.n_radial, 1)
        check_positive("patch_radius", self.patch_radius, "m", allow_none=True)
        check_range("edge_weight", self.edge_weight, 1e-3, 1.0, closed="(]")
        _count("gluing_rings", self.gluing_rings, 1)
        self._check_adaptive()
        if self.model != "mono" and not self.adaptive:
            r, h = self.patch_square, self.coarse_size
            if not self.block + self.gluing_rings * h <= r * (1.0 + 1e-12) < self.width:
                raise ValueError(
                    f"patch_radius={self.patch_extent} m must hold the hole's rings (to "
                    f"{self.block:.4g} m) and the gluing band's {self.gluing_rings} cell layers "
                    f"of {h:.4g} m beyond them, and leave cells outside (below {self.width:.4g} m)"
                )
        if self.material == "finite-strain":
            from ...models import FiniteStrainJ2

            if not callable(getattr(FiniteStrainJ2, "tangent", None)):
                raise ValueError(
                    "material='finite-strain' needs the consistent tangent of FiniteStrainJ2, "
                    "which this version does not have: use material='small-strain'"
                )

    def _check_adaptive(self) -> None:
        check_adaptive_options(self)
        if self.adaptive and self.model != "arlequin":
            raise ValueError(f"adaptive needs model='arlequin', got model={self.model!r}")
        if self.adaptive and self.patch_radius is not None:
            raise ValueError("adaptive starts from the coarse ring at the hole: give no "
                             f"patch_radius, got patch_radius={self.patch_radius}")  # fmt: skip

    @property
    def block(self) -> float:
        """The side (m) of the square [0, block]² holding the rings around the hole: 2a."""
        return BLOCK * self.radius

    @property
    def coarse_size(self) -> float:
        """The coarse cells' size (m) away from the hole: block / n_theta."""
        return self.block / self.n_theta

    @property
    def patch_square(self) -> float:
        """The patch's half side R (m): the largest grid line within ``patch_extent`` (the
        patch is the coarse cells in [0, R]², the hole's rings included)."""
        from .meshes import plate_lines

        lines = plate_lines(self.radius, self.n_theta, self.width, self.block)
        inside = lines[lines <= self.patch_extent * (1.0 + 1e-12)]
        return float(inside[-1])

    def progress_scale(self) -> tuple[float, str, float, str]:
        return 100.0, "%", 100.0, f"{self.command} ({self.model})"

    # -- running -----------------------------------------------------------------------------
