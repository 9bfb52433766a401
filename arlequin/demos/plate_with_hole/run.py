"""The run of the plate with a hole: the elastic response to first yield, the load steps past
it, what each state records."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from ...io import QuasiStaticRunWriter, ResultsFolder
from ...solvers import NewtonError, QuasiStaticSolver
from .result import HISTORY_KEYS, UNITS, PlateWithHoleResult
from .setup import PlateSetup, build, loaded_edge_average

if TYPE_CHECKING:  # annotations only: the configuration runs this module
    from .config import PlateWithHoleConfig

__all__ = ["plastic_measures", "run"]

logger = logging.getLogger(__name__)

#: The load factor of the probing elastic step (λ S, well below first yield).
PROBE = 1e-3


def plastic_measures(model: Any, eqps: np.ndarray) -> tuple[float, float]:
    """The plastic zone of a J2 model's state: its area (the quadrature weights with ε̄p > 0,
    m²) and its extent (the largest distance from the hole's centre of such a point, m)."""
    plastic = np.asarray(eqps) > 0.0
    if not plastic.any():
        return 0.0, 0.0
    dx = np.asarray(model.scalar_basis().dx)
    r = np.linalg.norm(np.asarray(model.quadrature_points()), axis=0)
    return float(dx[plastic].sum()), float(r[plastic].max())


class _Recorder:
    """The history of a run, one entry per converged state (an ``on_step`` listener)."""

    def __init__(self, config: PlateWithHoleConfig, setup: PlateSetup, system: Any):
        self.config, self.setup = config, setup
        self.edge = loaded_edge_average(setup, system, config.width)
        self.history: dict[str, list[Any]] = {k: [] for k in HISTORY_KEYS}

    def append(self, lam: float, u: np.ndarray, eqps: np.ndarray | None, iterations: int,
               residuals) -> None:  # fmt: skip
        h = self.history
        h["load"].append(float(lam * self.config.load))
        h["displacement"].append(float(self.edge @ u))
        area, extent = (0.0, 0.0) if eqps is None else plastic_measures(
            self.setup.plastic_model, eqps)  # fmt: skip
        h["plastic_area"].append(area)
        h["plastic_extent"].append(extent)
        h["newton_iterations"].append(int(iterations))
        h["residuals"].append([float(r) for r in residuals])

    def __call__(self, solver: Any) -> None:
        rec = solver.history[-1]
        s = self.setup
        state = solver.states[s.plastic_block][s.plastic_term]
        self.append(solver.t, solver.u, state.eqps, rec.iterations, rec.residuals)


def _steps(config: PlateWithHoleConfig, setup: PlateSetup, system: Any, recorder: _Recorder,
           listeners: list[Callable[[Any], Any]]) -> tuple[Any, float]:  # fmt: skip
    """The load path: a probing elastic step (λ = 1e-3: σ_vm ∝ λ at every quadrature point of
    the J2 model up to first yield, so it gives the load factor λ0 of first yield), the
    elastic step to λ0, then ``config.steps`` equal steps to λ = 1, every one by Newton from
    the last converged displacement and multipliers. Returns the solver and λ0."""
    solver = QuasiStaticSolver(system, load=1.0, steps=config.steps)
    solver.dt = PROBE
    solver.step()
    s = setup
    vm = float(np.max(np.asarray(solver.states[s.plastic_block][s.plastic_term].von_mises)))
    lam0 = PROBE * config.yield_stress / vm
    start = PROBE
    if lam0 < 1.0:
        solver.dt = lam0 - PROBE
        rec = solver.step()
        recorder.append(solver.t, solver.u, None, rec.iterations, rec.residuals)
        start = lam0
    solver.nominal = solver.dt = (1.0 - start) / config.steps
    solver.min_step = solver.nominal / 2**10
    while solver.status == "running":
        try:
            rec = solver.step()
        except NewtonError as err:
            err.result = solver.result(str(err))
            raise
        if rec is None:  # a limit load
            break
        for listener in listeners:
            listener(solver)
    return solver, lam0


def run(config: PlateWithHoleConfig, out: str | None = None,
        progress: Callable[[float], None] | None = None) -> PlateWithHoleResult:  # fmt: skip
    """Run the plate of ``config`` (see :mod:`arlequin.demos.plate_with_hole`)."""
    from .report import cell_fields, write_pictures

    start = time.perf_counter()
    setup = build(config)
    system = setup.problem.system()
    folder = (
        ResultsFolder(out, "arlequin plate-with-hole", config.inputs(), config.units())
        if out
        else None
    )
    recorder = _Recorder(config, setup, system)
    listeners: list[Callable[[Any], Any]] = [recorder]
    if folder is not None:
        layout = setup.problem.field_layout()
        units = {"eqps": "1", "von_mises": "Pa"}
        listeners.append(QuasiStaticRunWriter(folder, system, layout, cell_fields(setup), units))
    if progress is not None:
        listeners.append(lambda solver: progress(solver.t))
    recorder.append(0.0, np.zeros(system.n_dofs), None, 0, [])
    try:
        solver, lam0 = _steps(config, setup, system, recorder, listeners)
    except NewtonError as err:
        if folder is not None:
            folder.add_results({"history": recorder.history}, UNITS)
            folder.finish("failed", str(err))
        raise
    qs = solver.result()
    result = PlateWithHoleResult(
        history=recorder.history,
        wall_time_s=time.perf_counter() - start,
        n_elements=setup.n_elements,
        patch_fraction=setup.patch_fraction,
        n_dofs=int(system.n_dofs),
        first_yield_load=float(lam0 * config.load),
        status=qs.status,
        config=config.inputs(),
    )
    if folder is not None:
        folder.add_results(result.to_json(), UNITS)
        write_pictures(folder, setup, qs, result)
        folder.finish("complete", qs.message)
    logger.info("%s", result.summary())
    return result
