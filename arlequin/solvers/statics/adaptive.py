"""The quasi-static load stepping of an adaptive patch (``solve_quasi_static(..., adapt=)``).

After each converged step the adaptation object (:class:`arlequin.problem.adapt.AdaptivePatch`,
called duck-typed: the solvers never import the problem's set-up) is asked ``assess(solver,
step)``. ``None``: the step stands. A growth: the new problem and the committed fields moved
onto it come from ``adapt.grow(growth, u, states, step, λ)``; the solver goes on with them
(``replace_system``) and re-solves the multipliers by Newton at the same load (``resolve``); one
asked after the last step is not made (it would serve the next step, and there is none: the last
state stands as accepted). A *rejected* step (the coarse model yields outside the patch) is
first undone (``restore``): the patch grows from the committed state and the step is computed
again. Each growth records the relative jump of the total stored energy across it and the
iterations of the re-solve, and the time of its parts
(:class:`~arlequin.problem.adapt.Adaptation`: the rebuild and the transfer, the solver's new
operators, the re-solve, the rejected step's); listeners with an ``on_adapt(solver, adapt)``
member (the results writers) hear of it.

A growth for the next step is made after the step's listeners: until then it is the
adaptation's ``pending`` growth, so that a checkpoint written by a listener
(``solver.checkpoint()`` and ``adapt.checkpoint()``) holds it, and a run resumed from it
(``AdaptivePatch.resume``, ``restore=``) makes it first, as the uninterrupted run did.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...contract import SimulationError

__all__ = ["AdaptableSolver", "run_adaptive"]

logger = logging.getLogger(__name__)


class AdaptableSolver:
    """What :func:`run_adaptive` needs of a quasi-static solver besides ``replace_system``
    and ``resolve``: to undo a step, the least-squares multipliers of moved fields, the
    stored energy (a mixin of :class:`~arlequin.solvers.statics.quasi_static.QuasiStaticSolver`)."""

    _SNAPSHOT = ("u", "mu", "states", "t", "dt", "status", "_previous", "_first_stiffness",
                 "_last_stiffness")  # fmt: skip

    def snapshot(self) -> dict[str, Any]:
        """The committed state (to compute a step again, :meth:`restore`)."""
        return {"history": len(self.history), **{k: getattr(self, k) for k in self._SNAPSHOT}}

    def restore(self, snap: dict[str, Any]) -> None:
        """Back to a :meth:`snapshot` (the steps committed since forgotten)."""
        del self.history[snap["history"] :]
        for k in self._SNAPSHOT:
            setattr(self, k, snap[k])

    def _least_squares_multipliers(self) -> np.ndarray:
        """The multipliers that best balance the committed fields, min ‖r + Bᵀμ‖ on the free
        dofs: Newton starting from μ = 0 after a growth sees the whole coupling force as
        residual (and diverges from the elastic tangent of the yielding points)."""
        if not self.saddle.n_multipliers:
            return self.mu
        f_int, _, _ = self.ops.internal_force(self.u, self.states)
        r_free = self._residual_of(f_int, self.u, np.zeros_like(self.mu), self.t)[0]
        bf = self.saddle.b[:, self.saddle.free].tocsr()
        gram = (bf @ bf.T).tocsc()
        shift = 1e-12 * float(np.abs(gram.diagonal()).max())
        gram = gram + shift * sp.identity(gram.shape[0], format="csc")
        return spla.splu(gram).solve(-(bf @ r_free))

    def stored_energy(self) -> float:
        """The total stored energy (J) of the committed fields: ½ uᵀK u of the linear blocks
        and the nonlinear blocks' ``stored_energy_of_state`` (their internal work otherwise)."""
        zero = np.zeros(len(self.system.blocks))
        stored, _ = self.ops.stored_and_dissipated(self.states, zero)
        return float(self.ops.strain_linear(self.u).sum() + stored.sum())

    @property
    def previous(self) -> tuple[np.ndarray, float] | None:
        """The displacement and load factor of the step before the committed one, if any."""
        return None if self._previous is None else (self._previous[0], self._previous[2])


def _grow(solver: Any, adapt: Any, growth: Any, step: int, listeners: Sequence[Any],
          discarded: float = 0.0) -> None:  # fmt: skip
    before = solver.stored_energy()
    previous = solver.previous
    problem, u, states = adapt.grow(growth, solver.u, solver.states, step, solver.t)
    if previous is not None:  # the next step's predictor: the last increment, moved too
        previous = (adapt.transfer_displacement(previous[0]), previous[1])
    start = time.perf_counter()
    solver.replace_system(problem, u, states)
    system = time.perf_counter()
    iterations = solver.resolve(previous)
    after = solver.stored_energy()
    record = adapt.records[-1]
    record.newton_iterations = iterations
    record.system_time_s, record.resolve_time_s = system - start, time.perf_counter() - system
    record.discarded_time_s = discarded
    record.energy_jump = (after - before) / abs(before) if before else 0.0
    logger.info("patch grown: stored energy %.6g -> %.6g J (jump %.3g), %d Newton iterations",
                before, after, record.energy_jump, iterations)  # fmt: skip
    for listener in listeners:
        hook = getattr(listener, "on_adapt", None)
        if callable(hook):
            hook(solver, adapt)


def _finish(solver: Any, adapt: Any, watch: Any, message: str | None = None) -> Any:
    result = watch.finish(solver.result(message))
    result.adaptations = list(adapt.records)
    result.max_coarse_yield_ratio = float(adapt.max_coarse_yield_ratio)
    result.problem = adapt.problem
    return result


def run_adaptive(
    solver: Any,
    adapt: Any,
    on_step: Sequence[Callable[[Any], Any]] = (),
    callback: Callable[[Any], bool] | None = None,
) -> Any:
    """Load stepping with an adaptive patch (module docstring); the solver's problem is the
    one ``adapt`` was bound to.

    Returns
    -------
    QuasiStaticResult
        With ``adaptations``, ``max_coarse_yield_ratio``, ``band_plastic_fraction`` (the
        accepted steps' gluing bands, :class:`~arlequin.solvers.system.yield_watch.BandYieldWatch`)
        and the final ``problem``.

    Raises
    ------
    SimulationError
        A Newton failure (:class:`~arlequin.solvers.statics.quasi_static.NewtonError`) or the
        patch's cap (:class:`~arlequin.problem.adapt.PatchLimitError`); ``err.result`` holds every
        converged step.
    """
    watch = solver.band_watch
    # a resumed run (AdaptivePatch.resume): the growth its checkpoint's step had decided
    resumed = getattr(adapt, "pending", None)
    while solver.status == "running":
        try:
            if resumed is not None:
                _grow(solver, adapt, resumed, len(solver.history), on_step)
                resumed = None
            snap = solver.snapshot()
            start = time.perf_counter()
            rec = solver.step()
            if rec is None:  # a limit load
                break
            step = len(solver.history)
            growth = adapt.assess(solver, step)
            if growth is not None and growth.reject:
                discarded = time.perf_counter() - start  # the step and its assessment
                solver.restore(snap)
                _grow(solver, adapt, growth, step, on_step, discarded)
                continue
            watch(solver)
            # the growth for the next step, made after the listeners (a checkpoint one of them
            # writes holds it: a resumed run makes it first)
            adapt.pending = growth if growth is not None and solver.status == "running" else None
            for listener in on_step:
                listener(solver)
            # a growth for the next step: none after the last (its state was accepted)
            if growth is not None and solver.status == "running":
                _grow(solver, adapt, growth, step, on_step)
        except SimulationError as err:
            err.result = _finish(solver, adapt, watch, str(err))
            raise
        if callback is not None and callback(solver):
            solver.status = "stopped"
            return _finish(solver, adapt, watch, f"stopped by the callback at λ = {solver.t:.6g}")
    return _finish(solver, adapt, watch)
