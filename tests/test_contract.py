"""The model and constraint contract (arlequin.contract), checked on every model in models/.

For each model: the members the core calls exist, with the documented shapes and units (masses
and load resultants against the exact integrals of the mesh), the weight at quadrature points is
applied as documented, and each declared optional capability behaves as declared:

* ``"tangent"``: equal to central differences of ``internal_force`` (relative 1e-6);
* ``"critical_time_step"``: a lower bound of the computed critical step of the model alone
  (Lanczos on the lumped system), and not a useless one (≥ 0.5 of it).

A model without the tangent is refused by the implicit schemes with an error naming it, unless
the documented alternative (modified Newton on the initial stiffness) is asked for. The
unilateral constraints of the package follow their protocol and never mutate the states they
are given.
"""

from __future__ import annotations

import copy

import numpy as np
import pytest
import skfem

from arlequin.contract import (
    CapabilityError,
    DynamicModel,
    Model,
    UnilateralConstraint,
    capabilities,
)
from arlequin.models import (
    ContactSurface,
    FiniteStrainJ2,
    IsotropicElastic,
    J2Material,
    LevelSetContact,
    LinearElastic,
    PlaneObstacle,
    RigidContactPair,
    SignoriniContact,
    SmallStrainJ2,
    VoceHardening,
)
from arlequin.problem.system import Block, BlockTerm, CoupledSystem
from arlequin.solvers import LinearInequality, solve, stable_time_step

STEEL = IsotropicElastic(210e9, 0.3, 7850.0)
COPPER = J2Material(117e9, 0.35, 8930.0, 0.4e9, 0.1e9)
SOFT = J2Material(117e9, 0.35, 8930.0, 20e6, 0.1e9)  # yields at a strain of 1.7e-4
VOCE = VoceHardening(20e6, saturation=30e6, rate=50.0, modulus=1e8)


def _shift(mesh, dx):
    return type(mesh)(mesh.p + np.asarray(dx, float)[:, None], mesh.t)


def _models():
    line = skfem.MeshLine(np.linspace(0.0, 2.0, 7))
    tri = skfem.MeshTri.init_tensor(np.linspace(0, 1, 4), np.linspace(0, 2, 5))
    quad = _shift(skfem.MeshQuad.init_tensor(np.linspace(0, 1, 4), np.linspace(0, 2, 5)), [0.5, 0])
    tet = skfem.MeshTet.init_tensor(*(np.linspace(0, 1, 3),) * 3)
    hexa = skfem.MeshHex.init_tensor(np.linspace(0, 1, 3), np.linspace(0, 1, 3), [0, 0.5, 1.0])
    return {
        "elastic-1d": (LinearElastic(line, STEEL, "1d", area=1e-4), 2.0 * 1e-4),
        "elastic-plane": (LinearElastic(tri, STEEL, "plane_strain"), 2.0),
        "elastic-axi": (LinearElastic(quad, STEEL, "axisymmetric"), np.pi * (1.5**2 - 0.5**2) * 2),
        "elastic-tet": (LinearElastic(tet, STEEL, "3d"), 1.0),
        "elastic-hex": (LinearElastic(hexa, STEEL, "3d"), 1.0),
        "j2-axi": (FiniteStrainJ2(quad, COPPER, "axisymmetric"), np.pi * (1.5**2 - 0.5**2) * 2),
        "j2-plane": (FiniteStrainJ2(quad, COPPER, "plane_strain"), 2.0),
        "j2-hex": (FiniteStrainJ2(hexa, COPPER, "3d"), 1.0),
        # small-strain J2 soft enough that the contract's random u ~ 1e-4 m makes points flow
        "ssj2-axi": (
            SmallStrainJ2(quad, SOFT, "axisymmetric", kinematic_modulus=1e9, bbar=True),
            np.pi * (1.5**2 - 0.5**2) * 2,
        ),
        "ssj2-plane": (SmallStrainJ2(tri, SOFT, "plane_strain", hardening=VOCE), 2.0),
        "ssj2-hex": (SmallStrainJ2(hexa, SOFT, "3d", hardening=VOCE, kinematic_modulus=1e9), 1.0),
    }


MODELS = _models()


@pytest.fixture(params=sorted(MODELS))
def case(request):
    return MODELS[request.param]


def test_members_shapes_and_units(case):
    model, volume = case
    assert isinstance(model, Model) and isinstance(model, DynamicModel)
    n = model.n_dofs
    mesh = model.mesh
    assert n == model.n_components * mesh.nvertices
    assert model.kind in ("1d", "plane_strain", "plane_stress", "axisymmetric", "3d")
    assert isinstance(model.is_linear, bool)
    basis = model.scalar_basis()
    shape = basis.dx.shape  # (n_elems, n_qp): where weights live
    assert shape[0] == mesh.nelements
    # mass (kg): the lumped row sums of each component add up to ρ × volume
    rho = model.material.density
    m = np.asarray(model.mass(lumped=True))
    assert m.shape == (n,)
    for c in range(model.n_components):
        assert m[c :: model.n_components].sum() == pytest.approx(rho * volume, rel=1e-12)
    k = model.stiffness()
    assert k.shape == (n, n)
    assert abs(k - k.T).max() <= 1e-12 * abs(k).max()
    # the weight at quadrature points scales every assembled quantity
    w = np.full(shape, 0.25)
    assert np.asarray(model.mass(w, lumped=True)).sum() == pytest.approx(0.25 * m.sum())
    u = 1e-4 * np.sin(np.arange(n))
    f, _ = model.internal_force(u, model.initial_state(), None)
    fw, _ = model.internal_force(u, model.initial_state(w), w)
    assert f.shape == (n,)
    np.testing.assert_allclose(fw, 0.25 * f, rtol=1e-10, atol=1e-12 * np.abs(f).max())
    # loads (N): a uniform body force density resultant is f × volume
    b = model.body_force_vector(np.full(model.n_components, 3.0))
    assert b.shape == (n,)
    assert b[:: model.n_components].sum() == pytest.approx(3.0 * volume, rel=1e-12)
    facets = mesh.boundary_facets()
    t = model.traction_vector(facets, np.full(model.n_components, 2.0))
    assert t.shape == (n,) and np.all(np.isfinite(t))
    # the same model on another mesh
    other = model.with_mesh(mesh)
    assert type(other) is type(model) and other.kind == model.kind


def test_tangent_capability_behaves_as_declared(case):
    model, _ = case
    n = model.n_dofs
    rng = np.random.default_rng(1)
    u = 1e-4 * rng.standard_normal(n)
    state = model.initial_state()
    if "tangent" not in capabilities(model):
        assert not model.is_linear  # only nonlinear models may lack it
        return
    k = model.tangent(u, state)
    du = rng.standard_normal(n)
    h = 1e-7 * np.linalg.norm(u) / np.linalg.norm(du)
    fp, _ = model.internal_force(u + h * du, state)
    fm, _ = model.internal_force(u - h * du, state)
    fd = (fp - fm) / (2 * h)
    assert np.linalg.norm(k @ du - fd) <= 1e-6 * np.linalg.norm(fd)


def test_critical_time_step_capability_behaves_as_declared(case):
    model, _ = case
    assert "critical_time_step" in capabilities(model)
    system = CoupledSystem([Block("b", model, [BlockTerm(model)])])
    true = stable_time_step(system, "blocks").critical
    est = model.critical_time_step(np.zeros(model.n_dofs), model.initial_state())
    assert 0.5 * true <= est <= true * (1 + 1e-12), (est, true)


def test_j2_critical_step_follows_the_configuration():
    # an isochoric squash (height halved, width doubled, the density unchanged) of cells of
    # 1/3 × 1/2 m: the smallest size goes from 1/3 to 1/4 m, so the step drops by about 3/4
    model = MODELS["j2-plane"][0]
    x = model.mesh.p
    u = np.zeros(model.n_dofs)
    u[0::2] = x[0] - x[0].min()
    u[1::2] = -0.5 * x[1]
    ratio = model.critical_time_step(u) / model.critical_time_step(0 * u)
    assert 0.6 < ratio < 0.8, ratio


class ExplicitOnlyJ2(FiniteStrainJ2):
    """FiniteStrainJ2 with its tangent withdrawn (a member set to None opts out of a
    protocol): a nonlinear model without the capability, as a user's explicit-only model."""

    tangent = None


def test_implicit_scheme_refuses_a_model_without_tangent():
    assert "tangent" in capabilities(MODELS["j2-plane"][0])
    model = ExplicitOnlyJ2(MODELS["j2-plane"][0].mesh, COPPER, "plane_strain")
    assert "tangent" not in capabilities(model)
    system = CoupledSystem([Block("b", model, [BlockTerm(model)])])
    v0 = np.zeros(model.n_dofs)
    v0[1::2] = 1.0
    with pytest.raises(CapabilityError, match="ExplicitOnlyJ2"):
        solve(system, "newmark", n_steps=2, dt=1e-7, v0=v0)
    # the documented alternative: modified Newton with the initial stiffness
    r = solve(system, "newmark", n_steps=2, dt=1e-7, v0=v0, newton="initial")
    assert r.success and np.all(np.isfinite(r.u))


def test_objects_that_are_not_models_are_refused_by_name():
    from arlequin import ArlequinProblem, ContractError, Patch

    mesh = skfem.MeshTri()
    with pytest.raises(ContractError, match=r"patch's model is a MeshTri1, which lacks .*kind"):
        Patch(mesh, gluing_width=0.1)
    with pytest.raises(ContractError, match="coarse model is a MeshTri1"):
        ArlequinProblem(mesh)
    coarse = LinearElastic(mesh, STEEL)
    with pytest.raises(ContractError, match="patch 0 is a LinearElastic"):
        ArlequinProblem(coarse, [coarse])


def _constraints():
    bar = LinearElastic(skfem.MeshLine(np.linspace(-1.0, 0.0, 6)), STEEL, area=1e-4)
    surf = ContactSurface(bar.mesh, where=lambda x: x[0] > -0.5, area=1e-4)
    pair = RigidContactPair(surf, PlaneObstacle([0.0], [-1.0]), bar.n_dofs)
    g = np.zeros((1, bar.n_dofs))
    g[0, -1] = 1.0
    return bar, [
        LevelSetContact(pair, material=STEEL),
        SignoriniContact(pair),
        LinearInequality(g, 0.0, level="velocity"),
        LinearInequality(g, 0.0, level="displacement"),
    ]


@pytest.mark.parametrize("index", range(4))
def test_unilateral_constraints_follow_the_protocol_and_keep_states_immutable(index):
    bar, cons = _constraints()
    con = cons[index]
    assert isinstance(con, UnilateralConstraint)
    n = bar.n_dofs
    u, v = np.zeros(n), np.full(n, 1.0)
    state = con.initial_state(u, v)
    before = copy.deepcopy(state)
    trial = con.begin_step(state, 0.0, 1e-6, u, v)
    assert trial.active.shape == (con.n_rows,) and trial.matrix.shape == (con.n_rows, n)
    assert trial.rhs.shape == (con.n_rows,)
    lam = np.full(con.n_rows, -1.0 if "Contact" in type(con).__name__ else 1.0)
    trial2 = con.update_status(trial, u + 1e-6 * v, v, lam)
    assert trial2.iterations == trial.iterations + 1
    new = con.commit(
        state, trial2, t=1e-6, u=u + 1e-6 * v, v_before=v, v_after=v, multipliers=lam,
        impulse=1e-6 * lam,
    )  # fmt: skip
    assert np.isfinite(new.work)
    # the state given was not touched, and the same calls give the same new state
    for field in ("active", "work"):
        np.testing.assert_array_equal(getattr(state, field), getattr(before, field))
    again = con.commit(
        state, con.update_status(con.begin_step(state, 0.0, 1e-6, u, v), u + 1e-6 * v, v, lam),
        t=1e-6, u=u + 1e-6 * v, v_before=v, v_after=v, multipliers=lam, impulse=1e-6 * lam,
    )  # fmt: skip
    np.testing.assert_array_equal(again.active, new.active)
    assert again.work == new.work


class _RecordsTimeStep:
    """A nonlinear wrapper of a linear model that declares ``uses_time_step`` and records the
    ``dt`` the integrators pass (the contract: the step that leads to u, None at t = 0)."""

    is_linear = False
    uses_time_step = True

    def __init__(self, model):
        self.model, self.n_dofs, self.seen, self.seen_by_tangent = model, model.n_dofs, [], []

    def mass(self, weight=None, lumped=False):
        return self.model.mass(weight, lumped=lumped)

    def stiffness(self, weight=None):
        return self.model.stiffness(weight)

    def internal_force(self, u, state=None, weight=None, dt=None):
        self.seen.append(dt)
        return self.model.stiffness(weight) @ u, None

    def tangent(self, u, state=None, weight=None, dt=None):
        self.seen_by_tangent.append(dt)
        return self.model.stiffness(weight)


@pytest.mark.parametrize("scheme", ["explicit", "newmark"])
def test_models_that_use_the_time_step_receive_it(scheme):
    bar = LinearElastic(skfem.MeshLine(np.linspace(0.0, 1.0, 6)), STEEL, area=1e-4)
    model = _RecordsTimeStep(bar)
    system = CoupledSystem([Block("b", model, [BlockTerm(model)])])
    steps = [1e-6, 2e-6, 1.5e-6]
    from arlequin.solvers import StepSchedule

    with pytest.raises(ValueError, match="StepSchedule needs a function"):
        StepSchedule(steps)
    schedule = StepSchedule(lambda integ: steps[min(integ.step_count, 2)])
    solve(system, scheme, dt=schedule, n_steps=3, v0=np.ones(bar.n_dofs))
    assert model.seen[0] is None  # the initial evaluation
    assert sorted(set(model.seen[1:])) == sorted(set(steps))  # every later call: its step
    if scheme == "newmark":  # Newton's tangent: the same step as the force it derives
        assert model.seen_by_tangent and set(model.seen_by_tangent) <= set(steps)


def test_csr_with_data_is_copy_of_template_with_new_data():
    # csr_with_data's direct copy against copy.copy (its reference: the same attributes, the
    # same objects), and a class with a __copy__ hook taking copy.copy's path
    import scipy.sparse as sp

    from arlequin.contract import csr_pattern, csr_with_data

    indices, indptr = np.array([0, 2, 1], dtype=np.int32), np.array([0, 2, 3], dtype=np.int32)
    template = csr_pattern(indices, indptr, (2, 3))
    data = np.array([1.0, 2.0, 3.0])
    out, ref = csr_with_data(template, data), copy.copy(template)
    ref.data = data
    assert type(out) is type(ref) and out.__dict__.keys() == ref.__dict__.keys()
    assert all(out.__dict__[k] is ref.__dict__[k] for k in ref.__dict__)
    assert np.array_equal(out.toarray(), [[1.0, 0.0, 2.0], [0.0, 3.0, 0.0]])
    assert not template.data.any()  # the template keeps its zeros

    class Hooked(sp.csr_matrix):
        copies = 0

        def __copy__(self):
            type(self).copies += 1
            new = Hooked.__new__(Hooked)
            new.__dict__.update(self.__dict__)
            return new

    hooked = Hooked(template)
    out = csr_with_data(hooked, data)
    assert Hooked.copies == 1 and type(out) is Hooked and out.data is data
