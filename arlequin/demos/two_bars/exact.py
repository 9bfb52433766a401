"""The two-bar impact's exact solution and a run's errors against it.

Two identical elastic bars (E, ρ, c = √(E/ρ)), touching at t = 0: interface velocity
(v₀ + v₂)/2 and contact pressure ρc(v₀ − v₂)/2 during the contact, which lasts 2 L_min / c; then
the velocities are exchanged (SI units).
"""

from __future__ import annotations

import math
from typing import Any, Protocol

import numpy as np

__all__ = ["ImpactRecord", "exact_two_bars", "impact_metrics"]


class ImpactRecord(Protocol):
    """What :func:`impact_metrics` reads of a run: a
    :class:`~arlequin.demos.two_bars.TwoBarsResult` (whose module imports this one)."""

    exact: dict[str, Any]
    dt: float
    t: np.ndarray
    interface_velocity: np.ndarray
    contact_pressure: np.ndarray
    contact_duration: float
    final_velocities: Any
    total_energy: np.ndarray
    contact_work: np.ndarray


def exact_two_bars(
    lengths=(1.0, 1.0), young=210e9, density=7850.0, velocity=1.0, velocity2=0.0
) -> dict[str, Any]:
    """Exact solution of the two-bar impact (same material, bars touching at t = 0).

    Returns
    -------
    dict
        ``interface_velocity`` (m/s), ``pressure`` (Pa), ``duration`` (s),
        ``final_velocities`` (m/s, mass-weighted means), ``c`` (m/s).
    """
    c = math.sqrt(young / density)
    l1, l2 = (float(x) for x in lengths)
    lmin = min(l1, l2)
    dv = velocity - velocity2
    # impulse per unit area: ρ c dv/2 during 2 L_min / c -> ρ L_min dv
    return {
        "interface_velocity": 0.5 * (velocity + velocity2),
        "pressure": 0.5 * density * c * dv,
        "duration": 2.0 * lmin / c,
        "final_velocities": [velocity - lmin * dv / l1, velocity2 + lmin * dv / l2],
        "c": c,
    }


def impact_metrics(result: ImpactRecord, skip: int = 2) -> dict[str, float]:
    """Errors of an impact run against its exact solution.

    Over the records in contact (λ_v ≠ 0) except the first ``skip`` and the last ``skip``:
    rms of (interface velocity − exact)/|exact| and of (pressure − exact)/exact; the pressure
    error also over the exact contact interval t ∈ (2.5Δt, 2L/c − 2.5Δt)
    (``pressure_rms_error_exact_interval``, t = 0 the exact first contact). Also the
    duration error in steps, the final-velocity error / v₀, and the energy lost
    (E(0) − E(end))/E(0).
    """
    ex = result.exact
    act = np.nonzero(result.contact_pressure != 0.0)[0]
    if act.size <= 2 * skip:
        raise ValueError(
            f"the contact lasts {act.size} record(s), too few for the errors over the contact "
            f"(they skip {skip} at each end): refine the time step (a smaller cfl, now "
            f"dt = {result.dt:.3e} s against a contact of {ex['duration']:.3e} s) or record "
            "every step"
        )
    out = {"velocity_rms_error": math.nan, "pressure_rms_error": math.nan}
    if act.size > 2 * skip:
        sl = slice(act[0] + skip, act[-1] - skip + 1)
        vi = result.interface_velocity[sl]
        pr = result.contact_pressure[sl]
        vref = ex["interface_velocity"]
        scale_v = abs(vref) if vref != 0.0 else abs(ex["velocity_scale"])
        out["velocity_rms_error"] = float(np.sqrt(np.mean((vi - vref) ** 2)) / scale_v)
        p_err = np.sqrt(np.mean((pr - ex["pressure"]) ** 2))
        out["pressure_rms_error"] = float(p_err / ex["pressure"])
    # the same pressure error over the exact contact interval, with t = 0 the exact first
    # contact: t in (2.5 dt, 2L/c - 2.5 dt), free of the steps where contact starts and ends
    t = result.t
    window = (t > 2.5 * result.dt) & (t < ex["duration"] - 2.5 * result.dt)
    if np.count_nonzero(window):
        p_err = np.sqrt(np.mean((result.contact_pressure[window] - ex["pressure"]) ** 2))
        out["pressure_rms_error_exact_interval"] = float(p_err / ex["pressure"])
    else:
        out["pressure_rms_error_exact_interval"] = math.nan
    out["duration_error_steps"] = (result.contact_duration - ex["duration"]) / result.dt
    fin = np.asarray(result.final_velocities) - np.asarray(ex["final_velocities"])
    out["final_velocity_error"] = float(np.max(np.abs(fin)) / abs(ex["velocity_scale"]))
    e = result.total_energy
    out["energy_loss"] = float((e[0] - e[-1]) / e[0])
    out["max_energy_gain"] = float((np.max(e) - e[0]) / e[0])
    w = result.contact_work
    out["contact_work"] = float(w[-1])
    out["balance_error"] = float(np.max(np.abs(e - e[0] - w)) / e[0])
    return out
