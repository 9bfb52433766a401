"""Implicit dynamics with plasticity (issue 29, Must show 7): a plane-strain cantilever, coarse
linear-elastic Q1 model plus a nested SmallStrainJ2 patch (B-bar) at the clamp, loaded at its tip
past first yield and unloaded so that it keeps a permanent set; run by Newmark (average
acceleration, full Newton with the consistent tangents) at ≥ 10× the explicit critical step and
by central differences (lumped masses) at 0.9× that step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest
import skfem

from arlequin.coupling.patches import Patch, refine_region
from arlequin.models import IsotropicElastic, J2Material, LinearElastic, SmallStrainJ2
from arlequin.problem.arlequin_problem import ArlequinProblem
from arlequin.solvers import solve, stable_time_step

# steel with a low yield stress and linear hardening (SI)
E, NU, RHO, SY, HARD = 210e9, 0.3, 7800.0, 250e6, 10e9
L, H = 1.0, 0.25  # cantilever length and height (m)
PATCH, GLUE = 0.5, 0.125  # patch length from the clamp and its gluing band (m)


@dataclass
class Case:
    problem: ArlequinProblem
    coarse: LinearElastic
    fine: SmallStrainJ2
    period: float  # first bending period (Euler-Bernoulli), s
    t_load: float  # duration of the sin² load pulse, s
    t_end: float
    critical: float  # critical step of the explicit coupled system, s
    tip_dof: int  # global dof of the tip's deflection (coarse node (L, H/2))


def first_yield_load() -> float:
    """Tip force per unit depth (N/m) at first yield of the clamped section (beam theory; plane
    strain, σ_z = ν σ_x: σ_vm = σ_x √(1 − ν + ν²))."""
    return SY / math.sqrt(1.0 - NU + NU**2) * H**2 / (6.0 * L)


def build(overload=1.5, levels=1, nx=16, ny=4, pulse=4.0, free=2.0, j2=SmallStrainJ2) -> Case:
    """The cantilever: tip load ``overload`` × the first-yield load, a sin² pulse of ``pulse``
    first periods, then ``free`` periods of free vibration about the permanent set; ``j2`` the
    patch's model class."""
    coarse_mesh = skfem.MeshQuad.init_tensor(np.linspace(0, L, nx + 1), np.linspace(0, H, ny + 1))
    fine_mesh = refine_region(coarse_mesh, levels=levels, box=((0.0, 0.0), (PATCH, H)))
    coarse = LinearElastic(coarse_mesh, IsotropicElastic(E, NU, RHO), "plane_strain")
    fine = j2(fine_mesh, J2Material(E, NU, RHO, SY, HARD), "plane_strain", bbar=True)
    problem = ArlequinProblem(coarse, [Patch(fine, gluing_width=GLUE, overlap_method="nested")])
    for block in ("coarse", "patch0"):
        problem.add_dirichlet(block, lambda x: x[0] < 1e-9)
    ei = E / (1.0 - NU**2) * H**3 / 12.0
    period = 2.0 * math.pi / (1.875**2 * math.sqrt(ei / (RHO * H * L**4)))
    t_load = pulse * period

    def amplitude(t: float) -> float:
        return math.sin(math.pi * t / t_load) ** 2 if t < t_load else 0.0

    q = overload * first_yield_load() / H
    problem.add_traction([0.0, -q], where=lambda x: x[0] > L - 1e-9, amplitude=amplitude)
    system = problem.system()
    critical = stable_time_step(system, "coupled").critical
    p = coarse_mesh.p
    node = int(np.argmin((p[0] - L) ** 2 + (p[1] - 0.5 * H) ** 2))
    tip = int(system.dofmap.offsets[0]) + 2 * node + 1
    return Case(problem, coarse, fine, period, t_load, t_load + free * period, critical, tip)


@dataclass
class Run:
    times: np.ndarray
    tip: np.ndarray  # tip deflection (m)
    result: object

    def permanent_set(self, t_load: float) -> float:
        """Time mean of the tip deflection over the free vibration after the load (m)."""
        free = self.times >= t_load
        t, u = self.times[free], self.tip[free]
        return float(np.trapezoid(u, t) / (t[-1] - t[0]))


def run(case: Case, integrator: str, ratio: float = 10.0, **options) -> Run:
    """Explicit at its default step (0.9 × critical); implicit at a whole number of equal steps
    no shorter than ``ratio`` × the critical explicit step."""
    if integrator == "explicit":
        r = solve(case.problem, "explicit", t_end=case.t_end, save_fields=True, record_every=4)
    else:
        n = int(case.t_end // (ratio * case.critical))
        r = solve(case.problem, integrator, dt=case.t_end / n, n_steps=n, save_fields=True,
                  **options)  # fmt: skip
        assert r.dt >= ratio * case.critical
    assert r.status == 0 and r.times[-1] == pytest.approx(case.t_end)
    return Run(r.times, r.fields["u"][:, case.tip_dof], r)


def compare(case: Case, ref: Run, other: Run) -> tuple[float, float]:
    """(max over the implicit times of |Δ tip deflection| / max |tip deflection|, relative
    difference of the permanent sets)."""
    diff = np.abs(np.interp(other.times, ref.times, ref.tip) - other.tip)
    history = float(np.max(diff) / np.max(np.abs(ref.tip)))
    s_ref, s_other = ref.permanent_set(case.t_load), other.permanent_set(case.t_load)
    return history, abs(s_other - s_ref) / abs(s_ref)


def material_balance(r) -> tuple[float, float]:
    """(max_t |T + S + D − W| / W_ext(t_end), the same at t_end), W_ext(t_end) > 0 the net work
    of the load pulse."""
    w_end = float(r.total_external_work[-1])
    bal = r.material_balance
    return float(np.max(np.abs(bal)) / w_end), float(abs(bal[-1]) / w_end)


def plastic_extent(case: Case, r) -> tuple[float, float]:
    """(max ε̄p, largest x of a yielded quadrature point (m)) of the final patch state."""
    eqps = case.fine.equivalent_plastic_strain(r.states["patch0"][0])
    x = case.fine.quadrature_points()[0]
    return float(eqps.max()), float(x[eqps > 0.0].max())


# the default case: 3 periods of load pulse (peak 1.5 × the first-yield load), 1.5 free
@pytest.fixture(scope="module")
def default_runs():
    case = build(pulse=3.0, free=1.5)
    return case, run(case, "explicit"), run(case, "newmark")


def test_newmark_at_10x_matches_explicit(default_runs):
    case, exp, imp = default_runs
    ratio = imp.result.dt / exp.result.dt
    assert imp.result.dt >= 10.0 * case.critical and ratio >= 11.0  # 396 vs 4407 steps
    # it yields (in the patch's free zone, away from its gluing band) and keeps a set
    for r in (exp.result, imp.result):
        eqps, x_max = plastic_extent(case, r)
        assert eqps > 1e-3 and x_max < PATCH - GLUE  # measured 1.28e-3 up to x = 0.306 m
    s_exp = exp.permanent_set(case.t_load)
    assert s_exp < -0.1 * np.max(np.abs(exp.tip))  # −0.775 mm after a 6.00 mm peak
    history, set_diff = compare(case, exp, imp)
    # the bound, 1 %; measured 1.7e-3 of the 6.00 mm peak (Newmark's period error
    # at 88 steps a period) and 4.3e-3 on the set
    assert history <= 0.01, history
    assert set_diff <= 0.01, set_diff


def test_newmark_energy_balance_with_plastic_dissipation(default_runs):
    _, exp, imp = default_runs
    r = imp.result
    # the plastic dissipation is most of the pulse's net work: 3.06 kJ of 3.30 kJ
    assert r.total_dissipation[-1] > 0.8 * r.total_external_work[-1]
    assert r.total_dissipation[0] == 0.0 and np.all(np.diff(r.total_dissipation) >= 0.0)
    # T + stored + plastic dissipation − W: the bound 0.5 % of the external work;
    # measured 3.0e-4 (max over time and at the end: the trapezoidal rule's internal work
    # against the return map's backward-Euler dissipation, O(Δt) over the plastic steps)
    worst, end = material_balance(r)
    assert worst <= 5e-3 and end <= 5e-3, (worst, end)
    # the scheme's own balance (the internal work of the forces) closes to the Newton
    # tolerance: measured 7e-13
    assert r.relative_balance() <= 1e-9
    # central differences: measured 2.5e-5 (the explicit step is 11× shorter)
    worst, end = material_balance(exp.result)
    assert worst <= 1e-3 and end <= 1e-3, (worst, end)


def test_hht_runs_the_same_case(default_runs):
    case, exp, _ = default_runs
    hht = run(case, "hht", alpha=-0.05)
    history, set_diff = compare(case, exp, hht)
    # measured (α = −0.05): 1.7e-3 and 4.6e-3; HHT damps the high modes, the first one
    # (ωΔt = 0.07) barely
    assert history <= 0.01 and set_diff <= 0.01, (history, set_diff)
    worst, end = material_balance(hht.result)
    assert worst <= 5e-3 and end <= 5e-3, (worst, end)  # measured 3e-4


# ------------------------------------------------------------------ the energy accounting
def _short(case: Case, integrator: str, steps: int = 60):
    """The first ``steps`` steps of the case at 10× the critical step, loaded to yield."""
    opts = {} if integrator == "explicit" else {"dt": 10.0 * case.critical}
    return solve(case.problem, integrator, n_steps=steps, **opts)


def test_energies_use_the_models_stored_energy_and_dissipation():
    case = build(overload=3.0, pulse=0.5)
    r = _short(case, "newmark")
    system = case.problem.system()
    term = system.blocks[1].terms[0]
    state = r.states["patch0"][0]
    assert r.dissipation["patch0"][-1] > 0.0  # it has yielded
    assert r.stored["patch0"][-1] == case.fine.stored_energy_of_state(state, term.weight)
    assert r.dissipation["patch0"][-1] == case.fine.plastic_dissipation(state, term.weight)
    # the linear coarse block: ½ uᵀK u, no dissipation
    np.testing.assert_array_equal(r.stored["coarse"], r.strain["coarse"])
    assert not np.any(r.dissipation["coarse"])
    # the nonlinear block's strain is still the internal work: stored + dissipated, up to the
    # trapezoidal rule against the return map's backward Euler; measured 3.9e-3 of it here
    # (3× the first-yield load in half a period: large plastic increments per step)
    internal = r.strain["patch0"][-1]
    parts = r.stored["patch0"][-1] + r.dissipation["patch0"][-1]
    assert abs(parts - internal) <= 1e-2 * internal


def test_linear_runs_report_stored_equal_to_strain():
    """A linear system: stored = strain, no dissipation, the material balance is the balance
    (its existing accounting unchanged)."""
    coarse_mesh = skfem.MeshQuad.init_tensor(np.linspace(0, L, 9), np.linspace(0, H, 3))
    fine_mesh = refine_region(coarse_mesh, levels=1, box=((0.0, 0.0), (PATCH, H)))
    steel = IsotropicElastic(E, NU, RHO)
    coarse = LinearElastic(coarse_mesh, steel, "plane_strain")
    fine = LinearElastic(fine_mesh, steel, "plane_strain")
    problem = ArlequinProblem(coarse, [Patch(fine, gluing_width=GLUE, overlap_method="nested")])
    for block in ("coarse", "patch0"):
        problem.add_dirichlet(block, lambda x: x[0] < 1e-9)
    problem.add_traction([0.0, -1e6], where=lambda x: x[0] > L - 1e-9)
    for integrator in ("explicit", "newmark"):
        r = solve(problem, integrator, n_steps=40)
        for name in ("coarse", "patch0"):
            np.testing.assert_array_equal(r.stored[name], r.strain[name])
            assert not np.any(r.dissipation[name])
        np.testing.assert_array_equal(r.material_balance, r.balance)


class _NoEnergies(SmallStrainJ2):
    """SmallStrainJ2 without the optional energy members."""

    stored_energy_of_state = None


def test_models_without_energy_members_fall_back_to_the_internal_work():
    case = build(overload=3.0, pulse=0.5, j2=_NoEnergies)
    r = _short(case, "newmark")
    assert r.strain["patch0"][-1] > 0.0
    np.testing.assert_array_equal(r.stored["patch0"], r.strain["patch0"])
    assert not np.any(r.dissipation["patch0"])
    np.testing.assert_array_equal(r.material_balance, r.balance)


@pytest.mark.slow
def test_finer_patch_at_20x_the_explicit_step():
    """The patch refined twice (cells of 15.6 mm, 8 through the depth), 4 periods of load and
    2 free: Newmark and HHT at 20× the (halved) critical step, i.e. at the default case's step:
    the implicit step does not follow the patch's refinement. About 2 min."""
    case = build(levels=2, pulse=4.0, free=2.0)
    exp = run(case, "explicit")
    eqps, x_max = plastic_extent(case, exp.result)
    assert eqps > 2e-3 and x_max < PATCH - GLUE  # measured 2.40e-3 up to x = 0.340 m
    for integrator, opts in (("newmark", {}), ("hht", {"alpha": -0.05})):
        imp = run(case, integrator, ratio=20.0, **opts)  # 528 steps against 11749
        history, set_diff = compare(case, exp, imp)
        # measured: Newmark 4.1e-3 of the 6.52 mm peak and 8.8e-4 on the 1.18 mm set; HHT
        # 3.9e-3 and 8.7e-4 (the bound 1 %)
        assert history <= 0.01 and set_diff <= 0.01, (integrator, history, set_diff)
        # measured 3.1e-4 for both (the bound 0.5 %)
        worst, end = material_balance(imp.result)
        assert worst <= 5e-3 and end <= 5e-3, (integrator, worst, end)
