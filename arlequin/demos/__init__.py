"""Set-ups of the ``arlequin`` commands, each a function returning a result dataclass.

``run_taylor_bar`` (the Taylor bar: Arlequin, uniform or graded) and ``resume_taylor_bar`` (an
interrupted one, from its checkpoint) are re-exported here; the others live in their modules
(``two_bars``, ``wave``, ``patch_test``, ``block_impact``, ``cantilever``).
"""

from .taylor_bar import TaylorBarResult, resume_taylor_bar, run_taylor_bar

__all__ = ["TaylorBarResult", "resume_taylor_bar", "run_taylor_bar"]
