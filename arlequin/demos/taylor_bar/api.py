"""The Python entry points of the Taylor bar: :func:`run_taylor_bar` (its keywords make a
:class:`~arlequin.demos.taylor_bar.config.TaylorBarConfig`, checked, then run) and
:func:`resume_taylor_bar` (an interrupted run, from its checkpoint). SI units.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from ...coupling.weights import PartitionWeights
from ...models import BulkViscosity
from .config import TaylorBarConfig
from .models import LAW_DEFAULTS
from .result import TaylorBarResult
from .run import run_config
from .setup import build_bar, resolve

__all__ = ["resume_taylor_bar", "run_taylor_bar"]


def run_taylor_bar(
    model: str = "arlequin",
    elements_radial: int | None = None,
    mesh_size: float | None = None,
    t_end: float = 80e-6,
    velocity: float = 227.0,
    young: float = 117e9,
    poisson: float = 0.35,
    density: float = 8930.0,
    yield_stress: float = 0.4e9,
    hardening: float = 0.1e9,
    hardening_law: str = "linear",
    length: float = 32.4e-3,
    radius: float = 3.2e-3,
    bulk_viscosity: bool | BulkViscosity = False,
    *,
    patch_length: float | None = None,
    gluing_width: float | None = None,
    coarse_size: float | None = None,
    fine_size: float | None = None,
    weights: str | PartitionWeights | None = None,
    mediator: str | None = None,
    coupling: str | None = None,
    coarse_step_ratio: int | None = None,
    band_warning: float | None = None,
    friction: float = 0.0,
    fbar: bool = True,
    backend: str = "auto",
    safety: float = 0.8,
    estimate_every: int = 10,
    sample_interval: float = 0.5e-6,
    frame_interval: float = 2e-6,
    out: str | Path | None = None,
    progress: Callable[[float], None] | None = None,
    checkpoint_interval: float = 10e-6,
    resume: bool = False,
    check_only: bool = False,
    geometry: str = "axisymmetric",
    patch_surface: Any = None,
    **law_parameters: float,
) -> TaylorBarResult | None:
    """Run the Taylor bar impact (see :mod:`arlequin.demos.taylor_bar.run`).

    The keywords make a :class:`~arlequin.demos.taylor_bar.config.TaylorBarConfig` (each
    parameter described there; ``fbar`` is its ``not no_fbar``, the hardening laws' parameters
    are its fields), checked before any work, then run.

    Parameters
    ----------
    fbar : bool
        F-bar cells (default); False gives the plain (locking) Q1 cells.
    out : path, optional
        Results folder, written as the run goes.
    progress : callable, optional
        ``progress(t)`` at every record (the CLI's progress bar).
    check_only : bool
        Deprecated (a study checks its cases with :class:`TaylorBarConfig`): check every input
        and build the models, then return None without running or writing anything.
    resume : bool
        Continue the interrupted run of the folder ``out`` from its last checkpoint (the inputs
        must be the same; :func:`resume_taylor_bar` reads them from the checkpoint). Everything
        written until the checkpoint is kept and the values are those of an uninterrupted run.

    Returns
    -------
    TaylorBarResult

    Raises
    ------
    ValueError
        On bad input, before any computation; :class:`~arlequin.contract.SimulationError` if the
        run fails (an inverted cell names the cell, the step and the time), with the results
        folder marked failed and everything recorded until then kept.
    """
    if not isinstance(fbar, bool):
        raise ValueError(f"fbar must be True or False, got fbar={fbar!r}")
    unknown = sorted(set(law_parameters) - {p for d in LAW_DEFAULTS.values() for p in d})
    if unknown:
        raise ValueError(f"unknown parameters {unknown}: neither an option of run_taylor_bar nor "
                         f"a parameter of a hardening law")  # fmt: skip
    config = TaylorBarConfig(
        model=model, elements_radial=elements_radial, mesh_size=mesh_size, t_end=t_end,
        velocity=velocity, young=young, poisson=poisson, density=density,
        yield_stress=yield_stress, hardening=hardening, hardening_law=hardening_law,
        length=length, radius=radius, bulk_viscosity=bulk_viscosity, patch_length=patch_length,
        gluing_width=gluing_width, coarse_size=coarse_size, fine_size=fine_size, weights=weights,
        mediator=mediator, coupling=coupling, coarse_step_ratio=coarse_step_ratio,
        band_warning=band_warning, friction=friction,
        no_fbar=not fbar, backend=backend, safety=safety,
        estimate_every=estimate_every, sample_interval=sample_interval,
        frame_interval=frame_interval, checkpoint_interval=checkpoint_interval,
        geometry=geometry, patch_surface=patch_surface, **law_parameters,
    )  # fmt: skip
    if check_only:  # every input checked, the models built: nothing run, nothing written
        build_bar(config, resolve(config))
        return None
    return run_config(config, out=out, progress=progress, resume=resume)


def resume_taylor_bar(out: str | Path, progress: Callable[[float], None] | None = None,
                      ) -> TaylorBarResult:  # fmt: skip
    """Continue the interrupted Taylor bar run of the results folder ``out`` from its last
    checkpoint, with the inputs the checkpoint recorded (see :func:`run_taylor_bar`).

    Raises
    ------
    ValueError
        If ``out`` has no (readable) checkpoint.
    """
    return TaylorBarConfig.resume(str(out), progress)
