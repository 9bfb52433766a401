"""The quasi-static solver (arlequin.solvers.statics.quasi_static): load stepping with Newton on the
coupled saddle point, checked against the linear static solver (exact: the same equations), on
a nonlinear model with an exact tangent (quadratic convergence), and for its input errors."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import scipy.sparse as sp
import skfem

from arlequin import (
    ArlequinProblem,
    NewtonError,
    Patch,
    refine_region,
    solve_quasi_static,
    solve_static,
)
from arlequin.contract import StateError
from arlequin.models import IsotropicElastic, LinearElastic
from arlequin.solvers import QuasiStaticSolver

STEEL = IsotropicElastic(young=210e9, poisson=0.3, density=7850.0)


class StiffeningElastic(LinearElastic):
    """A nonlinear test model: f(u) = K u + c (K u)³ componentwise, tangent K + 3c diag((Ku)²) K
    (exact). ``limit`` raises a StateError where |u| exceeds it (an 'inverted cell')."""

    is_linear = False

    def __init__(self, *args, c: float = 0.0, limit: float | None = None, **kwargs):
        super().__init__(*args, **kwargs)
        self.c, self.limit = c, limit

    def initial_state(self, weight=None):
        return None

    def internal_force(self, u, state=None, weight=None):
        if self.limit is not None and np.max(np.abs(u)) > self.limit:
            raise StateError("displacement beyond the test limit")
        ku = self.stiffness(weight) @ u
        return ku + self.c * ku**3, state

    def tangent(self, u, state=None, weight=None):
        k = self.stiffness(weight)
        ku = k @ u
        return (k + sp.diags(3.0 * self.c * ku**2) @ k).tocsr()


def _problem(fine_model=None, traction=1e8):
    cm = skfem.MeshQuad.init_tensor(np.linspace(0, 2, 9), np.linspace(0, 1, 5))
    fm = refine_region(cm, levels=1, box=((1.0, 0.0), (2.0, 1.0)))
    coarse = LinearElastic(cm, STEEL, "plane_strain")
    fine = fine_model(fm) if fine_model else LinearElastic(fm, STEEL, "plane_strain")
    problem = ArlequinProblem(coarse, [Patch(fine, gluing_width=0.25)])
    problem.add_dirichlet("coarse", lambda x: np.isclose(x[0], 0.0))
    problem.add_traction([traction, 0.0], where=lambda x: np.isclose(x[0], 2.0))
    return problem


@pytest.mark.parametrize("condense", [True, False])
def test_linear_problem_equals_the_static_solve(condense):
    """Linear models: one Newton iteration a step, the static solution at every load factor
    (the same discrete equations: agreement to round-off)."""
    problem = _problem()
    static = solve_static(problem)
    result = solve_quasi_static(problem, load=1.0, steps=3, condense=condense)
    assert result.status == "completed"
    assert result.load_factors == pytest.approx([0.0, 1 / 3, 2 / 3, 1.0])
    # one iteration the first step; then the last increment extrapolated is exact (0 or 1)
    assert result.newton_iterations[0] == 1
    assert all(n <= 1 for n in result.newton_iterations)
    err = np.linalg.norm(result.u - static.u) / np.linalg.norm(static.u)
    assert err < 1e-10, err
    lam_s = static.multipliers["coupling:patch0"]
    lam_q = result.multipliers["coupling:patch0"]
    assert np.linalg.norm(lam_q - lam_s) < 1e-8 * np.linalg.norm(lam_s)


def test_condensed_and_full_newton_agree_on_a_nonlinear_patch():
    """The condensed Newton systems give the full saddle point's iterates (to round-off), and
    Newton converges quadratically with the exact tangent: once below 1e-3, each residual is
    at most 10 × the square of the previous one."""
    runs = []
    for condense in (True, False):
        problem = _problem(lambda m: StiffeningElastic(m, STEEL, "plane_strain", c=2e-16))
        res = solve_quasi_static(problem, load=1.0, steps=2, condense=condense)
        assert res.status == "completed"
        assert QuasiStaticSolver(problem, condense=condense).saddle.condensed == condense
        runs.append(res)
        for hist in res.residuals:
            for r0, r1 in itertools.pairwise(hist):
                if r0 < 1e-3 and r1 > 1e-14:
                    assert r1 <= 10.0 * r0**2, hist
    a, b = runs
    assert max(a.newton_iterations) > 1  # nonlinear enough to need iterations
    assert np.linalg.norm(a.u - b.u) <= 1e-9 * np.linalg.norm(b.u)


def test_a_state_error_cuts_the_step_then_stops_with_a_named_error():
    """A model that refuses every displacement beyond a bound: the step is cut down to the
    smallest, then NewtonError names the cause and keeps the converged steps."""
    probe = solve_quasi_static(_problem(), load=1.0, steps=1)
    umax = np.max(np.abs(probe.u))
    problem = _problem(lambda m: StiffeningElastic(m, STEEL, "plane_strain", limit=0.5 * umax))
    with pytest.raises(NewtonError, match="state was invalid") as err:
        solve_quasi_static(problem, load=1.0, steps=4, min_step=1 / 64)
    converged = err.value.result.load_factors
    assert converged[-1] == pytest.approx(0.5, abs=1 / 64 + 1e-12)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"steps": 0}, "steps"),
        ({"steps": 2.5}, "steps"),
        ({"load": -1.0}, "load"),
        ({"tol": 0.0}, "tol"),
        ({"max_iterations": 0}, "max_iterations"),
    ],
)
def test_bad_input_is_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        solve_quasi_static(_problem(), **kwargs)


def test_solve_static_never_gives_the_linear_answer_of_a_nonlinear_problem():
    """A nonlinear patch: solve_static solves it by Newton (the quasi-static solution in one
    load step, to the solver's tolerance), not by the linear solve of its initial stiffness."""
    problem = _problem(lambda m: StiffeningElastic(m, STEEL, "plane_strain", c=2e-16))
    static = solve_static(problem)
    qs = solve_quasi_static(problem, load=1.0, steps=4)
    assert np.linalg.norm(static.u - qs.u) <= 1e-8 * np.linalg.norm(qs.u)
    assert static.residual <= 1e-10
    assert set(static.strain_energy) == {"coarse"}  # the nonlinear block's is not given
    linear = solve_static(_problem())
    assert np.linalg.norm(static.u - linear.u) > 1e-3 * np.linalg.norm(linear.u)


def test_solve_static_of_a_yielding_j2_patch_is_elastoplastic():
    """SmallStrainJ2 (σy = 240 MPa, H = 10 GPa) pulled past yield (issue 29's report: the
    linear answer came back without a word): a plane-strain bar free laterally yields at
    σ_xx = σy / √(1 − ν + ν²) = 270 MPa; at 350 MPa the plastic strain of the patch's half
    (≈ 6e-3) is several times the elastic strain (1.7e-3), so the tip moves more than 1.2 times
    the elastic answer."""
    from arlequin.models import J2Material, SmallStrainJ2

    mat = J2Material(210e9, 0.3, 7850.0, 240e6, hardening_modulus=10e9)
    problem = _problem(lambda m: SmallStrainJ2(m, mat, "plane_strain", bbar=True), 3.5e8)
    plastic = solve_static(problem)
    elastic = solve_static(_problem(traction=3.5e8))
    # the tip is in the patch, which carries the energy there (measured ratio 2.32)
    tip = np.max(plastic.displacements["patch0"][0::2])
    assert tip > 1.2 * np.max(elastic.displacements["patch0"][0::2])


def test_a_coarse_model_past_yield_outside_the_patch_is_reported():
    """A J2 patch over half the bar: pulled at 350 MPa the coarse elastic half outside the
    patch carries at least 1.3 times the yield stress (240 MPa; von Mises of a plane strain bar
    free laterally: σ √(1 − ν + ν²) = 0.89 σ, and more at the clamped corners: 1.53 measured):
    CoarseYieldWarning and max_coarse_yield_ratio > 1; at 100 MPa it stays below 1 (0.38
    measured), without a warning."""
    import warnings

    from arlequin import CoarseYieldWarning
    from arlequin.models import J2Material, SmallStrainJ2

    mat = J2Material(210e9, 0.3, 7850.0, 240e6, hardening_modulus=10e9)

    def patch(m):
        return SmallStrainJ2(m, mat, "plane_strain", bbar=True)

    with pytest.warns(CoarseYieldWarning, match="outgrown the patches"):
        high = solve_quasi_static(_problem(patch, 3.5e8), load=1.0, steps=2)
    assert high.max_coarse_yield_ratio >= 3.5e8 * 0.889 / 240e6
    with warnings.catch_warnings():
        warnings.simplefilter("error", CoarseYieldWarning)
        low = solve_quasi_static(_problem(patch, 1.0e8), load=1.0, steps=1)
    assert 0.0 < low.max_coarse_yield_ratio < 1.0
