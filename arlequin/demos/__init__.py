"""Set-ups of the ``arlequin`` commands, each a function returning a result dataclass.

``run_taylor_bar`` (the Taylor bar on one mesh) is re-exported here; the others live in their
modules (``two_bars``, ``wave``, ``patch_test``, ``block_impact``, ``cantilever``).
"""

from .taylor_bar import TaylorBarResult, run_taylor_bar

__all__ = ["TaylorBarResult", "run_taylor_bar"]
