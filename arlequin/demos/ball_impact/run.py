"""The ball impact's run, as named steps: the bodies, the simulated time, the results folder and
its listeners, the integrator, the time loop, the result and its checks.

:func:`run_config` runs a configuration (``BallImpactConfig.run``; the Python entry point
:func:`~arlequin.demos.ball_impact.api.run_ball_impact` makes one from its keywords). SI units;
see :mod:`arlequin.demos.ball_impact`.
"""

from __future__ import annotations

import contextlib
import functools
import logging
import math
import time
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ...io import DynamicRunWriter, ResultsFolder
from ...solvers import solve
from ..taylor_bar.result import GluingBandPlasticityWarning
from .record import ImpactRecorder
from .report import AdaptationPictures, plot_patch_size, write_outputs
from .result import BallImpactResult, hertz
from .setup import ImpactBodies, ResolvedInputs, mono_cells

if TYPE_CHECKING:
    from .config import BallImpactConfig

__all__ = ["BAND_WARNING", "run_config"]

logger = logging.getLogger(__name__)

#: ε̄p in the block patch's gluing band above which a GluingBandPlasticityWarning is raised.
BAND_WARNING = 0.02


def run_config(config: BallImpactConfig, out: str | Path | None = None,
               progress: Callable[[float], None] | None = None) -> BallImpactResult:  # fmt: skip
    """Run the configured impact: the bodies, the time loop, the result and its outputs."""
    inputs = config.resolved
    _warn_outside_hertz(inputs)
    bodies = ImpactBodies(inputs.model, inputs.sizes, inputs.radius, inputs.block_radius,
                          inputs.block_height, inputs.ball_material, inputs.block_material,
                          rigid_wall=inputs.rigid_wall, friction=inputs.friction,
                          seed=None if inputs.adapt is None else inputs.sizes.reach)  # fmt: skip
    adapt = None
    if inputs.adapt is not None:  # the block's patch from a seed at the contact
        a = inputs.adapt
        adapt = bodies.adaptation(a["adapt_threshold"], a["adapt_buffer"], a["adapt_every"],
                                  a["max_patch_fraction"])  # fmt: skip
    values = _hertz_values(inputs, bodies)
    t_end = _simulated_time(inputs, bodies, values)
    record = config.inputs()  # the resolved inputs, the materials as objects of their fields
    folder = ResultsFolder(out, "arlequin ball-impact", record, config.units()) if out else None
    recorder = ImpactRecorder(bodies, folder, t_end, progress, adapt)
    listeners = [recorder]
    if folder is not None and adapt is not None:  # after the recorder: it follows the growths
        listeners.append(AdaptationPictures(folder, bodies))
    # a failed adaptive run (the patch's cap reached) keeps the patch's history picture too
    keep = None if folder is None or adapt is None else functools.partial(
        _patch_size_picture, folder, recorder, adapt)  # fmt: skip
    with _failures_recorded(folder, keep):
        res, wall = _time_loop(inputs, bodies, listeners, folder, t_end, adapt)
        # Arlequin: its patches' elements; a reference: all its elements, over the uniform
        # meshes'
        mono = mono_cells(inputs.sizes, inputs.block_radius, inputs.block_height,
                          inputs.rigid_wall)  # fmt: skip
        fine = bodies.fine_elements if inputs.model == "arlequin" else bodies.n_elements
        # still in contact at the end: a ValueError, and the folder says so
        result = recorder.result(res, wall, fine / mono, values, record)
    result.t_end = float(t_end)
    if adapt is not None:
        result.adaptations = [a.to_json() for a in res.adaptations]
        result.max_coarse_yield_ratio = float(res.max_coarse_yield_ratio)
    _warn_band_plasticity(result, inputs)
    if folder is not None:
        write_outputs(folder, result, bodies, res)
    logger.info(result.summary())
    return result


def _warn_outside_hertz(inputs: ResolvedInputs) -> None:
    """Log when the elastic run leaves the range of Hertz's quasi-static half-space."""
    if inputs.plastic:
        return
    bar_speed = math.sqrt(inputs.ball_material.young / inputs.ball_material.density)
    if inputs.velocity > 1e-3 * bar_speed:
        logger.warning("velocity %.4g m/s is above 1e-3 of the ball's bar wave speed (%.4g "
                       "m/s): Hertz's quasi-static solution is only a guide", inputs.velocity,
                       bar_speed)  # fmt: skip
    if not inputs.rigid_wall and inputs.block_size < 10.0 * inputs.radius:
        logger.warning(
            "a block under 10 ball radii (%.4g m) is not the half-space of Hertz's solution",
            inputs.block_size,
        )


def _hertz_values(inputs: ResolvedInputs, bodies: ImpactBodies) -> dict[str, float]:
    """Hertz's values with the discrete ball's mass (elastic regime; empty otherwise)."""
    if inputs.plastic:
        return {}
    ref = None if inputs.rigid_wall else inputs.block_material
    return hertz(inputs.radius, bodies.ball_mass, inputs.velocity, inputs.ball_material, ref)


def _simulated_time(inputs: ResolvedInputs, bodies: ImpactBodies,
                    values: dict[str, float]) -> float:  # fmt: skip
    """The given simulated time (s), or the default of the regime."""
    if inputs.t_end is not None:
        return inputs.t_end
    if inputs.plastic:
        # a fully plastic contact: F = 3 σ_y π a², a² = 2 R d, a spring k = 6π R σ_y whose
        # half period π √(m/k) is the loading; 1.5 × it covers the elastic unloading
        stiffness = 6.0 * math.pi * inputs.radius * inputs.block_material.yield_stress
        return 1.5 * math.pi * math.sqrt(bodies.ball_mass / stiffness)
    return 1.4 * values["hertz_contact_duration"]


@contextlib.contextmanager
def _failures_recorded(folder: ResultsFolder | None,
                       keep: Callable[[], None] | None = None) -> Iterator[None]:  # fmt: skip
    """``with _failures_recorded(folder):`` an exception inside marks the results folder
    failed (its message recorded, after ``keep()`` wrote what the run had) and propagates."""
    try:
        yield
    except Exception as exc:
        if folder is not None:
            if keep is not None:
                try:
                    keep()
                except Exception as err:  # the run's own error is the one to raise
                    logger.warning("the failed run's pictures: %s", err)
            folder.finish("failed", str(exc))
        raise


def _patch_size_picture(folder: ResultsFolder, recorder: ImpactRecorder, adapt: Any) -> None:
    """``patch_size.png`` from the rows recorded so far (a failed adaptive run)."""
    if recorder.rows["t"]:
        growths = [(a.time, a.patch_fraction) for a in adapt.records]
        plot_patch_size(recorder.rows, growths, str(folder.picture("patch_size")))


def _integrator(inputs: ResolvedInputs, bodies: ImpactBodies) -> tuple[str, dict[str, Any]]:
    """The integrator and its options: multi-time-step when the ratio M exceeds 1."""
    if inputs.coarse_step_ratio <= 1:
        return "explicit", {}
    options = {"slow_blocks": bodies.slow_blocks, "step_ratio": inputs.coarse_step_ratio,
               "resonance_bound": False, "energy_tolerance": 0.01}  # fmt: skip
    return "explicit-mts", options


def _plastic_fields(bodies: ImpactBodies) -> tuple[Any, dict[str, str] | None]:
    """The frames' cell fields of the block's J2 patch (cell means of ε̄p and of the von Mises
    stress) and their units, or (None, None) in the elastic regime and when the J2 law lives
    on a mesh of its own (``mono-zoned``: not the block's series)."""
    part = bodies.plastic_part()
    if part is None or part[4] is not None:
        return None, None
    _, block, index, _, _ = part

    def cell_data(integ: Any) -> dict[str, dict[str, np.ndarray]]:
        state = integ.states[block][index]
        return {block: {"plastic_strain": state.eqps.mean(axis=1),
                        "von_mises": state.von_mises.mean(axis=1)}}  # fmt: skip

    return cell_data, {"plastic_strain": "1", "von_mises": "Pa"}


def _time_loop(inputs: ResolvedInputs, bodies: ImpactBodies, listeners: list[Any],
               folder: ResultsFolder | None, t_end: float,
               adapt: Any = None) -> tuple[Any, float]:  # fmt: skip
    """The explicit run to ``t_end`` (s): its final state and its wall time (s); ``listeners``
    called after every step (the :class:`ImpactRecorder` first), ``adapt`` the adaptive block
    patch, if any."""
    frames = np.linspace(0.0, t_end, 11)[1:]
    cell_data, units = _plastic_fields(bodies)
    writers = ([DynamicRunWriter(folder, bodies.system, layout=bodies.layout, frame_times=frames,
                                 cell_data=cell_data, units=units)]
               if folder else [])  # fmt: skip
    integrator, options = _integrator(inputs, bodies)
    tic = time.perf_counter()
    # an adaptive patch rebuilds the problem (its body's patch), not only the system
    res = solve(bodies.system if adapt is None else bodies.problem, integrator, t_end=t_end,
                v0=bodies.initial_velocity(inputs.velocity), constraints=[bodies.contact],
                on_step=listeners, on_record=writers, t_eval=frames, adapt=adapt,
                **options)  # fmt: skip
    return res, time.perf_counter() - tic


def _warn_band_plasticity(result: BallImpactResult, inputs: ResolvedInputs) -> None:
    """Warn when the block's gluing band (glued to an elastic coarse model) yields."""
    if result.band_max_plastic_strain > BAND_WARNING:
        warnings.warn(f"equivalent plastic strain in the block's gluing band reaches "
                      f"{result.band_max_plastic_strain:.4f} > {BAND_WARNING}: the coarse model "
                      f"glued there is elastic; enlarge it (block_patch_size="
                      f"{inputs.sizes.block_patch:.4g} m)",
                      GluingBandPlasticityWarning, stacklevel=3)  # fmt: skip
