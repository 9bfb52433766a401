"""Adaptive patches in explicit runs (``solve(problem, "explicit", ..., adapt=AdaptivePatch())``).

The time loop of :func:`~arlequin.solvers.run.driver.solve` asks :class:`DynamicAdapter` after every
step whether a check is due (:meth:`DynamicAdapter.due`: every ``adapt.every`` steps, or every
``adapt.interval`` seconds of simulated time, at the initial state and at the last step; a
multi-time-step scheme at its macro times only). At a check the adaptation object
(:class:`arlequin.problem.adapt.AdaptivePatch`, duck-typed: ``bind``, ``assess``, ``grow``,
``transfer_displacement``) looks at the integrator's fields:

* ``None``: the interval since the last check stands; a snapshot of the integrator (and of what
  the recorder holds) becomes the committed state;
* a growth: the new problem and the fields moved onto it (the displacement *and* the velocity of
  the new fine nodes interpolated from the coarse field, the old fine nodes keeping theirs; the
  new fine cells' states virgin, the old ones kept) start a new integrator of the same scheme
  and options at the same time (its stable step, its multi-time-step ratios and its impulse
  factorisation those of the new system; its first impulse re-solves the multipliers), with the
  works accumulated so far, the step count and the stop times carried over;
* a *rejected* interval (the coarse model outside the patch above yield, or plastic flow in the
  gluing band): the integrator goes back to the committed snapshot (the recorder forgets the
  records taken since), the patch grows from that state and the interval is computed again.

Each growth records the relative jump of the total energy across it (``energy_jump``: the
scheme's kinetic energy plus the stored energy and the plastic dissipation of every block) and
the time of its parts, as a quasi-static growth does (:class:`~arlequin.problem.adapt.Adaptation`:
``wall_time_s`` the rebuilt problem and the moved fields, ``system_time_s`` the new integrator
(its operators, stable step, impulse factorisation, the rebuilt constraints),
``resolve_time_s`` its first impulse from the moved fields (the multipliers re-solved) and the
energies across the growth, ``discarded_time_s`` the rejected interval's steps);
listeners with an ``on_adapt(integrator, adapt)`` member hear of it (after a rejected interval
the integrator's time is the committed one, earlier than the last step they saw). Before that,
a rejected interval calls the ``on_rewind(integrator)`` member of the listeners that have one,
the integrator back at the committed state: they drop what they took after ``integrator.t``
(:class:`~arlequin.io.DynamicRunWriter` its history rows and field frames, on disk too), so that
their records are the committed trajectory's.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ...contract import SimulationError

__all__ = [
    "DynamicAdapter",
    "bind_adaptation",
    "finish_adaptive",
    "moved_constraint_state",
    "rebuild",
    "run_adaptive_loop",
    "total_energy",
]

logger = logging.getLogger(__name__)

#: The works an integrator accumulates (per block), carried over a growth.
_WORKS = ("_w_ext", "_w_coupling", "_w_constraint", "_w_internal", "_w_damping")


def total_energy(integ: Any) -> float:
    """The total energy (J) of an integrator's fields at ``t``: the scheme's kinetic energy,
    the stored energy (linear blocks ½ uᵀK u) and the plastic dissipation of every block."""
    e = integ.energies()
    return float(sum(sum(e[k].values()) for k in ("kinetic", "stored", "dissipation")))


class DynamicAdapter:
    """The adaptation of a nested patch inside :func:`~arlequin.solvers.solve`'s loop
    (module docstring).

    Parameters
    ----------
    adapt : AdaptivePatch
        Already bound to the run's problem.
    build : callable
        ``build(problem, t0, u0, v0, **changed) -> Integrator``: an integrator of the run's
        scheme and options (``changed`` replacing some: the rebuilt ``constraints``) on a new
        problem at time ``t0`` (s), its stop times set.
    listeners : sequence
        The run's listeners; those with an ``on_adapt(integrator, adapt)`` member are told of
        each growth, those with an ``on_rewind(integrator)`` member of each rejected interval
        (the integrator back at the committed state, before the growth: they drop what they
        recorded after its time ``integrator.t``).
    """

    def __init__(self, adapt: Any, build: Callable[..., Any], listeners: Sequence[Any]) -> None:
        self.adapt, self.build = adapt, build
        self.listeners = [h for h in (getattr(x, "on_adapt", None) for x in listeners)
                          if callable(h)]  # fmt: skip
        self.rewinders = [h for h in (getattr(x, "on_rewind", None) for x in listeners)
                          if callable(h)]  # fmt: skip
        self.every = int(adapt.every)
        self.interval = getattr(adapt, "interval", None)
        self._next_time: float | None = None
        self._late = False
        self._snap: tuple[Any, ...] | None = None
        self._committed_at = time.perf_counter()

    # -- when -----------------------------------------------------------------------------
    def due(self, integ: Any, k: int, last: bool) -> bool:
        """Whether step ``k`` (just taken) ends an interval: a check is made now."""
        if self.interval is None:
            wanted = k % self.every == 0
        else:
            wanted = integ.t >= self._next_time - 1e-9 * float(integ.step_size or integ.dt)
        self._late = self._late or wanted or last
        # a multi-time-step scheme restarts only at a macro time (its slow kick is whole)
        return self._late and getattr(integ, "_j", 0) == 0

    # -- the check ------------------------------------------------------------------------
    def check(self, loop: Any, k: int) -> tuple[Any, bool]:
        """The check after step ``k`` (0: the initial state, so that a user indicator of the
        wrong shape is refused before any step): ``(integrator to go on with, whether the loop
        went back to the committed state)``. ``loop`` has ``integ``, ``rec`` and ``pending``.

        Raises
        ------
        PatchLimitError, IndicatorError, SimulationError
            ``err.result`` holds what was recorded until then, with the adaptations.
        """
        self._late = False
        integ = loop.integ
        try:
            growth = self.adapt.assess(integ, k, due=True)
            rewound, discarded = False, 0.0
            if growth is not None and growth.reject and self._snap is not None:
                # the interval's steps and its assessment, computed again after the growth
                discarded = time.perf_counter() - self._committed_at
                integ = self._rewind(loop)
                rewound = True
            if growth is not None:
                integ = self._grow(loop, integ, growth, discarded)
        except (SimulationError, ValueError) as err:
            err.result = finish_adaptive(loop.rec.result(-1, str(err)), self.adapt)
            raise
        self._commit(loop)
        return integ, rewound

    def _commit(self, loop: Any) -> None:
        integ, rec = loop.integ, loop.rec
        lengths = {name: len(getattr(rec, name)) for name in ("times", "rows", "iters",
                                                              "sizes", "us", "vs")}  # fmt: skip
        mult = {name: len(v) for name, v in rec.mult.items()}
        records = {name: len(v) for name, v in rec.records.items()}
        pending = None if loop.pending is None else list(loop.pending)
        self._snap = (integ, integ.snapshot(), lengths, mult, records, pending)
        self._committed_at = time.perf_counter()
        if self.interval is not None:
            self._next_time = integ.t + self.interval

    def _rewind(self, loop: Any) -> Any:
        """Back to the committed snapshot: the integrator, the recorder's lists, the pending
        output times."""
        integ, snap, lengths, mult, records, pending = self._snap
        integ.restore(snap)
        rec = loop.rec
        for name, n in lengths.items():
            del getattr(rec, name)[n:]
        for name, values in list(rec.mult.items()):
            del values[mult.get(name, 0) :]
        for name, values in rec.records.items():
            del values[records.get(name, 0) :]
        loop.pending = None if pending is None else list(pending)
        loop.integ = rec.integ = integ
        logger.info("interval rejected: back to t = %.6e s (step %d)", integ.t, integ.step_count)
        # before the growth: the listeners forget what they took after the committed time
        for hook in self.rewinders:
            hook(integ)
        return integ

    # -- the growth -----------------------------------------------------------------------
    def _grow(self, loop: Any, integ: Any, growth: Any, discarded: float = 0.0) -> Any:
        start = time.perf_counter()
        before = total_energy(integ)
        step, t = integ.step_count, integ.t
        problem, u, states = self.adapt.grow(growth, integ.u, integ.states, step, t)
        v = self.adapt.transfer_displacement(integ.v)
        moved = time.perf_counter()
        changed = {}
        if integ.unilateral:  # contact pairs between bodies: rebuilt on the new dof map
            changed["constraints"] = self.adapt.constraints_for(problem)
        new = self.build(problem, t, u, v, **changed)
        built = time.perf_counter()
        # the moved states (the old fine cells' own, the new ones virgin) replace the initial
        # ones the constructor started from: forces, impulse and multipliers again from them
        new.states = {**new.states, **states}
        for c in new.unilateral:
            if c.name in integ.constraint_states:
                new.constraint_states[c.name] = moved_constraint_state(
                    integ.constraint_states[c.name], new.constraint_states[c.name], integ.ops.n
                )
        new._initialize()
        _carry(integ, new)
        after = total_energy(new)
        record = self.adapt.records[-1]
        record.energy_jump = (after - before) / abs(before) if before else 0.0
        record.energy_change = after - before
        # the whole rebuild and transfer (a multi-body problem's too, and the velocity's),
        # the new integrator, its first impulse and the energies
        record.wall_time_s, record.system_time_s = moved - start, built - moved
        record.resolve_time_s = time.perf_counter() - built
        record.discarded_time_s = discarded
        logger.info(
            "t = %.6e s: patch grown, total energy %.9g -> %.9g J (jump %.3g), stable step "
            "%.4g s", t, before, after, record.energy_jump, float(new.critical_dt or math.nan),
        )  # fmt: skip
        loop.integ = loop.rec.integ = new
        for hook in self.listeners:
            hook(new, self.adapt)
        return new


def moved_constraint_state(old: Any, new: Any, n_old: int) -> Any:
    """A unilateral constraint's committed state moved onto the grown system: its per-point
    history (statuses, multipliers, impulses, works, records: the contact points are the other
    body's, unchanged) from ``old``, what lives on the dofs (arrays of the old system's
    ``n_old`` dofs, a geometry with rows) from ``new``, its initial state there; nested
    dataclasses (a friction state's normal part) field by field."""
    if not dataclasses.is_dataclass(old) or type(old) is not type(new):
        return new
    values = {}
    for f in dataclasses.fields(old):
        a, b = getattr(old, f.name), getattr(new, f.name)
        on_dofs = isinstance(a, np.ndarray) and a.ndim >= 1 and a.shape[-1] == n_old
        if on_dofs or hasattr(a, "rows"):
            values[f.name] = b
        elif dataclasses.is_dataclass(a) and type(a) is type(b) and hasattr(b, "geometry"):
            values[f.name] = moved_constraint_state(a, b, n_old)
        else:
            values[f.name] = a
    return dataclasses.replace(old, **values)


def _carry(old: Any, new: Any) -> None:
    """What the new integrator continues from the old one: the step count, the works
    accumulated so far (the old step's pending halves included), the status counters, a
    multi-time-step scheme's macro steps and its energy reference shifted by the jump."""
    new.step_count = old.step_count
    new.step_size = old.step_size
    # the explicit scheme's works include the pending half of the step that ended at t
    works = old._works()
    new._w_ext, new._w_coupling, new._w_constraint = (np.array(w) for w in works)
    # a nonlinear block's strain energy is its internal work: it moves by the change of the
    # block's stored energy and dissipation across the growth (the new cells' elastic energy,
    # the old band's reweighting), so that its history goes on measuring the same energy
    lin = np.asarray(new.ops.block_linear)
    e_old, e_new = old.energies(), new.energies()
    names = new.ops.names
    moved = np.array([e_new[k][n] - e_old[k][n] for n in names for k in ("stored", "dissipation")])
    shift = moved.reshape(len(names), 2).sum(axis=1)
    new._w_internal = np.where(lin, old._w_internal, np.asarray(old._w_internal) + shift)
    new._w_damping = np.array(old._damping_work())
    new.n_status_failures = old.n_status_failures
    new.status = old.status  # a growth at the last stop time ends the run there
    if hasattr(old, "macro_steps") and hasattr(new, "macro_steps"):
        new.macro_steps = old.macro_steps
        new.ratios = list(old.ratios) + list(new.ratios)
        # the energy check's balance goes on across the jump (the jump is the growth's, not
        # the scheme's)
        new._energy0 = old._energy0 + (new.total_energy() - old.total_energy())
        new._energy_scale = max(new._energy_scale, old._energy_scale)


def bind_adaptation(adapt: Any, system: Any, restore: Any, options: dict[str, Any]) -> Any:
    """The run's problem checked for an adaptive patch (``adapt.bind``) before any work.

    Raises
    ------
    ValueError
        With a checkpoint to ``restore`` (its snapshot is of one patch) or extra
        ``constraints`` (their rows are on the dofs of the patch before it grows); the
        adaptation's own (:class:`~arlequin.problem.adapt.NonNestedPatchError`, ...).
    """
    if not (callable(getattr(adapt, "assess", None)) and callable(getattr(adapt, "grow", None))):
        raise ValueError(f"adapt must be an AdaptivePatch, got {type(adapt).__name__}")
    if restore is not None:
        raise ValueError("restore (a checkpoint) cannot be combined with adapt: the snapshot "
                         "is of the patch it was taken with")  # fmt: skip
    if options.get("constraints") and not callable(getattr(adapt, "constraints_for", None)):
        raise ValueError("extra constraints cannot be combined with adapt: their rows are on "
                         "the dofs of the patch before it grows (a BodyAdaptation's "
                         "constraints= rebuilds them)")  # fmt: skip
    return adapt.bind(system)


def rebuild(cls: type, problem: Any, dt: float | None, t0: float, u0: np.ndarray,
            v0: np.ndarray, step_controller: Any, options: dict[str, Any]) -> Any:  # fmt: skip
    """An integrator of the run's scheme and options on the grown ``problem`` from ``t0`` (s).

    A fixed step ``dt`` (s) above the grown system's critical step gives way to the scheme's
    default (its safety factor times the new critical step), logged.
    """
    try:
        return cls(problem, dt, t0=t0, u0=u0, v0=v0, step_controller=step_controller, **options)
    except ValueError as err:
        if dt is None or step_controller is not None:
            raise
        logger.warning("dt = %.4g s after the growth: %s; the scheme's default step instead",
                       dt, err)  # fmt: skip
        return cls(problem, None, t0=t0, u0=u0, v0=v0, **options)


def run_adaptive_loop(loop: Any, adapt: Any) -> Any:
    """``loop.run()`` (the driver's time loop with its ``adapter`` set), its result, or the
    partial result of a failure, with the adaptation's records (:func:`finish_adaptive`)."""
    try:
        return finish_adaptive(loop.run(), adapt)
    except ValueError as err:  # SimulationError, PatchLimitError, IndicatorError
        if getattr(err, "result", None) is not None:
            finish_adaptive(err.result, adapt)
        raise


def finish_adaptive(result: Any, adapt: Any) -> Any:
    """The run's :class:`DynamicResult` with the adaptation's records: ``adaptations``,
    ``max_coarse_yield_ratio`` and the final ``problem``."""
    result.adaptations = list(adapt.records)
    result.max_coarse_yield_ratio = float(adapt.max_coarse_yield_ratio)
    result.problem = adapt.problem
    return result
