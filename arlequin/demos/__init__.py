"""Set-ups of the ``arlequin`` commands, each a function returning a result dataclass.

``run_taylor_bar`` (the Taylor bar: Arlequin, uniform or graded), ``resume_taylor_bar`` (an
interrupted one, from its checkpoint) and ``run_ball_impact`` (the ball striking a block) are
re-exported here; the others live in their packages or modules (``two_bars``, ``wave``,
``patch_test``, ``block_impact``, ``cantilever``, ``sliding_block``).
"""

from .ball_impact import BallImpactResult, run_ball_impact
from .taylor_bar import TaylorBarResult, resume_taylor_bar, run_taylor_bar

__all__ = [
    "BallImpactResult",
    "TaylorBarResult",
    "resume_taylor_bar",
    "run_ball_impact",
    "run_taylor_bar",
]
