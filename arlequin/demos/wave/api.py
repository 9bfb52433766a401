"""The wave demo's Python entry point (its signature kept): it builds the checked
:class:`WaveConfig` from its keyword arguments and runs it."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from .config import WaveConfig
from .result import WaveResult
from .run import run_config

__all__ = ["run_wave"]


def run_wave(
    ratio: int = 4,
    pulse_width: float = 10,
    gluing_width: float = 10,
    coupling: str = "H1",
    mediator: str = "coarse",
    weights: str = "ramp",
    integrator: str = "explicit",
    dt: float | None = None,
    epsilon: float = 1e-3,
    length: float | None = None,
    out: str | Path | None = None,
    progress: Callable[[float], None] | None = None,
    check_only: bool = False,
) -> WaveResult | None:
    """Run the 1D wave demo (see :mod:`arlequin.demos.wave`).

    Parameters
    ----------
    ratio : int
        Coarse/fine element size ratio (1 = identical meshes).
    pulse_width, gluing_width : float
        Pulse support and gluing band widths, in coarse elements (the band is snapped to fine
        cells by the problem).
    coupling : {"L2", "H1"}
    mediator : {"coarse", "fine"}
    weights : {"ramp", "constant"}
    integrator : {"explicit", "implicit"} or a registry name
        ``"implicit"`` is the trapezoidal Newmark scheme (β = ¼, γ = ½, consistent mass).
    dt : float, optional
        Time step (s); default: the default step of the explicit scheme on the coupled system
        (0.9 × its critical step), for both integrators.
    epsilon : float
        Floor of α_coarse in the patch's free zone.
    length : float, optional
        H1 coupling length ℓ in coarse elements; default: the problem's default (the mean
        coarse cell size on the gluing band, i.e. one coarse element here).
    out : path, optional
        Results folder to write (:class:`arlequin.io.ResultsFolder`): results.json,
        history.csv of the coupled run (energies and works per model, every step), its field
        series (51 frames: displacement, velocity, alpha, the multiplier field) and wave.png.
        The result then keeps the coupled run's :class:`~arlequin.solvers.DynamicResult`
        with its fields (``result.dynamic``).
    progress : callable, optional
        ``progress(fraction)`` with the fraction of the coupled run's steps done, about 200
        times over the run (the CLI's progress bar).
    check_only : bool
        Deprecated: check every input (build the :class:`WaveConfig`) and return None without
        running or writing anything.

    Returns
    -------
    WaveResult
    """
    config = WaveConfig(ratio=ratio, pulse_width=pulse_width, gluing_width=gluing_width,
                        coupling=coupling, mediator=mediator, weights=weights,
                        integrator=integrator, dt=dt, epsilon=epsilon, length=length)  # fmt: skip
    if check_only:  # every input checked: nothing run, nothing written
        return None
    return run_config(config, out, progress)
