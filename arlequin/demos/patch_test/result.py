"""The patch test's result: the error, the residual of the exact fields and the sizes.

Two numbers are reported (fractions, see ``docs/theory.md``):

``max_error``       max over the nodes of both models of |u_h − u| / max |u|
``exact_residual``  relative residual of the exact fields, with the best multipliers (least
                    squares), in the discrete equations: a direct check of the formulation that
                    does not depend on the conditioning of the solve.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ...io import JsonResult

__all__ = ["RESULT_UNITS", "PatchTestResult"]

#: Units of the results written to results.json (all dimensionless).
RESULT_UNITS = {"max_error": "1", "exact_residual": "1", "n_coarse_dofs": "1",
                "n_fine_dofs": "1", "n_multipliers": "1"}  # fmt: skip


@dataclass
class PatchTestResult(JsonResult):
    """Outcome of a patch test (all values dimensionless fractions or counts).

    ``to_json()`` starts with ``max_error``, ``exact_residual``, ``n_coarse_dofs``,
    ``n_fine_dofs`` and ``n_multipliers`` (the field order), then the configuration.
    """

    max_error: float
    exact_residual: float
    n_coarse_dofs: int
    n_fine_dofs: int
    n_multipliers: int
    dim: str
    coupling: str
    weights: str
    mediator: str
    mesh: str
    seed: int
    overlap_method: str
    exact_expected: bool
    static: Any = field(default=None, repr=False, compare=False)

    json_exclude = ("static",)

    def summary(self) -> str:
        """One line: the configuration, the error and the residual of the exact solution."""
        return (
            f"patch test dim={self.dim} {self.mesh} {self.coupling} {self.weights} weights, "
            f"{self.mediator} mediator, seed {self.seed}: max_error={self.max_error:.3e}, "
            f"exact_residual={self.exact_residual:.3e} ({self.n_coarse_dofs} coarse + "
            f"{self.n_fine_dofs} fine dofs, {self.n_multipliers} multipliers)"
        )
