"""Impact of two elastic bars (the seed's Figure 1) and a bar against a rigid wall.

Two bars (SI units): bar 1 on [−L1, 0] at velocity v₀, bar 2 on [0, L2] at velocity v₂ (default
at rest), same material (E, ρ, c = √(E/ρ)), touching at t = 0. Exact solution for L1 = L2 = L:
interface velocity (v₀ + v₂)/2 and contact pressure ρc(v₀ − v₂)/2 during the contact, which lasts
2L/c; then the velocities are exchanged. With L1 ≠ L2 the contact lasts 2 min(L1, L2)/c.

Methods: the level-set (Signorini–Moreau) contact model (:class:`arlequin.models.LevelSetContact`)
with the θ-scheme (``integrator="theta"``, consistent mass) or central differences
(``integrator="explicit"``, lumped mass); the baseline Newmark + Signorini on displacements
(:class:`arlequin.models.SignoriniContact`): trapezoidal (β = ¼, γ = ½) or HHT-α (α = −0.1).

The time step is ``cfl × h_min / c``. Reported series (see :meth:`TwoBarsResult.to_json`) start at
t = 0. For the θ-scheme the multiplier of a record is the step's (the step ending at that time),
for Newmark the end-point value, for central differences the impulse at that time divided by Δt.

Sign conventions: λ_v ≤ 0 is the normal contact pressure; reports give ``contact_pressure = −λ_v``.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import skfem

from ..io import DynamicRunWriter, ResultsFolder
from ..models import (
    ContactSurface,
    DeformableContactPair,
    IsotropicElastic,
    LevelSetContact,
    LinearElastic,
    PlaneObstacle,
    RigidContactPair,
    SignoriniContact,
)
from ..problem.system import Block, BlockTerm, CoupledSystem
from ..solvers import solve
from .impact import JSON_KEYS, TwoBarsResult, exact_two_bars, impact_metrics
from .plots import plot_two_bars

__all__ = [
    "JSON_KEYS",
    "TwoBarsResult",
    "exact_two_bars",
    "impact_metrics",
    "plot_two_bars",
    "run_two_bars",
    "run_wall",
]

logger = logging.getLogger(__name__)

AREA = 1e-4  # bar cross-section (m²); the pressures do not depend on it


# ---------------------------------------------------------------------------------------------
# 1D set-ups
# ---------------------------------------------------------------------------------------------
def _bar(x0: float, x1: float, n: int, material: IsotropicElastic) -> LinearElastic:
    mesh = skfem.MeshLine(np.linspace(x0, x1, n + 1))
    return LinearElastic(mesh, material, kind="1d", area=AREA)


def _contact(kind: str, pair, material, name: str = "contact"):
    if kind == "levelset":
        return LevelSetContact(pair, material=material, name=name)
    return SignoriniContact(pair, name=name)


def _integrator_options(
    method: str, newmark: str, integrator: str, theta: float
) -> tuple[str, dict]:
    if method == "levelset":
        if integrator == "theta":
            return "theta", {"theta": theta}
        if integrator == "explicit":
            return "explicit", {}
        raise ValueError(f"integrator must be 'theta' or 'explicit', got {integrator!r}")
    if newmark == "trapezoidal":
        return "newmark", {"beta": 0.25, "gamma": 0.5}
    if newmark == "hht":
        return "hht", {"alpha": -0.1}
    raise ValueError(f"newmark must be 'trapezoidal' or 'hht', got {newmark!r}")


@dataclass
class _Impact:
    """A 1D impact set-up: the bars, their initial velocities, the contact pair, the step."""

    bodies: list[LinearElastic]
    names: list[str]
    v_init: list[float]
    pair_factory: Any  # DofMap -> ContactPair
    interface_dof: Any  # DofMap -> global dof of the reported interface velocity
    exact: dict[str, Any]
    config: dict[str, Any]
    material: IsotropicElastic
    dt: float
    t_end: float


@dataclass(frozen=True)
class _Scheme:
    """The method and time scheme of one run."""

    method: str  # "levelset" or "newmark"
    newmark: str
    integrator: str
    theta: float


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


def _run_1d(
    setup: _Impact, scheme: _Scheme, folder: ResultsFolder | None = None, prefix: str = "",
    progress: Callable[[float], None] | None = None, span: tuple[float, float] = (0.0, 1.0),
) -> TwoBarsResult:  # fmt: skip
    bodies, names = setup.bodies, setup.names
    method, newmark, integrator, theta = (
        scheme.method, scheme.newmark, scheme.integrator, scheme.theta
    )  # fmt: skip
    dt, t_end, material = setup.dt, setup.t_end, setup.material
    system = CoupledSystem([Block(n, b, [BlockTerm(b)]) for n, b in zip(names, bodies)])
    v0 = {n: np.full(b.n_dofs, v) for n, b, v in zip(names, bodies, setup.v_init)}
    pair = setup.pair_factory(system.dofmap)
    kind = "levelset" if method == "levelset" else "signorini"
    con = _contact(kind, pair, material)
    integ, opts = _integrator_options(method, newmark, integrator, theta)
    if integ == "explicit":
        opts["safety"] = 1.0
    meth = "levelset" if method == "levelset" else f"newmark-{newmark}"
    writers = []
    if folder is not None:
        frames = np.linspace(0.0, t_end, 61)
        writers.append(DynamicRunWriter(folder, system, frame_times=frames, prefix=prefix))
    listener = _progress_listener(progress, t_end, span)
    res = solve(
        system,
        integ,
        t_end=t_end,
        dt=dt,
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
    t = res.times
    lam = res.multipliers[con.name][:, 0]
    pressure = -lam
    kin = res.total_kinetic
    strain = res.total_strain
    # the history has one record per step (times[1:]); no work is done before the first step
    work = np.concatenate([[0.0], con.history(res).work])
    act = np.nonzero(lam != 0.0)[0]
    duration = float(t[act[-1]] - t[act[0]] + res.dt) if act.size else 0.0
    finals = []
    lumped = integ == "explicit"
    for b in system.blocks:
        vb = res.v[b.dofs]
        mb = system.block_mass(b)
        if lumped:
            finals.append(float(np.asarray(mb.sum(axis=1)).ravel() @ vb / mb.sum()))
        else:
            finals.append(float(np.ones(b.n_dofs) @ (mb @ vb) / mb.sum()))
    return TwoBarsResult(
        t=t,
        interface_velocity=res.fields["v"][:, setup.interface_dof(system.dofmap)],
        contact_pressure=pressure,
        kinetic=kin,
        internal=strain,
        total_energy=kin + strain,
        contact_work=work,
        final_velocities=finals,
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


def run_two_bars(
    method: str = "levelset",
    newmark: str = "trapezoidal",
    lengths: tuple[float, float] = (1.0, 1.0),
    young: float = 210e9,
    density: float = 7850.0,
    velocity: float = 1.0,
    velocity2: float = 0.0,
    elements: int = 100,
    cfl: float = 1.0,
    theta: float = 0.5,
    t_end: float | None = None,
    integrator: str = "theta",
    out: str | Path | None = None,
    progress: Callable[[float], None] | None = None,
    check_only: bool = False,
) -> TwoBarsResult | None:
    """Impact of two bars touching at t = 0 (see the module docstring).

    Parameters
    ----------
    method : {"levelset", "newmark", "both"}
        ``"both"`` runs the level-set model and the Newmark baseline (attached as ``.newmark``).
    newmark : {"trapezoidal", "hht"}
        Newmark variant: β = ¼, γ = ½, or HHT-α with α = −0.1.
    lengths : (float, float)
        L1, L2 (m).
    young, density : float
        E (Pa), ρ (kg/m³) of both bars.
    velocity, velocity2 : float
        Initial velocities of bar 1 and bar 2 (m/s); bar 1 must approach (v₀ > v₂).
    elements : int
        Elements per bar.
    cfl : float
        Δt = cfl × h_min / c.
    theta : float
        θ of the θ-scheme (level-set method), in [½, 1].
    t_end : float, optional
        End time (s); default 3 max(L1, L2)/c.
    integrator : {"theta", "explicit"}
        Time scheme of the level-set method (the θ-scheme with consistent mass, or central
        differences with lumped mass).
    out : path, optional
        Results folder (:class:`arlequin.io.ResultsFolder`): results.json, history.csv and
        one field series per bar (the Newmark baseline of ``method="both"`` in files prefixed
        ``newmark-trapezoidal_`` or ``newmark-hht_``), two_bars.png.
    progress : callable, optional
        ``progress(fraction)`` with the fraction of the simulated time done (both runs of
        ``method="both"`` together), at each new percent (the CLI's progress bar).
    check_only : bool
        Check every input and return None without running or writing anything.

    Returns
    -------
    TwoBarsResult
    """
    if method not in ("levelset", "newmark", "both"):
        raise ValueError(f"method must be 'levelset', 'newmark' or 'both', got {method!r}")
    _check_common(young, density, cfl, elements, t_end, theta, velocity=velocity,
                  velocity2=velocity2, length1=lengths[0], length2=lengths[1])  # fmt: skip
    l1, l2 = (float(x) for x in lengths)
    if not velocity > velocity2:
        raise ValueError(f"bar 1 must approach bar 2: velocity={velocity} <= velocity2={velocity2}")
    if check_only:
        return None
    material = IsotropicElastic(young, 0.3, density)
    ex = exact_two_bars((l1, l2), young, density, velocity, velocity2)
    ex["velocity_scale"] = velocity - velocity2
    c = ex["c"]
    n = int(elements)
    dt = cfl * min(l1, l2) / n / c
    t_end = 3.0 * max(l1, l2) / c if t_end is None else float(t_end)
    bar1 = _bar(-l1, 0.0, n, material)
    bar2 = _bar(0.0, l2, n, material)
    config = {
        "lengths": [l1, l2],
        "young": young,
        "density": density,
        "velocity": velocity,
        "velocity2": velocity2,
        "elements": n,
        "cfl": cfl,
        "theta": theta,
        "t_end": t_end,
    }

    def pair_factory(dofmap):
        s = ContactSurface(
            bar1.mesh, where=lambda x: x[0] > -0.5 * l1, offset=dofmap["bar1"], area=AREA
        )
        m = ContactSurface(
            bar2.mesh, where=lambda x: x[0] < 0.5 * l2, offset=dofmap["bar2"], area=AREA
        )
        return DeformableContactPair(s, m, dofmap)

    def interface_dof(dofmap):
        return int(dofmap["bar2"].node_dofs([np.argmin(bar2.mesh.p[0])])[0, 0])

    def one(meth: str, prefix: str = "", span: tuple[float, float] = (0.0, 1.0)) -> TwoBarsResult:
        setup = _Impact(
            [bar1, bar2],
            ["bar1", "bar2"],
            [velocity, velocity2],
            pair_factory,
            interface_dof,
            ex,
            dict(config, method=meth),
            material,
            dt,
            t_end,
        )
        return _run_1d(setup, _Scheme(meth, newmark, integrator, theta), folder, prefix,
                       progress, span)  # fmt: skip

    folder = _folder(out, "arlequin two-bars", dict(config, method=method, newmark=newmark,
                                                      integrator=integrator))  # fmt: skip
    if method == "both":
        res = one("levelset", span=(0.0, 0.5))
        # the baseline's files are prefixed (newmark-trapezoidal_history.csv...)
        res.newmark = one("newmark", f"newmark-{newmark}_", span=(0.5, 1.0))
    else:
        res = one(method)
    _finish(folder, res)
    return res


def run_wall(
    method: str = "levelset",
    newmark: str = "trapezoidal",
    length: float = 1.0,
    young: float = 210e9,
    density: float = 7850.0,
    velocity: float = 1.0,
    elements: int = 100,
    cfl: float = 1.0,
    theta: float = 0.5,
    t_end: float | None = None,
    integrator: str = "theta",
    out: str | Path | None = None,
) -> TwoBarsResult:
    """A bar on [−L, 0] at velocity v₀ > 0 against a rigid wall at x = 0 (touching at t = 0).

    Exact: pressure ρ c v₀ during 2L/c, then the bar rebounds at −v₀. The wall is a
    :class:`~arlequin.models.PlaneObstacle` (φ = −x). Parameters as :func:`run_two_bars`; the
    result's ``final_velocities`` has one entry and ``interface_velocity`` is the bar's
    contact-node velocity (exact 0 during contact).
    """
    if method not in ("levelset", "newmark"):
        raise ValueError(f"method must be 'levelset' or 'newmark', got {method!r}")
    _check_common(young, density, cfl, elements, t_end, theta, velocity=velocity, length=length)
    if not velocity > 0:
        raise ValueError(f"the bar must approach the wall: velocity={velocity}")
    material = IsotropicElastic(young, 0.3, density)
    c = math.sqrt(young / density)
    L = float(length)
    n = int(elements)
    dt = cfl * L / n / c
    t_end = 3.0 * L / c if t_end is None else float(t_end)
    bar = _bar(-L, 0.0, n, material)
    ex = {
        "interface_velocity": 0.0,
        "pressure": density * c * velocity,
        "duration": 2.0 * L / c,
        "final_velocities": [-velocity],
        "c": c,
        "velocity_scale": velocity,
    }
    config = {
        "length": L,
        "young": young,
        "density": density,
        "velocity": velocity,
        "elements": n,
        "cfl": cfl,
        "theta": theta,
        "t_end": t_end,
        "method": method,
    }

    def pair_factory(dofmap):
        s = ContactSurface(
            bar.mesh, where=lambda x: x[0] > -0.5 * L, offset=dofmap["bar"], area=AREA
        )
        return RigidContactPair(s, PlaneObstacle([0.0], [-1.0]), dofmap)

    def interface_dof(dofmap):
        return int(dofmap["bar"].node_dofs([np.argmax(bar.mesh.p[0])])[0, 0])

    folder = _folder(out, "arlequin two-bars --wall", dict(config, newmark=newmark,
                                                             integrator=integrator))  # fmt: skip
    setup = _Impact(
        [bar], ["bar"], [velocity], pair_factory, interface_dof, ex, config, material, dt, t_end
    )
    res = _run_1d(setup, _Scheme(method, newmark, integrator, theta), folder)
    _finish(folder, res)
    return res


_UNITS = {"lengths": "m", "length": "m", "young": "Pa", "density": "kg/m^3", "velocity": "m/s",
          "velocity2": "m/s", "elements": "1", "cfl": "1", "theta": "1", "t_end": "s",
          "method": "", "newmark": "", "integrator": ""}  # fmt: skip
_RESULT_UNITS = {"velocity_rms_error": "1", "pressure_rms_error": "1", "duration_error_steps": "1",
                 "final_velocity_error": "1", "energy_loss": "1", "max_energy_gain": "1",
                 "contact_work": "J", "balance_error": "1", "contact_duration": "s", "dt": "s",
                 "final_velocities": "m/s"}  # fmt: skip


def _check_common(young, density, cfl, elements, t_end, theta, **finite) -> None:
    """Refuse, before any work, the inputs that would end in a division by zero, a NaN or a
    meaningless run, naming the quantity and its value."""
    for name, value in {"young": young, "density": density, "cfl": cfl, **finite}.items():
        if isinstance(value, bool) or not isinstance(value, (int, float, np.number)):
            raise ValueError(f"{name} must be a number, got {value!r}")
        if not math.isfinite(value):
            raise ValueError(f"{name} must be finite, got {name}={value}")
    for name, value in {"young": young, "density": density, "cfl": cfl}.items():
        if not value > 0.0:
            raise ValueError(f"{name} must be positive, got {name}={value}")
    for name in ("length", "length1", "length2"):
        if name in finite and not finite[name] > 0.0:
            raise ValueError(f"bar lengths must be positive, got {name}={finite[name]}")
    if isinstance(elements, bool) or int(elements) != elements or elements < 1:
        raise ValueError(f"elements must be a positive integer, got elements={elements}")
    if t_end is not None and not (math.isfinite(t_end) and t_end > 0.0):
        raise ValueError(f"t_end must be positive and finite (s), got t_end={t_end}")
    if not 0.5 <= theta <= 1.0:
        raise ValueError(f"theta must lie in [1/2, 1], got theta={theta}")


def _folder(out, command: str, config: dict[str, Any]) -> ResultsFolder | None:
    return None if out is None else ResultsFolder(out, command, config, _UNITS)


def _finish(folder: ResultsFolder | None, res: TwoBarsResult) -> None:
    """Results of every run (``newmark-*`` prefixed for the baseline) and the picture."""
    if folder is None:
        return
    for r in [res] + ([res.newmark] if res.newmark is not None else []):
        vals = {**r.metrics(), "contact_duration": r.contact_duration, "dt": r.dt,
                "final_velocities": r.final_velocities}  # fmt: skip
        prefix = "" if r is res else f"{r.method}:"
        folder.add_results(
            {prefix + k: v for k, v in vals.items()},
            {prefix + k: u for k, u in _RESULT_UNITS.items()},
        )
    plot_two_bars(res, str(folder.picture("two_bars")))
    folder.finish()
