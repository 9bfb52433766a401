"""A plane-strain cantilever with a non-nested refined patch at its clamped end (the dynamics
tests' and benchmarks' set-up; no command of its own).

Modules: :mod:`.setup` (``build_cantilever``, ``Cantilever``, ``tri_grid``, ``STEEL``).
"""

from .setup import STEEL, Cantilever, build_cantilever, tri_grid

__all__ = ["STEEL", "Cantilever", "build_cantilever", "tri_grid"]
