"""The block impact's Python entry point (its signature kept): it builds the checked
:class:`BlockImpactConfig` from its keyword arguments and runs it."""

from __future__ import annotations

from .config import BlockImpactConfig
from .result import BlockImpactResult
from .run import run_config

__all__ = ["run_block_impact"]


def run_block_impact(
    dim: int = 2,
    target: str = "plane",
    elements: int = 20,
    velocity: float = 1.0,
    young: float = 210e9,
    poisson: float = 0.3,
    density: float = 7850.0,
    height: float = 0.1,
    aspect: float = 0.25,
    theta: float = 0.5,
    cfl: float = 1.0,
    gap_steps: float = 2.3,
    t_end: float | None = None,
    integrator: str = "theta",
) -> BlockImpactResult:
    """A block launched at v₀ onto a rigid plane or onto an identical block at rest, no gravity.

    The block (height H in the impact direction, the last coordinate; width aspect·H) has
    ``elements`` elements along H and ``round(aspect·elements)`` (≥ 2) across; plane strain in
    2D (MeshQuad), hexahedra in 3D. It starts at a gap of ``gap_steps`` v₀Δt (so that the
    activation falls inside a step) and moves at −v₀. Δt = cfl·h/c_d (dilatational speed).

    Returns
    -------
    BlockImpactResult
    """
    config = BlockImpactConfig(dim=dim, target=target, elements=elements, velocity=velocity,
                               young=young, poisson=poisson, density=density, height=height,
                               aspect=aspect, theta=theta, cfl=cfl, gap_steps=gap_steps,
                               t_end=t_end, integrator=integrator)  # fmt: skip
    return run_config(config)
