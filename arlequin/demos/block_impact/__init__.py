"""A block launched onto a rigid plane or onto an identical block (2D plane strain, 3D).

The level-set contact model's checks beyond 1D: a block of height H (the impact direction is the
last coordinate) starts at a small gap above the target at −v₀ and hits it; the gap of active
points must not drift, the penetration at activation must stay within the velocity-level bound
(1 − θ)Δt[[v_n]], and the energy lost in the impact must vanish with refinement. SI units. No
command of its own: the tests, ``examples/two_bars.py`` and the benchmarks run it from Python.

Modules: :mod:`.config` (``BlockImpactConfig``), :mod:`.setup`, :mod:`.run`
(``run_block_impact``) and :mod:`.result` (``BlockImpactResult``).
"""

from ..config import register_runner
from . import run as _run
from .api import run_block_impact
from .config import BlockImpactConfig
from .result import BlockImpactResult

__all__ = ["BlockImpactConfig", "BlockImpactResult", "run_block_impact"]

# the configuration runs through its package's runner (it does not import its run module);
# no results folder, no progress
register_runner(BlockImpactConfig, lambda config, out=None, progress=None: _run.run_config(config))
