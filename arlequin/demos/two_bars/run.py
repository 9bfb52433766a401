"""The 1D impact runs: one integrator run of an :class:`~.setup.Impact` and its result, and the
two-bar impact (:func:`run_two_bars`) as named steps.

The reported series (see :meth:`TwoBarsResult.to_json`) start at t = 0. For the θ-scheme the
multiplier of a record is the step's (the step ending at that time), for Newmark the end-point
value, for central differences the impulse at that time divided by Δt. Sign conventions: λ_v ≤ 0
is the normal contact pressure; reports give ``contact_pressure = −λ_v``.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ...io import DynamicRunWriter, ResultsFolder
from ...problem.system import Block, BlockTerm, CoupledSystem
from ...solvers import solve
from .report import finish, open_folder
from .result import TwoBarsResult
from .setup import Impact, Scheme, TwoBarsSetup, contact, integrator_options

if TYPE_CHECKING:
    from .config import TwoBarsConfig

__all__ = ["run_1d", "run_config"]

logger = logging.getLogger(__name__)


def _progress_listener(progress, t_end: float, span: tuple[float, float]):
    """An on_step listener reporting ``span[0] + (span[1] − span[0]) t/t_end`` at each new
    percent (None without ``progress``)."""
    if progress is None:
        return None
    last = [-1]

    def report(integ) -> None:
        frac = span[0] + (span[1] - span[0]) * min(integ.t / t_end, 1.0)
        pct = int(100 * frac)
        if pct != last[0]:
            last[0] = pct
            progress(frac)

    return report


def _solve(setup: Impact, scheme: Scheme, folder: ResultsFolder | None, prefix: str,
           progress: Callable[[float], None] | None, span: tuple[float, float]):  # fmt: skip
    """The integrator run: (system, contact model, integrator name, its result)."""
    bodies, names = setup.bodies, setup.names
    method = scheme.method
    system = CoupledSystem([Block(n, b, [BlockTerm(b)]) for n, b in zip(names, bodies)])
    v0 = {n: np.full(b.n_dofs, v) for n, b, v in zip(names, bodies, setup.v_init)}
    pair = setup.pair_factory(system.dofmap)
    kind = "levelset" if method == "levelset" else "signorini"
    con = contact(kind, pair, setup.material)
    integ, opts = integrator_options(method, scheme.newmark, scheme.integrator, scheme.theta)
    if integ == "explicit":
        opts["safety"] = 1.0
    writers = []
    if folder is not None:
        frames = np.linspace(0.0, setup.t_end, 61)
        writers.append(DynamicRunWriter(folder, system, frame_times=frames, prefix=prefix))
    listener = _progress_listener(progress, setup.t_end, span)
    res = solve(
        system,
        integ,
        t_end=setup.t_end,
        dt=setup.dt,
        v0=v0,
        constraints=[con],
        save_fields=True,
        on_record=writers,
        on_step=[listener] if listener is not None else [],
        **opts,
    )
    if res.n_status_failures:
        logger.warning(
            "%s: %d steps reached the status iteration cap", method, res.n_status_failures
        )
    return system, con, integ, res


def _final_velocities(system: CoupledSystem, res, lumped: bool) -> list[float]:
    """Mass-weighted mean velocity of each body at the end (m/s), with the run's mass."""
    finals = []
    for b in system.blocks:
        vb = res.v[b.dofs]
        mb = system.block_mass(b)
        if lumped:
            finals.append(float(np.asarray(mb.sum(axis=1)).ravel() @ vb / mb.sum()))
        else:
            finals.append(float(np.ones(b.n_dofs) @ (mb @ vb) / mb.sum()))
    return finals


def run_1d(
    setup: Impact, scheme: Scheme, folder: ResultsFolder | None = None, prefix: str = "",
    progress: Callable[[float], None] | None = None, span: tuple[float, float] = (0.0, 1.0),
) -> TwoBarsResult:  # fmt: skip
    """One impact run: its histories against time and its figures (a :class:`TwoBarsResult`);
    the fields written to ``folder`` (files prefixed ``prefix``), ``progress`` reported over
    ``span`` of the whole."""
    system, con, integ, res = _solve(setup, scheme, folder, prefix, progress, span)
    meth = "levelset" if scheme.method == "levelset" else f"newmark-{scheme.newmark}"
    t = res.times
    lam = res.multipliers[con.name][:, 0]
    pressure = -lam
    kin = res.total_kinetic
    strain = res.total_strain
    # the history has one record per step (times[1:]); no work is done before the first step
    work = np.concatenate([[0.0], con.history(res).work])
    act = np.nonzero(lam != 0.0)[0]
    duration = float(t[act[-1]] - t[act[0]] + res.dt) if act.size else 0.0
    return TwoBarsResult(
        t=t,
        interface_velocity=res.fields["v"][:, setup.interface_dof(system.dofmap)],
        contact_pressure=pressure,
        kinetic=kin,
        internal=strain,
        total_energy=kin + strain,
        contact_work=work,
        final_velocities=_final_velocities(system, res, integ == "explicit"),
        contact_duration=duration,
        dt=float(res.dt),
        fixed_point_iterations=res.status_iterations.astype(int),
        method=meth,
        integrator=integ,
        exact=setup.exact,
        config=setup.config,
        n_status_failures=int(res.n_status_failures),
        dynamic=res,
    )


def run_config(config: TwoBarsConfig, out: str | Path | None = None,
               progress: Callable[[float], None] | None = None) -> TwoBarsResult:  # fmt: skip
    """Run the two-bar impact of ``config`` (see :func:`run_two_bars`)."""
    setup = TwoBarsSetup(config)

    def one(meth: str, prefix: str = "", span: tuple[float, float] = (0.0, 1.0)) -> TwoBarsResult:
        scheme = Scheme(meth, config.newmark, config.integrator, config.theta)
        return run_1d(setup.impact(meth), scheme, folder, prefix, progress, span)

    # the inputs as run (the lengths as floats, the end time computed when not given), then
    # the choices: the order of results.json before the configuration
    given = config.inputs()
    inputs = {**setup.record, **{k: v for k, v in given.items() if k not in setup.record}}
    folder = open_folder(out, "arlequin two-bars", inputs, config.units())
    if config.method == "both":
        res = one("levelset", span=(0.0, 0.5))
        # the baseline's files are prefixed (newmark-trapezoidal_history.csv...)
        res.newmark = one("newmark", f"newmark-{config.newmark}_", span=(0.5, 1.0))
    else:
        res = one(config.method)
    finish(folder, res)
    return res
