"""Freely vibrating plane-strain cantilever with a non-nested refined patch (issue 3, Must show 4).

L/H = 4, clamped end covered by a jittered (non-nested) triangle patch glued along its interior
edge, mesh ratios 1:0.75 and 1:0.5. Released from its static deflection under a uniform body
force (mostly the first bending mode). Bound from the issue: max over t of |E(t) − E(0)|/E(0) ≤
1e-3 over 100 periods of the first mode (slow tests; the default run checks 10 periods), E the
α-weighted kinetic plus strain energy (explicit: mid-step velocities averaged), no blow-up, both
integrators (central differences at the default step, 0.9 × the computed critical step; the
trapezoidal Newmark rule at the same step).
"""

from __future__ import annotations

import numpy as np
import pytest

from arlequin.demos.cantilever import build_cantilever
from arlequin.solvers import solve

CASES = [(ratio, integ) for ratio in (0.75, 0.5) for integ in ("explicit", "newmark")]


def _run(ratio: float, integrator: str, periods: int):
    cant = build_cantilever(ratio=ratio)
    assert cant.problem.couplings[0].overlap.method == "intersection"  # non-nested overlap
    system = cant.problem.system()
    r = solve(system, integrator, t_end=periods * cant.period, u0=cant.u0, record_every=5)
    return cant, r


def _check(cant, r, periods: int) -> None:
    assert r.status == 0 and r.success
    assert r.times[-1] == pytest.approx(periods * cant.period)
    assert np.all(np.isfinite(r.total_energy))
    assert r.energy_drift() <= 1e-3, r.energy_drift()
    # the coupling is active: multipliers and the coupling work on each model are non-zero,
    # and the coupling forces do no net work on the coupled pair
    e0 = r.total_energy[0]
    assert np.max(np.abs(r.multipliers["coupling:patch0"])) > 0.0
    assert np.max(np.abs(r.coupling_work["coarse"])) > 1e-3 * e0
    assert np.max(np.abs(r.total_coupling_work)) < 1e-8 * e0
    # the clamps do no work
    assert np.max(np.abs(r.total_constraint_work)) < 1e-8 * e0


@pytest.mark.parametrize(("ratio", "integrator"), CASES)
def test_cantilever_energy_10_periods(ratio, integrator):
    cant, r = _run(ratio, integrator, 10)
    _check(cant, r, 10)


@pytest.mark.slow
@pytest.mark.parametrize(("ratio", "integrator"), CASES)
def test_cantilever_energy_100_periods(ratio, integrator):
    cant, r = _run(ratio, integrator, 100)
    _check(cant, r, 100)
