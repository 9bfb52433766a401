"""The run of a pressure vessel: first yield, the load steps, what each step records."""

from __future__ import annotations

import logging
import time
import warnings
from collections.abc import Callable
from dataclasses import fields
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ...contract import CoarseYieldWarning, SimulationError
from ...io import QuasiStaticRunWriter, ResultsFolder, read_checkpoint, write_checkpoint
from ...solvers import solve_quasi_static
from ..adaptive_options import fixed_patch
from ..plastic_report import plastic_report
from .hill import (
    cylinder_first_yield,
    cylinder_limit_load,
    sphere_first_yield,
    sphere_limit_load,
    sphere_outer_displacement,
    sphere_plastic_radius,
)
from .measures import bore_value, plastic_radius, von_mises
from .result import HISTORY_KEYS, UNITS, PressureVesselResult
from .setup import VesselSetup, build

if TYPE_CHECKING:  # annotations only: the configuration runs this module
    from .config import PressureVesselConfig

__all__ = ["CHECKPOINT", "CoarseYieldWarning", "resume", "run"]


logger = logging.getLogger(__name__)

#: The recorder's measures in history.csv, with their units (the load first).
MEASURE_UNITS = {"pressure": "Pa", "plastic_radius": "m", "outer_displacement": "m",
                 "inner_displacement": "m", "patch_fraction": "1"}  # fmt: skip


class _Recorder:
    """The history of a run, one entry per converged step (an ``on_step`` listener)."""

    def __init__(self, config: PressureVesselConfig, setup: VesselSetup, bore_area: float):
        self.config, self.setup, self.bore_area = config, setup, bore_area
        q = setup.plastic_model.quadrature_points()
        self.radius = np.linalg.norm(np.asarray(q), axis=0)
        self.history: dict[str, list[Any]] = {k: [] for k in HISTORY_KEYS}
        self.fraction = _patch_fraction(setup.meshes)
        dm = setup.problem.system().dofmap
        self._append(0.0, np.zeros(dm.n_dofs), None, 0, [], dm)
        #: the first yield found by the run: (pressure, bore σ_vm) (Pa) of the last
        #: converged state with no plastic point (on the patch of that state), and the
        #: first-yield pressure once a point has yielded (:meth:`first_yield_pressure`)
        self.elastic: tuple[float, float] | None = None
        self.yielded = False

    def on_adapt(self, solver: Any, adapt: Any) -> None:
        """The patch grew: follow its mesh (quadrature points, inner node, bore dofs); an
        elastic state, re-solved on the grown patch at the same load, is measured again."""
        self.setup.follow(adapt)
        q = self.setup.plastic_model.quadrature_points()
        self.radius = np.linalg.norm(np.asarray(q), axis=0)
        self.fraction = _patch_fraction(self.setup.meshes)
        self.__dict__.pop("_er", None)
        self._watch_first_yield(solver)

    def _watch_first_yield(self, solver: Any) -> None:
        """Keep the last elastic state's pressure and bore von Mises stress (the response is
        linear up to first yield: σ_vm ∝ P at every point), until a point yields."""
        if self.yielded:
            return
        state = solver.states[self.setup.plastic_block][0]
        if np.any(np.asarray(state.eqps) > 0.0):
            self.yielded = True
            return
        pressure = self.pressure(solver)
        if pressure > 0.0:
            vm = bore_value(self.radius, von_mises(state), self.config.inner, self.config.fine)
            self.elastic = (pressure, vm)

    def first_yield_pressure(self) -> float | None:
        """The first-yield pressure (Pa) from the run's last elastic state, σy P / σ_vm(bore)
        on the patch that state was computed on (None before any loaded elastic state)."""
        if self.elastic is None:
            return None
        pressure, vm = self.elastic
        return self.config.yield_stress * pressure / vm

    def _append(self, pressure, u, state, iterations, residuals, dm) -> None:
        s = self.setup
        block, node = s.outer_node
        self.history["outer_displacement"].append(float(u[dm[block].node_dofs([node])[0, 0]]))
        block, node = s.inner_node
        self.history["inner_displacement"].append(float(u[dm[block].node_dofs([node])[0, 0]]))
        eqps = np.zeros_like(self.radius) if state is None else np.asarray(state.eqps)
        front = plastic_radius(self.radius, eqps, self.config.inner, self.config.fine)
        self.history["plastic_radius"].append(front)
        self.history["pressure"].append(float(pressure))
        self.history["newton_iterations"].append(int(iterations))
        self.history["residuals"].append([float(r) for r in residuals])
        self.history["patch_fraction"].append(float(self.fraction))

    def pressure(self, solver: Any) -> float:
        if self.config.load_pressure is not None:
            return solver.t * self.config.load_pressure
        # the bore's reactions: their work on a unit radial displacement over the bore's area
        r = solver.reactions()
        u_dir = self._bore_directions(solver.system)
        return float(r @ u_dir / self.bore_area)

    def _bore_directions(self, system) -> np.ndarray:
        """e_r on every bore dof of the prescribed blocks (a unit radial displacement)."""
        if not hasattr(self, "_er"):
            er = np.zeros(system.n_dofs)
            a = self.config.inner
            for block in self.setup.bore_blocks:
                mesh = system.block(block).model.mesh
                rr = np.linalg.norm(mesh.p, axis=0)
                nodes = np.nonzero(rr <= a * (1.0 + 1e-9))[0]
                dofs = system.dofmap[block].node_dofs(nodes)
                er[dofs] = mesh.p[:, nodes] / rr[nodes]
            self._er = er
        return self._er

    def __call__(self, solver: Any) -> None:
        rec = solver.history[-1]
        state = solver.states[self.setup.plastic_block][0]
        self._append(self.pressure(solver), solver.u, state, rec.iterations, rec.residuals,
                     solver.system.dofmap)  # fmt: skip
        self._watch_first_yield(solver)
        self.max_coarse_yield_ratio = max(self.max_coarse_yield_ratio, self._coarse_ratio(solver))

    max_coarse_yield_ratio = 0.0

    def last(self, solver: Any = None) -> dict[str, float]:
        """The measures of the last converged step (the columns of history.csv)."""
        return {k: self.history[k][-1] for k in MEASURE_UNITS}

    def _coarse_ratio(self, solver: Any) -> float:
        """The largest von Mises / σy of the coarse elastic model outside the patch (0 for
        ``mono``): above 1, the coarse model carries stresses the material cannot."""
        if self.setup.plastic_block == "coarse":
            return 0.0
        ratio = self.setup.problem.coarse_yield_ratio(solver.u, self.config.yield_stress)
        return 0.0 if ratio is None else ratio


def _bore_area(setup: VesselSetup, a: float) -> float:
    """The discrete area of the bore (m², over the modelled quarter: per radian for the
    sphere's 2πr measure as the models integrate it): the work of a unit pressure on a unit
    radial displacement, Σ f·e_r with f the nodal forces of the unit pressure."""
    model = setup.plastic_model
    mesh = model.mesh
    bf = mesh.boundary_facets()
    mid = mesh.p[:, mesh.facets[:, bf]].mean(axis=1)
    bore = bf[np.linalg.norm(mid, axis=0) <= a * (1.0 + 1e-9)]
    f = model.traction_vector(bore, lambda x, n: -n)
    rr = np.linalg.norm(mesh.p, axis=0)
    er = (mesh.p / rr).T.ravel()
    return float(f @ er)


def _first_yield(config: PressureVesselConfig, setup: VesselSetup) -> float:
    """The pressure of first yield (Pa) of a fixed patch (or mono): the elastic response is
    linear, so a load step well inside it gives σ_vm ∝ P at every point of the J2 model.

    An adaptive run reads it from its own last elastic state instead
    (:meth:`_Recorder.first_yield_pressure`, on the patch grown by then): the seed, one ring
    all gluing band, misses part of the stress's steep rise at the bore (+1.7% off Hill on the
    default sphere, +3.1% at b/a = 3, +5.0% at b/a = 5). Only where the run has no elastic
    state (its first load step yields) is it probed here on a fixed patch of two rings."""
    from ...solvers import QuasiStaticSolver

    two_rings = config.inner + 2.0 * config.coarse
    if config.adaptive and two_rings < config.outer - 0.5 * config.coarse:  # a ring outside
        probe = fixed_patch(config, patch_outer=two_rings)
        return _first_yield(probe, build(probe))

    solver = QuasiStaticSolver(setup.problem, load=1e-3, steps=1)
    solver.step()
    state = solver.states[setup.plastic_block][0]
    radius = np.linalg.norm(np.asarray(setup.plastic_model.quadrature_points()), axis=0)
    vm = bore_value(radius, von_mises(state), config.inner, config.fine)
    if config.load_pressure is not None:
        p = 1e-3 * config.load_pressure
    else:
        p = _Recorder(config, setup, _bore_area(setup, config.inner)).pressure(solver)
    return config.yield_stress * p / vm


def _reference(config: PressureVesselConfig, pressure: float) -> dict[str, float]:
    a, b, sy = config.inner, config.outer, config.yield_stress
    if config.shape == "sphere":
        return {
            "first_yield_pressure": sphere_first_yield(a, b, sy),
            "limit_load": sphere_limit_load(a, b, sy),
            "plastic_radius": sphere_plastic_radius(pressure, a, b, sy),
            "outer_displacement": sphere_outer_displacement(
                pressure, a, b, config.young, config.poisson, sy
            ),
        }
    return {
        "first_yield_pressure": cylinder_first_yield(a, b, config.poisson, sy),
        "limit_load": cylinder_limit_load(a, b, sy),
    }


CHECKPOINT = "checkpoint.pkl"


def run(config: PressureVesselConfig, out: str | None = None,
        progress: Callable[[float], None] | None = None,
        restore: dict[str, Any] | None = None) -> PressureVesselResult:  # fmt: skip
    """Run the vessel of ``config`` (see :mod:`arlequin.demos.pressure_vessel`); ``restore``
    (a checkpoint of ``out``, :func:`resume`) continues an interrupted run."""
    start = time.perf_counter()
    setup, bore_area = _start(config, restore)
    folder = (
        ResultsFolder(out, "arlequin pressure-vessel", config.inputs(), config.units())
        if out
        else None
    )
    recorder = _Recorder(config, setup, bore_area)
    if restore is not None:
        recorder.history = restore["history"]
        recorder.max_coarse_yield_ratio = restore["max_coarse_yield_ratio"]
        recorder.elastic, recorder.yielded = restore.get("elastic"), restore.get("yielded", False)
        first_yield = restore["first_yield_pressure"]
    elif setup.adapt is None:
        first_yield = _first_yield(config, setup)
    else:  # from the run itself, after it (_Recorder.first_yield_pressure)
        first_yield = None
    listeners = _listeners(config, setup, folder, recorder, first_yield, progress, restore)
    try:
        with warnings.catch_warnings():  # the demo says it itself, with the run's figure
            warnings.simplefilter("ignore", CoarseYieldWarning)
            qs = solve_quasi_static(
                setup.problem, load=1.0, steps=config.steps, on_step=listeners,
                adapt=setup.adapt, restore=None if restore is None else restore["solver"],
            )  # fmt: skip
    except SimulationError as err:  # a Newton failure, the patch's cap
        if folder is not None:
            folder.add_results(_so_far(recorder, setup))
            folder.finish("failed", str(err))
        raise
    except KeyboardInterrupt:  # every converged step is on disk, with its checkpoint
        if folder is not None:
            folder.add_results(_so_far(recorder, setup))
            folder.finish("interrupted", f"interrupted: continue with --resume --out {out}")
        raise
    if first_yield is None:
        first_yield = recorder.first_yield_pressure()
    if first_yield is None:  # the first load step yielded already: no elastic state to read
        logger.info("no elastic state before first yield: the first yield probed on two rings")
        first_yield = _first_yield(config, setup)
    result = _result(config, setup, qs, recorder, first_yield, time.perf_counter() - start)
    if folder is not None:
        from .report import write_pictures

        folder.add_results(dict(result.to_json()), UNITS)
        write_pictures(folder, setup, qs, result)
        folder.finish("complete", qs.message)
    logger.info("%s", result.summary())
    return result


def _start(config: PressureVesselConfig,
           restore: dict[str, Any] | None) -> tuple[VesselSetup, float]:  # fmt: skip
    """The set-up of a run and its bore's area (on the seed patch, as the uninterrupted run's);
    a resumed adaptive run's set-up follows the grown patch of its checkpoint."""
    setup = build(config)
    bore_area = _bore_area(setup, config.inner)
    if restore is None:
        return setup, bore_area
    if restore.get("config", config) != config:
        names = [f.name for f in fields(config) if getattr(config, f.name)
                 != getattr(restore["config"], f.name, None)]  # fmt: skip
        raise ValueError(f"the checkpoint is of another configuration (it differs in {names})")
    if (restore.get("adapt") is None) != (setup.adapt is None):
        other = "without" if setup.adapt is not None else "with"
        raise ValueError(f"the checkpoint is of a run {other} an adaptive patch, not of this "
                         f"configuration (adaptive={config.adaptive})")  # fmt: skip
    if setup.adapt is not None:  # the grown problem, the growths so far
        setup.adapt.resume(setup.problem, restore["adapt"])
        setup.follow(setup.adapt)
    return setup, bore_area


def _so_far(recorder: _Recorder, setup: VesselSetup) -> dict[str, Any]:
    """The results of the converged steps so far (a stopped run's results.json): the history,
    and the growths of an adaptive patch."""
    out: dict[str, Any] = {"history": recorder.history}
    if setup.adapt is not None:
        out["adaptations"] = [a.to_json() for a in setup.adapt.records]
    return out


def _listeners(config, setup, folder, recorder, first_yield, progress, restore) -> list:
    """What each converged step calls: the recorder, the results folder's writer (the frames
    and rows of a resumed run first written again), the adaptation pictures and results.json
    (an adaptive run), the checkpoint, the progress."""
    listeners: list[Callable[[Any], Any]] = [recorder]
    if folder is not None:
        from .report import AdaptationPictures, cell_fields

        system = setup.problem.system()
        layout = setup.problem.field_layout()
        units = {"eqps": "1", "von_mises": "Pa"}
        replay = None if restore is None else restore["replay"]
        writer = QuasiStaticRunWriter(folder, system, layout, cell_fields(setup), units,
                                      replay=replay, measures=recorder.last,
                                      measure_units=MEASURE_UNITS)  # fmt: skip
        listeners.append(writer)
        adapt = setup.adapt
        if adapt is not None:
            # the pictures of the growths so far (a resumed run's) are on disk already
            listeners.append(AdaptationPictures(folder, setup, recorder.history,
                                                count=len(adapt.records)))  # fmt: skip
            # results.json after every step: a hard stop keeps every converged step's history
            listeners.append(lambda solver: folder.add_results(_so_far(recorder, setup)))
        path = folder.path / CHECKPOINT

        def checkpoint(solver: Any) -> None:
            # an adaptive run's: its patch's (the grown problem is rebuilt from its cells)
            write_checkpoint(path, {
                "config": config, "solver": solver.checkpoint(), "history": recorder.history,
                "max_coarse_yield_ratio": recorder.max_coarse_yield_ratio,
                "first_yield_pressure": first_yield, "elastic": recorder.elastic,
                "yielded": recorder.yielded,
                "adapt": None if adapt is None else adapt.checkpoint(),
            })  # fmt: skip

        listeners.append(checkpoint)
    if progress is not None:
        listeners.append(lambda solver: progress(solver.t))
    return listeners


def _result(config, setup, qs, recorder, first_yield, wall) -> PressureVesselResult:
    """The result of a finished run (its warning if the patch was outgrown)."""
    mesh = setup.meshes
    n_el = (mesh.mono.nelements if mesh.mono is not None
            else mesh.coarse.nelements + mesh.patch.nelements)  # fmt: skip
    limit = qs.status == "limit_load"
    ratio = recorder.max_coarse_yield_ratio
    if qs.max_coarse_yield_ratio is not None:  # a growing patch: the solver's, at every step
        ratio = max(ratio, qs.max_coarse_yield_ratio)
    result = PressureVesselResult(
        first_yield_pressure=first_yield,
        limit_load_reached=limit,
        limit_load=recorder.history["pressure"][-1] if limit else None,
        n_elements=int(n_el),
        n_dofs=int(qs.u.size),
        patch_fraction=_patch_fraction(mesh),
        wall_time_s=wall,
        history=recorder.history,
        reference=_reference(config, recorder.history["pressure"][-1]),
        config=config.inputs(),
        adaptations=[a.to_json() for a in qs.adaptations],
        max_coarse_yield_ratio=ratio,
        **plastic_report(
            qs.problem or setup.problem,
            setup.plastic_block,
            setup.plastic_model,
            qs.states[setup.plastic_block][0],
            qs.band_plastic_fraction,
        ),
    )
    if ratio > 1.0:
        warnings.warn(
            f"the coarse elastic model outside the patch carries von Mises stresses up to "
            f"{ratio:.3f} times the yield stress: the plastic zone has outgrown the patch, "
            "and the results past that load are not those of the J2 material (widen "
            "--patch-outer, use --adaptive, or --model mono)",
            CoarseYieldWarning,
            stacklevel=3,
        )
    return result


def resume(out: str, progress: Callable[[float], None] | None = None) -> PressureVesselResult:
    """Continue the interrupted run whose results folder is ``out`` from its last converged
    step (its checkpoint), with the inputs it was started with; the same steps and values as
    the uninterrupted run (an adaptive run's from its grown patch, its growths so far and the
    field series they opened).

    Raises
    ------
    CheckpointError
        A ValueError: no checkpoint in ``out``, or an unreadable one.
    """
    snap = read_checkpoint(Path(out) / CHECKPOINT)
    # the rows and frames of the checkpoint's steps (not those written after it, if any)
    solver = snap["solver"]
    snap["replay"] = QuasiStaticRunWriter.written(out, steps=len(solver["history"]),
                                                  load_factor=solver["t"])  # fmt: skip
    # an adaptive run's series: one a growth (fields/patch0_K.xdmf), K up to the checkpoint's
    adapt = snap.get("adapt")
    snap["replay"]["growths"] = 0 if adapt is None else len(adapt["records"])
    return run(snap["config"], out=out, progress=progress, restore=snap)


def _patch_fraction(meshes: Any) -> float:
    """The patch's share of the wall: the area (a solid mesh: the volume) of the coarse cells
    it covers over the coarse mesh's, the measure of the growths' records
    (:attr:`~arlequin.adapt.Adaptation.patch_fraction`), so that the history and the records
    agree; 1 for mono. The patch is whole rings of coarse cells from the bore: it covers the
    cells whose nodes all lie within its outer radius (its bore nodes, on the circle, are
    off the coarse chords, so its own area would differ by those slivers)."""
    if meshes.patch is None:
        return 1.0
    import skfem

    coarse = meshes.coarse
    measure = np.asarray(skfem.CellBasis(coarse, coarse.elem()).dx).sum(axis=1)
    outer = np.linalg.norm(meshes.patch.p, axis=0).max()
    radius = np.linalg.norm(coarse.p, axis=0)[coarse.t].max(axis=0)
    covered = radius <= outer * (1.0 + 1e-9)
    return float(measure[covered].sum() / measure.sum())
