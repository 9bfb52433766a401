"""The two-bar impact's Python entry point (its signature kept): it builds the checked
:class:`TwoBarsConfig` from its keyword arguments and runs it."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from .config import TwoBarsConfig
from .result import TwoBarsResult
from .run import run_config

__all__ = ["run_two_bars"]


def run_two_bars(
    method: str = "levelset",
    newmark: str = "trapezoidal",
    lengths: tuple[float, float] = (1.0, 1.0),
    young: float = 210e9,
    density: float = 7850.0,
    velocity: float = 1.0,
    velocity2: float = 0.0,
    elements: int = 100,
    cfl: float = 1.0,
    theta: float = 0.5,
    t_end: float | None = None,
    integrator: str = "theta",
    out: str | Path | None = None,
    progress: Callable[[float], None] | None = None,
    check_only: bool = False,
) -> TwoBarsResult | None:
    """Impact of two bars touching at t = 0 (see :mod:`arlequin.demos.two_bars`).

    Parameters
    ----------
    method : {"levelset", "newmark", "both"}
        ``"both"`` runs the level-set model and the Newmark baseline (attached as ``.newmark``).
    newmark : {"trapezoidal", "hht"}
        Newmark variant: β = ¼, γ = ½, or HHT-α with α = −0.1.
    lengths : (float, float)
        L1, L2 (m).
    young, density : float
        E (Pa), ρ (kg/m³) of both bars.
    velocity, velocity2 : float
        Initial velocities of bar 1 and bar 2 (m/s); bar 1 must approach (v₀ > v₂).
    elements : int
        Elements per bar.
    cfl : float
        Δt = cfl × h_min / c.
    theta : float
        θ of the θ-scheme (level-set method), in [½, 1].
    t_end : float, optional
        End time (s); default 3 max(L1, L2)/c.
    integrator : {"theta", "explicit"}
        Time scheme of the level-set method (the θ-scheme with consistent mass, or central
        differences with lumped mass).
    out : path, optional
        Results folder (:class:`arlequin.io.ResultsFolder`): results.json, history.csv and
        one field series per bar (the Newmark baseline of ``method="both"`` in files prefixed
        ``newmark-trapezoidal_`` or ``newmark-hht_``), two_bars.png.
    progress : callable, optional
        ``progress(fraction)`` with the fraction of the simulated time done (both runs of
        ``method="both"`` together), at each new percent (the CLI's progress bar).
    check_only : bool
        Deprecated: check every input (build the :class:`TwoBarsConfig`) and return None
        without running or writing anything.

    Returns
    -------
    TwoBarsResult
    """
    config = TwoBarsConfig(method=method, newmark=newmark, lengths=lengths, young=young,
                           density=density, velocity=velocity, velocity2=velocity2,
                           elements=elements, cfl=cfl, theta=theta, t_end=t_end,
                           integrator=integrator)  # fmt: skip
    if check_only:
        return None
    return run_config(config, out, progress)
