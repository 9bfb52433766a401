"""Impact of two elastic bars (the seed's Figure 1) and a bar against a rigid wall.

Two bars (SI units): bar 1 on [−L1, 0] at velocity v₀, bar 2 on [0, L2] at velocity v₂ (default
at rest), same material (E, ρ, c = √(E/ρ)), touching at t = 0. Exact solution for L1 = L2 = L
(:mod:`.exact`): interface velocity (v₀ + v₂)/2 and contact pressure ρc(v₀ − v₂)/2 during the
contact, which lasts 2L/c; then the velocities are exchanged. With L1 ≠ L2 the contact lasts
2 min(L1, L2)/c.

Methods (:mod:`.setup`): the level-set (Signorini–Moreau) contact model with the θ-scheme or
central differences; the baseline Newmark + Signorini on displacements, trapezoidal or HHT-α.

Modules: :mod:`.config` (``TwoBarsConfig``, the ``arlequin two-bars`` options), :mod:`.setup`,
:mod:`.run` (``run_two_bars``), :mod:`.wall` (``run_wall``), :mod:`.exact`, :mod:`.result`
(``TwoBarsResult``) and :mod:`.report` (the results folder and the picture).
"""

from ..config import register_runner
from . import run as _run
from .api import run_two_bars
from .config import TwoBarsConfig
from .exact import exact_two_bars, impact_metrics
from .report import plot_two_bars
from .result import JSON_KEYS, TwoBarsResult
from .wall import run_wall

__all__ = [
    "JSON_KEYS",
    "TwoBarsConfig",
    "TwoBarsResult",
    "exact_two_bars",
    "impact_metrics",
    "plot_two_bars",
    "run_two_bars",
    "run_wall",
]

# the configuration runs through its package's runner (it does not import its run module)
register_runner(TwoBarsConfig, _run.run_config)
