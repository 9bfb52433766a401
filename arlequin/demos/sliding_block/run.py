"""The sliding block's run, as named steps: set up (:mod:`.setup`), integrate, analyse against
the exact solution, write the results folder (:mod:`.report`).

The integration is one explicit run from the initial state, except for a launch under gravity:
the ramp is run first, then the run continues from the ramp's final state with V added to the
x velocity of every node, as the pressure loading's run starts from its static state with V.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ...io import DynamicRunWriter, ResultsFolder
from ...solvers import solve
from .result import SlidingBlockResult
from .setup import SlidingBlockSetup, build

if TYPE_CHECKING:
    from .config import SlidingBlockConfig

__all__ = ["SAFETY", "STOP_FRACTION", "run"]

logger = logging.getLogger(__name__)

#: Ratio of the time step to the critical step of the block. Friction feeds the normal force
#: into the tangential one (a non-symmetric coupling) and lowers the stable step: measured on the
#: 3D block (μ = 0.3, 4 cells across), 0.9 diverges after about 1 ms when the steps vary to land
#: on the output times, 0.72 and 0.45 stay stable.
SAFETY = 0.6

#: The block has stopped when its time-averaged mean velocity falls below this fraction of V.
STOP_FRACTION = 1e-3

#: The per-step histories a run keeps (the keys of :class:`_Steps`).
_KEYS = ("t", "v", "slip", "fw", "cw", "e", "it", "ux", "dw")


def run(
    config: SlidingBlockConfig,
    out: str | Path | None = None,
    progress: Callable[[float], None] | None = None,
) -> SlidingBlockResult:
    """Run the sliding block of ``config`` (see :mod:`arlequin.demos.sliding_block`).

    Parameters
    ----------
    config : SlidingBlockConfig
    out : path, optional
        Results folder (the package docstring).
    progress : callable, optional
        ``progress(fraction)`` of the simulated time, at each new percent.

    Returns
    -------
    SlidingBlockResult
    """
    folder = ResultsFolder(out, "arlequin sliding-block", config.inputs(), config.units()) \
        if out else None  # fmt: skip
    setup = build(config)
    steps = _Steps(setup, progress)
    writer = None
    t_eval = np.linspace(0.0, setup.t_total, 101)[1:]
    if folder is not None:
        writer = DynamicRunWriter(folder, setup.system, frame_times=t_eval[::5])
    tic = time.perf_counter()
    try:
        n_steps = _integrate(setup, steps, writer, t_eval)
    except Exception as exc:
        if folder is not None:
            folder.finish("failed", str(exc))
        raise
    wall = time.perf_counter() - tic
    arr = {k: np.asarray(v) for k, v in steps.data.items()}
    result = _result(setup, arr, n_steps, wall)
    if folder is not None:
        from .report import write_results

        write_results(folder, result, arr)
    logger.info(result.summary())
    return result


# -- integration ------------------------------------------------------------------------------
class _Steps:
    """The per-step monitor (``on_step``): times from the end of the ramp (s), mean velocity
    along x (m/s), largest slip velocity of the contact nodes (m/s), friction, contact and
    damping works (J), kinetic + strain − external work (J), fixed-point iterations, mean x
    displacement of the contact nodes (m). ``offsets`` carry the works of the ramp over a
    launch (:func:`_integrate`)."""

    def __init__(self, setup: SlidingBlockSetup, progress: Callable[[float], None] | None):
        self.setup = setup
        self.progress = progress
        self.data: dict[str, list] = {k: [] for k in _KEYS}
        self.offsets: dict[str, float] | None = None
        self.integ: Any = None
        self._pct = -1
        self._mx_sum = float(setup.mass_x.sum())

    def __call__(self, integ: Any) -> None:
        s, d, dim = self.setup, self.data, self.setup.dim
        self.integ = integ
        v = integ.v
        st = integ.constraint_states[s.contact.name]
        e = integ.energies()
        fw = float(getattr(st, "friction_work", 0.0))
        cw = float(st.work)
        dw = sum(e["damping_work"].values())
        w_ext = sum(e["external_work"].values())
        if self.offsets is not None:
            off = self.offsets
            fw, cw, dw, w_ext = fw + off["fw"], cw + off["cw"], dw + off["dw"], w_ext + off["ext"]
        d["t"].append(integ.t - s.loading.ramp)
        d["v"].append(float(s.mass_x @ v[0::dim]) / self._mx_sum)
        d["slip"].append(float(np.abs(v[s.bottom_x]).max()))
        d["fw"].append(fw)
        d["cw"].append(cw)
        d["dw"].append(dw)
        d["e"].append(sum(e["kinetic"].values()) + sum(e["strain"].values()) - w_ext)
        d["it"].append(int(integ.status_iterations))
        d["ux"].append(float(integ.u[s.bottom_x].mean()))
        if self.progress is not None:
            t_total = s.t_total
            pct = int(100 * integ.t / t_total)
            if pct != self._pct:
                self._pct = pct
                self.progress(min(integ.t / t_total, 1.0))


def _solve(setup: SlidingBlockSetup, t0: float, t_end: float, u0: np.ndarray, v0: np.ndarray,
           t_eval: np.ndarray, steps: _Steps, records: list) -> Any:  # fmt: skip
    """One explicit run of the block from ``t0`` to ``t_end`` (s)."""
    return solve(setup.system, "explicit", t_end=t_end, t0=t0, u0=u0, v0=v0,
                 constraints=[setup.contact], t_eval=t_eval, on_step=[steps],
                 on_record=records, safety=SAFETY, damping=setup.damping)  # fmt: skip


def _integrate(setup: SlidingBlockSetup, steps: _Steps, writer: DynamicRunWriter | None,
               t_eval: np.ndarray) -> int:  # fmt: skip
    """Integrate from the initial state to the end; returns the number of steps.

    A launch under gravity: the ramp to its end, then a second run from the ramp's final state
    with V added to every node's x velocity (the contact starts afresh, as the pressure launch
    does), its works continuing those of the ramp.
    """
    load = setup.loading
    records = [writer] if writer is not None else []
    if not load.launch:
        res = _solve(setup, 0.0, setup.t_total, load.u0, load.v0, t_eval, steps, records)
        return int(res.n_steps)
    ramp = load.ramp
    # the output times on either side of the launch, the ramp's end one of them (an output
    # time a round-off away from it would be a sliver of a step)
    far = np.abs(t_eval - ramp) > 1e-9 * ramp
    first = _solve(setup, 0.0, ramp, load.u0, load.v0,
                   np.append(t_eval[far & (t_eval < ramp)], ramp), steps, records)  # fmt: skip
    integ = steps.integ
    u1, v1 = integ.u.copy(), integ.v.copy()
    v1[0 :: setup.dim] += load.launch
    launch = _Launch(integ, steps, writer)
    second = _solve(
        setup, ramp, setup.t_total, u1, v1, t_eval[far & (t_eval > ramp)], steps, [launch]
    )
    return int(first.n_steps) + int(second.n_steps)


class _Launch:
    """The second run's record listener after a launch under gravity: at its initial state it
    sets the monitor's offsets (the ramp's final works; the kinetic energy the launch gave,
    counted as work of the loads); then it forwards the records to the results writer with the
    same offsets (the initial state, the ramp's end, is already written)."""

    def __init__(self, ramp_end: Any, steps: _Steps, writer: DynamicRunWriter | None) -> None:
        e = ramp_end.energies()
        st = ramp_end.constraint_states[steps.setup.contact.name]
        self.energies_end = e
        self.energy_end = sum(e["kinetic"].values()) + sum(e["strain"].values())
        self.works_end = {"fw": float(getattr(st, "friction_work", 0.0)), "cw": float(st.work),
                          "dw": sum(e["damping_work"].values()),
                          "ext": sum(e["external_work"].values())}  # fmt: skip
        self.steps_end = ramp_end.step_count
        self.steps = steps
        self.writer = writer
        self.given: dict[str, float] = {}

    def __call__(self, integ: Any) -> None:
        if self.steps.offsets is None:
            e = integ.energies()
            gain = sum(e["kinetic"].values()) + sum(e["strain"].values()) - self.energy_end
            offsets = dict(self.works_end)
            offsets["ext"] += gain
            self.steps.offsets = offsets
            # the launch's energy per block, counted with the external work in the history
            self.given = {n: e["kinetic"][n] + e["strain"][n] - self.energies_end["kinetic"][n]
                          - self.energies_end["strain"][n] for n in e["kinetic"]}  # fmt: skip
            return
        if self.writer is not None:
            self.writer(_Continued(integ, self))


class _Continued:
    """The second run's integrator as the results writer sees it: step counts and works
    continuing those of the ramp, the launch's energy with the external work."""

    def __init__(self, integ: Any, launch: _Launch) -> None:
        self._integ = integ
        self._launch = launch

    def __getattr__(self, name: str) -> Any:
        return getattr(self._integ, name)

    @property
    def step_count(self) -> int:
        return self._integ.step_count + self._launch.steps_end

    def energies(self) -> dict[str, dict[str, float]]:
        e = self._integ.energies()
        end = self._launch.energies_end
        out = dict(e)
        for k in ("external_work", "coupling_work", "constraint_work", "damping_work"):
            out[k] = {n: w + end[k][n] for n, w in e[k].items()}
        out["external_work"] = {n: w + self._launch.given[n]
                                for n, w in out["external_work"].items()}  # fmt: skip
        return out


# -- analysis ---------------------------------------------------------------------------------
def _result(setup: SlidingBlockSetup, arr: dict[str, np.ndarray], n_steps: int,
            wall: float) -> SlidingBlockResult:  # fmt: skip
    """The result of a run's per-step histories, against the exact solution."""
    config, load = setup.config, setup.loading
    t, vbar = arr["t"], arr["v"]
    velocity = config.launch_velocity
    e_total = arr["e"] - arr["fw"] - arr["cw"] - arr["dw"]
    scale = max(float(np.abs(arr["e"]).max()), 1e-300)
    balance = float(np.abs(e_total - e_total[0]).max() / scale) if e_total.size else 0.0
    slip_after, slipping = _slip_after_stop(t, arr["slip"], load.t_stop, velocity)
    its = arr["it"]
    values, counts = np.unique(its, return_counts=True)
    # a sticking point's work is 0 to round-off, of either sign: 1e-12 of the energy scale
    neg = int(np.sum(np.diff(arr["fw"]) > 1e-12 * scale)) if arr["fw"].size > 1 else 0
    if config.gravity is not None:
        start = arr["ux"][int(np.searchsorted(t, 0.0))]
    else:
        start = float(load.u0[setup.bottom_x].mean())
    return SlidingBlockResult(
        t=t.tolist(), mean_velocity=vbar.tolist(), friction_work=arr["fw"].tolist(),
        contact_work=arr["cw"].tolist(), total_energy=arr["e"].tolist(),
        stop_time=_stop_time(setup, t, vbar), sliding_distance=float(arr["ux"][-1] - start),
        fixed_point_iterations={"mean": float(its.mean()), "max": int(its.max()),
                                "counts": {int(a): int(b) for a, b in zip(values, counts)}},
        acceleration=_acceleration(setup, t, vbar), expected_acceleration=float(load.a_exact),
        expected_stop_time=load.t_stop, energy_balance_error=balance,
        max_slip_after_stop=slip_after, slipping_steps_after_stop=slipping,
        negative_dissipation_steps=neg, ramp_time=load.ramp, n_steps=n_steps, wall_time_s=wall,
        config=config.inputs(), damping_work=arr["dw"].tolist(), slip_velocity=arr["slip"],
    )  # fmt: skip


def _acceleration(setup: SlidingBlockSetup, t: np.ndarray, vbar: np.ndarray) -> float:
    """The slope (m/s²) of the straight line through the sliding phase: between 0.9 and 0.1 of
    the launch velocity with the pressure loading or when the block stops, else the whole run
    after the ramp."""
    velocity = setup.config.launch_velocity
    after = _after_launch(t, velocity)
    if setup.config.gravity is None or setup.loading.t_stop is not None:
        sel = after & (vbar > 0.1 * velocity) & (vbar < 0.9 * velocity)
    else:
        sel = after
    return float(np.polyfit(t[sel], vbar[sel], 1)[0]) if sel.sum() > 2 else 0.0


def _after_launch(t: np.ndarray, velocity: float) -> np.ndarray:
    """The records after the launch (t > 0: a launch under gravity is recorded at t = 0 before
    it) or, without a launch, after the ramp (t ≥ 0)."""
    return t > 0.0 if velocity > 0.0 else t >= 0.0


def _stop_time(setup: SlidingBlockSetup, t: np.ndarray, vbar: np.ndarray) -> float | None:
    """When the mean velocity averaged over one shear period 4H/c_s (centred) falls below
    :data:`STOP_FRACTION` V after the launch (s); None without a launch or a stop."""
    velocity = setup.config.launch_velocity
    after = _after_launch(t, velocity)
    if not velocity > 0.0 or not after.any():
        return None
    t, vbar = t[after], vbar[after]
    period = 4.0 * setup.config.height / setup.c_s
    dt_mean = float(np.mean(np.diff(t))) if t.size > 1 else float(t[0])
    win = max(1, round(period / dt_mean))
    avg = np.convolve(vbar, np.ones(win) / win, mode="valid")
    centre = t[win // 2 : win // 2 + avg.size]
    k = np.nonzero(avg <= STOP_FRACTION * velocity)[0]
    return float(centre[k[0]]) if k.size else None


def _slip_after_stop(t: np.ndarray, slip: np.ndarray, t_stop: float | None,
                     velocity: float) -> tuple[float | None, float | None]:  # fmt: skip
    """The largest slip velocity of the contact nodes after 1.1 × the exact stop time (m/s),
    and the fraction of those steps with a node slipping faster than 1e-6 V."""
    if t_stop is None or not np.any(t > 1.1 * t_stop):
        return None, None
    late = slip[t > 1.1 * t_stop]
    return float(late.max()), float(np.mean(late > 1e-6 * velocity))
