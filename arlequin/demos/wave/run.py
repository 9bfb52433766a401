"""The wave demo's run, as named steps: the time step, the coupled run, the single-mesh
reference, the reflected and transmitted energies.

Reflection is measured so that numerical dispersion is not counted: the reflected wave is the
difference, in the coarse-only region [0, X_p], between the coupled coarse solution and a single
coarse-mesh run of the same pulse with the same integrator and time step, taken at the snapshot
time t_m = (W + G + 10) h / c, when the pulse's tail (moving at most at c) has cleared the gluing
band by 5 h, while the transmitted pulse is still 10 h short of the far end (nothing reflected from
it can have returned). Its energy (kinetic with the integrator's mass, plus strain, on the coarse
elements of [0, X_p]) over the incident energy (the pulse's initial energy) is the reflected
fraction. The transmitted fraction is the α-weighted energy of both models in the patch's free
zone [X_p + G, L] at t_m over the incident energy. The energy drift is max_t |E(t) − E(0)|/E(0)
of the coupled run (E the α-weighted kinetic plus strain energy).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import skfem

from ...io import DynamicRunWriter, ResultsFolder
from ...models import LinearElastic
from ...problem.system import Block, BlockTerm, CoupledSystem
from ...solvers import (
    DEFAULT_SAFETY,
    CentralDifference,
    check_time_step,
    get_integrator,
    solve,
    stable_time_step,
)
from ...solvers.dynamics.controllers import check_step
from .report import write_results
from .result import WaveResult
from .setup import H, WaveSetup, build_wave

if TYPE_CHECKING:
    from .config import WaveConfig

__all__ = ["run_config"]

logger = logging.getLogger(__name__)


def _region_energy(
    model: LinearElastic,
    weight: float,
    cells: np.ndarray,
    u: np.ndarray,
    v: np.ndarray,
    lumped: bool,
) -> float:
    """Energy (J) of the given cells of a 1D model (weight constant there)."""
    sub = LinearElastic(
        skfem.MeshLine(np.sort(model.mesh.p[0, np.unique(model.mesh.t[:, cells])])),
        model.material,
        area=model.area,
    )
    nodes = np.unique(model.mesh.t[:, cells])
    order = np.argsort(model.mesh.p[0, nodes])
    nodes = nodes[order]
    us, vs = u[nodes], v[nodes]
    k = sub.stiffness(weight)
    m = sub.mass(weight, lumped=lumped)
    kin = 0.5 * float(vs @ (m * vs if lumped else m @ vs))
    return kin + 0.5 * float(us @ (k @ us))


def _time_step(config: WaveConfig, setup: WaveSetup, cls) -> tuple[float, int]:
    """The step (s; default 0.9 of the coupled explicit critical step, a given one checked
    against it for central differences) and the number of steps to the snapshot."""
    dt = None if config.dt is None else check_step(config.dt, "time step dt (s)")
    stable = stable_time_step(setup.system)
    if dt is None:
        dt = DEFAULT_SAFETY * stable.critical
    elif issubclass(cls, CentralDifference):
        check_time_step(dt, stable)  # implicit schemes are unconditionally stable here
    t_m = setup.layout["travel"] * H / setup.c
    return dt, math.ceil(t_m / dt)


def _coupled_run(config: WaveConfig, setup: WaveSetup, dt: float, n_steps: int, opts: dict,
                 folder: ResultsFolder | None,
                 progress: Callable[[float], None] | None):  # fmt: skip
    """The coupled run from the pulse (the patch at rest), its fields written to ``folder``."""
    fm, system = setup.fine, setup.system
    u0 = {"coarse": setup.u0c, "patch0": np.zeros(fm.n_dofs)}
    v0 = {"coarse": setup.v0c, "patch0": np.zeros(fm.n_dofs)}
    writers = []
    if folder is not None:
        frames = np.linspace(0.0, n_steps * dt, 51)
        writers.append(DynamicRunWriter(folder, system, setup.problem.field_layout(), frames))
    if progress is not None:
        every = max(1, n_steps // 200)

        def report(integ, every=every, n=n_steps) -> None:
            if integ.step_count % every == 0 or integ.step_count == n:
                progress(integ.step_count / n)

        writers.append(report)
    return solve(system, config.registry_name, n_steps=n_steps, dt=dt, u0=u0, v0=v0,
                 on_record=writers, save_fields=folder is not None, **opts)  # fmt: skip


def _reference_run(config: WaveConfig, setup: WaveSetup, dt: float, n_steps: int, opts: dict):
    """The coarse model alone, same pulse, integrator and step (its final state)."""
    cm = setup.coarse
    ref_system = CoupledSystem([Block("coarse", cm, [BlockTerm(cm)])])
    return solve(
        ref_system,
        config.registry_name,
        n_steps=n_steps,
        dt=dt,
        u0={"coarse": setup.u0c},
        v0={"coarse": setup.v0c},
        record_every=n_steps,
        **opts,
    )


def _energies(config: WaveConfig, setup: WaveSetup, res, ref, lumped: bool):
    """The reflected and transmitted energies (J) at the snapshot, and the band's end (in
    coarse elements)."""
    cm, fm, lay = setup.coarse, setup.fine, setup.layout
    coarse_mesh, fine_mesh = setup.coarse_mesh, setup.fine_mesh
    split = setup.system.split(res.u)
    split_v = setup.system.split(res.v)
    du = split["coarse"] - ref.u
    dv = split_v["coarse"] - ref.v
    centers = coarse_mesh.p[0, coarse_mesh.t].mean(axis=0) / H
    only = np.nonzero(centers < lay["x_patch"])[0]
    reflected = _region_energy(cm, 1.0, only, du, dv, lumped)
    # transmitted: α-weighted energy of both models in the free zone
    epsilon = config.epsilon
    band_end = setup.problem.couplings[0].gluing_width / H + lay["x_patch"]
    free_c = np.nonzero(centers > band_end)[0]
    fcent = fine_mesh.p[0, fine_mesh.t].mean(axis=0) / H
    free_f = np.nonzero(fcent > band_end)[0]
    transmitted = _region_energy(cm, epsilon, free_c, split["coarse"], split_v["coarse"], lumped)
    transmitted += _region_energy(
        fm, 1.0 - epsilon, free_f, split["patch0"], split_v["patch0"], lumped
    )
    return reflected, transmitted, band_end


def _result(config: WaveConfig, setup: WaveSetup, res, ref, dt: float, n_steps: int,
            lumped: bool, keep_run: bool) -> WaveResult:  # fmt: skip
    """The result of the runs: the energy fractions, the drift, the snapshot's fields."""
    reflected, transmitted, band_end = _energies(config, setup, res, ref, lumped)
    e0 = float(res.total_energy[0])
    split = setup.system.split(res.u)
    mult = [np.max(np.abs(m)) for k, m in res.multipliers.items() if k.startswith("coupling")]
    summary_config = {
        "ratio": int(config.ratio),
        "pulse_width": config.pulse_width,
        "gluing_width": config.gluing_width,
        "coupling": config.coupling,
        "mediator": config.mediator,
        "weights": config.weights,
        "integrator": config.integrator,
        "epsilon": config.epsilon,
        "snapshot_time": n_steps * dt,
        "length": config.length,
    }
    fields = {
        "x_coarse": setup.coarse_mesh.p[0],
        "u_coarse": split["coarse"],
        "u_reference": ref.u,
        "u0_coarse": setup.u0c,
        "x_fine": setup.fine_mesh.p[0],
        "u_fine": split["patch0"],
        "x_patch": setup.layout["x_patch"] * H,
        "band_end": band_end * H,
        "times": res.times,
        "energy": res.total_energy,
    }
    return WaveResult(
        reflected_energy_fraction=reflected / e0,
        transmitted_energy_fraction=transmitted / e0,
        energy_drift=res.energy_drift(),
        dt=float(dt),
        n_steps=n_steps,
        incident_energy=e0,
        config=summary_config,
        multiplier_max=float(max(mult)) if mult else 0.0,
        coupling_work_max=float(np.max(np.abs(res.coupling_work["coarse"]))),
        fields=fields,
        dynamic=res if keep_run else None,
    )


def run_config(config: WaveConfig, out: str | Path | None = None,
               progress: Callable[[float], None] | None = None) -> WaveResult:  # fmt: skip
    """Run the wave demo of ``config`` (see :func:`run_wave`)."""
    cls = get_integrator(config.registry_name)
    folder = None
    if out is not None:
        # the inputs as run: the ratio an integer, a given step a float
        dt = None if config.dt is None else check_step(config.dt, "time step dt (s)")
        inputs = {**config.inputs(), "ratio": int(config.ratio), "dt": dt}
        folder = ResultsFolder(out, "arlequin wave", inputs, config.units())
    setup = build_wave(config)
    dt, n_steps = _time_step(config, setup, cls)
    lumped = bool(cls.lumped_default)
    opts = {"check_dt": False} if issubclass(cls, CentralDifference) else {}
    res = _coupled_run(config, setup, dt, n_steps, opts, folder, progress)
    ref = _reference_run(config, setup, dt, n_steps, opts)
    result = _result(config, setup, res, ref, dt, n_steps, lumped, folder is not None)
    logger.info(result.summary())
    if folder is not None:
        write_results(folder, result)
    return result
