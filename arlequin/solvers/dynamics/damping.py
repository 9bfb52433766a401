"""Rayleigh damping for the explicit scheme: C = α M + β K₀, and its stable step.

The damping force ``−C v`` uses the α-weighted lumped mass M of the integrator and the
block-diagonal weighted initial stiffness K₀ of the system (the linear stiffness of linear
blocks, the models' small-strain ``stiffness`` for nonlinear ones), so in an Arlequin overlap it
is shared by the partition weights like the energies it damps. β damping leaves rigid motions
undamped; α damping slows them too (it is a drag proportional to the mass).

A mode of pulsation ω gets the damping ratio ξ(ω) = α/(2ω) + βω/2. Central differences with the
damping force at t_n taken with the velocity v^{n−1/2} (the only explicit choice) are stable for
``ω Δt ≤ 2 (√(1 + ξ²) − ξ)`` (Belytschko, Liu & Moran, *Nonlinear Finite Elements*, §6.2; the
amplification matrix of this staggered form gives the same limit, checked in
``tests/test_damping.py``): the critical step is reduced by that factor at ω_max, and for α > 0
by at most 2/α whatever the mode.

The dissipated energy is reported as ``damping_work`` (J, ≤ 0 for a dissipating run: the work
of the damping forces) in :meth:`Integrator.energies`, so that kinetic + strain − external −
coupling − constraint − damping works stays constant.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from .stability import StableStep

__all__ = ["RayleighDamping"]


@dataclass(frozen=True)
class RayleighDamping:
    """Rayleigh damping C = α M + β K₀ (module docstring).

    Parameters
    ----------
    mass : float
        α (1/s), ≥ 0.
    stiffness : float
        β (s), ≥ 0.
    """

    mass: float = 0.0
    stiffness: float = 0.0

    def __post_init__(self) -> None:
        for name in ("mass", "stiffness"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                unit = "1/s" if name == "mass" else "s"
                raise ValueError(f"Rayleigh {name} coefficient must be a non-negative number "
                                 f"({unit}), got {name}={value}")  # fmt: skip

    @classmethod
    def from_ratio(cls, ratio: float, pulsation: float) -> RayleighDamping:
        """Stiffness-proportional damping with the damping ratio ``ratio`` at ``pulsation``.

        Parameters
        ----------
        ratio : float
            ξ ≥ 0 (1) at that mode; higher modes are damped more (ξ ∝ ω).
        pulsation : float
            ω > 0 (rad/s).
        """
        if not (math.isfinite(ratio) and ratio >= 0.0):
            raise ValueError(f"damping ratio must be a non-negative number, got ratio={ratio}")
        if not (math.isfinite(pulsation) and pulsation > 0.0):
            raise ValueError(f"pulsation must be positive (rad/s), got pulsation={pulsation}")
        return cls(0.0, 2.0 * ratio / pulsation)

    @property
    def active(self) -> bool:
        """Whether C is non-zero."""
        return self.mass > 0.0 or self.stiffness > 0.0

    def ratio(self, pulsation: float | np.ndarray) -> float | np.ndarray:
        """ξ(ω) = α/(2ω) + βω/2 (1) at the pulsation ω (rad/s)."""
        w = np.asarray(pulsation, dtype=float)
        return 0.5 * self.mass / w + 0.5 * self.stiffness * w

    def matrix(self, mass: np.ndarray, stiffness: sp.spmatrix) -> sp.csr_matrix:
        """C (N·s/m), shape (n, n), from the lumped mass (n,) (kg) and K₀ (n, n) (N/m)."""
        c = self.stiffness * sp.csr_matrix(stiffness)
        if self.mass:
            c = c + sp.diags(self.mass * np.asarray(mass, dtype=float))
        return sp.csr_matrix(c)

    def stable_step(self, undamped: StableStep) -> StableStep:
        """The critical step with this damping, from the undamped estimate (s)."""
        w = undamped.omega_max
        xi = float(self.ratio(w))
        factor = math.sqrt(1.0 + xi * xi) - xi
        crit = undamped.critical * factor
        if self.mass:
            crit = min(crit, 2.0 / self.mass)
        method = f"{undamped.method}, Rayleigh damping xi_max={xi:.3g}"
        return replace(undamped, critical=crit, block_bound=undamped.block_bound * factor,
                       method=method)  # fmt: skip
