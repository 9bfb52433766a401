"""Finite-strain J2 model (models/plasticity/finite_strain_j2.py) against closed-form and exact
properties.

Reference values come from:
* the closed-form uniaxial-strain response of Hencky J2 with linear hardening (for a fixed
  principal frame the exponential-map return is small-strain J2 in logarithmic strains, exact for
  any step size);
* exact properties: objectivity, zero stress under rigid rotation, plastic incompressibility
  (det C_p = 1), the internal force as the derivative of the stored energy (elastic steps), the
  small-strain limit (LinearElastic), and homogeneous deformations giving zero interior forces on
  distorted meshes (patch test, with F-bar).
"""

from __future__ import annotations

import numpy as np
import pytest
import skfem
from _meshes import perturb

from arlequin.models import (
    FiniteStrainJ2,
    InvertedElementError,
    J2Material,
    LinearElastic,
    hencky_j2_return,
)
from arlequin.problem.system import Block, BlockTerm, CoupledSystem
from arlequin.solvers import SimulationError, solve, stable_time_step

# Taylor-bar copper (DESIGN §4): E, ν, ρ, σ_y, H
COPPER = J2Material(117e9, 0.35, 8930.0, 0.4e9, 0.1e9)


def mesh_for(kind: str, n: int = 3, distort: float = 0.0, seed: int = 0) -> skfem.Mesh:
    """Unit-ish box in mm, Q1 cells; axisymmetric starts off the axis at r = 0."""
    x = np.linspace(0.0, 3.2e-3, n + 1)
    z = np.linspace(0.0, 4.0e-3, n + 2)
    if kind == "3d":
        mesh = skfem.MeshHex.init_tensor(x, x, z)
    else:
        mesh = skfem.MeshQuad.init_tensor(x, z)
    if distort:
        mesh = perturb(mesh, 3.2e-3 / n, distort, seed)
    return mesh


def homogeneous_u(model: FiniteStrainJ2, grad: np.ndarray) -> np.ndarray:
    """Nodal displacement u = (F − 1) X for an in-plane displacement gradient ``grad``."""
    u = np.zeros(model.n_dofs)
    d = model.dim
    disp = grad[:d, :d] @ model.mesh.p
    u[model.nodal_dofs()] = disp
    return u


def uniaxial_strain_closed_form(strain: float, m: J2Material) -> tuple[float, float, float]:
    """τ_11, τ_22 (Pa) and ε̄p for F = diag(exp(strain), 1, 1), monotone loading from rest."""
    K, G, H, sy = m.bulk_modulus, m.shear_modulus, m.hardening_modulus, m.yield_stress
    norm_trial = 2.0 * G * np.sqrt(2.0 / 3.0) * abs(strain)  # ‖dev τ‖ of the elastic trial
    f = norm_trial - np.sqrt(2.0 / 3.0) * sy
    dgamma = max(f, 0.0) / (2.0 * G + 2.0 / 3.0 * H)
    norm = norm_trial - 2.0 * G * dgamma
    sign = np.sign(strain)
    tau11 = K * strain + sign * np.sqrt(2.0 / 3.0) * norm
    tau22 = K * strain - sign * norm / np.sqrt(6.0)
    return tau11, tau22, np.sqrt(2.0 / 3.0) * dgamma


# ------------------------------------------------------------------ constitutive update
@pytest.mark.parametrize("strain", [1e-3, 0.05, 0.5, -0.7])
@pytest.mark.parametrize("steps", [1, 25])
@pytest.mark.parametrize("planar", [False, True])
def test_uniaxial_strain_matches_closed_form(strain, steps, planar):
    ident = np.eye(3)[:, :, None]
    eqps = np.zeros(1)
    cp_inv = ident.copy()
    for k in range(1, steps + 1):
        F = np.diag([np.exp(strain * k / steps), 1.0, 1.0])[:, :, None]
        be_trial = np.einsum("ik...,kl...,jl...->ij...", F, cp_inv, F)
        tau, be, eqps, _ = hencky_j2_return(be_trial, eqps, COPPER, planar=planar)
        Finv = np.linalg.inv(F[:, :, 0])[:, :, None]
        cp_inv = np.einsum("ik...,kl...,jl...->ij...", Finv, be, Finv)
    tau11, tau22, ep = uniaxial_strain_closed_form(strain, COPPER)
    assert tau[0, 0, 0] == pytest.approx(tau11, rel=1e-10)
    assert tau[1, 1, 0] == pytest.approx(tau22, rel=1e-10, abs=1e-6 * COPPER.yield_stress)
    assert eqps[0] == pytest.approx(ep, rel=1e-10, abs=1e-14)
    # plastic flow is isochoric: det C_p⁻¹ = 1
    assert np.linalg.det(cp_inv[:, :, 0]) == pytest.approx(1.0, abs=1e-12)


def test_planar_eigen_decomposition_matches_lapack():
    # closed-form 2×2 + out-of-plane eigenpairs rebuild the tensor, degenerate cases included
    from arlequin.models.plasticity.j2 import _from_principal, _sym_eig_planar

    rng = np.random.default_rng(8)
    a = np.zeros((3, 3, 50))
    m = rng.normal(size=(2, 2, 50))
    a[:2, :2] = np.einsum("ikn,jkn->ijn", m, m)
    a[2, 2] = rng.uniform(0.1, 2.0, 50)
    a[:2, :2, :5] = np.eye(2)[:, :, None]  # isotropic in-plane block
    values, vectors = _sym_eig_planar(a)
    assert np.allclose(_from_principal(values, vectors), a, atol=1e-13)
    assert np.allclose(np.sort(values, axis=0), np.linalg.eigvalsh(a.transpose(2, 0, 1)).T)


def test_objectivity_and_rigid_rotation():
    rng = np.random.default_rng(3)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.linalg.det(q))
    stretch = np.diag([1.3, 0.9, 0.8])
    eqps = np.zeros(1)
    tau0 = hencky_j2_return((stretch @ stretch.T)[:, :, None], eqps, COPPER)
    F = q @ stretch
    tau1 = hencky_j2_return((F @ F.T)[:, :, None], eqps, COPPER)
    assert np.allclose(tau1[0][:, :, 0], q @ tau0[0][:, :, 0] @ q.T, atol=1e-6)  # Pa, τ ~ 1e10
    assert tau1[2][0] == pytest.approx(tau0[2][0], rel=1e-12)
    tau_rot = hencky_j2_return(np.einsum("ik,jk->ij", q, q)[:, :, None], eqps, COPPER)[0]
    assert np.abs(tau_rot).max() <= 1e-3  # Pa: round-off of ln(1)


# ------------------------------------------------------------------ assembled model
@pytest.mark.parametrize("kind", ["plane_strain", "3d"])
@pytest.mark.parametrize("fbar", [True, False])
def test_homogeneous_plastic_deformation_is_a_patch_test(kind, fbar):
    # a homogeneous F gives uniform τ; the interior nodal forces vanish on a distorted mesh
    # (with F-bar this needs the cell's mean dilatation: the centre value fails in 3D)
    mesh = mesh_for(kind, n=3 if kind != "3d" else 2, distort=0.2, seed=1)
    model = FiniteStrainJ2(mesh, COPPER, kind=kind, fbar=fbar)
    grad = np.array([[0.10, 0.05, 0.02], [-0.03, -0.25, 0.01], [0.0, 0.04, 0.08]])
    u = homogeneous_u(model, grad)
    f, state = model.internal_force(u)
    assert state.eqps.min() > 0.05  # well into plastic flow
    assert np.ptp(state.eqps) <= 1e-12  # uniform
    interior = np.setdiff1d(np.arange(mesh.nvertices), mesh.boundary_nodes())
    dofs = model.nodal_dofs()[:, interior].ravel()
    assert np.abs(f[dofs]).max() <= 1e-10 * np.abs(f).max()


def _axisymmetric_equilibrium_field(model):
    """u_r = a r, u_z = b z: τ_rr = τ_θθ (F_rr = F_θθ), so the uniform field is in equilibrium."""
    return homogeneous_u(model, np.diag([-0.12, 0.3, 0.0]))


@pytest.mark.parametrize("fbar", [True, False])
def test_axisymmetric_uniform_radial_field_in_equilibrium(fbar):
    # F = diag(1 + a, 1 + b, 1 + a) everywhere: τ_rr = τ_θθ, and ∫ (τ ∂N/∂r + τ N/r) 2πR dA₀ is
    # a boundary term, integrated exactly by 2×2 Gauss points on bilinear cells
    mesh = mesh_for("axisymmetric", n=3, distort=0.2, seed=2)
    model = FiniteStrainJ2(mesh, COPPER, fbar=fbar)
    u = _axisymmetric_equilibrium_field(model)
    f, state = model.internal_force(u)
    assert state.eqps.min() > 0.05
    assert np.allclose(state.kirchhoff[0, 0], state.kirchhoff[2, 2], rtol=1e-12)
    interior = np.setdiff1d(np.arange(mesh.nvertices), mesh.boundary_nodes())
    assert np.abs(f[model.nodal_dofs()[:, interior].ravel()]).max() <= 1e-10 * np.abs(f).max()


@pytest.mark.parametrize("kind", ["axisymmetric", "plane_strain", "3d"])
@pytest.mark.parametrize("fbar", [True, False])
def test_internal_force_is_the_energy_gradient(kind, fbar):
    # elastic (huge yield stress): f = ∂W/∂u for the Hencky energy W of the (F-bar) deformation;
    # checked by central differences along random directions at a finite (10%) strain
    material = J2Material(117e9, 0.35, 8930.0, 1e15, 0.0)
    mesh = mesh_for(kind, n=2, distort=0.2, seed=4)
    model = FiniteStrainJ2(mesh, material, kind=kind, fbar=fbar)
    rng = np.random.default_rng(5)
    u = 0.1 * 3.2e-3 * rng.uniform(-1, 1, model.n_dofs) / 2
    weight = rng.uniform(0.2, 1.0, model.shape)  # any positive weight at quadrature points
    state = model.initial_state()
    f, _ = model.internal_force(u, state, weight)
    for _ in range(3):
        du = rng.normal(size=model.n_dofs) * 1e-3 * 3.2e-3
        h = 1e-3
        dw = (
            model.stored_energy(u + h * du, state, weight)
            - model.stored_energy(u - h * du, state, weight)
        ) / (2 * h)
        assert f @ du == pytest.approx(dw, rel=1e-6)


@pytest.mark.parametrize("kind", ["axisymmetric", "plane_strain", "3d"])
def test_small_strain_limit_is_linear_elasticity(kind):
    mesh = mesh_for(kind, n=2, distort=0.2, seed=6)
    model = FiniteStrainJ2(mesh, COPPER, kind=kind, fbar=False)
    linear = LinearElastic(mesh, COPPER.elastic, kind=kind, intorder=3)
    rng = np.random.default_rng(7)
    u = 1e-9 * rng.uniform(-1, 1, model.n_dofs)  # strains ~1e-6, far below yield (3.4e-3)
    f, state = model.internal_force(u)
    assert state.eqps.max() == 0.0
    ku = linear.stiffness() @ u
    # geometric nonlinearity is O(strain) relative
    assert np.abs(f - ku).max() <= 1e-5 * np.abs(ku).max()


def test_weight_scales_the_force():
    mesh = mesh_for("axisymmetric", n=2)
    model = FiniteStrainJ2(mesh, COPPER)
    u = homogeneous_u(model, np.diag([0.02, -0.2, 0.0]))
    f1, _ = model.internal_force(u)
    f2, _ = model.internal_force(u, weight=0.25)
    assert np.allclose(f2, 0.25 * f1, rtol=1e-13, atol=1e-12 * np.abs(f1).max())


def test_state_is_not_mutated():
    mesh = mesh_for("plane_strain", n=2)
    model = FiniteStrainJ2(mesh, COPPER)
    state = model.initial_state()
    before = state.cp_inv.copy(), state.eqps.copy()
    model.internal_force(homogeneous_u(model, np.diag([0.1, -0.3, 0.0])), state)
    assert np.array_equal(state.cp_inv, before[0]) and np.array_equal(state.eqps, before[1])


# ------------------------------------------------------------------ bad input and failures
def test_inverted_cell_is_reported():
    mesh = mesh_for("plane_strain", n=2)
    model = FiniteStrainJ2(mesh, COPPER)
    u = homogeneous_u(model, np.diag([0.0, -1.5, 0.0]))  # F_zz = −0.5
    with pytest.raises(InvertedElementError, match="det F"):
        model.internal_force(u)


def test_inverted_cell_stops_a_run_with_the_step_and_time():
    # a bar driven far too fast (10 × the wave speed per step) inverts a cell; the run stops with
    # a SimulationError that keeps the records until then
    mesh = mesh_for("axisymmetric", n=2)
    model = FiniteStrainJ2(mesh, COPPER)
    system = CoupledSystem([Block("bar", model, [BlockTerm(model)])], [])
    v0 = np.zeros(model.n_dofs)
    v0[model.dofs_where(lambda x: x[1] > 3e-3, components=[1])] = -2e5
    with pytest.raises(SimulationError, match="det F") as info:
        solve(system, "explicit", dt=1e-8, n_steps=50, v0=v0, check_dt=False)
    assert info.value.step >= 1 and info.value.result is not None


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"yield_stress": 0.0}, "yield_stress"),
        ({"yield_stress": np.nan}, "yield_stress"),
        ({"hardening_modulus": -1.0}, "hardening_modulus"),
        ({"poisson": 0.5}, "poisson"),
    ],
)
def test_bad_material(kwargs, name):
    args = {"young": 117e9, "poisson": 0.35, "density": 8930.0, "yield_stress": 4e8}
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        J2Material(**args)


def test_bad_mesh_and_kind():
    with pytest.raises(ValueError, match="MeshQuad"):
        FiniteStrainJ2(skfem.MeshTri(), COPPER)
    with pytest.raises(ValueError, match="kind"):
        FiniteStrainJ2(skfem.MeshQuad(), COPPER, kind="3d")
    model = FiniteStrainJ2(skfem.MeshQuad(), COPPER)
    with pytest.raises(ValueError, match="shape"):
        model.internal_force(np.zeros(3))


# ------------------------------------------------------------------ dynamics
def test_small_amplitude_dynamics_match_linear_elasticity():
    # an elastic wave of 1e-3 m/s in a copper cylinder: the finite-strain model (committed states,
    # explicit central differences) follows the linear model to the size of the strains (~1e-7)
    mesh = mesh_for("axisymmetric", n=3)
    runs = []
    for model in (
        FiniteStrainJ2(mesh, COPPER, fbar=False),
        LinearElastic(mesh, COPPER.elastic, kind="axisymmetric", intorder=3),
    ):
        system = CoupledSystem([Block("bar", model, [BlockTerm(model)])], [])
        v0 = np.zeros(model.n_dofs)
        v0[model.dofs_where(lambda x: x[1] > 3e-3, components=[1])] = -1e-3
        runs.append(solve(system, "explicit", t_end=2e-6, v0=v0))
    nonlinear, linear = runs
    assert nonlinear.times.size == linear.times.size
    scale = np.abs(linear.u).max()
    assert np.abs(nonlinear.u - linear.u).max() <= 1e-5 * scale


# ------------------------------------------------------------------ as an Arlequin patch
def _cylinder_with_plastic_patch(fine_model: str, speed: float):
    """Coarse elastic copper cylinder (axisymmetric) with a refined patch at its base, which is
    held axially (z = 0); everything above the base moves down at ``speed`` (m/s)."""
    import arlequin

    radius, length = 3.2e-3, 16e-3
    cm = skfem.MeshQuad.init_tensor(np.linspace(0, radius, 3), np.linspace(0, length, 11))
    pm = arlequin.refine_region(cm, levels=1, box=((0.0, 0.0), (radius, 6.4e-3)))
    coarse = LinearElastic(cm, COPPER.elastic, kind="axisymmetric", intorder=3)
    if fine_model == "j2":
        fine = FiniteStrainJ2(pm, COPPER, fbar=False)
    else:
        fine = LinearElastic(pm, COPPER.elastic, kind="axisymmetric", intorder=3)
    patch = arlequin.Patch(fine, gluing_width=1.6e-3, weights="ramp", coupling="H1")
    problem = arlequin.ArlequinProblem(coarse, [patch])
    problem.add_dirichlet("patch0", where=lambda x: np.isclose(x[1], 0.0), components=[1])
    system = problem.system()
    v0 = {"coarse": np.zeros(coarse.n_dofs), "patch0": np.zeros(fine.n_dofs)}
    v0["coarse"][coarse.nodal_dofs()[1]] = -speed
    v0["patch0"][fine.nodal_dofs()[1]] = -speed * (pm.p[1] > 0.0)
    dt = 0.9 * stable_time_step(system).critical  # 1.06e-7 s
    return system, solve(system, "explicit", dt=dt, n_steps=25, v0=v0)


def test_plastic_patch_glued_to_elastic_coarse_model():
    # small amplitude (strains ~1e-7): the J2 patch follows the linear patch to O(strain)
    # (measured 2.1e-7 relative)
    _, lin = _cylinder_with_plastic_patch("linear", 1e-3)
    _, j2 = _cylinder_with_plastic_patch("j2", 1e-3)
    assert np.abs(j2.u - lin.u).max() <= 1e-5 * np.abs(lin.u).max()
    assert j2.states["patch0"][0].eqps.max() == 0.0
    # 50 m/s: the patch yields at the base, and the mediator rows still hold to round-off
    system, run = _cylinder_with_plastic_patch("j2", 50.0)
    assert run.status == 0
    assert run.states["patch0"][0].eqps.max() > 0.01  # measured 0.048 after 2.66 µs
    coupling = [c for c in system.constraints if c.kind == "coupling"]
    for c in coupling:
        scale = np.abs(c.matrix).max() * np.abs(run.u).max()
        assert np.abs(c.matrix @ run.u).max() <= 1e-10 * scale


@pytest.mark.parametrize("kind", ["axisymmetric", "plane_strain", "3d"])
@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_stored_energy_of_a_state_is_the_stored_energy_at_its_displacement(kind, backend):
    # ψ from the state's own τ (Hencky: ψ = (tr τ)²/(18K) + |dev τ|²/(4G)) against ψ(ε_e)
    # recomputed from u and C_p⁻¹, after a plastic step on a distorted mesh: the same to
    # round-off. With bulk viscosity the state's τ is still the material stress (its pressure
    # is not stored), so elastic_energy_of_state holds; stored_energy_of_state, paired with
    # plastic_dissipation in the energy contract, is refused (the viscous work is dissipated)
    if kind == "3d" and backend == "numba":
        backend = "numpy"  # the numba kernel is planar
    mesh = mesh_for(kind, n=3 if kind != "3d" else 2, distort=0.2, seed=6)
    model = FiniteStrainJ2(mesh, COPPER, kind=kind, backend=backend)
    rng = np.random.default_rng(7)
    u = homogeneous_u(model, np.array([[0.10, 0.05, 0.0], [-0.03, -0.25, 0.0], [0, 0, 0.0]]))
    u += 0.02 * 3.2e-3 * rng.uniform(-1, 1, model.n_dofs)
    weight = rng.uniform(0.2, 1.0, model.shape)
    _, state = model.internal_force(u)
    assert state.eqps.max() > 0.05
    exact = model.stored_energy(u, state, weight)
    assert model.stored_energy_of_state(state, weight) == pytest.approx(exact, rel=1e-10)
    viscous = FiniteStrainJ2(mesh, COPPER, kind=kind, backend=backend, bulk_viscosity=True)
    with pytest.raises(ValueError, match="bulk viscosity"):
        viscous.stored_energy_of_state(state)
    # a compressive step in 1 ns: a viscous pressure q > 0 in the forces, none in the state
    f_visc, v_state = viscous.internal_force(u, dt=1e-9)
    f_plain, _ = model.internal_force(u)
    assert not np.allclose(f_visc, f_plain)
    exact = viscous.stored_energy(u, v_state, weight)
    assert viscous.elastic_energy_of_state(v_state, weight) == pytest.approx(exact, rel=1e-10)
