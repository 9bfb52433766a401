"""Optional timers of the explicit step: compiled kernels, linear algebra and the rest.

Off by default and free when off (one attribute lookup at each timed call). A
:class:`StepTimer` used as a context manager switches them on for the code it encloses::

    with StepTimer() as timer:
        solve(system, "explicit", t_end=1e-5)
    timer.report()  # seconds in the models' internal forces, in products and solves, per step

What is timed, with ``time.perf_counter`` (or the thread's CPU time, ``clock="thread"``):

* ``kernel``: the nonlinear models' ``internal_force`` calls (the compiled J2 kernels with their
  gathers and assemblies);
* ``linear_algebra``: sparse mat-vecs (the linear blocks' stiffness, the rows' transfers), the
  factorised impulse solves and the dense Schur products of contact, and the products and
  per-block sums of the energy bookkeeping (the powers of the constraint forces Bᵀλ·v and
  Gᵀλ·v, of the external, friction and damping forces, and the internal work's Δu·f̄), also
  counted apart in ``energy_products``; and the explicit step's compiled full-length vector
  updates (the kick v⁻ + Δt̄ a, the predictor u + Δt v, the velocity at t, the finite-state
  check's Σx², :mod:`arlequin.linalg.vector_updates`) and its diagonal solve M⁻¹ f, dense
  linear algebra of one pass each, also counted apart in ``vector_updates`` (with the
  finite-state check of any scheme stepped inside the timer);
* ``step``: :meth:`Integrator.step <arlequin.solvers.dynamics.base.Integrator.step>` as a whole, so
  ``other = step − kernel − linear_algebra`` is the Python layer around them (the overhead).
"""

from __future__ import annotations

from time import perf_counter, thread_time

__all__ = [
    "CLOCKS",
    "SWITCH",
    "StepTimer",
    "energy_products_done",
    "timer_start",
    "vector_updates_done",
]

#: The clocks of the timers: the wall clock, or the CPU time of the calling thread (on a
#: machine shared with other jobs, the time the step's own Python layer uses, without the
#: waits for a core; the compiled kernels' other threads are not in it).
CLOCKS = {"wall": perf_counter, "thread": thread_time}


class _Switch:
    """Holds the timer switched on (the innermost :class:`StepTimer` context) or None."""

    __slots__ = ("timer",)

    def __init__(self) -> None:
        self.timer: StepTimer | None = None


#: ``SWITCH.timer``: the timer switched on, or None; the timed calls test it and do nothing
#: else when it is None.
SWITCH = _Switch()


class StepTimer:
    """Accumulated wall times (s) of the explicit steps run inside its context.

    Attributes
    ----------
    kernel, linear_algebra, step : float
        Seconds in the models' internal forces, in sparse/dense products and solves, and in
        whole steps (the first two included).
    energy_products : float
        The part of ``linear_algebra`` in the energy bookkeeping's products and sums.
    vector_updates : float
        The part of ``linear_algebra`` in the step's compiled vector updates and its diagonal
        solve (module docstring).
    steps : int
        Steps timed.
    first_step : float
        Seconds of the first step, not counted in the others when ``skip_first``.

    Parameters
    ----------
    skip_first : bool
        Keep the first step (the integrator's lazy set-up) out of the figures (default True).
    clock : {"wall", "thread"}
        ``time.perf_counter`` (default) or ``time.thread_time`` (see :data:`CLOCKS`).
    """

    def __init__(self, skip_first: bool = True, clock: str = "wall") -> None:
        if clock not in CLOCKS:
            raise ValueError(f"clock must be one of {sorted(CLOCKS)}, got {clock!r}")
        self.clock = CLOCKS[clock]
        self.clock_name = clock
        self.kernel = 0.0
        self.linear_algebra = 0.0
        self.energy_products = 0.0
        self.vector_updates = 0.0
        self.step = 0.0
        self.steps = 0
        self.first_step = 0.0
        self.skip_first = bool(skip_first)
        self._started = False
        self._outer: StepTimer | None = None

    def end_step(self, seconds: float) -> None:
        """Count one step of ``seconds`` (s). With ``skip_first``, the first step (which makes
        the integrator's lazy set-up: critical-step estimates, factorisations) is kept apart in
        :attr:`first_step` and the kernel and linear-algebra times until its end (the
        integrator's initial forces among them) are dropped."""
        if self.skip_first and not self._started:
            self._started = True
            self.first_step = seconds
            self.kernel = self.linear_algebra = 0.0
            self.energy_products = self.vector_updates = 0.0
            return
        self.step += seconds
        self.steps += 1

    def __enter__(self) -> StepTimer:
        self._outer, SWITCH.timer = SWITCH.timer, self
        return self

    def __exit__(self, *exc) -> None:
        SWITCH.timer, self._outer = self._outer, None

    @property
    def other(self) -> float:
        """Seconds of the steps outside kernels and linear algebra (the overhead)."""
        return self.step - self.kernel - self.linear_algebra

    def report(self) -> dict[str, float]:
        """The times (s), the steps, steps per second and the overhead's share of the step."""
        step = self.step
        return {
            "steps": self.steps,
            "first_step_seconds": self.first_step,
            "step_seconds": step,
            "kernel_seconds": self.kernel,
            "linear_algebra_seconds": self.linear_algebra,
            "energy_products_seconds": self.energy_products,
            "vector_updates_seconds": self.vector_updates,
            "other_seconds": self.other,
            "overhead_share": self.other / step if step > 0 else 0.0,
            "steps_per_second": self.steps / step if step > 0 else 0.0,
        }


def timer_start() -> float:
    """The clock of the timer switched on (0.0 when off), before an energy product or a vector
    update (:func:`energy_products_done`, :func:`vector_updates_done`)."""
    timer = SWITCH.timer
    return timer.clock() if timer is not None else 0.0


def energy_products_done(tic: float) -> None:
    """Count the time since ``tic`` (:func:`timer_start`) as linear algebra of the
    energy bookkeeping (nothing when the timers are off)."""
    timer = SWITCH.timer
    if timer is not None:
        seconds = timer.clock() - tic
        timer.linear_algebra += seconds
        timer.energy_products += seconds


def vector_updates_done(tic: float) -> None:
    """Count the time since ``tic`` (:func:`timer_start`) as linear algebra
    of the step's vector updates (nothing when the timers are off). For calls outside the other
    timed regions only (no time counted twice)."""
    timer = SWITCH.timer
    if timer is not None:
        seconds = timer.clock() - tic
        timer.linear_algebra += seconds
        timer.vector_updates += seconds
