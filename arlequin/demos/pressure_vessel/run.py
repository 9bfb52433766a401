"""The run of a pressure vessel: first yield, the load steps, what each step records."""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from ...contract import SimulationError
from ...io import QuasiStaticRunWriter, ResultsFolder
from ...solvers import solve_quasi_static
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

__all__ = ["run"]

logger = logging.getLogger(__name__)


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

    def on_adapt(self, solver: Any, adapt: Any) -> None:
        """The patch grew: follow its mesh (quadrature points, inner node, bore dofs)."""
        self.setup.follow(adapt)
        q = self.setup.plastic_model.quadrature_points()
        self.radius = np.linalg.norm(np.asarray(q), axis=0)
        self.fraction = _patch_fraction(self.setup.meshes)
        self.__dict__.pop("_er", None)

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
    """The pressure of first yield (Pa): the elastic response is linear, so a load step well
    inside it gives σ_vm ∝ P at every point of the J2 model."""
    from ...solvers import QuasiStaticSolver

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


def run(config: PressureVesselConfig, out: str | None = None,
        progress: Callable[[float], None] | None = None) -> PressureVesselResult:  # fmt: skip
    """Run the vessel of ``config`` (see :mod:`arlequin.demos.pressure_vessel`)."""
    from .report import AdaptationPictures, cell_fields, write_pictures

    start = time.perf_counter()
    setup = build(config)
    system = setup.problem.system()
    folder = (
        ResultsFolder(out, "arlequin pressure-vessel", config.inputs(), config.units())
        if out
        else None
    )
    recorder = _Recorder(config, setup, _bore_area(setup, config.inner))
    listeners: list[Callable[[Any], Any]] = [recorder]
    if folder is not None:
        layout = setup.problem.field_layout()
        units = {"eqps": "1", "von_mises": "Pa"}
        writer = QuasiStaticRunWriter(folder, system, layout, cell_fields(setup), units)
        listeners.append(writer)
        if setup.adapt is not None:
            listeners.append(AdaptationPictures(folder, setup))
    if progress is not None:
        listeners.append(lambda solver: progress(solver.t))
    try:
        first_yield = _first_yield(config, setup)
        qs = solve_quasi_static(setup.problem, load=1.0, steps=config.steps, on_step=listeners,
                                adapt=setup.adapt)  # fmt: skip
    except SimulationError as err:
        if folder is not None:
            folder.add_results({"history": recorder.history})
            folder.finish("failed", str(err))
        raise
    mesh = setup.meshes
    n_el = (mesh.mono.nelements if mesh.mono is not None
            else mesh.coarse.nelements + mesh.patch.nelements)  # fmt: skip
    limit = qs.status == "limit_load"
    result = PressureVesselResult(
        first_yield_pressure=first_yield,
        limit_load_reached=limit,
        limit_load=recorder.history["pressure"][-1] if limit else None,
        n_elements=int(n_el),
        n_dofs=int(system.n_dofs),
        patch_fraction=_patch_fraction(mesh),
        wall_time_s=time.perf_counter() - start,
        history=recorder.history,
        reference=_reference(config, recorder.history["pressure"][-1]),
        config=config.inputs(),
        adaptations=[a.to_json() for a in qs.adaptations],
        max_coarse_yield_ratio=qs.max_coarse_yield_ratio,
    )
    if folder is not None:
        folder.add_results({k: v for k, v in result.to_json().items()}, UNITS)
        write_pictures(folder, setup, qs, result)
        folder.finish("complete", qs.message)
    logger.info("%s", result.summary())
    return result


def _patch_fraction(meshes: Any) -> float:
    """The patch's share of the wall's area (1 for mono)."""
    return 1.0 if meshes.patch is None else _area(meshes.patch) / _area(meshes.coarse)


def _area(mesh: Any) -> float:
    p = mesh.p[:, mesh.t]  # (2, 4, n): a quadrilateral's area by the shoelace formula
    x, y = p[0], p[1]
    return float(0.5 * np.abs(np.sum(x * np.roll(y, -1, axis=0) - y * np.roll(x, -1, axis=0),
                                     axis=0)).sum())  # fmt: skip
