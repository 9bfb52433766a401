"""The Taylor bar impact: finite-strain J2, explicit dynamics, the level-set wall.

A copper bar (length L, radius R, axisymmetric Q1 F-bar cells) moving at −v₀ along z touches a
rigid frictionless wall z = 0 at t = 0 (L = 32.4 mm, R = 3.2 mm, v₀ = 227 m/s,
E = 117 GPa, ν = 0.35, ρ = 8930 kg/m³, σ_y0 = 0.4 GPa, H = 0.1 GPa, 80 µs). Three models
(:mod:`arlequin.demos.taylor_bar.models`): ``arlequin`` (default) a coarse linear-elastic bar plus a
refined finite-strain patch over the impacted end, glued by a mediator in a band at the patch's
top (docs/arlequin_taylor.md); ``mono`` one uniform finite-strain mesh; ``graded`` one
conforming finite-strain mesh, fine over the patch region and coarse above. The wall is the
level-set contact model on the impact face and the lower lateral surface (which folds onto the
wall as the mushroom forms), lift-off allowed; the axis carries u_r = 0. Central differences
with the step re-estimated from the current configuration every few steps
(:class:`~arlequin.solvers.CriticalFraction`).

Energy balance, at every record: KE + W_el + D_p + D_visc + W_c = KE_0 with KE the explicit
scheme's kinetic energy ½ṽ^{n−½}·M v^{n+½}, W_el the stored (Hencky) energy, D_p and D_visc the
plastic and bulk-viscosity dissipations, W_c ≥ 0 the energy the wall removed (minus the work of
the contact forces on the bar, the loss of stopping the impact face at t = 0 included) and KE_0
= ½ v₀·M v₀ with the lumped mass. Reported: the final length (axial position of the top-face
node on the axis), the footprint (mushroom) radius (the largest distance from the axis of a
node of the impact face), the maximum equivalent plastic strain and the balance error
max_t abs(KE + W_el + D_p + D_visc + W_c − W_coupling − KE_0) / KE_0 (W_coupling, the net work of
the mediator's forces, is zero on one mesh). SI units throughout.

The run writes its results as it goes (``out=DIR``): results.json (inputs with units, then the
results), history.csv (one row per record), fields/bar.xdmf (u, v, ε̄p and the von Mises
stress on the reference mesh; warp by ``displacement`` in ParaView; ``arlequin``:
fields/coarse.xdmf and fields/patch.xdmf with the weights and the multipliers) and, at the end,
taylor_bar.png (the final shape coloured by ε̄p; ``arlequin``: both models, initial and final)
and taylor_bar_history.png.

The run is a sequence of named steps on a checked configuration
(:class:`~arlequin.demos.taylor_bar.config.TaylorBarConfig`): the inputs resolved
(:func:`~arlequin.demos.taylor_bar.setup.resolve`), the bar built, the kernels warmed up, the
recorder, the results folder and the checkpoints set up, the integration, the result assembled
and written.
"""

from __future__ import annotations

import logging
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ...io import ResultsFolder
from ...solvers import solve
from .checkpoint import CheckpointWriter, load_checkpoint, read_frames
from .models import ArlequinBar
from .models_3d import ArlequinBar3D
from .record import MultiplierHistory, TaylorRecorder
from .report import write_results
from .result import (
    DERIVED_INPUT_UNITS,
    RESULT_UNITS,
    GluingBandPlasticityWarning,
    TaylorBarResult,
)
from .setup import Resolved, build_bar, resolve

if TYPE_CHECKING:
    from .config import TaylorBarConfig

__all__ = ["resume_run", "run_config"]

logger = logging.getLogger(__name__)


def run_config(config: TaylorBarConfig, out: str | Path | None = None,
               progress: Callable[[float], None] | None = None,
               resume: bool = False) -> TaylorBarResult:  # fmt: skip
    """Run the Taylor bar of a (checked) configuration.

    Parameters
    ----------
    config : TaylorBarConfig
    out : path, optional
        Results folder, written as the run goes.
    progress : callable, optional
        ``progress(t)`` at every record, t the simulated time (s).
    resume : bool
        Continue the interrupted run of the folder ``out`` from its last checkpoint (written by
        a run of the same inputs).

    Returns
    -------
    TaylorBarResult
    """
    r = resolve(config)
    bar, n_z, record = build_bar(config, r)
    _record_inputs(config, r, n_z, record)
    _warm_up(bar.model, config.geometry)
    run = _open(config, bar, record, out, progress, resume)
    logger.info("Taylor bar (%s): %d x %d fine cells, %s backend", config.model, r.n_r, n_z,
                bar.model.backend)  # fmt: skip
    res = _integrate(config, r, bar, run)
    result = _result(config, r, bar, n_z, record, run, res)
    _finish(run, result)
    return result


def resume_run(out: str | Path, progress: Callable[[float], None] | None = None,
               ) -> TaylorBarResult:  # fmt: skip
    """Continue the interrupted run of the results folder ``out`` from its last checkpoint,
    with the configuration the checkpoint recorded.

    Raises
    ------
    ValueError
        If ``out`` has no (readable) checkpoint.
    """
    config = load_checkpoint(out, None)["call"]
    return run_config(config, out=out, progress=progress, resume=True)


def _record_inputs(c: TaylorBarConfig, r: Resolved, n_z: int, record: dict[str, Any]) -> None:
    """The rest of the inputs recorded in results.json (with the resolved counts and sizes)."""
    record.update({
        "elements_radial": r.n_r, "elements_axial": n_z, "mesh_size": c.radius / r.n_r,
        "t_end": c.t_end, "velocity": c.velocity, "young": c.young, "poisson": c.poisson,
        "density": c.density, "yield_stress": c.yield_stress, "hardening": c.hardening,
        "hardening_law": c.hardening_law, "length": c.length, "radius": c.radius,
        "bulk_viscosity": bool(r.visc), "fbar": bool(r.fbar), "backend": c.backend,
        "safety": c.safety, "estimate_every": int(c.estimate_every),
        "sample_interval": c.sample_interval, "frame_interval": c.frame_interval,
        "friction": float(c.friction), **c.law_parameters(),
    })  # fmt: skip
    if r.visc:
        record.update(bulk_viscosity_linear=r.visc.linear,
                      bulk_viscosity_quadratic=r.visc.quadratic)  # fmt: skip


def _warm_up(fine_model: Any, geometry: str) -> None:
    """Compile (or load) the J2 kernels before the clock starts."""
    if fine_model.backend == "numba":
        from ...models.plasticity.j2_kernel import warm_up
        from ...models.plasticity.j2_kernel_3d import warm_up_solid

        warm_up_solid() if geometry == "3d" else warm_up()


@dataclass
class _Run:
    """What a run sets up around the integration: the initial velocity and kinetic energy, the
    results folder, the recorders, the checkpoints (and the one resumed), the timings."""

    v0: np.ndarray
    ke0: float
    folder: ResultsFolder | None
    recorder: TaylorRecorder
    multipliers: MultiplierHistory | None
    saver: CheckpointWriter | None
    checkpoint: dict[str, Any] | None
    start: float = 0.0
    end: float = 0.0
    integrator: Any = None  # the multi-time-step integrator (its macro steps and ratios)


def _open(c: TaylorBarConfig, bar: Any, record: dict[str, Any], out: str | Path | None,
          progress: Callable[[float], None] | None, resume: bool) -> _Run:  # fmt: skip
    """The initial state, the checkpoint to resume, the results folder, the recorders."""
    v0 = bar.initial_velocity(c.velocity)
    ke0 = 0.5 * float(v0 @ (bar.lumped_mass() * v0))
    frames = np.arange(0.0, c.t_end * (1 + 1e-12), c.frame_interval)
    ckpt = load_checkpoint(out, record) if resume else None
    # the frames written before the interruption, read before the folder's series reopen
    old_frames = read_frames(out, bar.series_meshes()) if ckpt is not None else {}
    # every input checked: the results folder opens (results.json with the inputs, "running")
    folder = None
    if out is not None:
        units = {**DERIVED_INPUT_UNITS, **type(c).units()}
        folder = ResultsFolder(out, "arlequin taylor-bar", record, units)
    con = bar.contact
    rec = TaylorRecorder(bar, con.name, con.pair.slave.weights, ke0, folder, frames, progress)
    lam_history = MultiplierHistory("coupling:patch") if c.model == "arlequin" else None
    saver = None
    if folder is not None:
        saver = CheckpointWriter(folder.path, c.checkpoint_interval, record, c, rec, lam_history)
    if ckpt is not None:
        saver.resume_from(ckpt, old_frames)
    return _Run(v0, ke0, folder, rec, lam_history, saver, ckpt)


def _integrate(c: TaylorBarConfig, r: Resolved, bar: Any, run: _Run) -> Any:
    """The explicit integration (multi-time-step with ``coarse_step_ratio`` > 1); the folder is
    marked failed if it raises."""
    n_samples = max(1, round(c.t_end / c.sample_interval))
    t_eval = np.linspace(0.0, c.t_end, n_samples + 1)[1:]
    ratio = r.coarse_step_ratio
    run.start = time.perf_counter()
    try:
        # the fastest fine modes are those of the distorted cells at the impact face, far from
        # the gluing band the coarse force acts through: no resonance bound (it would keep
        # m = 1), the energy check at the Interface's 1% balance stops a resonating run
        mts = {"slow_blocks": (bar.coarse_block,), "step_ratio": int(ratio),
               "safety": c.safety, "resonance_bound": False,
               "energy_tolerance": 0.01} if ratio > 1 else {}  # fmt: skip
        on_step = [run.recorder.count_step]
        if run.multipliers is not None:
            on_step.append(run.multipliers)
        if mts:
            on_step.append(lambda integ: setattr(run, "integrator", integ))
        ckpt = run.checkpoint
        res = solve(
            bar.system,
            "explicit-mts" if mts else "explicit",
            t_end=c.t_end,
            v0=run.v0,
            constraints=[bar.contact],
            **mts,
            step_controller=r.controller,
            t_eval=t_eval,
            on_record=[run.recorder],
            on_step=on_step,
            on_checkpoint=run.saver,
            restore=None if ckpt is None else (ckpt["snapshot"], ckpt["recorder"]),
        )
    except Exception as exc:
        if run.folder is not None:
            run.folder.finish("failed", str(exc))
        raise
    run.end = time.perf_counter()
    return res


def _result(c: TaylorBarConfig, r: Resolved, bar: Any, n_z: int, record: dict[str, Any],
            run: _Run, res: Any) -> TaylorBarResult:  # fmt: skip
    """The result of the integration: the quantities of interest, the timings, the history."""
    rec = run.recorder
    wall_time = run.end - run.start
    loop_time = run.end - (rec.loop_start if rec.loop_start is not None else run.start)
    fine_model = bar.model
    state = res.states[bar.fine_block][0]
    ip = int(np.argmax(state.eqps))
    xq = fine_model.quadrature_points().reshape(bar.fine_mesh.dim(), -1)[:, ip]
    steps = np.asarray(res.step_sizes if res.step_sizes is not None else [res.dt])
    n_qp = state.eqps.size
    hist = rec.history
    if c.model != "arlequin":  # the single-mesh history keeps the keys of its Interface
        hist.pop("coupling_work")
    result = TaylorBarResult(
        final_length=hist["length"][-1],
        mushroom_radius=hist["radius"][-1],
        max_plastic_strain=float(state.eqps.max()),
        energy_balance_error=float(max(rec.balance)),
        n_elements=bar.n_elements,
        mesh_size=c.radius / r.n_r,
        n_steps=int(res.n_steps),
        wall_time_s=wall_time,
        history=hist,
        elements_radial=r.n_r,
        elements_axial=n_z,
        max_plastic_strain_at=[float(x) for x in xq],
        initial_kinetic_energy=run.ke0,
        impact_loss=hist["contact_work"][0],
        fixed_point_iterations=rec.iteration_summary(),
        min_dt=float(steps[steps > 0].min()) if np.any(steps > 0) else float(res.dt),
        qp_updates_per_second=n_qp * res.n_steps / loop_time,
        setup_time_s=wall_time - loop_time,
        config=record,
        model=fine_model,
        u=res.u,
        state=state,
        setup=bar,
    )
    if c.model == "graded":
        fine_cells = bar.graded_fine_elements
        result.arlequin = {
            "coarse_elements": bar.n_elements - fine_cells, "fine_elements": fine_cells,
            "coarse_size": r.sizes.coarse_size, "fine_size": r.sizes.fine_size,
            "patch_length": r.sizes.patch_length,
        }  # fmt: skip
    if c.model == "arlequin":
        _arlequin_results(r, bar, run, result)
    return result


def _arlequin_results(r: Resolved, bar: Any, run: _Run, result: TaylorBarResult) -> None:
    """The Arlequin pair's results (sizes, the band's plastic strain, the multipliers' chatter,
    the step ratios) and the warning when plastic flow reaches the gluing band."""
    assert isinstance(bar, (ArlequinBar, ArlequinBar3D)) and run.multipliers is not None
    s = bar.sizes
    band_eqps = bar.band_plastic_strain(result.state)
    chatter = run.multipliers.chatter()
    result.arlequin = {
        "coarse_elements": bar.coarse_elements, "fine_elements": bar.fine_elements,
        "coarse_size": s.coarse_size, "fine_size": s.fine_size,
        "patch_fraction": bar.patch_fraction,
        "patch_length": getattr(bar, "patch_top", s.patch_length),
        "gluing_width": s.gluing_width, "band_max_plastic_strain": band_eqps,
        "multiplier_chatter": chatter["global"],
        "multiplier_chatter_per_row": chatter["per_row"],
    }  # fmt: skip
    result.multiplier_history = run.multipliers
    integ = run.integrator
    result.arlequin["coarse_step_ratio"] = int(r.coarse_step_ratio)
    if integ is not None:  # the ratio each macro step could use (≤ coarse_step_ratio)
        result.arlequin["macro_steps"] = int(integ.macro_steps)
        result.arlequin["mean_step_ratio"] = float(np.mean(integ.ratios))
    if band_eqps > r.band_warning:
        msg = (f"equivalent plastic strain in the gluing band reaches {band_eqps:.4f} > "
               f"{r.band_warning} (band_warning): the coarse model glued there is elastic; "
               f"lengthen the patch (patch_length={s.patch_length:.4g} m)")  # fmt: skip
        warnings.warn(msg, GluingBandPlasticityWarning, stacklevel=4)


def _finish(run: _Run, result: TaylorBarResult) -> None:
    """The results and pictures written, the folder marked complete, the checkpoint removed."""
    if run.folder is not None:
        write_results(run.folder, result, RESULT_UNITS)
    if run.saver is not None:
        run.saver.remove()
    logger.info(result.summary())
