"""The explicit step's time split into compiled kernels, linear algebra and the rest (overhead).

Runs a short window of a demo with the library's step timers on
(:class:`arlequin.linalg.timing.StepTimer`: ``time.perf_counter`` around the models' internal
forces, around the sparse/dense products and solves, and around each whole step; no profiler)
and prints JSON: steps, steps per second, the seconds of the steps in kernels, in linear algebra
and in the rest, the overhead's share of the step, the elements, the wall time of the run and the
process's peak resident memory. The linear algebra includes the energy bookkeeping's products
and per-block sums (the constraint forces' powers, the internal work), also reported apart
(``energy_products_seconds``), and the step's compiled vector updates with its diagonal solve
M⁻¹f (the kick, the predictor, the velocity at t, the finite-state check's Σx²:
``vector_updates_seconds``), with the shares they would leave if counted as overhead, as they
were before they were timed: ``overhead_share_vector_updates_as_other`` (the vector updates),
``overhead_share_energy_as_other`` (both). The first step of a run (the integrator's lazy
set-up: the critical step's eigenvalue estimate, the first factorisations) is timed apart
(``first_step_seconds``) and left out of the other figures. The case runs once untimed first
(the kernels' compilation or cache load); with ``--repeat N`` it runs N times and the round
with the shortest step time is reported (all rounds' step times in ``step_seconds_all``).

Cases (the demos' defaults, Arlequin models):

* ``taylor-2d``: the axisymmetric Arlequin Taylor bar (``arlequin taylor-bar``) to ``--t-end``
  (default 20 µs of its 80 µs);
* ``taylor-3d``: the quarter bar of hexahedra (``--geometry 3d``) to ``--t-end`` (default 5 µs);
* ``ball``: the plastic ball impact (``arlequin ball-impact --regime plastic``, multi-time-step
  as by default) to ``--t-end`` (default 15 µs, in contact: the demo's summary, refused
  before the ball leaves, is not made);
* ``ball-1``: the same without multi-time-step (``--coarse-step-ratio 1``).

    python benchmarks/explicit_step.py [--case taylor-2d] [--repeat N] [--t-end T] [--clock thread]

``--clock thread`` times with the main thread's CPU time (``time.thread_time``): on a machine
shared with other jobs the Python layer's own cost, without the waits for a core (the kernels'
other threads are not counted, so ``kernel_seconds`` is then the main thread's share).

The coupled step against the models alone on a cantilever is ``benchmarks/coupling_overhead.py``.
"""

from __future__ import annotations

import argparse
import json
import resource
import sys
import time

import _threads  # before numba runs: OpenMP threads sleep between parallel regions

CASES = ("taylor-2d", "taylor-3d", "ball", "ball-1")
DEFAULT_T_END = {"taylor-2d": 20e-6, "taylor-3d": 5e-6, "ball": 15e-6, "ball-1": 15e-6}


def _run(case: str, t_end: float):
    """One run of ``case`` to ``t_end`` (s): (its result, its element count)."""
    if case.startswith("taylor"):
        from arlequin.demos.taylor_bar import run_taylor_bar

        geometry = "3d" if case == "taylor-3d" else "axisymmetric"
        r = run_taylor_bar(t_end=t_end, geometry=geometry)
        return r, r.n_elements
    from arlequin.demos.ball_impact import run_ball_impact

    ratio = 1 if case == "ball-1" else None
    try:
        r = run_ball_impact(regime="plastic", t_end=t_end, coarse_step_ratio=ratio)
    except ValueError as exc:
        # a window that ends in contact: the demo refuses its summary, the steps are timed
        if "still in contact" not in str(exc):
            raise
        return None, None
    return r, r.n_elements


def _ball_elements() -> int:
    """The plastic ball impact's elements (its bodies as ``run_ball_impact`` builds them)."""
    from arlequin.demos.ball_impact import BallImpactConfig
    from arlequin.demos.ball_impact.setup import ImpactBodies

    i = BallImpactConfig(regime="plastic").resolved
    bodies = ImpactBodies(i.model, i.sizes, i.radius, i.block_radius, i.block_height,
                          i.ball_material, i.block_material, rigid_wall=i.rigid_wall,
                          friction=i.friction)  # fmt: skip
    return bodies.n_elements


def _share(rep: dict, *also: str) -> float:
    """The overhead's share of the step with the timed parts ``also`` counted as overhead."""
    step = rep["step_seconds"]
    return round((rep["other_seconds"] + sum(rep[k] for k in also)) / step, 4) if step > 0 else 0.0


def measure(case: str, t_end: float | None = None, repeat: int = 1, clock: str = "wall") -> dict:
    """The timed split of ``case`` (see the module docstring) as a JSON-ready dict."""
    from arlequin.linalg.timing import StepTimer

    if case not in CASES:
        raise ValueError(f"case must be one of {CASES}, got {case!r}")
    if repeat < 1:
        raise ValueError(f"repeat must be at least 1, got {repeat}")
    t_end = DEFAULT_T_END[case] if t_end is None else float(t_end)
    if not t_end > 0.0:
        raise ValueError(f"t_end must be positive (s), got {t_end}")
    _run(case, min(t_end, 0.5e-6))  # compile or load the kernels
    best, rounds = None, []
    for _ in range(repeat):
        t0 = time.perf_counter()
        with StepTimer(clock=clock) as timer:
            _, elements = _run(case, t_end)
        wall = time.perf_counter() - t0
        rounds.append(timer.step)
        if best is None or timer.step < best[0].step:
            best = (timer, wall, elements)
    timer, wall, elements = best
    if elements is None:  # a ball window ending in contact: no summary
        elements = _ball_elements()
    rep = timer.report()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return {
        "case": case,
        "clock": clock,
        "t_end_s": t_end,
        "elements": elements,
        "steps": rep["steps"],
        "steps_per_second": round(rep["steps_per_second"], 2),
        "overhead_share": round(rep["overhead_share"], 4),
        "step_seconds": round(rep["step_seconds"], 4),
        "kernel_seconds": round(rep["kernel_seconds"], 4),
        "linear_algebra_seconds": round(rep["linear_algebra_seconds"], 4),
        "energy_products_seconds": round(rep["energy_products_seconds"], 4),
        "vector_updates_seconds": round(rep["vector_updates_seconds"], 4),
        # the shares with the vector updates, then also the energy bookkeeping's products,
        # counted as overhead (as before they were timed: for comparison with earlier figures)
        "overhead_share_vector_updates_as_other": _share(rep, "vector_updates_seconds"),
        "overhead_share_energy_as_other": _share(
            rep, "vector_updates_seconds", "energy_products_seconds"
        ),
        "other_seconds": round(rep["other_seconds"], 4),
        "other_ms_per_step": round(1e3 * rep["other_seconds"] / max(rep["steps"], 1), 4),
        "first_step_seconds": round(rep["first_step_seconds"], 4),
        "wall_time_s": round(wall, 3),
        "step_seconds_all": [round(x, 4) for x in rounds],
        "peak_memory_mb": round(peak, 1),
        "threads": _threads.settings(),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", choices=CASES, default="taylor-2d")
    parser.add_argument("--repeat", type=int, default=1,
                        help="runs; the one with the shortest step time is reported")  # fmt: skip
    parser.add_argument("--t-end", type=float, default=None, help="simulated time (s)")
    parser.add_argument("--clock", choices=["wall", "thread"], default="wall",
                        help="the timers' clock: wall time, or the main thread's CPU time "
                             "(other jobs' load left out; kernels' other threads too)")  # fmt: skip
    args = parser.parse_args(argv)
    print(json.dumps(measure(args.case, args.t_end, args.repeat, args.clock), indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
