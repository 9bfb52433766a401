"""Rayleigh damping in the explicit scheme, against the scheme's exact modal recurrence.

With C = α M + β K and the lumped mass, the modes of (K, M) stay uncoupled: a run started on
one mode follows the scalar recurrence of that mode, x^{n+1} = x^n + Δt v^{n+1/2},
v^{n+1/2} = v^{n−1/2} + Δt̄ (−ω² x^n − 2ξω v^{n−1/2}), to round-off. The stable limit of that
recurrence is ω Δt = 2(√(1 + ξ²) − ξ) (checked on its amplification matrix here).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg as sla
import skfem

from arlequin.models import IsotropicElastic, LinearElastic
from arlequin.solvers import RayleighDamping, solve
from arlequin.solvers.system.operators import as_system

MAT = IsotropicElastic(1.0, 0.0, 1.0)


def _bar(n: int = 20) -> LinearElastic:
    return LinearElastic(skfem.MeshLine(np.linspace(0.0, 1.0, n + 1)), MAT)


def _amplification(h: float, xi: float) -> np.ndarray:
    # state (x^n, v^{n-1/2}) of the mode ω = 1 with the step h
    return np.array([[1 - h * h, h * (1 - 2 * xi * h)], [-h, 1 - 2 * xi * h]])


@pytest.mark.parametrize("xi", [0.0, 0.05, 0.5, 2.0])
def test_stable_limit_of_the_staggered_damped_scheme(xi):
    limit = 2.0 * (math.sqrt(1 + xi * xi) - xi)
    below = max(abs(np.linalg.eigvals(_amplification(limit * (1 - 1e-6), xi))))
    above = max(abs(np.linalg.eigvals(_amplification(limit * (1 + 1e-3), xi))))
    assert below <= 1.0 + 1e-9 and above > 1.0 + 1e-6


def _mode(model, k):
    system = as_system(model)
    m = system.mass(lumped=True)
    w2, phi = sla.eigh(system.stiffness().toarray(), np.diag(m))
    return math.sqrt(w2[k]), phi[:, k], m


def test_a_damped_mode_follows_the_scheme_recurrence_and_the_continuous_decay():
    model = _bar()
    omega, phi, m = _mode(model, 1)  # the first elastic mode of the free-free bar
    xi = 0.02
    damping = RayleighDamping.from_ratio(xi, omega)
    assert damping.ratio(omega) == pytest.approx(xi, rel=1e-14)
    period = 2 * math.pi / omega
    n = 4000
    dt = 20 * period / n
    r = solve(model, "explicit", n_steps=n, dt=dt, u0=phi, damping=damping, record_every=n)
    x, v = 1.0, 0.0
    v = v + 0.5 * dt * (-(omega**2) * x)  # the first half step (v^{-1/2} = v^0 = 0)
    for _ in range(n):
        x = x + dt * v
        v = v + dt * (-(omega**2) * x - 2 * xi * omega * v)
    amp = float(phi @ (m * r.u))  # φ is M-orthonormal
    assert amp == pytest.approx(x, rel=1e-9, abs=1e-12)
    # the continuous damped oscillator (ω Δt = 0.031: the scheme's error is O((ω Δt)²))
    wd = omega * math.sqrt(1 - xi * xi)
    t = n * dt
    exact = math.exp(-xi * omega * t) * (math.cos(wd * t) + xi * omega / wd * math.sin(wd * t))
    assert amp == pytest.approx(exact, abs=2e-3)
    assert math.exp(-xi * omega * t) < 0.1  # it has decayed


def test_energy_balance_closes_with_the_damping_work():
    # random data on every mode, α and β damping, constant step: the discrete balance with the
    # damping work closes to round-off (linear system), as without damping
    model = _bar()
    rng = np.random.default_rng(1)
    u0, v0 = 1e-3 * rng.standard_normal(model.n_dofs), 1e-3 * rng.standard_normal(model.n_dofs)
    damping = RayleighDamping(mass=0.05, stiffness=2e-3)
    r = solve(model, "explicit", t_end=20.0, u0=u0, v0=v0, damping=damping, record_every=50)
    work = r.total_damping_work
    assert work[-1] < -0.5 * r.total_energy[0]  # most of the energy dissipated
    assert np.all(np.diff(work) <= 0.0)
    assert r.relative_balance() <= 1e-10


def test_stiffness_damping_leaves_a_rigid_translation_alone_and_mass_damping_drags_it():
    model = _bar()
    v0 = np.ones(model.n_dofs)
    beta = solve(model, "explicit", n_steps=200, v0=v0, damping=RayleighDamping(stiffness=1e-2))
    # round-off only: 8e-13 (the undamped run's own, from K u of the translated bar: 1.5e-12)
    assert np.allclose(beta.v, 1.0, rtol=0.0, atol=5e-12)
    alpha = 0.5
    r = solve(model, "explicit", n_steps=200, v0=v0, damping=RayleighDamping(mass=alpha))
    # the mass-proportional drag: v^{1/2} = (1 − α Δt/2) v^0 (the first half step), then
    # v^{n+1/2} = (1 − α Δt) v^{n−1/2}; the reported v^200 is the mean of v^{199½} and v^{200½}
    h = r.dt
    expected = (1 - 0.5 * alpha * h) ** 2 * (1 - alpha * h) ** 199
    assert np.allclose(r.v, expected, rtol=0.0, atol=5e-12)  # the round-off above
    assert expected < 0.95  # a visible drag


def test_the_critical_step_is_lowered_and_a_step_above_it_refused():
    model = _bar()
    undamped = solve(model, "explicit", n_steps=1)
    omega_max = 2.0 / undamped.critical_dt
    damping = RayleighDamping.from_ratio(1.0, omega_max)  # ξ = 1 at ω_max
    damped = solve(model, "explicit", n_steps=1, damping=damping)
    assert damped.critical_dt == pytest.approx(undamped.critical_dt * (math.sqrt(2) - 1))
    with pytest.raises(ValueError, match="Rayleigh damping"):
        solve(model, "explicit", n_steps=1, dt=0.9 * undamped.critical_dt, damping=damping)


def test_bad_damping_is_refused():
    with pytest.raises(ValueError, match="stiffness coefficient must be a non-negative"):
        RayleighDamping(stiffness=-1.0)
    with pytest.raises(ValueError, match="mass coefficient"):
        RayleighDamping(mass=float("nan"))
    with pytest.raises(ValueError, match="damping ratio"):
        RayleighDamping.from_ratio(-0.1, 1.0)
    with pytest.raises(ValueError, match="pulsation"):
        RayleighDamping.from_ratio(0.1, 0.0)
    model = _bar()
    with pytest.raises(TypeError, match="RayleighDamping"):
        solve(model, "explicit", n_steps=1, damping=0.01)
    with pytest.raises(ValueError, match="multi-time-step"):
        solve(model, "explicit-mts", n_steps=1, damping=RayleighDamping(stiffness=1e-3),
              slow_blocks=("model",))  # fmt: skip
