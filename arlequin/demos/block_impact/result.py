"""The block impact's result: energies, the contact's activation figures, the iterations (SI)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...io import JsonResult

__all__ = ["BlockImpactResult"]


@dataclass
class BlockImpactResult(JsonResult):
    """A block launched onto a rigid plane or onto an identical block at rest (SI units).

    Attributes
    ----------
    dim : int
    target : str
        ``"plane"`` or ``"block"``.
    elements : int
        Elements in the impact direction.
    dt : float
        Time step (s); h the element size (m).
    h : float
    t : ndarray, shape (n_rec,)
    total_energy : ndarray, shape (n_rec,)
        Kinetic + strain (J).
    contact_work : ndarray, shape (n_rec,)
        Accumulated contact work (J).
    first_contact, separation : int
        Record indices: the first record with λ ≠ 0 and the first record after the last one
        with λ ≠ 0.
    energy_loss : float
        (E(first contact − 1) − E(separation)) / E(0).
    max_gap_drift : float
        max over active points and steps of |d_n(t) − d_n(t_activation)| (m).
    max_penetration_excess : float
        max over activations of d_n(t_act) − (1 − θ)Δt[[v_n]]⁻ (m) (≤ 0 means within the bound).
    max_penetration : float
        Largest d_n at activation (m).
    iterations : ndarray of int
        Fixed-point iterations of every step.
    iterations_contact : ndarray of int
        Those of the steps with an active point.
    n_status_failures : int
    final_velocities : list of float
        Mean velocity (impact component) of each body at the end (m/s).
    """

    dim: int
    target: str
    elements: int
    dt: float
    h: float
    t: np.ndarray
    total_energy: np.ndarray
    contact_work: np.ndarray
    first_contact: int
    separation: int
    energy_loss: float
    max_gap_drift: float
    max_penetration_excess: float
    max_penetration: float
    iterations: np.ndarray
    iterations_contact: np.ndarray
    n_status_failures: int
    final_velocities: list[float]
    theta: float = 0.5

    def iteration_distribution(self) -> dict[int, int]:
        """{iterations: number of steps} over the steps with contact."""
        vals, counts = np.unique(self.iterations_contact, return_counts=True)
        return {int(v): int(c) for v, c in zip(vals, counts)}
