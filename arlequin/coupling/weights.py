"""Energy partition weights α_coarse, α_fine at quadrature points.

In the overlap S of a coarse model and a patch, α_coarse + α_fine = 1. With ``d`` the distance (m)
from a point of the patch to the patch's *interior boundary* (the part of its boundary inside the
coarse domain) and ``w`` the gluing-band width:

``RampWeights``
    α_coarse = a − (a − ε) min(d / w, 1) (continuous, α_coarse = a on the interior boundary,
    default a = 1; piecewise linear in d)
``ConstantWeights``
    α_coarse = ``value`` for d < w, ε beyond (cell-wise constant)
``CallableWeights``
    user functions α_coarse(x), α_fine(x)

Beyond the band, inside the patch, the fine model carries the energy: α_coarse = ε (a small
positive floor, so the coarse problem stays non-singular), α_fine = 1 − ε.

Evaluation
----------
Ramps are evaluated as nodal values interpolated with the mesh's own first-order basis: on every
cell whose vertices lie on one side of the band's inner edge this is exactly the piecewise-linear
ramp, which is what makes the weighted integrals exact (see ``docs/theory.md``). Constant weights
are evaluated cell by cell from the cell centroid, user callables at the quadrature points.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = [
    "CallableWeights",
    "ConstantWeights",
    "PartitionWeights",
    "RampWeights",
    "WeightSumError",
    "check_partition_of_unity",
    "make_weights",
]


class WeightSumError(ValueError):
    """α_coarse + α_fine differs from 1 at an overlap quadrature point."""


@dataclass(frozen=True)
class PartitionWeights:
    """Base class. Subclasses define α_coarse and α_fine as functions of (x, d, w).

    Attributes
    ----------
    epsilon : float
        Floor of α_coarse inside the patch beyond the gluing band, in (0, 1).
    mode : {"nodal", "cell", "point"}
        How values reach quadrature points (see module docstring).
    """

    epsilon: float = 1e-3
    mode = "point"

    def __post_init__(self) -> None:
        if not 0.0 < self.epsilon < 1.0:
            raise ValueError(f"weight floor epsilon must lie in (0, 1), got epsilon={self.epsilon}")

    def alpha_coarse(self, x: np.ndarray, d: np.ndarray, width: float) -> np.ndarray:
        """α_coarse at points ``x`` (dim, ...), distances ``d`` (...) to the interior boundary."""
        raise NotImplementedError

    def alpha_fine(self, x: np.ndarray, d: np.ndarray, width: float) -> np.ndarray:
        """α_fine at points ``x`` (dim, ...) with distances ``d`` (...); default 1 − α_coarse."""
        return 1.0 - self.alpha_coarse(x, d, width)


@dataclass(frozen=True)
class RampWeights(PartitionWeights):
    """Linear ramp across the gluing band: α_coarse goes from ``edge`` (interior boundary) to ε.

    Attributes
    ----------
    edge : float
        α_coarse on the patch's interior boundary, in (ε, 1]; default 1 (the fine model carries
        nothing there). A value below 1 keeps some weight, hence mass and stiffness, on the
        fine model's edge: in explicit dynamics the mediator's impulses act on the edge nodes
        whatever their weight, and nodes of vanishing mass then take large fine-scale velocity
        corrections (see the Taylor bar in ``docs/arlequin_taylor.md``).
    """

    edge: float = 1.0
    mode = "nodal"

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.epsilon < self.edge <= 1.0:
            raise ValueError(
                f"ramp edge weight must lie in (epsilon, 1] = ({self.epsilon}, 1], got "
                f"edge={self.edge}"
            )

    def alpha_coarse(self, x, d, width):
        ramp = np.minimum(np.asarray(d, dtype=float) / width, 1.0)
        return self.edge - (self.edge - self.epsilon) * ramp


@dataclass(frozen=True)
class ConstantWeights(PartitionWeights):
    """α_coarse = ``value`` in the gluing band, ε beyond it."""

    value: float = 0.5
    mode = "cell"

    def __post_init__(self) -> None:
        super().__post_init__()
        if not 0.0 < self.value < 1.0:
            raise ValueError(f"constant gluing weight must lie in (0, 1), got value={self.value}")

    def alpha_coarse(self, x, d, width):
        d = np.asarray(d, dtype=float)
        return np.where(d < width, self.value, self.epsilon)


@dataclass(frozen=True)
class CallableWeights(PartitionWeights):
    """User weights: ``coarse(x)`` and ``fine(x)`` take points (dim, ...) and return (...).

    Their sum is checked against 1 at every overlap quadrature point (1e-12).
    """

    coarse: Callable[[np.ndarray], np.ndarray] | None = None
    fine: Callable[[np.ndarray], np.ndarray] | None = None
    mode = "point"

    def __post_init__(self) -> None:
        if self.coarse is None or self.fine is None:
            raise ValueError("CallableWeights needs both the coarse and the fine weight functions")

    def alpha_coarse(self, x, d, width):
        return np.asarray(self.coarse(x), dtype=float)

    def alpha_fine(self, x, d, width):
        return np.asarray(self.fine(x), dtype=float)


def make_weights(weights: str | PartitionWeights, epsilon: float = 1e-3) -> PartitionWeights:
    """Accept ``"ramp"``, ``"constant"`` or a :class:`PartitionWeights` instance."""
    if isinstance(weights, PartitionWeights):
        return weights
    if weights == "ramp":
        return RampWeights(epsilon=epsilon)
    if weights == "constant":
        return ConstantWeights(epsilon=epsilon)
    raise ValueError(f"weights must be 'ramp', 'constant' or a PartitionWeights, got {weights!r}")


def check_partition_of_unity(
    alpha_coarse: np.ndarray, alpha_fine: np.ndarray, x: np.ndarray, tol: float = 1e-12
) -> None:
    """Raise :class:`WeightSumError` unless α_coarse + α_fine = 1 and both lie in [0, 1].

    Parameters
    ----------
    alpha_coarse, alpha_fine : ndarray, shape (n_elems, n_qp)
    x : ndarray, shape (dim, n_elems, n_qp)
        Quadrature points (m), to say where the largest violation is.
    """
    ac = np.asarray(alpha_coarse, dtype=float)
    af = np.asarray(alpha_fine, dtype=float)
    for name, a in (("alpha_coarse", ac), ("alpha_fine", af)):
        if not np.all(np.isfinite(a)):
            raise WeightSumError(f"{name} has non-finite values at overlap quadrature points")
        bad = (a < -tol) | (a > 1.0 + tol)
        if np.any(bad):
            i = np.unravel_index(np.argmax(np.abs(a - np.clip(a, 0, 1))), a.shape)
            raise WeightSumError(
                f"{name} must lie in [0, 1]; got {a[i]:.6g} at x = {x[(slice(None), *i)]}"
            )
    err = np.abs(ac + af - 1.0)
    if err.size and err.max() > tol:
        i = np.unravel_index(np.argmax(err), err.shape)
        raise WeightSumError(
            f"partition weights do not sum to one: |alpha_coarse + alpha_fine - 1| = {err[i]:.3e} "
            f"(tolerance {tol:g}) at x = {x[(slice(None), *i)]}"
        )
