"""SmallStrainJ2: the consistent tangent against finite differences, closed-form paths, bad input.

1. The tangent equals a central difference of the internal force (relative 1e-6 in the norm of
   K·δ over a random δ) in elastic, plastic, unloading and reloading states, for every kind, with
   a non-uniform weight α, linear and Voce isotropic hardening, with and without kinematic
   hardening.
2. Uniaxial stress and pure shear (3D), loading past yield, unloading and reverse loading, with
   linear isotropic and linear kinematic hardening (and Voce, monotonic), equal their closed
   forms to 1e-10, through the point function and through the model on one cell (whose nodal
   forces are the B-matrix integral of the homogeneous stress).
3. Stored energy plus dissipation equal the work of the forces over a cycle (to 1e-3).
4. Bad input is refused with a ValueError naming the value.
"""

from __future__ import annotations

import numpy as np
import pytest
import skfem

from arlequin.models import (
    CallableHardening,
    J2Material,
    LinearHardening,
    SmallStrainJ2,
    SmallStrainState,
    VoceHardening,
    small_strain_return,
)

# steel-like: E = 200 GPa, ν = 0.3, σ_y0 = 250 MPa (yield strain 1.25e-3)
E, NU, SY = 200e9, 0.3, 250e6
H_ISO, H_KIN = 10e9, 20e9  # Pa
VOCE = VoceHardening(SY, saturation=150e6, rate=40.0, modulus=2e9)


def _material(law: str) -> J2Material:
    if law == "voce":
        return J2Material.with_law(E, NU, 7800.0, VOCE)
    return J2Material(E, NU, 7800.0, SY, H_ISO)


def _distorted(mesh, amount=0.08, seed=3):
    """The mesh with its interior nodes moved (non-affine cells)."""
    rng = np.random.default_rng(seed)
    p = mesh.p.copy()
    inner = np.ones(p.shape[1], bool)
    inner[mesh.boundary_nodes()] = False
    p[:, inner] += amount * rng.uniform(-1, 1, (p.shape[0], inner.sum()))
    return type(mesh)(p, mesh.t)


def _mesh(kind: str):
    if kind == "3d":
        return _distorted(skfem.MeshHex.init_tensor(*(np.linspace(0, 1, 3),) * 3))
    x0 = 0.5 if kind == "axisymmetric" else 0.0
    return _distorted(skfem.MeshQuad.init_tensor(np.linspace(x0, x0 + 1, 4), np.linspace(0, 1, 4)))


# ---------------------------------------------------------------------------------------------
# 1. the consistent tangent
# ---------------------------------------------------------------------------------------------
def _fd_error(model, u, state, alpha, seed):
    """‖K δ − (f(u + hδ) − f(u − hδ))/2h‖ / ‖…‖ over a random δ."""
    rng = np.random.default_rng(seed)
    du = rng.standard_normal(model.n_dofs)
    h = 1e-7 * np.linalg.norm(u) / np.linalg.norm(du)
    fp, _ = model.internal_force(u + h * du, state, alpha)
    fm, _ = model.internal_force(u - h * du, state, alpha)
    fd = (fp - fm) / (2.0 * h)
    k = model.tangent(u, state, alpha)
    return np.linalg.norm(k @ du - fd) / np.linalg.norm(fd)


@pytest.mark.parametrize("bbar", [False, True])
@pytest.mark.parametrize("kinematic", [0.0, H_KIN])
@pytest.mark.parametrize("law", ["linear", "voce"])
@pytest.mark.parametrize("kind", ["plane_strain", "axisymmetric", "3d"])
def test_tangent_is_the_derivative_of_the_internal_force(kind, law, kinematic, bbar):
    model = SmallStrainJ2(_mesh(kind), _material(law), kind, kinematic_modulus=kinematic,
                          bbar=bbar)  # fmt: skip
    rng = np.random.default_rng(7)
    alpha = rng.uniform(0.2, 1.0, model.shape)  # a non-uniform weight α ≠ 1
    n = model.n_dofs
    virgin = model.initial_state()
    direction = rng.standard_normal(n)
    u_small = 2e-5 * direction  # cells of 1/3 m: strains ~ 1e-4, below the yield strain 1.25e-3
    u_big = 4e-3 * direction  # strains ~ 2e-2: every point flows
    errors = {}
    _, trial = model.internal_force(u_small, virgin, alpha)
    assert np.all(trial.eqps == 0.0)
    errors["elastic"] = _fd_error(model, u_small, virgin, alpha, 1)
    _, loaded = model.internal_force(u_big, virgin, alpha)
    assert np.mean(loaded.eqps > 0.0) > 0.9
    errors["plastic"] = _fd_error(model, u_big, virgin, alpha, 2)
    # the check discriminates: the elastic stiffness is not the derivative there
    elastic_as_tangent = type("Elastic", (), {"internal_force": model.internal_force,
                              "tangent": lambda s, u, st, w: model.stiffness(w)})()  # fmt: skip
    elastic_as_tangent.n_dofs = n
    assert _fd_error(elastic_as_tangent, u_big, virgin, alpha, 2) > 1e-2
    # from the committed plastic state: unloading (every point elastic) and reloading (flowing)
    # (3% back: strain changes ~ 6e-4, below the 2.5e-3 of elastic unloading)
    _, unloading = model.internal_force(0.97 * u_big, loaded, alpha)
    assert np.all(unloading.eqps == loaded.eqps) and np.any(loaded.eqps > 0.0)
    errors["unloading"] = _fd_error(model, 0.97 * u_big, loaded, alpha, 3)
    _, reloading = model.internal_force(1.3 * u_big, loaded, alpha)
    assert np.mean(reloading.eqps > loaded.eqps) > 0.5
    errors["reloading"] = _fd_error(model, 1.3 * u_big, loaded, alpha, 4)
    print(f"FD {kind} {law} H_kin={kinematic:g} bbar={bbar}: " +
          ", ".join(f"{k} {v:.1e}" for k, v in errors.items()))  # fmt: skip
    assert max(errors.values()) <= 1e-6, errors


def test_tangent_of_an_elastic_state_is_the_stiffness_and_states_stay_untouched():
    model = SmallStrainJ2(_mesh("axisymmetric"), _material("linear"), "axisymmetric")
    u = 1e-5 * np.random.default_rng(0).standard_normal(model.n_dofs)
    k, k0 = model.tangent(u), model.elastic.stiffness()
    assert abs(k - k0).max() <= 1e-12 * abs(k0).max()  # the elastic B-matrix assembly = skfem's
    assert abs(model.stiffness() - k0).max() <= 1e-12 * abs(k0).max()
    bbar = SmallStrainJ2(model.mesh, model.material, "axisymmetric", bbar=True)
    assert abs(bbar.tangent(u) - bbar.stiffness()).max() <= 1e-12 * abs(k0).max()
    state = model.internal_force(200 * u)[1]
    before = [np.array(a) for a in (state.plastic_strain, state.eqps, state.back_stress)]
    f1, trial = model.internal_force(300 * u, state)
    f2, _ = model.internal_force(300 * u, state)
    np.testing.assert_array_equal(f1, f2)  # the same committed state gives the same answer
    for a, b in zip(before, (state.plastic_strain, state.eqps, state.back_stress)):
        np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match="read-only"):
        trial.eqps[0, 0] = 1.0
    f, kk, again = model.linearization(300 * u, state)
    np.testing.assert_array_equal(f, f1)
    assert abs(kk - model.tangent(300 * u, state)).max() == 0.0
    np.testing.assert_array_equal(again.eqps, trial.eqps)


# ---------------------------------------------------------------------------------------------
# 2. closed forms
# ---------------------------------------------------------------------------------------------
def _path_1d(modulus, yield_stress, h_iso, h_kin, e1, e3, n=5):
    """Closed form of the 1D rate-independent model |s − h_kin p| ≤ Y + h_iso κ, s = M(e − p):

    loading 0 → e1 past yield: s = M e up to e_y = Y/M, then s = Y + M_t (e − e_y) with
    M_t = M h/(M + h), h = h_iso + h_kin, p = (s − Y)/h;
    unloading e1 → e2 = (e1 + e_r)/2 (half-way to reverse yield): s = s1 − M (e1 − e), p = p1;
    reverse yield at s_r = h_kin p1 − (Y + h_iso p1), e_r = e1 − (s1 − s_r)/M; beyond it, down to
    e3: s = s_r − M_t (e_r − e), p = p1 + (s − s_r)/h, κ = p1 + (p1 − p).
    Returns the sample strains e, stresses s, plastic strains p and accumulated κ.
    """
    h = h_iso + h_kin
    mt = modulus * h / (modulus + h)
    ey = yield_stress / modulus
    s1 = yield_stress + mt * (e1 - ey)
    p1 = (s1 - yield_stress) / h
    sr = h_kin * p1 - (yield_stress + h_iso * p1)
    er = e1 - (s1 - sr) / modulus
    e2 = 0.5 * (e1 + er)
    assert er > e3 and e1 > ey
    e = np.r_[np.linspace(0.5 * ey, e1, n), np.linspace(e1, e2, n)[1:], np.linspace(e2, e3, n)[1:]]
    s = np.where(e <= ey, modulus * e, yield_stress + mt * (e - ey))
    p = np.maximum((s - yield_stress) / h, 0.0)
    back = np.arange(e.size) >= n  # unloading and reverse loading
    s_unload = s1 - modulus * (e1 - e)
    s_rev = sr - mt * (er - e)
    s = np.where(back, np.where(e >= er, s_unload, s_rev), s)
    p = np.where(back, np.where(e >= er, p1, p1 + (s_rev - sr) / h), p)
    kappa = np.where(back & (e < er), 2 * p1 - p, np.where(back, p1, p))
    return e, s, p, kappa


def _uniaxial(h_iso, h_kin):
    """Uniaxial stress σ_11 = s: ε = (e, l, l), l = −νs/E − p/2; ε_p = (p, −p/2, −p/2); ε̄p = κ."""
    e, s, p, kappa = _path_1d(E, SY, h_iso, h_kin, 8e-3, -6e-3)
    z = np.zeros_like(e)
    lat = -NU * s / E - p / 2
    strain = np.stack([e, lat, lat, z, z, z])
    stress = np.stack([s, z, z, z, z, z])
    plastic = np.stack([p, -p / 2, -p / 2, z, z, z])
    return strain, stress, plastic, kappa


def _shear(h_iso, h_kin):
    """Pure shear τ = σ_12, γ = 2ε_12: G, τ_y = σ_y0/√3, iso H/3, kin H_kin/3 in γ_p
    (√3|τ − β_12| = σ_y0 + H ε̄p with β_12 = H_kin γ_p/3, ε̄p = κ_γ/√3); Mandel xy = √2 × tensor."""
    g = E / (2 * (1 + NU))
    gam, tau, gp, kappa = _path_1d(g, SY / np.sqrt(3), h_iso / 3, h_kin / 3, 1.2e-2, -1e-2)
    z = np.zeros_like(gam)
    r2 = np.sqrt(2.0)
    strain = np.stack([z, z, z, z, z, r2 * gam / 2])
    stress = np.stack([z, z, z, z, z, r2 * tau])
    plastic = np.stack([z, z, z, z, z, r2 * gp / 2])
    return strain, stress, plastic, kappa / np.sqrt(3)


HARDENINGS = {"isotropic": (H_ISO, 0.0), "kinematic": (0.0, H_KIN), "mixed": (H_ISO, H_KIN)}


@pytest.mark.parametrize("path", [_uniaxial, _shear])
@pytest.mark.parametrize("hardening", sorted(HARDENINGS))
def test_point_return_follows_the_closed_forms(path, hardening):
    h_iso, h_kin = HARDENINGS[hardening]
    strain, stress, plastic, eqps = path(h_iso, h_kin)
    mat = J2Material(E, NU, 7800.0, SY, h_iso)
    state = (np.zeros(6), 0.0, np.zeros(6))
    for k in range(strain.shape[1]):
        ret = small_strain_return(strain[:, k], *state, mat, h_kin)
        state = (ret.plastic_strain, ret.eqps, ret.back_stress)
        # stresses to 1e-10 σ_y0, strains to 1e-10 of the yield strain
        np.testing.assert_allclose(ret.stress, stress[:, k], rtol=0, atol=1e-10 * SY)
        np.testing.assert_allclose(ret.plastic_strain, plastic[:, k], rtol=0, atol=1e-10 * SY / E)
        assert abs(ret.eqps - eqps[k]) <= 1e-10 * SY / E
        # the back stress is ⅔ H_kin ε_p (linear Prager, from a virgin state)
        np.testing.assert_allclose(ret.back_stress, 2 / 3 * h_kin * plastic[:, k], atol=1e-10 * SY)
    assert eqps[-1] > eqps[strain.shape[1] // 2] > 0  # the path did flow back


def test_point_return_follows_voce_loading():
    # inverse closed form: at ε̄p = p (monotonic uniaxial stress), σ = σ_y(p) + H_kin p and
    # ε = σ/E + p, lateral −νσ/E − p/2
    p = np.linspace(0.0, 0.05, 11)[1:]
    s = VOCE.flow_stress(p) + H_KIN * p
    mat = J2Material.with_law(E, NU, 7800.0, VOCE)
    state = (np.zeros(6), 0.0, np.zeros(6))
    for pk, sk in zip(p, s):
        lat = -NU * sk / E - pk / 2
        ret = small_strain_return(np.array([sk / E + pk, lat, lat, 0, 0, 0]), *state, mat, H_KIN)
        state = (ret.plastic_strain, ret.eqps, ret.back_stress)
        np.testing.assert_allclose(ret.stress, [sk, 0, 0, 0, 0, 0], rtol=0, atol=1e-10 * SY)
        assert abs(ret.eqps - pk) <= 1e-10 * SY / E


@pytest.mark.parametrize("bbar", [False, True])
@pytest.mark.parametrize("path", [_uniaxial, _shear])
@pytest.mark.parametrize("hardening", ["isotropic", "kinematic"])
def test_one_cell_follows_the_closed_forms(path, hardening, bbar):
    # one unit hexahedron under the homogeneous displacement u = ε x: every quadrature point
    # has the closed-form stress, and the nodal forces are the B-matrix integral of a uniform
    # stress, f_a = σ ∫∇N_a dV = σ s_a / 4 with s_a = 2 x_a − 1 (the corner's face normals
    # times the face integral of N_a, 1/4)
    h_iso, h_kin = HARDENINGS[hardening]
    strain, stress, _, eqps = path(h_iso, h_kin)
    mesh = skfem.MeshHex()
    mat = J2Material(E, NU, 7800.0, SY, h_iso)
    model = SmallStrainJ2(mesh, mat, kinematic_modulus=h_kin, bbar=bbar)
    from arlequin.models import from_mandel

    state = model.initial_state()
    alpha = 0.5
    signs = 2 * mesh.p - 1
    for k in range(strain.shape[1]):
        eps = from_mandel(strain[:, k])
        u = (eps @ mesh.p).T.ravel()
        f, state = model.internal_force(u, state, alpha)
        exact = from_mandel(stress[:, k])
        np.testing.assert_allclose(state.stress, np.broadcast_to(stress[:, k, None, None],
                                   state.stress.shape), rtol=0, atol=1e-10 * SY)  # fmt: skip
        np.testing.assert_allclose(state.eqps, eqps[k], rtol=0, atol=1e-10 * SY / E)
        f_exact = alpha * (exact @ signs / 4).T.ravel()
        np.testing.assert_allclose(f, f_exact, rtol=0, atol=1e-10 * SY)
    assert model.plastic_dissipation(state) > 0.0 and model.stored_energy(state) > 0.0
    np.testing.assert_allclose(model.von_mises(state), state.von_mises)


@pytest.mark.parametrize("hardening", sorted(HARDENINGS))
def test_stored_energy_plus_dissipation_is_the_work_of_the_forces(hardening):
    # one hexahedron strained to 8e-3 and back to -6e-3 (ε = e diag(1, -1/2, -1/2)) in 1,100
    # steps: the trapezoidal work of the nodal forces equals the stored energy (elastic and of
    # the back stress) plus the dissipation Σ σ_y(ε̄p_n+1) Δε̄p, to the O(Δε̄p) of the backward
    # Euler dissipation (measured 2.7e-4, 1.6e-6, 2.4e-4 relative for isotropic, kinematic,
    # mixed)
    h_iso, h_kin = HARDENINGS[hardening]
    mesh = skfem.MeshHex()
    model = SmallStrainJ2(mesh, J2Material(E, NU, 7800.0, SY, h_iso), kinematic_modulus=h_kin)
    state, work = model.initial_state(), 0.0
    f_old, u_old = np.zeros(model.n_dofs), np.zeros(model.n_dofs)
    for e in np.r_[np.linspace(0, 8e-3, 400), np.linspace(8e-3, -6e-3, 700)[1:]]:
        u = (np.diag([e, -e / 2, -e / 2]) @ mesh.p).T.ravel()
        f, state = model.internal_force(u, state)
        work += 0.5 * (f + f_old) @ (u - u_old)
        f_old, u_old = f, u
    total = model.stored_energy(state) + model.plastic_dissipation(state)
    assert abs(total - work) <= 1e-3 * work


# ---------------------------------------------------------------------------------------------
# 4. bad input
# ---------------------------------------------------------------------------------------------
def test_bad_input_is_refused_by_name():
    mesh = skfem.MeshQuad()
    mat = _material("linear")
    with pytest.raises(ValueError, match="yield_stress=0"):
        J2Material(E, NU, 7800.0, 0.0)
    with pytest.raises(ValueError, match="yield_stress=-1"):
        J2Material(E, NU, 7800.0, -1.0)
    with pytest.raises(ValueError, match="hardening_modulus=-1"):
        J2Material(E, NU, 7800.0, SY, -1e9)
    with pytest.raises(ValueError, match="hardening modulus=-1"):
        SmallStrainJ2(mesh, mat, hardening=LinearHardening(SY, -1e9))
    softening = CallableHardening(lambda e, r: SY - 1e9 * e, lambda e, r: -1e9 + 0 * e)
    with pytest.raises(ValueError, match="softening"):
        SmallStrainJ2(mesh, mat, hardening=softening)
    with pytest.raises(ValueError, match="kinematic_modulus=-2"):
        SmallStrainJ2(mesh, mat, kinematic_modulus=-2e9)
    with pytest.raises(ValueError, match="'plane_stress'"):
        SmallStrainJ2(mesh, mat, "plane_stress")
    with pytest.raises(ValueError, match="'2d'"):
        SmallStrainJ2(mesh, mat, "2d")
    with pytest.raises(ValueError, match="J2Material"):
        SmallStrainJ2(mesh, mat.elastic)
    model = SmallStrainJ2(mesh, mat, hardening=VOCE)
    assert model.material.law == VOCE and model.material.yield_stress == SY
    with pytest.raises(ValueError, match="shape"):
        model.internal_force(np.zeros(3))
    assert isinstance(model.initial_state(), SmallStrainState)
