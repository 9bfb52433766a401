"""Variable time steps of the explicit scheme, output times, and redoing / restarting steps.

The step sequence is Δt_n = Δt₀ (1 + 0.3 sin(2πn/P)) with max Δt_n = 0.9 Δt_crit (Δt₀ = 0.9
Δt_crit/1.3). Its period P Δt₀ = 0.46 T₁ (T₁ the first mode period) is held fixed in time while
Δt₀ is refined, and lies between the first two mode periods (far from both): a smooth
modulation, not the per-step random jumps that make a variable-step scheme parametrically
unstable. The variable-step central difference is velocity Verlet with the steps Δt_n, so it
is second order for any step sequence: the observed order of the displacement at a fixed time,
against a run on the same mesh at 1e-3 of the critical step, must be at least 1.9. The energy is
the α-weighted kinetic energy of the full-step velocity plus the strain energy (docs/dynamics.md);
over 100 periods it must stay within 1e-3 of its initial value (measured 2.7e-4 for the bar,
9.3e-6 for the cantilever; orders 1.97 and 2.03).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp
import skfem

from arlequin.demos.cantilever import build_cantilever
from arlequin.demos.two_bars import run_two_bars
from arlequin.models import (
    ContactSurface,
    DeformableContactPair,
    IsotropicElastic,
    LevelSetContact,
    LinearElastic,
)
from arlequin.problem.system import Block, BlockTerm, CoupledSystem, LinearConstraint
from arlequin.solvers import (
    CentralDifference,
    CriticalFraction,
    StepSchedule,
    ThetaScheme,
    solve,
    stable_time_step,
)

MODULATION = 0.46  # P Δt₀ / T₁


def schedule(dt0: float, period_steps: float) -> StepSchedule:
    return StepSchedule(
        lambda it: dt0 * (1.0 + 0.3 * math.sin(2.0 * math.pi * it.step_count / period_steps))
    )


def clamped_bar(n: int = 60):
    """Fixed–free bar (c = 1, L = 1): T₁ = 4 L / c; initial shape: the first mode."""
    bar = LinearElastic(skfem.MeshLine(np.linspace(0.0, 1.0, n + 1)), IsotropicElastic(1.0, 0.0))
    clamp = LinearConstraint(
        sp.csr_matrix(([1.0], ([0], [0])), shape=(1, bar.n_dofs)), None, "clamp", kind="dirichlet"
    )
    system = CoupledSystem([Block("bar", bar, [BlockTerm(bar)])], [clamp])
    u0 = 1e-3 * np.sin(0.5 * np.pi * bar.mesh.p[0])
    return system, u0, 4.0


def order_and_energy(system, u0, period: float, t_fixed: float, energy_periods: int):
    crit = stable_time_step(system).critical
    ref = solve(system, "explicit", t_end=t_fixed, dt=1e-3 * crit, u0=u0, record_every=10**9)
    errs, dts = [], []
    for k in range(3):
        dt0 = 0.9 * crit / 1.3 / 2**k
        run = solve(
            system,
            "explicit",
            t_eval=[t_fixed],
            u0=u0,
            step_controller=schedule(dt0, MODULATION * period / dt0),
        )
        assert run.times[-1] == t_fixed  # the output time is reached exactly
        if k == 0:
            # the sequence does reach its largest steps (all but the last, shortened one)
            n = np.arange(run.n_steps - 1)
            taken = dt0 * (1.0 + 0.3 * np.sin(2.0 * np.pi * n / (MODULATION * period / dt0)))
            assert 0.89 * crit <= taken.max() <= 0.9 * crit * (1 + 1e-12)
        errs.append(float(np.max(np.abs(run.u - ref.u))))
        dts.append(dt0)
    order = float(np.polyfit(np.log(dts), np.log(errs), 1)[0])
    dt0 = 0.9 * crit / 1.3
    long = solve(
        system,
        "explicit",
        t_end=energy_periods * period,
        u0=u0,
        step_controller=schedule(dt0, MODULATION * period / dt0),
        record_every=10,
    )
    return order, errs, long


def test_bar_variable_steps_second_order_and_energy():
    system, u0, period = clamped_bar()
    order, errs, long = order_and_energy(system, u0, period, 0.15 * period, 100)
    assert order >= 1.9, (order, errs)
    assert long.energy_drift() <= 1e-3
    # the steps really vary: (max − min)/max = 0.6/1.3 = 0.46 for the sequence
    assert np.ptp(long.step_sizes[1:]) > 0.45 * long.step_sizes.max()


@pytest.mark.slow
def test_cantilever_variable_steps_second_order_and_energy():
    cant = build_cantilever(ratio=0.5)
    system = cant.problem.system()
    order, errs, long = order_and_energy(system, cant.u0, cant.period, 0.12 * cant.period, 100)
    assert order >= 1.9, (order, errs)
    assert long.energy_drift() <= 1e-3
    # the coupling forces still do no net work on the coupled pair
    assert np.max(np.abs(long.total_coupling_work)) < 1e-8 * long.total_energy[0]


@pytest.mark.parametrize("integrator", ["explicit", "newmark", "theta"])
def test_t_eval_reached_exactly_and_only_recorded(integrator):
    system, u0, _ = clamped_bar(20)
    t_eval = [0.013, 0.5, 0.51, 1.7, np.pi / 2.0]
    t_eval.sort()
    r = solve(system, integrator, t_eval=t_eval, u0=u0, dt=0.03)
    assert r.times.tolist() == [0.0, *t_eval]  # bitwise: the steps land on them
    assert r.step_sizes.max() <= 0.03
    with pytest.raises(ValueError, match="strictly increasing"):
        solve(system, integrator, t_eval=[0.2, 0.1], u0=u0, dt=0.03)


def test_critical_fraction_controller_follows_the_estimate():
    system, u0, _ = clamped_bar(20)
    r = solve(system, "explicit", n_steps=50, u0=u0, step_controller=CriticalFraction(0.5, 7))
    crit = stable_time_step(system).critical
    np.testing.assert_allclose(r.step_sizes[1:], 0.5 * crit, rtol=1e-12)  # linear: constant


def test_caller_steps_equal_a_schedule():
    """step(dt) by the caller redoes the pending impulse: same run as a schedule, bitwise."""
    system, u0, _ = clamped_bar(20)
    crit = stable_time_step(system).critical
    sizes = 0.5 * crit * (1.0 + 0.3 * np.sin(np.arange(40)))
    a = CentralDifference(system, step_controller=StepSchedule(lambda it: sizes[it.step_count]),
                          u0=u0)  # fmt: skip
    b = CentralDifference(system, dt=0.1 * crit, u0=u0)
    for dt in sizes[:30]:
        a.step()
        b.step(dt)
    # v and the multipliers reported at t depend on the step that follows t
    b.set_step_size(sizes[30])
    assert a.t == b.t
    np.testing.assert_array_equal(a.u, b.u)
    np.testing.assert_array_equal(a.v, b.v)
    assert a.energies() == b.energies()
    with pytest.raises(ValueError, match="exceeds the critical step"):
        b.step(1.01 * crit)


def _two_bar_system(n: int = 30):
    mat = IsotropicElastic(1.0, 0.0, 1.0)
    bars = [
        LinearElastic(skfem.MeshLine(np.linspace(x0, x0 + 1.0, n + 1)), mat, area=1.0)
        for x0 in (-1.0, 0.0)
    ]
    system = CoupledSystem([Block(f"bar{i}", b, [BlockTerm(b)]) for i, b in enumerate(bars)])
    dm = system.dofmap
    pair = DeformableContactPair(
        ContactSurface(bars[0].mesh, where=lambda x: x[0] > -0.5, offset=dm["bar0"]),
        ContactSurface(bars[1].mesh, where=lambda x: x[0] < 0.5, offset=dm["bar1"]),
        dm,
    )
    v0 = {"bar0": np.ones(bars[0].n_dofs)}
    return system, LevelSetContact(pair, kappa=1.0), v0


@pytest.mark.parametrize("cls", [CentralDifference, ThetaScheme])
def test_snapshot_redo_and_restart_with_contact(cls):
    """A step redone from a snapshot, and a fresh integrator restored from it, give the same
    run to the bit: the contact constraint's state is an immutable record the integrator owns."""
    system, con, v0 = _two_bar_system()
    dt = 0.02
    a = cls(system, dt, v0=v0, constraints=[con])
    for _ in range(20):  # into the contact (it starts at t = 0 and lasts 2 L / c = 2)
        a.step()
    snap = a.snapshot()
    for _ in range(15):
        a.step()
    first = (a.u.copy(), a.v.copy(), a.energies(), a.constraint_states["contact"].work)
    a.restore(snap)
    for _ in range(15):
        a.step()
    again = (a.u.copy(), a.v.copy(), a.energies(), a.constraint_states["contact"].work)
    fresh = cls(system, dt, v0=v0, constraints=[con])
    fresh.restore(snap)
    for _ in range(15):
        fresh.step()
    other = (fresh.u, fresh.v, fresh.energies(), fresh.constraint_states["contact"].work)
    for run in (again, other):
        np.testing.assert_array_equal(run[0], first[0])
        np.testing.assert_array_equal(run[1], first[1])
        assert run[2] == first[2] and run[3] == first[3]
    assert first[3] < 0.0  # the contact did (dissipative) work


def test_contact_history_has_one_record_per_step_for_every_scheme():
    """The two recorders agree: the contact history is aligned with the result's times[1:]."""
    for integrator in ("theta", "explicit"):
        r = run_two_bars(elements=20, integrator=integrator, cfl=0.9)
        dyn = r.dynamic
        assert len(dyn.history("contact")) == dyn.times.size - 1
        assert r.contact_work.size == r.t.size


def test_driver_and_integrator_refuse_what_they_cannot_do():
    system, u0, _ = clamped_bar(10)
    with pytest.raises(ValueError, match=r"unknown option\(s\) \['betta'\] for the 'explicit'"):
        solve(system, "explicit", n_steps=2, u0=u0, betta=0.3)
    with pytest.raises(ValueError, match="dt must be a number of seconds, got the string"):
        solve(system, "explicit", n_steps=2, dt="1e-6")
    with pytest.raises(ValueError, match=r"strictly increasing, got 0.2 s then 0.1 s"):
        solve(system, "explicit", t_eval=[0.2, 0.1])
    from arlequin.contract import ContractError

    with pytest.raises(ContractError, match="constraint 1 is a MeshLine1"):
        solve(system, "explicit", n_steps=2, constraints=[skfem.MeshLine()])
    a = CentralDifference(system, u0=u0)
    a.set_stops([0.05])
    while a.status == "running":
        a.step()
    assert a.t == 0.05
    with pytest.raises(RuntimeError, match=r"finished at t = 5\.000000e-02 s"):
        a.step()
    other, _, _ = clamped_bar(12)
    with pytest.raises(ValueError, match="cannot be restored into a CentralDifference on 13"):
        CentralDifference(other).restore(a.snapshot())
    with pytest.raises(ValueError, match="snapshot of a CentralDifference"):
        ThetaScheme(system, 0.01).restore(a.snapshot())


def test_one_controller_serves_several_integrators_and_a_model_alone_runs():
    """The critical-step estimate lives in each integrator, not in the shared controller."""
    controller = CriticalFraction(0.9, every=5)
    coarse, u_c, _ = clamped_bar(10)
    fine, u_f, _ = clamped_bar(80)
    r1 = solve(coarse, "explicit", n_steps=10, u0=u_c, step_controller=controller)
    r2 = solve(fine, "explicit", n_steps=10, u0=u_f, step_controller=controller)
    assert r1.dt == pytest.approx(0.9 * stable_time_step(coarse).critical)
    assert r2.dt == pytest.approx(0.9 * stable_time_step(fine).critical)
    bar = fine.blocks[0].model
    r3 = solve(bar, "explicit", n_steps=3, u0=u_f)  # a model alone: block "model"
    assert list(r3.kinetic) == ["model"]


@pytest.mark.parametrize("integrator", ["explicit", "newmark", "hht", "theta"])
def test_constraint_work_agrees_with_the_integrators(integrator):
    """A bar hitting a wall (velocity-level LinearInequality): the constraint's own work, from
    the step impulses, equals the integrator's constraint work (the same forces and motion)."""
    from arlequin.solvers import LinearInequality

    n = 20
    bar = LinearElastic(skfem.MeshLine(np.linspace(0.0, 1.0, n + 1)), IsotropicElastic(1.0, 0.0))
    system = CoupledSystem([Block("bar", bar, [BlockTerm(bar)])])
    g = sp.csr_matrix(([1.0], ([0], [n])), shape=(1, bar.n_dofs))
    wall = LinearInequality(g, 1e-4, level="velocity", name="wall")
    r = solve(system, integrator, t_end=2.5, dt=0.04, constraints=[wall],
              v0=np.full(bar.n_dofs, 1e-3))  # fmt: skip
    own = r.constraint_states["wall"].work
    assert own < 0.0
    # exact for the schemes whose displacement increment is Δt (v⁻ + v⁺)/2 (trapezoidal
    # Newmark, θ = ½) or that apply impulses (explicit); HHT's β = (1 − α)²/4 ≠ ¼ moves u by
    # more than that: measured 1.0e-3 relative
    tol = 2e-3 if integrator == "hht" else 1e-12
    assert own == pytest.approx(r.total_constraint_work[-1], rel=tol)


def test_verbose_runs_log_their_progress(monkeypatch, caplog):
    # `arlequin -v`: every LOG_INTERVAL seconds of wall time one line with the step, t and dt
    import logging

    import numpy as np
    import skfem

    from arlequin.models import IsotropicElastic, LinearElastic
    from arlequin.problem.system import Block, BlockTerm, CoupledSystem
    from arlequin.solvers import solve
    from arlequin.solvers.run import driver

    monkeypatch.setattr(driver, "LOG_INTERVAL", 0.0)
    bar = LinearElastic(skfem.MeshLine(np.linspace(0, 1, 11)), IsotropicElastic(1e9, 0.0, 1e3))
    system = CoupledSystem([Block("bar", bar, [BlockTerm(bar)])])
    with caplog.at_level(logging.INFO, logger="arlequin.solvers.run.driver"):
        solve(system, "explicit", n_steps=3, v0=np.ones(bar.n_dofs))
    lines = [r.getMessage() for r in caplog.records if r.name == "arlequin.solvers.run.driver"]
    assert len(lines) == 3 and lines[-1].startswith("step 3, t = ")
