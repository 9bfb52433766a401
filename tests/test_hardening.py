"""Hardening laws and the J2 material point with each of them, against closed forms.

Reference values come from:
* the uniaxial-strain path F = diag(exp ε, 1, 1) of Hencky J2 (radial in logarithmic strains, so
  the exponential-map return is exact for any step size): on the plastic branch
  ‖dev τ‖ = √(2/3) σ_y(ε̄p) and ‖dev τ_trial‖ = 2G √(2/3) |ε|, hence the inverse closed form
  |ε| = σ_y(ε̄p, ε̄̇p)/(2G) + (3/2) ε̄p and τ_11 = K ε + sign(ε) (2/3) σ_y, for *any* law: choose ε̄p,
  compute ε, check that the return gives ε̄p back;
* the laws' own definitions (σ_y(0), slopes by central differences);
* exact properties of the return: idempotence, the yield condition after return, objectivity,
  the small-strain limit (Hooke's law with K, G).
"""

from __future__ import annotations

import numpy as np
import pytest
import skfem

from arlequin.models import (
    CallableHardening,
    FiniteStrainJ2,
    J2Material,
    JohnsonCookHardening,
    LinearHardening,
    VoceHardening,
    j2_return_map,
    j2_update,
    make_hardening,
)

E, NU, RHO = 117e9, 0.35, 8930.0  # copper of the Taylor bar (DESIGN §4)
SQ23 = np.sqrt(2.0 / 3.0)

LAWS = {
    "linear": LinearHardening(0.4e9, 0.1e9),
    "voce": VoceHardening(0.4e9, 0.2e9, 8.0, 0.05e9),
    "johnson-cook": JohnsonCookHardening(0.4e9, 0.3e9, 0.4),
    "johnson-cook-rate": JohnsonCookHardening(0.4e9, 0.3e9, 0.4, c=0.02, reference_rate=1.0),
    "callable": CallableHardening(
        lambda e, r: 0.4e9 * (1.0 + e) ** 0.3, lambda e, r: 0.12e9 * (1.0 + e) ** -0.7
    ),
}


def material(name: str) -> J2Material:
    return J2Material.with_law(E, NU, RHO, LAWS[name])


def uniaxial_strain_for(m: J2Material, eqps: float, sign: float, dt: float | None) -> float:
    """The log strain ε of the uniaxial-strain path that ends at ε̄p (one step of size dt from
    rest for rate-dependent laws; any monotone path otherwise)."""
    rate = eqps / dt if dt else 0.0
    sy = float(m.law.flow_stress(np.array([eqps]), rate)[0])
    return sign * (sy / (2.0 * m.shear_modulus) + 1.5 * eqps)


def uniaxial_path(m: J2Material, strain: float, steps: int, dt: float | None = None):
    """Run the return along F = diag(exp(ε k/steps), 1, 1); returns τ, ε̄p, C_p⁻¹ (batch of 1)."""
    cp_inv = np.eye(3)[:, :, None]
    eqps = np.zeros(1)
    for k in range(1, steps + 1):
        F = np.diag([np.exp(strain * k / steps), 1.0, 1.0])[:, :, None]
        be = np.einsum("ik...,kl...,jl...->ij...", F, cp_inv, F)
        tau, be_new, eqps, _, _ = j2_return_map(be, eqps, m, planar=True, dt=dt)
        Finv = np.linalg.inv(F[:, :, 0])[:, :, None]
        cp_inv = np.einsum("ik...,kl...,jl...->ij...", Finv, be_new, Finv)
    return tau, eqps, cp_inv


# ------------------------------------------------------------------ the laws themselves
@pytest.mark.parametrize("name", sorted(LAWS))
def test_slope_is_the_derivative_of_the_flow_stress(name):
    law = LAWS[name]
    e = np.array([1e-3, 0.05, 0.3, 1.0, 2.5])
    h = 1e-6
    fd = (law.flow_stress(e + h, 10.0) - law.flow_stress(e - h, 10.0)) / (2 * h)
    assert np.allclose(law.slope(e, 10.0), fd, rtol=1e-6)
    assert law.initial_yield_stress == pytest.approx(0.4e9, rel=1e-14)


def test_johnson_cook_rate_term_and_its_slope():
    law = LAWS["johnson-cook-rate"]
    e = np.array([0.2])
    # below the reference rate the factor is 1 (max(ε̄̇/ε̄̇0, 1))
    assert law.flow_stress(e, 0.5)[0] == pytest.approx(LAWS["johnson-cook"].flow_stress(e)[0])
    r, h = 1e4, 1e-2
    fd = (law.flow_stress(e, r + h) - law.flow_stress(e, r - h)) / (2 * h)
    assert law.rate_slope(e, r)[0] == pytest.approx(fd[0], rel=1e-6)
    expected = (0.4e9 + 0.3e9 * 0.2**0.4) * (1.0 + 0.02 * np.log(1e4))  # the definition
    assert law.flow_stress(e, r)[0] == pytest.approx(expected, rel=1e-14)


@pytest.mark.parametrize(
    ("law", "params", "match"),
    [
        ("linear", {"yield_stress": -1.0}, "yield_stress must be positive"),
        ("linear", {"yield_stress": 1e8, "modulus": -1.0}, "hardening modulus must be >= 0"),
        ("voce", {"yield_stress": 1e8, "saturation": 1e8, "rate": 0.0}, "Voce rate"),
        ("johnson-cook", {"a": 1e8, "b": 1e8, "n": 0.0}, "Johnson-Cook n"),
        ("johnson-cook", {"a": 1e8, "b": 1e8, "n": 0.5, "c": np.nan}, "Johnson-Cook C"),
        ("swift", {}, "hardening law must be one of"),
    ],
)
def test_bad_hardening_parameters_are_named(law, params, match):
    with pytest.raises(ValueError, match=match):
        make_hardening(law, **params)


def test_material_checks_its_law():
    with pytest.raises(ValueError, match=r"use J2Material\.with_law"):
        J2Material(E, NU, RHO, 0.3e9, 0.0, LAWS["voce"])  # σ_y(0) = 0.4 GPa ≠ 0.3 GPa
    with pytest.raises(ValueError, match="rate_slope_fn"):
        CallableHardening(lambda e, r: 1e8 + 0 * e, lambda e, r: 0 * e, rate_dependent=True)
    with pytest.raises(ValueError, match="initial flow stress must be positive"):
        CallableHardening(lambda e, r: 0 * e, lambda e, r: 0 * e)


# ------------------------------------------------------------------ the material point
@pytest.mark.parametrize("name", sorted(LAWS))
@pytest.mark.parametrize("target", [0.01, 0.4, 2.5])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_uniaxial_strain_matches_the_inverse_closed_form(name, target, sign):
    m = material(name)
    rated = m.law.rate_dependent
    dt = 1e-6 if rated else None
    strain = uniaxial_strain_for(m, target, sign, dt)
    # a rate-dependent law is path dependent: one step; the others: 1 and 40 steps
    for steps in [1] if rated else [1, 40]:
        tau, eqps, cp_inv = uniaxial_path(m, strain, steps, dt)
        assert eqps[0] == pytest.approx(target, rel=1e-10)
        sy = float(m.law.flow_stress(np.array([target]), target / dt if dt else 0.0)[0])
        assert tau[0, 0, 0] == pytest.approx(m.bulk_modulus * strain + sign * 2 / 3 * sy, rel=1e-10)
        assert tau[1, 1, 0] == pytest.approx(tau[2, 2, 0], rel=1e-12)  # transverse isotropy
        assert np.linalg.det(cp_inv[:, :, 0]) == pytest.approx(1.0, abs=1e-12)  # isochoric flow


@pytest.mark.parametrize("name", ["voce", "johnson-cook"])
def test_point_update_from_the_deformation_gradient(name):
    # j2_update(F, state) along F = diag(e^ε k/40, 1, 1): the same closed form, and with a
    # log_volume it sees F only through its deviatoric part (the F-bar use)
    m = material(name)
    strain = uniaxial_strain_for(m, 0.4, -1.0, None)
    cp, eqps = np.eye(3)[:, :, None], np.zeros(1)
    for k in range(1, 41):
        F = np.diag([np.exp(strain * k / 40), 1.0, 1.0])[:, :, None]
        tau, cp, eqps, _ = j2_update(F, cp, eqps, m, planar=True)
    assert eqps[0] == pytest.approx(0.4, rel=1e-10)
    sy = float(m.law.flow_stress(np.array([0.4]))[0])
    assert tau[0, 0, 0] == pytest.approx(m.bulk_modulus * strain - 2 / 3 * sy, rel=1e-10)
    # an isotropic factor on F changes nothing when the volume is given
    tau2, cp2, eqps2, _ = j2_update(1.1 * F, cp, eqps, m, log_volume=np.array([strain]))
    tau1, cp1, eqps1, _ = j2_update(F, cp, eqps, m)
    assert np.allclose(tau2, tau1, rtol=1e-12, atol=1e-6) and np.allclose(eqps2, eqps1)
    assert np.allclose(cp2, cp1, rtol=1e-12)


def _random_trial(n: int, amplitude: float, seed: int, spread: float = 0.0):
    """Trial b_e = F Fᵀ for random F near 1 (batch of n; amplitudes log-uniform over
    ``spread`` decades below ``amplitude``) and random ε̄p."""
    rng = np.random.default_rng(seed)
    scale = amplitude * 10.0 ** rng.uniform(-spread, 0.0, n)
    F = np.eye(3)[:, :, None] + scale * rng.uniform(-1, 1, (3, 3, n))
    F *= np.sign(np.linalg.det(F.transpose(2, 0, 1)))[None, None]
    be = np.einsum("ikn,jkn->ijn", F, F)
    return be, rng.uniform(0.0, 1.0, n)


@pytest.mark.parametrize("name", sorted(LAWS))
def test_return_meets_the_yield_condition_and_is_idempotent(name):
    m = material(name)
    dt = 1e-6 if m.law.rate_dependent else None
    be, eqps = _random_trial(400, 0.03, seed=4, spread=2.0)  # a mix of elastic and plastic points
    tau, be_new, eqps_new, dgamma, work = j2_return_map(be, eqps, m, dt=dt)
    plastic = dgamma > 0.0
    assert 50 < plastic.sum() < 350  # both branches exercised
    dev = tau - np.einsum("kkn->n", tau) / 3.0 * np.eye(3)[:, :, None]
    norm = np.sqrt(np.einsum("ijn,ijn->n", dev, dev))
    rate = (eqps_new - eqps) / dt if dt else 0.0
    flow = SQ23 * m.law.flow_stress(eqps_new, rate)
    assert np.allclose(norm[plastic], flow[plastic], rtol=1e-10)  # on the yield surface
    assert np.all(norm[~plastic] <= SQ23 * m.law.flow_stress(eqps[~plastic]) * (1 + 1e-12))
    assert np.all(work[plastic] > 0.0) and np.all(work[~plastic] == 0.0)
    if m.law.rate_dependent:
        return  # its stress sits on the rate-raised surface: at rest it would flow again
    # returning again from the returned state changes nothing
    tau2, _, eqps2, dgamma2, _ = j2_return_map(be_new, eqps_new, m)
    assert np.all(dgamma2 <= 1e-12 * np.maximum(dgamma, 1e-300) + 1e-15)
    assert np.allclose(eqps2, eqps_new, rtol=0, atol=1e-14)
    assert np.allclose(tau2, tau, rtol=0, atol=1e-9 * np.abs(tau).max())


@pytest.mark.parametrize("name", ["voce", "johnson-cook"])
def test_return_is_objective(name):
    m = material(name)
    be, eqps = _random_trial(50, 0.2, seed=5)
    rng = np.random.default_rng(6)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.linalg.det(q))
    rotated = np.einsum("ik,kln,jl->ijn", q, be, q)  # b_e → Q b_e Qᵀ under x → Q x
    tau0, _, e0, _, w0 = j2_return_map(be, eqps, m)
    tau1, _, e1, _, w1 = j2_return_map(rotated, eqps, m)
    assert np.allclose(tau1, np.einsum("ik,kln,jl->ijn", q, tau0, q), rtol=0,
                       atol=1e-10 * np.abs(tau0).max())  # fmt: skip
    assert np.allclose(e1, e0, rtol=1e-12) and np.allclose(w1, w0, rtol=1e-10)


def test_small_strain_limit_is_hookes_law():
    m = material("voce")
    rng = np.random.default_rng(9)
    H = 1e-9 * rng.uniform(-1, 1, (3, 3, 20))  # strains ~1e-9, far below yield
    F = np.eye(3)[:, :, None] + H
    B = np.einsum("ikn,jkn->ijn", H, np.eye(3)[:, :, None] + H) + np.swapaxes(H, 0, 1)
    B = 0.5 * (B + np.swapaxes(B, 0, 1))  # b_e − 1 = H + Hᵀ + H Hᵀ, without round-off
    assert np.allclose(B + np.eye(3)[:, :, None], np.einsum("ikn,jkn->ijn", F, F), atol=1e-15)
    tau = j2_return_map(B, np.zeros(20), m, minus_identity=True)[0]
    eps = 0.5 * (H + np.swapaxes(H, 0, 1))
    tr = np.einsum("kkn->n", eps)
    hooke = m.bulk_modulus * tr * np.eye(3)[:, :, None] + 2 * m.shear_modulus * (
        eps - tr / 3 * np.eye(3)[:, :, None]
    )
    # the geometric terms are O(|H|) relative: 1e-9; the b_e − 1 input keeps full accuracy
    assert np.allclose(tau, hooke, rtol=0, atol=1e-8 * np.abs(hooke).max())


# ------------------------------------------------------------------ one element, each law
@pytest.mark.parametrize("backend", ["numpy", "numba"])
@pytest.mark.parametrize("name", ["linear", "voce", "johnson-cook", "johnson-cook-rate"])
def test_one_element_uniaxial_strain_matches_the_closed_form(name, backend):
    # one plane-strain Q1 cell stretched homogeneously, F = diag(exp ε, 1, 1), in 30 steps
    # (one for the rate-dependent law): the model's stress and ε̄p are the closed form's
    m = material(name)
    mesh = skfem.MeshQuad.init_tensor(np.array([0.0, 1e-3]), np.array([0.0, 1e-3]))
    model = FiniteStrainJ2(mesh, m, "plane_strain", backend=backend)
    dt = 1e-6 if m.law.rate_dependent else None
    target = 0.8
    strain = uniaxial_strain_for(m, target, -1.0, dt)
    steps = 1 if dt else 30
    state = model.initial_state()
    increments = []
    for k in range(1, steps + 1):
        u = np.zeros(model.n_dofs)
        u[model.nodal_dofs()[0]] = np.expm1(strain * k / steps) * mesh.p[0]
        before = state.eqps.max()
        _, state = model.internal_force(u, state, dt=dt)
        increments.append(state.eqps.max() - before)
    assert np.allclose(state.eqps, target, rtol=1e-10)
    sy = float(m.law.flow_stress(np.array([target]), target / dt if dt else 0.0)[0])
    assert np.allclose(state.kirchhoff[0, 0], m.bulk_modulus * strain - 2 / 3 * sy, rtol=1e-10)
    # plastic work per unit volume: σ_y(ε̄p_{n+1}) Δε̄p summed over the steps, a right Riemann
    # sum of ∫ σ_y dε̄p; σ_y increasing, so  0 ≤ W − ∫ ≤ (σ_y(end) − σ_y(0)) max Δε̄p
    if dt:
        assert np.allclose(state.plastic_work, sy * target, rtol=1e-10)
    else:
        grid = np.linspace(0.0, target, 20001)
        exact = np.trapezoid(m.law.flow_stress(grid), grid)  # quadrature error ~1e-9 relative
        bound = (sy - m.yield_stress) * max(increments)
        excess = state.plastic_work - exact
        assert np.all(excess >= -1e-8 * exact) and np.all(excess <= bound + 1e-8 * exact)
    assert model.plastic_dissipation(state) == pytest.approx(
        state.plastic_work[0, 0] * 1e-6, rel=1e-12
    )  # J: per-volume work × the 1 mm² × 1 m cell
