"""The driver: :func:`solve` integrates a coupled system from t0 to t_end (``solve_ivp`` style).

It builds the integrator (a registry name or a class), tells it the stop times (the requested
output times ``t_eval`` and the end time, which the steps land on exactly), steps it, and records
through a :class:`~arlequin.solvers.run.recorder.Recorder` into a :class:`DynamicResult`.
"""

from __future__ import annotations

import inspect
import logging
import math
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ...contract import SimulationError
from ...linalg.threads import blas_threads
from ..dynamics.adaptive_dynamic import DynamicAdapter, bind_adaptation, rebuild, run_adaptive_loop
from ..dynamics.base import Integrator
from ..dynamics.controllers import FixedStep
from ..dynamics.registry import get_integrator
from ..system.yield_watch import BandYieldWatch
from .recorder import Recorder
from .result import DynamicResult

logger = logging.getLogger(__name__)

#: Wall-time interval (s) of the progress lines logged at INFO (``arlequin -v``).
LOG_INTERVAL = 2.0


def _log_progress(integ: Integrator) -> None:
    """One INFO line: step, time, step size and the kinetic energy plus the internal work (the
    strain energy of linear blocks)."""
    try:
        energy = f"{integ.total_energy():.6e} J"
    except Exception:  # an integrator without energies: the kinematics only
        energy = "n/a"
    logger.info(
        "step %d, t = %.6e s, dt = %.3e s, kinetic energy + internal work %s",
        integ.step_count,
        integ.t,
        float(integ.step_size or integ.dt),
        energy,
    )


__all__ = ["options_of", "solve"]


def _check_t_eval(t_eval: Any, t0: float, t_end: float | None) -> np.ndarray:
    times = np.asarray(t_eval, dtype=float).ravel()
    if times.size == 0:
        raise ValueError("t_eval is empty: give at least one output time (s)")
    if not np.all(np.isfinite(times)):
        raise ValueError(f"t_eval must be finite, got {times[~np.isfinite(times)][:3]}")
    if np.any(np.diff(times) <= 0.0):
        k = int(np.nonzero(np.diff(times) <= 0.0)[0][0])
        raise ValueError(
            f"t_eval must be strictly increasing, got {times[k]} s then {times[k + 1]} s"
        )
    if times[0] < t0:
        raise ValueError(f"t_eval must not start before t0 = {t0} s, got {times[0]} s")
    if t_end is not None and times[-1] > t_end * (1.0 + 1e-12) + 1e-300:
        raise ValueError(f"t_eval must end by t_end = {t_end} s, got {times[-1]} s")
    return times


def options_of(cls: type[Integrator]) -> list[str]:
    """The keyword options an integrator class accepts (its ``__init__`` and its bases')."""
    names: set[str] = set()
    for klass in cls.__mro__:
        init = klass.__dict__.get("__init__")
        if init is None:
            continue
        for p in inspect.signature(init).parameters.values():
            if p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD) and p.name not in (
                "self",
                "system",
            ):
                names.add(p.name)
    return sorted(names)


def solve(
    system: Any,
    integrator: str | type[Integrator] = "explicit",
    t_end: float | None = None,
    dt: float | None = None,
    *,
    n_steps: int | None = None,
    t0: float = 0.0,
    u0: Any = None,
    v0: Any = None,
    t_eval: Sequence[float] | None = None,
    step_controller: Any = None,
    callback: Callable[[Integrator], bool | None] | None = None,
    record_every: int = 1,
    save_fields: bool = False,
    on_record: Sequence[Callable[[Integrator], None]] = (),
    on_step: Sequence[Callable[[Integrator], None]] = (),
    on_checkpoint: Callable[[Integrator, Recorder], None] | None = None,
    restore: Any = None,
    adapt: Any = None,
    **options: Any,
) -> DynamicResult:
    """Integrate a coupled system in time.

    Parameters
    ----------
    system : CoupledSystem or ArlequinProblem
        The system (a problem is turned into its system).
    integrator : str or Integrator subclass
        ``"explicit"`` (central difference), ``"newmark"``, ``"hht"``, ``"theta"``... or a class.
    t_end : float, optional
        End time (s). With a fixed step the step is reduced (never increased) so that an integer
        number of equal steps reaches ``t_end`` exactly; other controllers shorten the last step.
    dt : float, optional
        Fixed time step (s); default: the integrator's default (see its class).
    n_steps : int, optional
        Number of steps instead of ``t_end``.
    t0 : float
        Initial time (s).
    u0, v0 : ndarray or dict, optional
        Initial displacement (m) and velocity (m/s) (see :class:`Integrator`).
    t_eval : sequence of float, optional
        Output times (s), strictly increasing within [t0, t_end]: the steps are shortened to
        land on them exactly, and only the initial state and these times are recorded
        (``record_every`` is then ignored). Given without ``t_end``, the last one is the end.
    step_controller : StepController, float or callable, optional
        Chooses each step (see :mod:`arlequin.solvers.dynamics.controllers`), e.g.
        ``CriticalFraction(0.9, every=20)`` or ``lambda integ: dt_n``.
    callback : callable, optional
        ``callback(integrator)`` at every recorded step (after the initial state too); returning
        True stops the run (``status = 1``).
    record_every : int
        Without ``t_eval``: record every ``record_every`` steps (and the last step).
    save_fields : bool
        Also record u and v (memory: n_rec × n each).
    on_record : sequence of callables
        ``listener(integrator)`` after each record, before ``callback`` (results writers).
    on_step : sequence of callables
        ``listener(integrator)`` after every step, before any record of that step (cheap
        per-step monitors, e.g. a multiplier history; they must not change the integrator).
    on_checkpoint : callable, optional
        ``on_checkpoint(integrator, recorder)`` after each record and its listeners: where a
        long run saves ``integrator.snapshot()`` and ``recorder.state()`` to resume from.
    restore : tuple, optional
        ``(snapshot, recorder_state)`` of a checkpoint: the run continues from the snapshot's
        time with what was recorded until then (the same system, integrator, options, stops and
        listeners as the interrupted run give the same steps and values bit for bit).
    adapt : AdaptivePatch or BodyAdaptation, optional
        A nested patch of ``system`` (an :class:`~arlequin.ArlequinProblem`; a body's of a
        multi-body problem with a ``BodyAdaptation``) that grows where the material yields
        (:mod:`arlequin.problem.adapt`), checked every ``adapt.every`` steps or
        ``adapt.interval`` s (:mod:`arlequin.solvers.dynamics.adaptive_dynamic`); the result gains
        ``adaptations``, ``max_coarse_yield_ratio`` and the final ``problem``. Not with
        ``restore``; extra ``constraints`` only with a ``BodyAdaptation`` that rebuilds them.
    **options
        Passed to the integrator class (``beta``, ``gamma``, ``alpha``, ``theta``, ``safety``,
        ``constraints``, ``consistent_initial``...).

    Returns
    -------
    DynamicResult

    Raises
    ------
    SimulationError
        On NaN/overflow or a failed step; ``err.result`` holds what was recorded until then.
    """
    cls = get_integrator(integrator)
    with blas_threads(cls.blas_threads):
        return _solve(cls, system, t_end, dt, n_steps, t0, u0, v0, t_eval, step_controller,
                      callback, record_every, save_fields, on_record, on_step, on_checkpoint,
                      restore, options, adapt)  # fmt: skip


def _solve(cls, system, t_end, dt, n_steps, t0, u0, v0, t_eval, step_controller, callback,
           record_every, save_fields, on_record, on_step, on_checkpoint, restore,
           options, adapt=None) -> DynamicResult:  # fmt: skip
    """:func:`solve` with the integrator's class resolved."""
    _check_options(cls, options)
    if adapt is not None:
        system = bind_adaptation(adapt, system, restore, options)
    if t_end is None and n_steps is None and t_eval is not None:
        t_end = float(np.max(np.asarray(t_eval, dtype=float)))
    t0, t_end, n_steps = _check_span(t0, t_end, n_steps, record_every)
    times = _check_t_eval(t_eval, t0, t_end) if t_eval is not None else None
    integ = cls(system, dt, t0=t0, u0=u0, v0=v0, step_controller=step_controller, **options)
    if t_end is not None and isinstance(integ.controller, FixedStep):
        _land_on_end(integ, t0, t_end)
    stops: list[float] = []
    if times is not None:
        stops += times[times > t0].tolist()
    if t_end is not None:
        stops.append(t_end)
    if stops:
        integ.set_stops(stops)
    # the J2 patches' gluing bands at every sample (the problem's own band_plasticity)
    band = BandYieldWatch(lambda: getattr(adapt, "problem", system), when="t", deferred=True)
    rec = Recorder(integ, save_fields, (*on_record, band))
    if restore is not None:
        snapshot, recorder_state = restore
        integ.restore(snapshot)
        if stops:
            integ.set_stops(stops)
        rec.load_state(recorder_state)
        t_start = integ.t
    else:
        rec.record()
        if on_checkpoint is not None:
            on_checkpoint(integ, rec)
        if callback is not None and callback(integ):
            return rec.result(1, "stopped by the callback at the initial state")
        t_start = t0
    pending = None
    if times is not None:
        pending = list(times[times > t_start + 1e-12 * float(integ.dt)])
    loop = _Loop(integ, rec, n_steps, t_end, record_every, pending, callback, on_step,
                 on_checkpoint)  # fmt: skip
    if adapt is not None:

        def build(problem, t_start, u_start, v_start, **changed):
            new = rebuild(cls, problem, dt, t_start, u_start, v_start, step_controller,
                          {**options, **changed})  # fmt: skip
            if t_end is not None and isinstance(new.controller, FixedStep):
                _land_on_end(new, t_start, t_end)
            if stops:
                new.set_stops(stops)
            return new

        loop.adapter = DynamicAdapter(adapt, build, (*on_step, *on_record, band))
    return _watched(loop, adapt, band)


def _watched(loop: _Loop, adapt: Any, band: BandYieldWatch) -> DynamicResult:
    """The loop's run, its result (a failure's too) with the bands' largest plastic share."""
    try:
        result = run_adaptive_loop(loop, adapt) if adapt is not None else loop.run()
    except SimulationError as err:
        if isinstance(err.result, DynamicResult):
            band.finish(err.result)
        raise
    return band.finish(result)


def _check_options(cls, options) -> None:
    """Refuse options the integrator class does not take (named, with the known ones)."""
    known = options_of(cls)
    unknown = sorted(set(options) - set(known))
    if unknown:
        raise ValueError(
            f"unknown option(s) {unknown} for the {cls.name!r} scheme ({cls.__name__}); its "
            f"options are {[k for k in known if k not in ('t0', 'u0', 'v0', 'dt')]}"
        )


def _check_span(t0, t_end, n_steps, record_every) -> tuple[float, float | None, int | None]:
    """The run's span checked: ``(t0, t_end, n_steps)``, exactly one of the last two given."""
    if (t_end is None) == (n_steps is None):
        raise ValueError("give exactly one of t_end (s) or n_steps")
    if int(record_every) != record_every or record_every < 1:
        raise ValueError(f"record_every must be a positive integer, got {record_every}")
    t0 = float(t0)
    if t_end is not None:
        t_end = float(t_end)
        if not (math.isfinite(t_end) and t_end > t0):
            raise ValueError(f"t_end must be finite and exceed t0, got t_end={t_end}, t0={t0}")
    else:
        if int(n_steps) != n_steps or n_steps < 1:
            raise ValueError(f"n_steps must be a positive integer, got {n_steps}")
        n_steps = int(n_steps)
    return t0, t_end, n_steps


def _land_on_end(integ, t0: float, t_end: float) -> None:
    """A fixed step shortened (at most) so that a whole number of steps lands on ``t_end``."""
    steps = max(1, math.ceil((t_end - t0) / integ.dt * (1.0 - 1e-12)))
    dt_run = (t_end - t0) / steps
    if abs(dt_run - integ.dt) > 1e-14 * integ.dt:
        integ.controller = FixedStep(dt_run)
        integ.set_step_size(dt_run)


class _Loop:
    """The time loop of :func:`solve`: step, notify, record (at ``t_eval`` times or every
    ``record_every`` steps), checkpoint, ask the callback; until the end or a stop."""

    def __init__(self, integ, rec, n_steps, t_end, record_every, pending, callback, on_step,
                 on_checkpoint) -> None:  # fmt: skip
        self.integ, self.rec = integ, rec
        self.n_steps, self.t_end, self.record_every = n_steps, t_end, record_every
        self.pending, self.callback = pending, callback
        self.on_step, self.on_checkpoint = on_step, on_checkpoint
        self.adapter = None  # an adaptive patch's checks (adaptive_dynamic.DynamicAdapter)

    def _done(self, k: int) -> bool:
        if self.n_steps is not None and k >= self.n_steps:
            return True
        return self.t_end is not None and self.integ.status == "finished"

    def _step(self) -> None:
        integ = self.integ
        try:
            integ.step()
        except SimulationError as err:
            integ.status = "failed"
            err.result = self.rec.result(-1, str(err))
            raise

    def _take(self, k: int) -> bool:
        """Whether step ``k`` is recorded."""
        integ = self.integ
        last = integ.status == "finished" or (self.n_steps is not None and k == self.n_steps)
        if self.pending is None:
            return k % self.record_every == 0 or last
        take = bool(self.pending) and integ.t >= self.pending[0] - 1e-12 * float(integ.step_size)
        if take:
            self.pending.pop(0)
        return take

    def run(self) -> DynamicResult:
        integ, rec = self.integ, self.rec
        k = integ.step_count
        verbose = logger.isEnabledFor(logging.INFO)
        next_log = time.perf_counter() + LOG_INTERVAL
        if self.adapter is not None:
            integ, _ = self.adapter.check(self, k)
        while not self._done(k):
            self._step()
            k += 1
            for listener in self.on_step:
                listener(integ)
            if verbose and time.perf_counter() >= next_log:
                _log_progress(integ)
                next_log = time.perf_counter() + LOG_INTERVAL
            if self._take(k):
                rec.record()
                if self.on_checkpoint is not None:
                    self.on_checkpoint(integ, rec)
                if self.callback is not None and self.callback(integ):
                    msg = f"stopped by the callback at step {k}, t = {integ.t:.6e} s"
                    return rec.result(1, msg)
            if self.adapter is not None and self.adapter.due(integ, k, self._done(k)):
                # after the record: a growth goes on from the recorded state, a rejected
                # interval forgets its records (adaptive_dynamic)
                integ, _ = self.adapter.check(self, k)
                k = integ.step_count
        return rec.result(0, f"reached t = {integ.t:.6e} s in {integ.step_count} steps")
