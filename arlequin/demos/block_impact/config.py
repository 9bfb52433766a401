"""The block impact's configuration (no subcommand: the tests and examples run it from Python)."""

from __future__ import annotations

from dataclasses import dataclass

from ..config import DemoConfig, option

__all__ = ["BlockImpactConfig"]


@dataclass(frozen=True)
class BlockImpactConfig(DemoConfig):
    """A block launched at v₀ onto a rigid plane or onto an identical block at rest (SI units);
    see :func:`~arlequin.demos.block_impact.run_block_impact`."""

    dim: int = option(2, "dimension (2: plane strain, 3)", "1", choices=(2, 3))
    target: str = option("plane", "what the block hits", "", choices=("plane", "block"))
    elements: int = option(20, "elements along the height", "1")
    velocity: float = option(1.0, "impact velocity v0", "m/s")
    young: float = option(210e9, "Young's modulus", "Pa")
    poisson: float = option(0.3, "Poisson's ratio", "1")
    density: float = option(7850.0, "density", "kg/m^3")
    height: float = option(0.1, "block height H (impact direction)", "m")
    aspect: float = option(0.25, "width / height", "1")
    theta: float = option(0.5, "theta of the theta-scheme", "1")
    cfl: float = option(1.0, "dt = cfl h / c_d (dilatational speed)", "1")
    gap_steps: float = option(2.3, "initial gap, in steps v0 dt", "1")
    t_end: float | None = option(None, "end time", "s", default_help="gap/v0 + 3 H/c")
    integrator: str = option("theta", "time scheme (theta, or central differences)", "",
                             choices=("theta", "explicit"))  # fmt: skip

    def check(self) -> None:
        """Refuse a dimension other than 2 or 3 and an unknown target."""
        if self.dim not in (2, 3):
            raise ValueError(f"dim must be 2 or 3, got {self.dim}")
        if self.target not in ("plane", "block"):
            raise ValueError(f"target must be 'plane' or 'block', got {self.target!r}")
