"""The ball impact's Python entry point, :func:`run_ball_impact`: its keywords make a
:class:`~arlequin.demos.ball_impact.config.BallImpactConfig` (every input checked), which runs.
SI units; see :mod:`arlequin.demos.ball_impact`.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from ...models import IsotropicElastic, J2Material
from .config import BallImpactConfig
from .result import BallImpactResult

__all__ = ["run_ball_impact"]


def run_ball_impact(
    regime: str = "elastic",
    model: str = "arlequin",
    velocity: float | None = None,
    ball_radius: float = 0.01,
    block_radius: float = 0.1,
    block_height: float = 0.1,
    ball_material: IsotropicElastic | None = None,
    block_material: IsotropicElastic | J2Material | None = None,
    patch_size: float | None = None,
    block_patch_size: float | None = None,
    fine_size: float | None = None,
    coarse_size: float | None = None,
    friction: float = 0.0,
    rigid_wall: bool = False,
    coarse_step_ratio: int | None = None,
    t_end: float | None = None,
    adaptive: bool = False,
    adapt_threshold: float = 0.8,
    adapt_buffer: int = 1,
    adapt_every: int = 50,
    max_patch_fraction: float = 0.5,
    out: str | Path | None = None,
    progress: Callable[[float], None] | None = None,
    check_only: bool = False,
) -> BallImpactResult | None:
    """Run the ball impact (:mod:`arlequin.demos.ball_impact`).

    Parameters
    ----------
    regime : {"elastic", "plastic"}
    model : {"arlequin", "mono", "mono-zoned", "graded"}
        See :class:`~arlequin.demos.ball_impact.setup.ImpactBodies`.
    velocity : float, optional
        v0 (m/s); default 1 (elastic), 10 (plastic).
    ball_radius, block_radius, block_height : float
        R, R_B, H_B (m).
    ball_material : IsotropicElastic, optional
        Default steel (210 GPa, 0.3, 7850 kg/m³).
    block_material : IsotropicElastic or J2Material, optional
        Default steel (elastic regime) or :data:`~arlequin.demos.ball_impact.COPPER`
        (plastic).
    patch_size : float, optional
        Radius of the patches around the contact point (m), below R/2; default 0.2 R
        (elastic), 0.4 R (plastic).
    block_patch_size : float, optional
        Radius of the block's patch (m), if larger (the plastic zone's extent); default
        ``patch_size`` (elastic), 0.8 R (plastic; at most half the block's size).
    fine_size, coarse_size : float, optional
        Cell sizes (m) of the patches and of the coarse models at the contact; default
        coarse π R/120 (the ball's O-grid n = 30) and fine the largest power-of-two refinement
        of it with 10 cells across Hertz's contact radius (elastic) or coarse/2 (plastic). The
        coarse size is rounded to the O-grid, the fine one to a power-of-two refinement of it.
    friction : float
        Coulomb coefficient μ between the bodies (0: frictionless).
    rigid_wall : bool
        The ball against the rigid plane z = 0 (no block).
    coarse_step_ratio : int, optional
        M > 1: the coarse models' forces once every m ≤ M steps, the largest m that keeps them
        stable (``"explicit-mts"``, :class:`~arlequin.solvers.SubcycledCentralDifference`
        with its resonance bound off and a 1% energy check), Arlequin only. 1: one step for
        every model. Default: :data:`~arlequin.demos.ball_impact.DEFAULT_STEP_RATIO` (2) for
        ``arlequin``, 1 for the single-mesh models; larger ratios can resonate with the
        patches (the energy check then stops the run: the rigid-wall default at M = 8 did).
    t_end : float, optional
        Simulated time (s); default 1.4 × Hertz's duration (elastic) or 1.5 π √(m/k) with
        k = 6π R σ_y, the stiffness of a fully plastic contact at a mean pressure 3 σ_y
        (plastic).
    adaptive, adapt_threshold, adapt_buffer, adapt_every, max_patch_fraction
        The block's J2 patch adapts (plastic regime, :mod:`arlequin.adapt`): a seed of radius
        ``patch_size`` grows where the coarse block's von Mises stress reaches β σy or the
        plastic zone nears the band (plus rings ≥ 0 of coarse cells), checked every N ≥ 1
        steps; beyond F in (0, 1] of the block the run stops (``PatchLimitError``).
    out : path, optional
        Results folder.
    progress : callable, optional
        ``progress(fraction)`` of the simulated time.
    check_only : bool
        Deprecated: check every input and return None (making a
        :class:`~arlequin.demos.ball_impact.config.BallImpactConfig` does the same).

    Returns
    -------
    BallImpactResult
    """
    config = BallImpactConfig(
        regime=regime, model=model, velocity=velocity, ball_radius=ball_radius,
        block_radius=block_radius, block_height=block_height, ball_material=ball_material,
        block_material=block_material, patch_size=patch_size,
        block_patch_size=block_patch_size, fine_size=fine_size, coarse_size=coarse_size,
        friction=friction, rigid_wall=rigid_wall, coarse_step_ratio=coarse_step_ratio,
        t_end=t_end, adaptive=adaptive, adapt_threshold=adapt_threshold,
        adapt_buffer=adapt_buffer, adapt_every=adapt_every,
        max_patch_fraction=max_patch_fraction,
    )  # fmt: skip
    if check_only:
        return None
    return config.run(out=out, progress=progress)
