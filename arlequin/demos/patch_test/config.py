"""The patch test's configuration (``arlequin patch-test``): one field a parameter."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

from ..config import DemoConfig, check_choice, option

__all__ = ["DIMS", "LAYOUTS", "PatchTestConfig"]

#: Dimensions of the patch test (``"axi"``: axisymmetric).
DIMS = ("1", "2", "3", "axi")
#: Patch layouts of :func:`~arlequin.demos.patch_test.run_patch_test`.
LAYOUTS = ("random", "strip", "square")


def _positive_int(name: str, value: Any) -> None:
    if isinstance(value, bool) or int(value) != value or value < 1:
        raise ValueError(f"{name} must be a positive integer, got {name}={value}")


@dataclass(frozen=True)
class PatchTestConfig(DemoConfig):
    """A uniform-stress patch test: a random (or grid) coarse + patch configuration.

    Every value is a choice or a count; ``dim`` may be given as an integer from Python (it is
    kept as its string).
    """

    command: ClassVar[str] = "patch-test"
    title: ClassVar[str] = "uniform-stress patch test of a random coarse + patch configuration"
    description: ClassVar[str] = (
        "Build a random configuration from the seed, solve the uniform-stress problem and report "
        "max_error and exact_residual (fractions)."
    )
    switches: ClassVar[tuple[str, ...]] = ("json", "out")

    dim: str = option("2", "dimension (axi: axisymmetric)", "", choices=DIMS)
    coupling: str = option("H1", "coupling operator", "", choices=("L2", "H1"))
    weights: str = option("ramp", "partition weights in the gluing band", "",
                          choices=("constant", "ramp"))  # fmt: skip
    mediator: str = option("coarse", "mediator space", "", choices=("coarse", "fine"))
    mesh: str = option("nested", "patch mesh nested in the coarse one or not", "",
                       choices=("nested", "nonnested"))  # fmt: skip
    seed: int = option(0, "seed of the random configuration (>= 0)", "1")
    layout: str = option(
        "random",
        "random configuration, a strip spanning the domain, or an interior square (2D)",
        "",
        choices=LAYOUTS,
    )
    ratio: int = option(4, "coarse/fine size ratio (strip, square)", "1")
    band_cells: int = option(1, "gluing band in coarse cells (strip, square)", "coarse cells")

    def __post_init__(self) -> None:
        object.__setattr__(self, "dim", str(self.dim))  # 2 from Python is "2"
        super().__post_init__()

    def check(self) -> None:
        """Refuse an unknown choice, a negative seed and, for the grid layouts, a 3D or
        axisymmetric dimension or a non-positive ratio or band."""
        if self.dim not in DIMS:
            raise ValueError(f"dim must be one of {DIMS}, got {self.dim!r}")
        if self.mesh not in ("nested", "nonnested"):
            raise ValueError(f"mesh must be 'nested' or 'nonnested', got {self.mesh!r}")
        if self.layout not in LAYOUTS:
            raise ValueError(f"layout must be one of {LAYOUTS}, got {self.layout!r}")
        seed = self.seed
        if isinstance(seed, bool) or int(seed) != seed or seed < 0:
            raise ValueError(f"seed must be a non-negative integer, got seed={seed}")
        check_choice("coupling", self.coupling, ("L2", "H1"))
        if isinstance(self.weights, str):  # from Python, also a PartitionWeights
            check_choice("weights", self.weights, ("constant", "ramp"))
        check_choice("mediator", self.mediator, ("coarse", "fine"))
        if self.layout != "random":
            if self.dim != "2":
                raise ValueError(
                    f"layout={self.layout!r} is a 2D plane-strain layout, got dim={self.dim!r}"
                )
            _positive_int("ratio", self.ratio)
            _positive_int("band_cells", self.band_cells)
