"""The Python entry point of the sliding block: :func:`run_sliding_block` (keyword arguments ->
a :class:`~arlequin.demos.sliding_block.config.SlidingBlockConfig`, then its run)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from .config import DAMPING, SlidingBlockConfig
from .result import SlidingBlockResult

__all__ = ["run_sliding_block"]


def run_sliding_block(
    dim: int = 2,
    friction: float = 0.3,
    velocity: float | None = None,
    incline: float = 0.0,
    pressure: float | None = None,
    gravity: float | None = None,
    elements: int = 4,
    t_end: float | None = None,
    damping: float = DAMPING,
    ramp_time: float | None = None,
    young: float = 210e9,
    poisson: float = 0.3,
    density: float = 7850.0,
    height: float = 0.01,
    width: float = 0.02,
    out: str | Path | None = None,
    progress: Callable[[float], None] | None = None,
    check_only: bool = False,
) -> SlidingBlockResult | None:
    """Run the sliding block (see :mod:`arlequin.demos.sliding_block`).

    Parameters
    ----------
    dim : {2, 3}
        Plane strain (Q1) or 3D (Q1 hexahedra, a square base width × width).
    friction : float
        Coulomb coefficient μ (0: the frictionless model, no tangential rows).
    velocity : float or None
        Launch velocity V along x (m/s, ≥ 0): at t = 0 with the pressure loading; at the end of
        the ramp under gravity (x downslope; 0: the block stays at rest on the incline). None
        (the default, as on the command line): 1 m/s with the pressure loading, 0 under
        gravity.
    incline : float
        Incline θ of the plane (degrees), gravity loading.
    pressure, gravity : float, optional
        The loading: a top pressure p (Pa; default 1e5 Pa when neither is given) or gravity g
        (m/s²).
    elements : int
        Elements across the height (2 × as many along the width).
    t_end : float, optional
        Simulated time after the launch or the ramp (s); default 1.3 × the exact stop time when
        the block stops, else 200 H/c_d.
    damping : float
        Damping ratio ξ₁ at the first shear mode (0: undamped).
    ramp_time : float, optional
        Duration of the gravity ramp (s); default
        :data:`~arlequin.demos.sliding_block.config.RAMP_TRANSITS` H/c_d.
    young, poisson, density : float
        E (Pa), ν, ρ (kg/m³).
    height, width : float
        H and the base width (m).
    out : path, optional
        Results folder (see :mod:`arlequin.demos.sliding_block`).
    progress : callable, optional
        ``progress(fraction)`` of the simulated time, at each new percent.
    check_only : bool
        Deprecated: check every input and return None without running or writing anything
        (making a :class:`SlidingBlockConfig` does the same).

    Returns
    -------
    SlidingBlockResult
    """
    config = SlidingBlockConfig(
        dim=dim, friction=friction, velocity=velocity, incline=incline, pressure=pressure,
        gravity=gravity, elements=elements, t_end=t_end, damping=damping, ramp_time=ramp_time,
        young=young, poisson=poisson, density=density, height=height, width=width,
    )  # fmt: skip
    if check_only:
        return None
    return config.run(out=out, progress=progress)
