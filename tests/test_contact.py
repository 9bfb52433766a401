"""Unit tests of the level-set contact model (models/contact/level_set.py): geometry, statuses,
protocol."""

from __future__ import annotations

import logging

import numpy as np
import pytest
import scipy.sparse as sp
import skfem

from arlequin.models import (
    ContactConvergenceError,
    ContactSurface,
    DeformableContactPair,
    IsotropicElastic,
    LevelSetContact,
    LevelSetObstacle,
    LinearElastic,
    PlaneObstacle,
    RigidContactPair,
    SignoriniContact,
    SphereObstacle,
    acoustic_impedance,
)
from arlequin.problem.system import Block, BlockTerm, CoupledSystem
from arlequin.solvers import solve

STEEL = IsotropicElastic(210e9, 0.3, 7850.0)


def test_obstacles_phi_and_gradient():
    x = np.array([[0.0, 1.0, 3.0], [2.0, 0.0, 0.0]])
    plane = PlaneObstacle([0.0, 0.5], [0.0, 2.0])  # free space y > 0.5
    np.testing.assert_allclose(plane.phi(x), [1.5, -0.5, -0.5])
    np.testing.assert_allclose(plane.gradient(x), [[0, 0, 0], [1, 1, 1]])
    ball = SphereObstacle([0.0, 0.0], 1.0)
    np.testing.assert_allclose(ball.phi(x), [1.0, 0.0, 2.0])
    np.testing.assert_allclose(ball.gradient(x)[:, 0], [0.0, 1.0])
    cavity = SphereObstacle([0.0, 0.0], 4.0, inside=True)
    np.testing.assert_allclose(cavity.phi(x), [2.0, 3.0, 1.0])
    ls = LevelSetObstacle(
        lambda p: 1.0 - p[0], lambda p: np.vstack([-np.ones(p.shape[1]), 0 * p[1]])
    )
    np.testing.assert_allclose(ls.phi(x), [1.0, 0.0, -2.0])
    with pytest.raises(ValueError, match="radius"):
        SphereObstacle([0.0], -1.0)


def test_acoustic_impedance_default_kappa():
    # 1D: rho * sqrt(E / rho); 2D/3D: rho * c_d with the dilatational speed
    assert acoustic_impedance(210e9, 7850.0) == pytest.approx(np.sqrt(210e9 * 7850.0))
    m = 210e9 * 0.7 / (1.3 * 0.4)
    assert acoustic_impedance(210e9, 7850.0, 0.3) == pytest.approx(np.sqrt(m * 7850.0))


def test_surface_weights_2d_3d():
    # vertex quadrature: the weights of a face sum to its measure
    quad = skfem.MeshQuad.init_tensor(np.linspace(0, 0.3, 4), np.linspace(0, 1, 3))
    s = ContactSurface(quad, where=lambda x: x[1] < 1e-9)
    assert s.n_points == 4
    np.testing.assert_allclose(s.weights, [0.05, 0.1, 0.1, 0.05])
    axes = (np.linspace(0, 0.2, 3), np.linspace(0, 0.1, 2), np.linspace(0, 1, 2))
    hexm = skfem.MeshHex.init_tensor(*axes)
    s3 = ContactSurface(hexm, where=lambda x: x[2] < 1e-9)
    assert s3.weights.sum() == pytest.approx(0.02)
    # axisymmetric: ∫ N_a 2πr ds, exact for r linear on each segment, so the total is the disc
    # of radius 0.3 exactly and the node on the axis gets its share 2πℓ²/6 (ℓ its segment)
    s_axi = ContactSurface(quad, where=lambda x: x[1] < 1e-9, axisymmetric=True)
    assert s_axi.weights.sum() == pytest.approx(np.pi * 0.3**2, rel=1e-12)
    on_axis = quad.p[0, s_axi.nodes] == 0.0
    ell = np.diff(np.unique(quad.p[0]))[0]
    assert s_axi.weights[on_axis] == pytest.approx([2 * np.pi * ell**2 / 6], rel=1e-12)


@pytest.mark.parametrize("dim", [2, 3])
def test_deformable_pair_gap_and_rows(dim):
    """Two blocks apart by g: d_n = −g; G u is the linearised gap change (finite differences)."""
    g = 1e-3
    lat = [np.linspace(0, 1, 3)] * (dim - 1)
    mk = skfem.MeshQuad if dim == 2 else skfem.MeshHex
    top = LinearElastic(mk.init_tensor(*lat, np.linspace(g, 1 + g, 3)), STEEL)
    bot = LinearElastic(mk.init_tensor(*lat, np.linspace(-1, 0, 3)), STEEL)
    n = top.n_dofs + bot.n_dofs
    slave = ContactSurface(top.mesh, where=lambda x: x[-1] < g + 0.1)
    master = ContactSurface(bot.mesh, where=lambda x: x[-1] > -0.1, offset=top.n_dofs)
    pair = DeformableContactPair(slave, master, n)
    geo = pair.geometry(np.zeros(n))
    np.testing.assert_allclose(geo.gap, -g)
    np.testing.assert_allclose(geo.normal[-1], 1.0)  # master outward normal points up
    rng = np.random.default_rng(0)
    du = 1e-7 * rng.standard_normal(n)
    fd = pair.geometry(du).gap - geo.gap
    np.testing.assert_allclose(geo.rows @ du, fd, atol=1e-12)
    # approach: the top block moving down gives [[v_n]] > 0
    v = np.zeros(n)
    v[dim - 1 : top.n_dofs : dim] = -1.0
    np.testing.assert_allclose(geo.rows @ v, 1.0)


def test_compiled_segment_search_is_the_numpy_path():
    # a curved slave surface above a deformed master: points over segment ends tie between
    # two segments (the first one is taken by both paths); same segments, parameters, gaps
    # and rows bit for bit
    ball = skfem.MeshQuad.init_tensor(np.linspace(0.0, 0.6, 13), np.linspace(0.0, 0.5, 5))
    x = ball.p.copy()
    x[1] += 0.02 + 0.1 * x[0] ** 2  # its bottom a parabola 2 cm above the block at the axis
    ball = skfem.MeshQuad(x, ball.t)
    block = skfem.MeshQuad.init_tensor(np.linspace(0.0, 0.8, 9), np.linspace(-0.4, 0.0, 3))
    n = ball.p.size + block.p.size
    slave = ContactSurface(ball, where=lambda x: x[1] < 0.02 + 0.1 * x[0] ** 2 + 1e-3)
    master = ContactSurface(block, where=lambda x: x[1] > -1e-9, offset=ball.p.size)
    fast = DeformableContactPair(slave, master, n)
    ref = DeformableContactPair(slave, master, n, compiled=False)
    rng = np.random.default_rng(0)
    for u in (np.zeros(n), 1e-3 * rng.standard_normal(n)):
        xs = slave.positions(u)
        for a, b in zip(fast._project(xs, u), ref._project(xs, u)):
            np.testing.assert_array_equal(a, b)
        # the fast pair's whole geometry is one compiled call (segment_geometry)
        assert fast._segments is not None and ref._segments is None
        ga, gb = fast.geometry(u), ref.geometry(u)
        np.testing.assert_array_equal(ga.gap, gb.gap)
        np.testing.assert_array_equal(ga.normal, gb.normal)
        np.testing.assert_array_equal(ga.jump.master_shape, gb.jump.master_shape)
        for arr in ("data", "indices", "indptr"):
            np.testing.assert_array_equal(getattr(ga.rows, arr), getattr(gb.rows, arr))


def test_point_to_triangle_projection():
    tet = skfem.MeshTet.init_tensor(np.linspace(0, 1, 3), np.linspace(0, 1, 3), np.array([-1, 0.0]))
    master = ContactSurface(tet, where=lambda x: x[2] > -1e-9, offset=0)
    small = (np.array([0.3, 0.4]), np.array([0.6, 0.7]), np.array([0.2, 0.3]))
    line = skfem.MeshTet.init_tensor(*small)
    slave = ContactSurface(line, where=lambda x: x[2] < 0.2 + 1e-9, offset=tet.p.size)
    pair = DeformableContactPair(slave, master, tet.p.size + line.p.size)
    geo = pair.geometry(np.zeros(tet.p.size + line.p.size))
    np.testing.assert_allclose(geo.gap, -0.2)  # 0.2 m above the plane z = 0
    # the master part of each row interpolates (weights sum to 1 on the z components)
    rows = geo.rows.toarray()
    np.testing.assert_allclose(rows[:, 2 : tet.p.size : 3].sum(axis=1), 1.0)


def _bar_on_wall(n=10, v0=1.0, kappa=None, **kw):
    bar = LinearElastic(skfem.MeshLine(np.linspace(-1.0, 0.0, n + 1)), STEEL, kind="1d", area=1e-4)
    system = CoupledSystem([Block("bar", bar, [BlockTerm(bar)])])
    surf = ContactSurface(bar.mesh, where=lambda x: x[0] > -0.5, area=1e-4)
    pair = RigidContactPair(surf, PlaneObstacle([0.0], [-1.0]), system.n_dofs)
    con = LevelSetContact(pair, kappa=kappa, material=STEEL, **kw)
    return system, con, np.full(bar.n_dofs, v0)


def test_levelset_statuses_and_weak_residual():
    system, con, v0 = _bar_on_wall()
    c = np.sqrt(210e9 / 7850.0)
    dt = 0.1 / c
    res = solve(system, "theta", n_steps=5, dt=dt, v0=v0, constraints=[con], theta=0.5)
    h = con.history(res)
    state = res.constraint_states["contact"]
    # the end node hits the wall at t = 0: active from the first step, S_d = S_v = 1, λ_v < 0
    assert h.active[:, 0].all() and h.s_d[:, 0].all() and h.s_v[:, 0].all()
    assert np.all(h.lam[:, 0] < 0.0)
    np.testing.assert_allclose(h.vn[:, 0], 0.0, atol=1e-12)
    assert con.kappa == pytest.approx(np.sqrt(210e9 * 7850.0))
    # weak λ equation satisfied by the converged step
    lam = res.multipliers["contact"][-1]
    np.testing.assert_allclose(con.weak_residual(res.v, lam, state.active, res.u), 0.0, atol=1e-20)
    # contact work is the kinetic energy lost (θ = 1/2: exact energy identity)
    e = res.total_energy
    assert state.work == pytest.approx(e[-1] - e[0], rel=1e-9)


def test_fixed_point_failure_is_reported(caplog):
    system, con, v0 = _bar_on_wall(max_iterations=1)
    dt = 0.1 / np.sqrt(210e9 / 7850.0)
    # force a wrong initial guess: status iterations are needed at the release, cap 1
    with caplog.at_level(logging.WARNING):
        res = solve(system, "theta", n_steps=60, dt=dt, v0=v0, constraints=[con], theta=0.5)
    assert res.n_status_failures >= 1
    msgs = [r.getMessage() for r in caplog.records]
    assert any("not converged" in m and "t =" in m for m in msgs)
    system, con, v0 = _bar_on_wall(max_iterations=1, on_failure="raise")
    with pytest.raises(ContactConvergenceError, match="not converged"):
        solve(system, "theta", n_steps=60, dt=dt, v0=v0, constraints=[con], theta=0.5)


def test_signorini_baseline_enforces_gap():
    bar = LinearElastic(skfem.MeshLine(np.linspace(-1.0, 0.0, 11)), STEEL, kind="1d", area=1e-4)
    system = CoupledSystem([Block("bar", bar, [BlockTerm(bar)])])
    surf = ContactSurface(bar.mesh, where=lambda x: x[0] > -0.5, area=1e-4)
    pair = RigidContactPair(surf, PlaneObstacle([0.0], [-1.0]), system.n_dofs)
    con = SignoriniContact(pair)
    dt = 0.1 / np.sqrt(210e9 / 7850.0)
    res = solve(system, "newmark", n_steps=5, dt=dt, v0=np.ones(bar.n_dofs), constraints=[con])
    h = con.history(res)
    assert h.active[0, 0]
    # displacement level: d_n = 0 on active steps, never a penetration (Newmark may chatter)
    np.testing.assert_allclose(h.gap[h.active[:, 0], 0], 0.0, atol=1e-15)
    assert np.all(h.gap[:, 0] <= 1e-15)
    lam = res.multipliers["contact"][1:, 0]
    assert np.all(lam[h.active[:, 0]] <= 0.0) and np.all(lam[~h.active[:, 0]] == 0.0)


def test_invalid_parameters():
    system, con, _ = _bar_on_wall()
    with pytest.raises(ValueError, match="kappa"):
        LevelSetContact(con.pair, kappa=-1.0)
    with pytest.raises(ValueError, match="eta"):
        LevelSetContact(con.pair, kappa=1.0, eta=0.0)
    with pytest.raises(ValueError, match="on_failure"):
        LevelSetContact(con.pair, kappa=1.0, on_failure="ignore")
    assert sp.issparse(con.matrix()) and con.matrix().shape == (1, system.n_dofs)


def test_rows_on_a_kept_pattern_equal_scipy_constructions():
    # csr_with_data against scipy's constructor (exact: the same arrays), the template's index
    # arrays read-only and shared, and stack_active's pattern path against a fresh stacking
    from arlequin.contract import csr_pattern, csr_with_data, same_pattern
    from arlequin.solvers.system.rows import stack_active

    rng = np.random.default_rng(3)
    m, w, n = 5, 4, 40
    cols = np.sort(rng.choice(n, (m, w), replace=False), axis=1)
    indices, indptr = cols.ravel().astype(np.int32), np.arange(0, m * w + 1, w, dtype=np.int32)
    template = csr_pattern(indices, indptr, (m, n))
    a, b = (csr_with_data(template, rng.standard_normal(m * w)) for _ in range(2))
    ref = sp.csr_matrix((a.data, indices, indptr), shape=(m, n))
    assert np.array_equal(a.toarray(), ref.toarray()) and a.format == "csr"
    assert same_pattern(a, b) and not same_pattern(a, ref)
    with pytest.raises(ValueError):
        a.indices[0] = 1  # shared by every matrix of the pattern: never changed in place

    class Trial:
        def __init__(self, matrix, active):
            self.matrix, self.active, self.rhs = matrix, active, np.zeros(m)

    active = np.array([True, False, True, True, False])
    cache: dict = {}
    first, _, _ = stack_active([Trial(a, active)], n, cache)
    second, _, idx = stack_active([Trial(b, active)], n, cache)  # the kept pattern
    fresh, _, _ = stack_active([Trial(b, active)], n)
    assert same_pattern(first, second)
    for arr in ("data", "indices", "indptr"):
        assert np.array_equal(getattr(second, arr), getattr(fresh, arr))
    assert np.array_equal(second.toarray(), b.toarray()[idx[0]])
