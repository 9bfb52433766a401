"""The run of the plate with a hole: the elastic response to first yield, the load steps past
it, what each state records."""

from __future__ import annotations

import logging
import time
import warnings
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from ...contract import BandYieldWarning, CoarseYieldWarning, SimulationError
from ...io import QuasiStaticRunWriter, ResultsFolder
from ...problem.adapt import cell_rings
from ...solvers import NewtonError, QuasiStaticSolver
from ...solvers.statics.adaptive import run_adaptive
from ...solvers.system.yield_watch import BandYieldWatch
from ..adaptive_options import fixed_patch
from ..plastic_report import plastic_report
from .result import HISTORY_KEYS, UNITS, PlateWithHoleResult
from .setup import PlateSetup, area, build, loaded_edge_average

if TYPE_CHECKING:  # annotations only: the configuration runs this module
    from .config import PlateWithHoleConfig

__all__ = ["plastic_measures", "run"]

logger = logging.getLogger(__name__)

#: The load factor of the probing elastic step (λ S, well below first yield).
PROBE = 1e-3
#: The recorder's measures in history.csv, with their units (the nominal stress first).
MEASURE_UNITS = {"load": "Pa", "displacement": "m", "plastic_area": "m^2",
                 "plastic_extent": "m", "patch_fraction": "1"}  # fmt: skip


def plastic_measures(model: Any, eqps: np.ndarray) -> tuple[float, float]:
    """The plastic zone of a J2 model's state: its area (the quadrature weights with ε̄p > 0,
    m²) and its extent (the largest distance from the hole's centre of such a point, m)."""
    plastic = np.asarray(eqps) > 0.0
    if not plastic.any():
        return 0.0, 0.0
    dx = np.asarray(model.scalar_basis().dx)
    r = np.linalg.norm(np.asarray(model.quadrature_points()), axis=0)
    return float(dx[plastic].sum()), float(r[plastic].max())


def plastic_cover_fraction(setup: PlateSetup, eqps: np.ndarray, rings: int) -> float | None:
    """The share of the plate's area of the smallest nested patch holding the plastic zone
    and its gluing band: the coarse cells over a fine cell with ε̄p > 0, plus ``rings``
    layers of coarse cells around them (None without a coarse model over a patch). An
    adaptive patch's measure of tightness: its area over this one."""
    if setup.plastic_block == "coarse":
        return None
    pc = setup.problem.couplings[0]
    parent = np.empty(setup.plastic_model.mesh.nelements, dtype=np.int64)
    parent[pc.overlap.fine_cells] = pc.overlap.coarse_cells
    cover = np.zeros(setup.coarse.nelements, dtype=bool)
    cover[parent[(np.asarray(eqps) > 0.0).any(axis=1)]] = True
    if not cover.any():
        return 0.0
    cover = cell_rings(setup.coarse, cover, rings)
    cells = area(setup.coarse.restrict(np.nonzero(cover)[0]))
    return cells / area(setup.coarse)


def band_fraction(setup: PlateSetup) -> float | None:
    """The share of the plate's area of the patch's gluing band (its fine cells' area; None
    without a coarse model over a patch)."""
    if setup.plastic_block == "coarse":
        return None
    cells = setup.problem.couplings[0].fine_gluing_cells
    return area(setup.plastic_model.mesh.restrict(cells)) / area(setup.coarse)


class _Recorder:
    """The history of a run, one entry per converged state (an ``on_step`` listener)."""

    def __init__(self, config: PlateWithHoleConfig, setup: PlateSetup, system: Any):
        self.config, self.setup = config, setup
        self.edge = loaded_edge_average(setup, system, config.width)
        self.history: dict[str, list[Any]] = {k: [] for k in HISTORY_KEYS}
        self.max_coarse_yield_ratio = 0.0
        self.adaptations: list[dict[str, Any]] = []
        # the patch's gluing band after each accepted step (its warning: the run's own, at
        # the end, with the figure)
        self.band = BandYieldWatch(lambda: self.setup.problem)

    def on_adapt(self, solver: Any, adapt: Any) -> None:
        """The patch grew: follow its problem (the loaded edge's dofs, the J2 model)."""
        self.setup.follow(adapt)
        self.edge = loaded_edge_average(self.setup, solver.system, self.config.width)
        self.adaptations = [a.to_json() for a in adapt.records]

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
        h["patch_fraction"].append(float(self.setup.patch_fraction))

    def __call__(self, solver: Any) -> None:
        rec = solver.history[-1]
        s = self.setup
        state = solver.states[s.plastic_block][s.plastic_term]
        self.append(solver.t, solver.u, state.eqps, rec.iterations, rec.residuals)
        if s.plastic_block != "coarse":  # a coarse elastic model over a patch
            value = s.problem.coarse_yield_ratio(solver.u, self.config.yield_stress)
            self.max_coarse_yield_ratio = max(self.max_coarse_yield_ratio, value or 0.0)
            self.band(solver)

    def last(self, solver: Any = None) -> dict[str, float]:
        """The measures of the last converged state (the columns of history.csv)."""
        return {k: self.history[k][-1] for k in MEASURE_UNITS}

    def results(self) -> dict[str, Any]:
        """What the run has so far (written to results.json after each step, and at a
        failure): every converged state, the growths, the coarse model's largest yield ratio."""
        return {"history": self.history, "adaptations": self.adaptations,
                "max_coarse_yield_ratio": self.max_coarse_yield_ratio}  # fmt: skip


def _probe(solver: Any, setup: PlateSetup, yield_stress: float) -> float:
    """The load factor λ0 of first yield from a probing elastic step of ``solver`` (λ = 1e-3:
    σ_vm ∝ λ at every quadrature point of the J2 model up to first yield)."""
    solver.dt = PROBE
    solver.step()
    state = solver.states[setup.plastic_block][setup.plastic_term]
    return PROBE * yield_stress / float(np.max(np.asarray(state.von_mises)))


def _first_yield_of_seed(config: PlateWithHoleConfig) -> float:
    """λ0 of an adaptive run: the probe on the smallest fixed patch whose gluing band leaves
    the hole's rings outside it ([0, 2a + band]²). The seed is its own gluing band: the
    coarse mediator there holds the fine field to the coarse one, whose 8 cells along the
    quarter hole miss part of the stress concentration (1 level: first yield at 98.72 MPa on
    the seed, 96.08 on that patch, 95.92 on the default fixed patch)."""
    band = config.gluing_rings * config.coarse_size
    probe = fixed_patch(config, patch_radius=config.block + band)
    setup = build(probe)
    return _probe(QuasiStaticSolver(setup.problem, load=1.0, steps=1), setup, config.yield_stress)


def _steps(config: PlateWithHoleConfig, setup: PlateSetup, system: Any, recorder: _Recorder,
           listeners: list[Callable[[Any], Any]]) -> tuple[Any, float]:  # fmt: skip
    """The load path: a probing elastic step (:func:`_probe`, giving the load factor λ0 of
    first yield), the elastic step to λ0, then ``config.steps`` equal steps to λ = 1, every
    one by Newton from the last converged displacement and multipliers. Returns the solver and
    λ0. The step to λ0 is recorded, and written to the results folder's rows without a frame
    (a writer's ``rows``); the probe is not."""
    problem = setup.problem if setup.adapt is None else setup.adapt.bind(setup.problem)
    solver = QuasiStaticSolver(problem, load=1.0, steps=config.steps)
    if setup.adapt is None:
        lam0, start = _probe(solver, setup, config.yield_stress), PROBE
    else:
        lam0, start = _first_yield_of_seed(config), 0.0
    if lam0 < 1.0:
        solver.dt = lam0 - start
        rec = solver.step()
        recorder.append(solver.t, solver.u, None, rec.iterations, rec.residuals)
        for listener in listeners:
            if callable(getattr(listener, "rows", None)):
                listener.rows(solver)
        start = lam0
    solver.nominal = solver.dt = (1.0 - start) / config.steps
    solver.min_step = solver.nominal / 2**10
    if setup.adapt is not None:  # the growing patch's load stepping (its listeners told)
        run_adaptive(solver, setup.adapt, listeners)
        return solver, lam0
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
    from .report import write_pictures

    start = time.perf_counter()
    setup = build(config)
    system = setup.problem.system()
    folder = (
        ResultsFolder(out, "arlequin plate-with-hole", config.inputs(), config.units())
        if out
        else None
    )
    recorder = _Recorder(config, setup, system)
    listeners = _listeners(setup, system, folder, recorder, progress)
    recorder.append(0.0, np.zeros(system.n_dofs), None, 0, [])
    try:
        with warnings.catch_warnings():  # the demo says it itself, with the run's figure
            warnings.simplefilter("ignore", CoarseYieldWarning)
            warnings.simplefilter("ignore", BandYieldWarning)
            solver, lam0 = _steps(config, setup, system, recorder, listeners)
    except SimulationError as err:  # a Newton failure, the adaptive patch's cap
        if folder is not None:
            folder.add_results(recorder.results(), UNITS)
            folder.finish("failed", str(err))
        raise
    except KeyboardInterrupt:  # every converged step is on disk
        if folder is not None:
            folder.add_results(recorder.results(), UNITS)
            folder.finish("interrupted", "interrupted")
        raise
    qs = solver.result()
    state = solver.states[setup.plastic_block][setup.plastic_term]
    result = PlateWithHoleResult(
        history=recorder.history,
        wall_time_s=time.perf_counter() - start,
        n_elements=setup.n_elements,
        patch_fraction=setup.patch_fraction,
        n_dofs=int(solver.system.n_dofs),
        first_yield_load=float(lam0 * config.load),
        status=qs.status,
        config=config.inputs(),
        adaptations=list(recorder.adaptations),
        max_coarse_yield_ratio=_coarse_ratio(setup, recorder),
        plastic_cover_fraction=plastic_cover_fraction(setup, state.eqps, config.gluing_rings),
        band_fraction=band_fraction(setup),
        **plastic_report(
            setup.problem, setup.plastic_block, setup.plastic_model, state, recorder.band.fraction
        ),
    )
    if folder is not None:
        folder.add_results(result.to_json(), UNITS)
        write_pictures(folder, setup, qs, result)
        folder.finish("complete", qs.message)
    if (result.max_coarse_yield_ratio or 0.0) > 1.0:
        warnings.warn(
            f"the coarse elastic model outside the patch carries von Mises stresses up to "
            f"{result.max_coarse_yield_ratio:.3f} times the yield stress: the plastic zone has "
            "outgrown the patch (widen --patch-radius, use --adaptive, or --model mono)",
            CoarseYieldWarning,
            stacklevel=3,
        )
    _warn_band(result)
    logger.info("%s", result.summary())
    return result


def _warn_band(result: PlateWithHoleResult) -> None:
    """The run's BandYieldWarning, with its figures, if the patch yielded in its band."""
    if (result.band_plastic_fraction or 0.0) > 0.0:
        warnings.warn(
            f"the patch yielded in its gluing band ({result.band_plastic_fraction:.3g} of the "
            "band plastic at the worst step): the band's fields are the coupling's, not the "
            "material's (widen --patch-radius, or use --adaptive)",
            BandYieldWarning,
            stacklevel=3,
        )


def _listeners(setup: PlateSetup, system: Any, folder: ResultsFolder | None,
               recorder: _Recorder, progress: Callable[[float], None] | None) -> list:  # fmt: skip
    """What each converged step calls: the recorder, the results folder's writer (the frames,
    Newton's rows) and the history so far in results.json (an interrupted run, a failed one
    and one stopped at the adaptive patch's cap keep every converged step on disk), the
    pictures of the growths, the progress."""
    listeners: list[Callable[[Any], Any]] = [recorder]
    if folder is not None:
        from .report import AdaptationPictures, cell_fields

        layout = setup.problem.field_layout()
        units = {"eqps": "1", "von_mises": "Pa"}
        listeners.append(QuasiStaticRunWriter(folder, system, layout, cell_fields(setup), units,
                                              measures=recorder.last,
                                              measure_units=MEASURE_UNITS))  # fmt: skip
        listeners.append(lambda solver: folder.add_results(recorder.results(), UNITS))
        if setup.adapt is not None:
            listeners.append(AdaptationPictures(folder, setup, recorder.config.radius,
                                                recorder.config.load))  # fmt: skip
    if progress is not None:
        listeners.append(lambda solver: progress(solver.t))
    return listeners


def _coarse_ratio(setup: PlateSetup, recorder: _Recorder) -> float | None:
    """The largest von Mises / σy of the coarse elastic model outside the patch over the run
    (0 for mono, None for the graded mesh: no coarse model over a patch)."""
    if setup.adapt is not None:  # the adaptation's, at every step
        return max(recorder.max_coarse_yield_ratio, setup.adapt.max_coarse_yield_ratio)
    if setup.plastic_block == "coarse":
        return 0.0 if setup.zone_cells is None else None
    return recorder.max_coarse_yield_ratio
