"""Adaptive patches: a nested patch that grows where the material starts to yield (issue 31).

An :class:`AdaptivePatch` given to :func:`arlequin.solve_quasi_static` (``adapt=``) watches one
nested patch of an :class:`~arlequin.problem.arlequin_problem.ArlequinProblem` (a region of the
coarse mesh refined ``levels`` times) after each converged load step:

* the *indicator* flags coarse cells: by default those outside the patch whose von Mises stress
  (the coarse model's linear elastic stress at its quadrature points) reaches β (``threshold``,
  default 0.8) of the patch material's yield stress, and, where the patch's plastic zone
  (ε̄p > 0) comes within ``band_cells`` fine cells of its gluing band, the coarse cells next to
  the patch there; any callable of an :class:`AdaptView` may replace it (one flag per coarse
  cell);
* a step after which a coarse cell outside the patch carries more than the yield stress is not
  accepted: the patch grows and the step is computed again from the committed state;
* the flagged cells plus ``buffer`` rings of coarse cells join the patch: the new patch is the
  refinement of the old coarse cells and the new ones (``refine(cells)``, default
  :func:`~arlequin.coupling.patches.refine_region` with the patch's levels), its model built by
  ``model_factory(mesh)``, the overlap, weights, gluing band and coupling rows rebuilt
  (:meth:`ArlequinProblem.with_patches`);
* the fields move to the new patch (:meth:`AdaptivePatch.grow`): the old fine nodes and cells
  keep their displacement and state (matched by coordinates and centroids), the new fine nodes
  take the coarse displacement interpolated (exact for nested meshes), the new cells a virgin
  state (the coarse model is elastic there: no plastic strain); the solver then re-solves the
  multipliers by Newton at the same load.

Beyond ``max_fraction`` of the coarse mesh's area the run stops with :class:`PatchLimitError`
(every converged step kept). The core never imports the models: the patch's model is asked
for the optional members of :class:`arlequin.contract.SupportsCellStates`. SI units.
"""

from __future__ import annotations

import logging
import math
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from scipy.spatial import cKDTree
from skfem import CellBasis

from ..contract import ContractError, SimulationError, SupportsCellStates
from ..coupling.exactness import ExactnessWarning
from ..coupling.fields import evaluate_field
from ..coupling.patches import refine_region
from ..geometry.locate import cell_centroids
from ..geometry.reference import scalar_element_for
from .adaptation import Adaptation, check_bounds, check_settings
from .arlequin_problem import ArlequinProblem, von_mises_of

__all__ = [
    "AdaptView",
    "Adaptation",
    "AdaptivePatch",
    "Growth",
    "IndicatorError",
    "NonNestedPatchError",
    "PatchLimitError",
    "cell_rings",
]

logger = logging.getLogger(__name__)


class NonNestedPatchError(ValueError):
    """Adaptation needs a nested patch (coarse cells refined); this patch is not one."""


class IndicatorError(ValueError):
    """A user indicator returned something else than one flag per coarse cell."""


class PatchLimitError(SimulationError):
    """The patch would exceed ``max_fraction`` of the coarse mesh: the run stops (``result``
    holds every converged step, ``step`` and ``time`` the step that asked for the growth)."""


@dataclass(frozen=True)
class AdaptView:
    """What an indicator sees after a converged step (read only).

    Attributes
    ----------
    step : int
    time : float
        The load factor λ.
    problem : ArlequinProblem
    coarse_u, patch_u : ndarray
        The blocks' displacements (m).
    patch_state : object
        The patch model's committed state.
    patch_cells : ndarray of int
        The coarse cells the patch covers.
    coarse_von_mises : ndarray, shape (n_coarse_cells,)
        The coarse model's largest von Mises stress in each cell (Pa).
    yield_stress : float
        The patch material's initial yield stress (Pa).
    """

    step: int
    time: float
    problem: ArlequinProblem
    coarse_u: np.ndarray
    patch_u: np.ndarray
    patch_state: Any
    patch_cells: np.ndarray
    coarse_von_mises: np.ndarray
    yield_stress: float


@dataclass(frozen=True)
class Growth:
    """The verdict of :meth:`AdaptivePatch.assess`: the coarse cells of the next patch, and
    whether the step must be computed again."""

    cells: np.ndarray
    reject: bool


def cell_rings(mesh: Any, mask: np.ndarray, rings: int) -> np.ndarray:
    """``mask`` of cells grown by ``rings`` layers of cells sharing a node with it."""
    out = mask.copy()
    for _ in range(int(rings)):
        nodes = np.zeros(mesh.nvertices, dtype=bool)
        nodes[mesh.t[:, out]] = True
        out = out | nodes[mesh.t].any(axis=0)
    return out


def _plane_measures(mesh: Any) -> np.ndarray:
    """The cells' plane measures (m², m³), whatever the models' kinematics."""
    return np.asarray(CellBasis(mesh, scalar_element_for(mesh)).dx).sum(axis=1)


def _match(old: np.ndarray, new: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """(new indices, old indices) of the points of ``new`` (dim, n) within ``tol`` of one of
    ``old``."""
    dist, idx = cKDTree(old.T).query(new.T, distance_upper_bound=tol)
    hit = np.isfinite(dist)
    return np.nonzero(hit)[0], idx[hit]


class AdaptivePatch:
    """A nested patch that grows where the material starts to yield (module docstring).

    Parameters
    ----------
    model_factory : callable, optional
        ``model_factory(mesh) -> Model``: the patch's model on a new mesh (default the patch
        model's ``with_mesh``). It must have the members of
        :class:`~arlequin.contract.SupportsCellStates`.
    levels : int, optional
        Refinement levels of the patch (default: read from the patch, fine cells per coarse
        cell = 2^(dim levels)).
    refine : callable, optional
        ``refine(cells) -> mesh``: the patch mesh of coarse ``cells`` (default
        ``refine_region(coarse_mesh, levels, cells=cells)``; give one that projects curved
        boundary nodes as the patch was built).
    threshold : float
        β in (0, 1]: the coarse cells whose von Mises stress reaches β σ_y join the patch.
    buffer : int
        Rings of coarse cells added around the flagged ones.
    band_cells : int
        The plastic zone within this many fine cells of the gluing band grows the patch.
    every : int
        The indicator is evaluated every ``every`` steps (quasi-static: the yield check every
        step; explicit runs: both every ``every`` time steps).
    interval : float, optional
        Explicit runs: evaluate every ``interval`` seconds of simulated time instead (s).
    max_fraction : float
        Largest share of the coarse mesh's area the patch may reach, in (0, 1].
    indicator : callable, optional
        ``indicator(view: AdaptView) -> (n_coarse_cells,) bool``, replacing the default.
    patch : int
        Which patch of the problem adapts.
    reject_band_plasticity : bool
        A step after which plastic flow reached the gluing band (where the weights let the
        patch's fine modes yield almost freely, ε̄p meaningless once the band moves on) is not
        accepted either, when the patch can grow there: computed again after the growth.
    closure : callable, optional
        ``closure(mask) -> mask``: the coarse cells of the grown patch (boolean, one per coarse
        cell) completed to a shape the problem keeps (the pressure vessel: whole rings, so that
        the gluing band stays a ring: bands with corners do not reproduce a uniform stress with
        a coarse mediator and let the fine modes there yield spuriously). It may only add cells.
    band_weight : float
        In [0, 1): plastic strain at the patch's quadrature points where its weight α_f is
        below this is disregarded by the indicator and by ``reject_band_plasticity`` (default
        0: every plastic point counts). Near the band's outer edge α_f → ε: the fine model's
        stress there, the multipliers' forces over a vanishing stiffness, is not the coupled
        model's (α_c σ_c + α_f σ_f), and yields where the coarse stress is 0.85 σ_y (the plate
        with a hole).
    """

    def __init__(
        self,
        model_factory: Callable[[Any], Any] | None = None,
        levels: int | None = None,
        refine: Callable[[np.ndarray], Any] | None = None,
        threshold: float = 0.8,
        buffer: int = 1,
        band_cells: int = 2,
        every: int = 1,
        max_fraction: float = 0.9,
        indicator: Callable[[AdaptView], np.ndarray] | None = None,
        patch: int = 0,
        reject_band_plasticity: bool = True,
        closure: Callable[[np.ndarray], np.ndarray] | None = None,
        interval: float | None = None,
        band_weight: float = 0.0,
    ) -> None:
        check_settings(threshold, buffer, band_cells, every, patch, interval)
        self.interval = None if interval is None else float(interval)
        check_bounds(max_fraction, band_weight, levels, indicator)
        self.model_factory, self.levels, self.refine = model_factory, levels, refine
        self.threshold, self.buffer, self.band_cells = float(threshold), int(buffer), band_cells
        self.every, self.max_fraction, self.indicator = int(every), float(max_fraction), indicator
        self.index, self.reject_band_plasticity = int(patch), bool(reject_band_plasticity)
        if closure is not None and not callable(closure):
            raise ValueError(f"closure must be callable, got {type(closure).__name__}")
        self.closure, self.band_weight = closure, float(band_weight)
        self.records: list[Adaptation] = []
        self.max_coarse_yield_ratio = 0.0
        self.problem: ArlequinProblem | None = None
        #: the growth decided after the last accepted step and not made yet (the solver makes
        #: it after the step's listeners: a checkpoint one of them writes holds it)
        self.pending: Growth | None = None
        self._resumed: ArlequinProblem | None = None  # the problem of :meth:`resume`

    # -- set-up ------------------------------------------------------------------------------
    @property
    def name(self) -> str:
        return self.problem.block_names[self.index + 1]

    @property
    def patch_fraction(self) -> float:
        """The current patch's share of the coarse mesh's area."""
        return float(self._measure[self.cells].sum() / self._measure.sum())

    def bind(self, problem: Any) -> ArlequinProblem:
        """Check ``problem`` (an ArlequinProblem, its patch nested, its coarse model linear,
        the patch's model with :class:`~arlequin.contract.SupportsCellStates`) and keep it."""
        if not isinstance(problem, ArlequinProblem):
            hint = (": adapt one body with arlequin.adapt.BodyAdaptation(adapt, body)"
                    if hasattr(problem, "bodies") else "")  # fmt: skip
            raise ValueError(f"adaptation needs an ArlequinProblem, got "
                             f"{type(problem).__name__}{hint}")  # fmt: skip
        if not 0 <= self.index < len(problem.patches):
            raise ValueError(f"patch={self.index}: the problem has {len(problem.patches)} patches")
        coarse = problem.coarse
        if not coarse.is_linear or not callable(getattr(coarse, "stress_at_quadrature", None)):
            raise ValueError("adaptation needs a linear coarse model with stress_at_quadrature(u)")
        self.problem, resumed, self._resumed = problem, problem is self._resumed, None
        if not resumed:
            # a new run: the growths and the coarse yield ratio of an earlier run with this
            # object are not this one's (a new list: the earlier result keeps its own)
            self.records, self.max_coarse_yield_ratio, self.pending = [], 0.0, None
        pc = problem.couplings[self.index]
        if pc.overlap.method != "nested":
            raise NonNestedPatchError(
                f"adaptive patches grow nested patches (coarse cells refined): {self.name} "
                f"overlaps the coarse mesh by {pc.overlap.method!r} (build it with "
                "Patch.from_region or refine_region)"
            )
        model = pc.fine_model
        if not isinstance(model, SupportsCellStates):
            raise ContractError(
                f"the model of {self.name}, a {type(model).__name__}, lacks state_of_cells, "
                "with_cells or yield_stress (arlequin.contract.SupportsCellStates)"
            )
        self.cells = np.unique(pc.overlap.coarse_cells)
        dim, ratio = coarse.mesh.dim(), model.mesh.nelements / self.cells.size
        levels = math.log2(ratio) / dim if ratio >= 1 else -1.0
        if self.levels is None and (levels < 0 or abs(levels - round(levels)) > 1e-9):
            raise NonNestedPatchError(f"{self.name} has {ratio:.6g} cells per coarse cell: not "
                                      "a uniform refinement of whole coarse cells")  # fmt: skip
        self.levels = round(levels) if self.levels is None else int(self.levels)
        if self.refine is None:
            cmesh, lv = coarse.mesh, self.levels
            self.refine = lambda cells: refine_region(cmesh, lv, cells=cells)
        if self.model_factory is None:
            self.model_factory = model.with_mesh
        self._check_refine(model.mesh)
        self._measure = _plane_measures(coarse.mesh)
        if self.patch_fraction > self.max_fraction:
            raise ValueError(
                f"max_fraction={self.max_fraction} is below the share of the coarse mesh the "
                f"patch {self.name} covers from the start ({self.patch_fraction:.4g})"
            )
        return problem

    def _check_refine(self, mesh: Any) -> None:
        again = self.refine(self.cells)
        tol = 1e-6 * float(np.ptp(mesh.p, axis=1).max())
        hit, _ = _match(cell_centroids(mesh), cell_centroids(again), tol)
        if again.nelements != mesh.nelements or hit.size != mesh.nelements:
            raise NonNestedPatchError(
                f"refine(cells) of the {self.cells.size} coarse cells under {self.name} does not "
                f"give its mesh ({again.nelements} cells, {hit.size} matching of "
                f"{mesh.nelements}): the patch is not nested, or give the refine= that built it"
            )

    # -- checkpoints -------------------------------------------------------------------------
    def checkpoint(self) -> dict[str, Any]:
        """What a run needs to continue with this patch (picklable; :meth:`resume`).

        Returns
        -------
        dict
            ``cells`` (the patch's coarse cells), ``records`` (the growths so far, copies),
            ``max_coarse_yield_ratio``, ``pending`` (the coarse cells of the growth decided
            after the last accepted step and not made yet, or None), and what
            :meth:`resume` checks the problem by: ``n_coarse_cells`` and ``patch``.
        """
        return {
            "cells": np.array(self.cells, dtype=np.int64),
            "records": [replace(r) for r in self.records],
            "max_coarse_yield_ratio": float(self.max_coarse_yield_ratio),
            "pending": None if self.pending is None else np.array(self.pending.cells),
            "n_coarse_cells": int(self.problem.coarse.mesh.nelements),
            "patch": self.index,
        }

    def resume(self, problem: Any, snapshot: dict[str, Any]) -> ArlequinProblem:
        """The grown problem of a :meth:`checkpoint`, rebuilt from the problem the run
        started on (``problem``, with its seed patch) as :meth:`grow` built it, and this
        object back at the checkpoint (its growths, coarse yield ratio, pending growth).

        Pass the grown problem on with the solver's checkpoint,
        ``solve_quasi_static(grown, adapt=self, restore=solver_checkpoint)``: :meth:`bind`
        keeps the growths of a resumed run, and the solver first makes a pending growth
        (decided after the checkpoint's step, not made before the run stopped), so that the
        run goes on as the uninterrupted one.

        Raises
        ------
        ValueError
            ``snapshot`` is not a :meth:`checkpoint`, or one of another problem (another
            coarse mesh or patch, or cells that do not contain the seed's).
        """
        keys = ("cells", "records", "max_coarse_yield_ratio", "pending", "n_coarse_cells",
                "patch")  # fmt: skip
        missing = [k for k in keys if k not in snapshot] if isinstance(snapshot, dict) else keys
        if missing:
            raise ValueError(f"resume: the snapshot is not an AdaptivePatch.checkpoint() "
                             f"(it lacks {list(missing)})")  # fmt: skip
        self.bind(problem)
        n, cells = problem.coarse.mesh.nelements, np.asarray(snapshot["cells"], dtype=np.int64)
        if (
            snapshot["n_coarse_cells"] != n
            or snapshot["patch"] != self.index
            or not np.isin(self.cells, cells).all()
            or cells.max() >= n
            or cells.min() < 0
        ):
            raise ValueError(
                f"resume: the snapshot is of another problem (patch {snapshot['patch']} on "
                f"{cells.size} of {snapshot['n_coarse_cells']} coarse cells; this one: patch "
                f"{self.index} on {self.cells.size} of {n}, which the snapshot's must contain)"
            )  # fmt: skip
        if not np.array_equal(cells, self.cells):  # grown (the seed itself otherwise)
            self.problem, self.cells = self._problem_on(problem, cells), cells
        self.records = [replace(r) for r in snapshot["records"]]
        self.max_coarse_yield_ratio = float(snapshot["max_coarse_yield_ratio"])
        pending = snapshot["pending"]
        self.pending = None if pending is None else Growth(np.asarray(pending, np.int64), False)
        self._resumed = self.problem
        return self.problem

    # -- the indicator -----------------------------------------------------------------------
    def view(self, solver: Any, step: int) -> AdaptView:
        """What the indicator sees of the solver's committed fields."""
        parts = solver.system.split(solver.u)
        coarse = self.problem.coarse
        vm = von_mises_of(coarse.stress_at_quadrature(parts["coarse"])).max(axis=1)
        model = self.problem.patches[self.index].model
        sy = float(np.min(model.yield_stress(None)))
        return AdaptView(step, float(solver.t), self.problem, parts["coarse"], parts[self.name],
                         solver.states[self.name][0], self.cells, vm, sy)  # fmt: skip

    def assess(self, solver: Any, step: int, due: bool | None = None) -> Growth | None:
        """After a converged step: None (keep the patch) or the :class:`Growth` to make
        (``due``: whether the indicator is evaluated now; default every ``every`` steps)."""
        view = self.view(solver, step)
        n = self.problem.coarse.mesh.nelements
        outside = np.ones(n, dtype=bool)
        outside[self.cells] = False
        ratio = view.coarse_von_mises / view.yield_stress
        worst = float(ratio[outside].max()) if outside.any() else 0.0
        band_flags, in_band = self._band_flags(view, outside)
        reject = worst > 1.0 or (in_band and self.reject_band_plasticity and band_flags.any())
        if not reject:
            self.max_coarse_yield_ratio = max(self.max_coarse_yield_ratio, worst)
            if (step % self.every) if due is None else not due:
                return None
        flags = self._flags(view, ratio, outside, band_flags)
        if reject:
            flags = flags | (ratio > 1.0) | band_flags
        flags &= outside
        if not flags.any():
            return None
        grown = cell_rings(self.problem.coarse.mesh, flags, self.buffer) | ~outside
        if self.closure is not None:
            closed = np.asarray(self.closure(grown.copy()), dtype=bool)
            if closed.shape != grown.shape or np.any(grown & ~closed):
                raise IndicatorError(f"closure must return a mask of shape {grown.shape} that "
                                     "keeps every cell it was given")  # fmt: skip
            grown = closed
        if reject:
            msg = "step %d: %s (coarse σ_vm/σy = %.4g outside %s): the patch grows and the step"
            why = "plastic flow in the gluing band" if worst <= 1.0 else "the coarse model yields"
            logger.info(msg + " is computed again", step, why, worst, self.name)
        return Growth(np.nonzero(grown)[0], reject)

    def _flags(self, view: AdaptView, ratio: np.ndarray, outside: np.ndarray,
               band_flags: np.ndarray) -> np.ndarray:  # fmt: skip
        n = outside.size
        if self.indicator is not None:
            flags = np.asarray(self.indicator(view))
            if flags.shape != (n,) or flags.dtype != bool:
                raise IndicatorError(f"the indicator must return one boolean flag per coarse "
                                     f"cell, shape ({n},), got shape {flags.shape} of "
                                     f"{flags.dtype}")  # fmt: skip
            return flags
        return (outside & (ratio >= self.threshold)) | band_flags

    def _band_flags(self, view: AdaptView, outside: np.ndarray) -> tuple[np.ndarray, bool]:
        """The coarse cells outside the patch next to the parents of the plastic fine cells
        within ``band_cells`` fine cells of the gluing band, and whether plastic flow reached
        the band itself."""
        pc = self.problem.couplings[self.index]
        model = pc.fine_model
        eqps = getattr(model, "equivalent_plastic_strain", None)
        ep = np.asarray(eqps(view.patch_state) if callable(eqps) else view.patch_state.eqps)
        fmesh = model.mesh
        band = np.zeros(fmesh.nelements, dtype=bool)
        band[pc.fine_gluing_cells] = True
        plastic_points = ep > 0.0
        if self.band_weight > 0.0:  # the band's outer part, where α_f σ_f is not σ_f
            plastic_points &= np.asarray(pc.alpha_fine) >= self.band_weight
        plastic = plastic_points.any(axis=1)
        near = cell_rings(fmesh, band, self.band_cells) & plastic
        if not near.any():
            return np.zeros(outside.size, dtype=bool), False
        parent = np.empty(fmesh.nelements, dtype=np.int64)
        parent[pc.overlap.fine_cells] = pc.overlap.coarse_cells
        touched = np.zeros(outside.size, dtype=bool)
        touched[parent[near]] = True
        # the nearest cells outside: the parents' rings out to the patch's boundary
        cmesh = self.problem.coarse.mesh
        for _ in range(2 + self.band_cells // 2**self.levels):
            touched = cell_rings(cmesh, touched, 1)
            if (touched & outside).any():
                break
        return touched & outside, bool(plastic[band].any())

    # -- growing -----------------------------------------------------------------------------
    def grow(self, growth: Growth, u: np.ndarray, states: dict[str, list[Any]], step: int,
             time_: float) -> tuple[ArlequinProblem, np.ndarray, dict[str, list[Any]]]:  # fmt: skip
        """The new problem on the coarse cells ``growth.cells`` and the committed fields
        ``u``, ``states`` (of the current problem) moved onto it: the new displacement and the
        patch's new state (the other blocks' states are the solver's initial ones: linear).

        Raises
        ------
        PatchLimitError
            The new patch would exceed ``max_fraction`` of the coarse mesh.
        """
        start = time.perf_counter()
        cells = np.asarray(growth.cells, dtype=np.int64)
        fraction = float(self._measure[cells].sum() / self._measure.sum())
        if fraction > self.max_fraction * (1.0 + 1e-12):
            raise PatchLimitError(
                f"the patch {self.name} would cover {fraction:.3f} of the coarse mesh after step "
                f"{step}, beyond max_fraction={self.max_fraction}: the run stops ("
                + (
                    "the coarse model would carry plastic flow)"
                    if growth.reject
                    else "the material nears yield beyond the patch)"
                ),
                step=step,
                time=time_,
            )
        old = self.problem
        old_pc = old.couplings[self.index]
        new = self._problem_on(old, cells)
        model = new.patches[self.index].model
        self._last = (old, new)
        u_new = self._transfer_u(old, new, u)
        state = self._transfer_state(old_pc, new.couplings[self.index], states[self.name][0])
        self.problem, self.cells, self.pending = new, cells, None
        rec = Adaptation(step, float(time_), int(model.mesh.nelements), int(cells.size), fraction,
                         bool(growth.reject), wall_time_s=time.perf_counter() - start)  # fmt: skip
        self.records.append(rec)
        logger.info("step %d: %s grew to %d coarse cells (%d fine, %.3f of the mesh)", step,
                    self.name, cells.size, model.mesh.nelements, fraction)  # fmt: skip
        return new, u_new, {self.name: [state]}

    def _problem_on(self, base: ArlequinProblem, cells: np.ndarray) -> ArlequinProblem:
        """``base`` with the adapted patch on the coarse ``cells``: its mesh ``refine(cells)``,
        its model ``model_factory(mesh)``, the couplings built (their exactness warnings
        logged)."""
        model = self.model_factory(self.refine(cells))
        patches = list(base.patches)
        patches[self.index] = replace(patches[self.index], model=model)
        new = base.with_patches(patches)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ExactnessWarning)
            new.couplings  # noqa: B018
        for w in caught:
            logger.info("%s", w.message)
        return new

    def transfer_displacement(self, u: np.ndarray) -> np.ndarray:
        """A displacement of the problem before the last growth moved onto the grown one (as
        :meth:`grow` moves the committed one)."""
        return self._transfer_u(*self._last, u)

    def _transfer_u(self, old: ArlequinProblem, new: ArlequinProblem, u: np.ndarray) -> np.ndarray:
        old_map, new_map = old.dofmap(), new.dofmap()
        parts = old_map.split(u)
        out = {k: v for k, v in parts.items() if k != self.name}
        d = int(old.coarse.n_components)
        fmesh_old = old.patches[self.index].model.mesh
        fmesh = new.patches[self.index].model.mesh
        tol = 1e-9 * float(np.ptp(fmesh.p, axis=1).max())
        hit, src = _match(fmesh_old.p, fmesh.p, tol)
        values = np.zeros((fmesh.nvertices, d))
        values[hit] = parts[self.name].reshape(-1, d)[src]
        rest = np.setdiff1d(np.arange(fmesh.nvertices), hit)
        if rest.size:
            values[rest] = evaluate_field(old.coarse.mesh, parts["coarse"], fmesh.p[:, rest], d).T
        out[self.name] = values.ravel()
        return new_map.assemble(out, "transferred displacement")

    def _transfer_state(self, old_pc: Any, new_pc: Any, state: Any) -> Any:
        model, old_model = new_pc.fine_model, old_pc.fine_model
        init = model.initial_state(new_pc.alpha_fine)
        if state is None:
            return init
        tol = 1e-9 * float(np.ptp(model.mesh.p, axis=1).max())
        hit, src = _match(cell_centroids(old_model.mesh), cell_centroids(model.mesh), tol)
        if hit.size != old_model.mesh.nelements:
            raise NonNestedPatchError(f"{hit.size} of the {old_model.mesh.nelements} cells of "
                                      f"{self.name} are in the grown patch")  # fmt: skip
        return model.with_cells(init, hit, old_model.state_of_cells(state, src))
