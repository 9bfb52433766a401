"""The multi-time-step scheme (arlequin.solvers.dynamics.subcycling) on a 1D Arlequin bar.

The set-up: a coarse bar of 80 elements (1 m each) with a patch four times finer over its right
half, glued over 10 m (H1, coarse mediator, ramp weights), a cos² pulse of 10 m in the coarse-only
zone. The coarse model alone has a critical step 4× the coupled one, so its own limit allows up
to 3 fine steps per macro step at the default safety (0.9); the resonance bound allows one at the
default step and four at 0.3 of the critical step.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import skfem

from arlequin import ArlequinProblem, Patch
from arlequin.contract import SimulationError
from arlequin.models import IsotropicElastic, LinearElastic
from arlequin.solvers import (
    CentralDifference,
    SubcycledCentralDifference,
    solve,
    stable_time_step,
)

YOUNG, DENSITY = 1.0e9, 1.0e3
C = math.sqrt(YOUNG / DENSITY)


@pytest.fixture(scope="module")
def bar():
    mat = IsotropicElastic(YOUNG, 0.0, DENSITY)
    cm = LinearElastic(skfem.MeshLine(np.linspace(0.0, 80.0, 81)), mat, area=1.0)
    fm = LinearElastic(skfem.MeshLine(np.linspace(40.0, 80.0, 161)), mat, area=1.0)
    patch = Patch(fm, gluing_width=10.0, weights="ramp", coupling="H1", mediator="coarse",
                  epsilon=1e-3)  # fmt: skip
    system = ArlequinProblem(cm, [patch]).system()
    x = cm.mesh.p[0]
    pulse = np.where(abs(x - 20.0) < 5.0, np.cos(np.pi * (x - 20.0) / 10.0) ** 2, 0.0)
    u0 = {"coarse": 1e-3 * pulse, "patch0": np.zeros(fm.n_dofs)}
    dt = 0.9 * stable_time_step(system).critical
    return system, u0, dt


def test_one_step_ratio_is_the_one_step_scheme(bar):
    # m = 1 changes no operation: the same numbers bit for bit
    system, u0, dt = bar
    t_end = 50.0 / C
    one = solve(system, "explicit", t_end=t_end, dt=dt, u0=u0, t_eval=[0.5 * t_end, t_end])
    mts = solve(system, "explicit-mts", t_end=t_end, dt=dt, u0=u0, t_eval=[0.5 * t_end, t_end],
                slow_blocks=["coarse"], step_ratio=1)  # fmt: skip
    assert np.array_equal(one.u, mts.u) and np.array_equal(one.v, mts.v)
    assert np.array_equal(one.total_energy, mts.total_energy)


def _quarters(res) -> list[float]:
    bal = np.abs(res.balance) / res.total_energy.max()
    return [bal[k * bal.size // 4 : (k + 1) * bal.size // 4].max() for k in range(4)]


def test_resonance_bound_keeps_the_macro_step_below_half_the_fast_period(bar):
    system, u0, dt = bar
    crit = dt / 0.9
    near = SubcycledCentralDifference(system, dt, u0=u0, step_ratio=4)
    # at 0.9 of the critical step, H ω_f ≤ 0.9π leaves no room: one step
    assert near.fast_frequency() * crit == pytest.approx(2.0327, rel=1e-4)  # ω_f = 2/Δt_f
    assert near._m_n == 1
    small = SubcycledCentralDifference(system, 0.3 * crit, u0=u0, step_ratio=8)
    assert small._m_n == 4  # ⌊0.9π / (2.0327 × 0.3)⌋ = 4 (the slow cap is 11)
    free = SubcycledCentralDifference(system, 0.3 * crit, u0=u0, step_ratio=8,
                                      resonance_bound=False)  # fmt: skip
    assert free._m_n == 8


def test_four_steps_per_coarse_step_bounded_energy(bar):
    # h = 0.3 Δt_crit, m = 4 (H ω_f = 2.4 < 0.9π): 18000 fine steps, about 27 transits of
    # the pulse through the band. Measured: 0.61%, 0.57%, 0.56%, 0.58% per quarter (the
    # one-step scheme: 1.7e-15). The energy form oscillates (the scheme conserves another
    # quadratic form) but does not drift: the scheme is symplectic.
    system, u0, dt = bar
    res = solve(system, "explicit-mts", n_steps=18000, dt=0.3 * dt / 0.9, u0=u0, step_ratio=4,
                record_every=18)  # fmt: skip
    quarters = _quarters(res)
    assert max(quarters) < 0.008
    assert quarters[-1] < 1.1 * quarters[0]


def test_two_steps_at_the_default_step_without_the_bound(bar):
    # the default step with m = 2 (resonance_bound=False): H ω_f = 3.66, still stable at this
    # step (measured 0.86%, 0.81%, 0.74%, 0.69% per quarter over 6000 steps), though steps of
    # 0.82 or 0.94 Δt_crit are not (a review's eigenvalue analysis): the bound is the default
    system, u0, dt = bar
    res = solve(system, "explicit-mts", n_steps=6000, dt=dt, u0=u0, step_ratio=2,
                resonance_bound=False, record_every=6)  # fmt: skip
    quarters = _quarters(res)
    assert max(quarters) < 0.012
    assert quarters[-1] <= quarters[0]


def test_macro_steps_follow_the_slow_critical_step(bar):
    system, u0, dt = bar
    integ = SubcycledCentralDifference(system, dt, u0=u0, step_ratio=8, resonance_bound=False)
    for _ in range(30):
        integ.step()
    cap = math.floor(integ.safety * integ.slow_critical_time_step() / dt)
    assert cap == 3  # the coarse bar alone: 4× the coupled critical step, times 0.9
    assert set(integ.ratios) == {3}
    assert integ.macro_steps == 10


def test_resonating_macro_step_stops_with_a_clear_error(bar):
    # m = 3 at the default step (H ω_f = 5.5 > π, the bound switched off): measured, the
    # balance error passes 5% after about 1150 steps and the run stops
    system, u0, dt = bar
    with pytest.raises(SimulationError, match="lower step_ratio"):
        solve(system, "explicit-mts", n_steps=3000, dt=dt, u0=u0, step_ratio=3,
              resonance_bound=False, record_every=100)  # fmt: skip


def test_output_times_land_on_macro_times(bar):
    system, u0, dt = bar
    t_eval = np.linspace(0.0, 40.0 / C, 8)[1:]
    res = solve(system, "explicit-mts", t_end=t_eval[-1], dt=0.3 * dt, u0=u0, t_eval=t_eval,
                step_ratio=4)  # fmt: skip
    assert np.array_equal(res.times[1:], t_eval)
    assert max(res.step_sizes) <= 0.3 * dt  # shortened macro steps never lengthen a fine step


def test_snapshot_inside_a_macro_step_restores_bit_for_bit(bar):
    system, u0, dt = bar
    integ = SubcycledCentralDifference(system, dt, u0=u0, step_ratio=3, resonance_bound=False)
    for _ in range(7):  # ends inside a macro step (7 = 2 × 3 + 1)
        integ.step()
    snap = integ.snapshot()
    for _ in range(50):
        integ.step()
    u_first = integ.u.copy()
    integ.restore(snap)
    for _ in range(50):
        integ.step()
    assert np.array_equal(integ.u, u_first)


def test_step_size_and_stops_cannot_change_inside_a_macro_step(bar):
    system, u0, dt = bar
    integ = SubcycledCentralDifference(system, dt, u0=u0, step_ratio=2, resonance_bound=False)
    integ.step()
    with pytest.raises(RuntimeError, match="start of a macro step"):
        integ.set_step_size(0.5 * dt)
    assert integ.dt == dt  # refused, unchanged
    with pytest.raises(RuntimeError, match="falls inside the current macro step"):
        integ.set_stops([integ.t + 0.5 * dt])


@pytest.mark.parametrize(
    "options, match",
    [
        ({"step_ratio": 0}, "step_ratio must be a positive integer"),
        ({"step_ratio": 1.5}, "step_ratio must be a positive integer"),
        ({"step_ratio": True}, "step_ratio must be a positive integer"),
        ({"slow_blocks": ["shell"]}, r"slow_blocks \['shell'\] are not blocks"),
        ({"slow_blocks": ["coarse", "patch0"]}, "at least one block must advance"),
        ({"slow_blocks": []}, "slow_blocks is empty"),
        ({"energy_tolerance": 0.0}, "energy_tolerance must be a positive number"),
        ({"check_every": 0}, "check_every must be a positive integer"),
    ],
)
def test_bad_options(bar, options, match):
    system, u0, dt = bar
    with pytest.raises(ValueError, match=match):
        SubcycledCentralDifference(system, dt, u0=u0, **options)


def test_registered_names():
    from arlequin.solvers import get_integrator

    for name in ("explicit-mts", "subcycling", "multi-time-step"):
        assert get_integrator(name) is SubcycledCentralDifference
    assert issubclass(SubcycledCentralDifference, CentralDifference)
