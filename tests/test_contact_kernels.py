"""The contact step's shortcuts against their references (models/contact/kernel.py, records.py,
the plane's fixed rows, arlequin/solvers/system/rows.py's kept patterns): every comparison is exact,
byte for byte, since the shortcuts claim the same numbers as the numpy and scipy paths."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.sparse as sp
import skfem

from arlequin.contract import csr_pattern, csr_with_data
from arlequin.models import (
    ContactSurface,
    LevelSetContact,
    PlaneObstacle,
    RigidContactPair,
    SphereObstacle,
)
from arlequin.models.contact.kernel import (
    equal_gathered,
    level_set_begin,
    level_set_status,
    plane_gaps,
    rows_sum_dot,
    rows_times,
    scaled_entries,
)
from arlequin.models.contact.records import ContactTrial, build, evolve
from arlequin.solvers.system.rows import stack_active


def same_bytes(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


def random_rows(rng, m=40, n=300, density=0.05, zeros=True):
    """CSR rows with explicit zeros, negative zeros and an empty row (the cases where a change
    of summation order or of the starting value would show)."""
    g = sp.random(m, n, density=density, random_state=rng, format="csr")
    g.data = rng.standard_normal(g.nnz) * 10.0 ** rng.integers(-8, 8, g.nnz)
    if zeros and g.nnz > 4:
        g.data[:2] = 0.0
        g.data[2:4] = -0.0
    empty = sp.csr_matrix((np.zeros(0), np.zeros(0, np.int32), np.zeros(2, np.int32)), (1, n))
    out = sp.vstack([g[:3], empty, g[3:]], format="csr")
    assert out.nnz == g.nnz and np.sum(out.data == 0.0) >= 4  # the zeros kept
    return out


@pytest.mark.parametrize("seed", range(4))
def test_rows_products_equal_scipy_bit_for_bit(seed):
    # reference: scipy's CSR product (the path the kernels replace)
    rng = np.random.default_rng(seed)
    g = random_rows(rng)
    x, z = rng.standard_normal((2, g.shape[1]))
    x[:5] = -0.0
    assert same_bytes(rows_times(g.indptr, g.indices, g.data, x), g @ x)
    # the work's w · G (x + z): scipy's row products, then summed in order (a plain loop; BLAS's
    # dot may pair the terms, so it is compared to round-off)
    w = rng.standard_normal(g.shape[0])
    rows = g @ (x + z)
    total = 0.0
    for wi, ri in zip(w, rows):
        total += wi * ri
    got = rows_sum_dot(g.indptr, g.indices, g.data, x, z, w)
    assert same_bytes(np.float64(got), np.float64(total))
    assert got == pytest.approx(float(w @ rows), rel=1e-13, abs=1e-300)


@pytest.mark.parametrize("seed", range(4))
def test_level_set_status_kernels_equal_numpy(seed):
    # reference: the numpy expressions of LevelSetContact (begin_step's first statuses and
    # update_status), written out here as they were before the kernels
    rng = np.random.default_rng(seed)
    g = random_rows(rng)
    m = g.shape[0]
    v = rng.standard_normal(g.shape[1])
    gap = rng.standard_normal(m) * 1e-6
    gap[:3] = 0.0
    was = rng.random(m) < 0.3
    dt = 1.3e-7
    vn0, gap_pred, s_d, active = level_set_begin(g.indptr, g.indices, g.data, v, gap, dt, was)
    ref_vn0 = g @ v
    ref_pred = gap + dt * ref_vn0
    ref_sd = (ref_pred >= 0.0) | was
    assert same_bytes(vn0, ref_vn0) and same_bytes(gap_pred, ref_pred)
    assert same_bytes(s_d, ref_sd) and same_bytes(active, ref_sd & (was | (ref_vn0 > 0.0)))
    lam = -np.abs(rng.standard_normal(m)) * (rng.random(m) < 0.5)
    kappa = 4.0e7
    vn, s_v, new, changed = level_set_status(g.indptr, g.indices, g.data, v, lam, kappa, s_d,
                                             active)  # fmt: skip
    ref_sv = lam - kappa * (g @ v) <= 0.0
    assert same_bytes(vn, g @ v) and same_bytes(s_v, ref_sv) and same_bytes(new, s_d & ref_sv)
    assert changed == bool(np.any((s_d & ref_sv) != active))
    assert not level_set_status(g.indptr, g.indices, g.data, v, lam, kappa, s_d, new)[3]


def test_equal_gathered():
    # reference: (values == b[idx]).all(), NaN never equal and 0.0 == -0.0 as with ==
    b = np.arange(10.0)
    idx = np.array([1, 4, 7])
    values = b[idx]
    assert equal_gathered(values, b, idx)
    b[5] = -1.0  # outside idx
    assert equal_gathered(values, b, idx)
    b[7] = np.nan
    assert not equal_gathered(values, b, idx)
    values[2] = np.nan  # NaN is never equal, as with ==
    assert not equal_gathered(values, b, idx)
    assert equal_gathered(np.array([0.0]), np.array([-0.0]), np.array([0]))


def test_evolve_and_build_as_dataclasses():
    a, b = np.zeros(3), np.ones(3)
    fields = {f.name: a for f in dataclasses.fields(ContactTrial)}
    trial = build(ContactTrial, **fields)
    assert trial == ContactTrial(**fields)
    new = evolve(trial, active=b, iterations=2)
    ref = dataclasses.replace(trial, active=b, iterations=2)
    assert all(getattr(new, k) is getattr(ref, k) for k in fields)
    assert trial.active is a  # the original unchanged
    with pytest.raises(dataclasses.FrozenInstanceError):
        new.active = a
    with pytest.raises(TypeError, match="no field"):
        evolve(trial, activ=b)
    with pytest.raises(TypeError, match="needs the fields"):
        build(ContactTrial, active=a)


def bar_surface():
    mesh = skfem.MeshQuad.init_tensor(np.linspace(0, 1, 5), np.linspace(0, 0.5, 3))
    return ContactSurface(mesh, where=lambda x: x[1] < 1e-12), 2 * mesh.p.shape[1]


def test_plane_rows_made_once_equal_the_per_step_ones():
    # reference: the normals and rows of a general level-set obstacle (computed at each step)
    # with the plane's own phi and gradient
    surface, n = bar_surface()
    plane = PlaneObstacle([0.0, -1e-3], [0.3, 1.0])
    assert plane.constant_normal and not SphereObstacle([0.0, 5.0], 1.0).constant_normal
    fixed = RigidContactPair(surface, plane, n)

    class General(PlaneObstacle):
        constant_normal = False

    general = RigidContactPair(surface, General([0.0, -1e-3], [0.3, 1.0]), n)
    rng = np.random.default_rng(0)
    for _ in range(3):
        u = rng.standard_normal(n) * 1e-4
        a, b = fixed.geometry(u), general.geometry(u)
        # the plane's gaps come from one compiled pass (plane_gaps), whose sum over the two
        # components runs in order where BLAS's product may not: equal to a few ulps of the
        # positions (a 1 m bar), not byte for byte
        np.testing.assert_allclose(a.gap, b.gap, rtol=0.0, atol=4 * np.spacing(1.0))
        assert same_bytes(a.normal, b.normal)
        for arr in ("data", "indices", "indptr"):
            assert same_bytes(getattr(a.rows, arr), getattr(b.rows, arr))
        e = rng.standard_normal(a.normal.shape)
        assert same_bytes(a.jump(e).toarray(), b.jump(e).toarray())
    assert fixed.geometry(u).rows is fixed.geometry(2 * u).rows  # made once
    with pytest.raises(ValueError):
        fixed.geometry(u).normal[0, 0] = 1.0  # shared by every step: read-only


@pytest.mark.parametrize("dim", [2, 3])
def test_plane_gaps_kernel_against_the_obstacle_phi(dim):
    # reference: PlaneObstacle.phi of the positions X + u[dofs], negated (the numpy path)
    rng = np.random.default_rng(dim)
    m, n = 25, 400
    x_ref = rng.uniform(-1e-2, 1e-2, (dim, m))
    dofs = rng.choice(n, (dim, m), replace=False)
    u = rng.standard_normal(n) * 1e-4
    plane = PlaneObstacle(rng.standard_normal(dim) * 1e-3, rng.standard_normal(dim))
    ref = -plane.phi(x_ref + u[dofs])
    got = plane_gaps(x_ref, dofs, u, plane.normal, plane.point)
    # a sum of dim products of positions ~1e-2 m: equal to a few ulps of 1e-2
    np.testing.assert_allclose(got, ref, rtol=0.0, atol=8 * np.spacing(1e-2))


def test_constraint_step_against_the_numpy_reference():
    # the compiled path of LevelSetContact (CSR rows) against its numpy reference (the same
    # rows as a non-CSR matrix): the same trial and statuses
    surface, n = bar_surface()
    pair = RigidContactPair(surface, PlaneObstacle([0.0, 0.0], [0.0, 1.0]), n)
    con = LevelSetContact(pair, kappa=4e7)
    rng = np.random.default_rng(1)
    u, v = rng.standard_normal((2, n)) * 1e-3
    state = con.initial_state(u, v)
    trial = con.begin_step(state, 0.0, 1e-7, u, v)
    geo = trial.geometry
    slow = dataclasses.replace(geo, rows=geo.rows.tocoo())
    ref = con._first_statuses(slow, v, 1e-7, state.active)
    got = (trial.vn_start, trial.gap_pred, trial.s_d, trial.active)
    assert all(same_bytes(x, y) for x, y in zip(got, ref))
    lam = -np.abs(rng.standard_normal(pair.n_points))
    new = con.update_status(trial, u, v, lam)
    old = con.update_status(dataclasses.replace(trial, geometry=slow), u, v, lam)
    for k in ("active", "vn", "s_v", "lam", "used", "changed", "iterations"):
        assert same_bytes(getattr(new, k), getattr(old, k)), k
    with pytest.raises(ValueError):
        trial.rhs[0] = 1.0  # the shared zeros of the trials are read-only


def test_state_keeps_u_on_the_geometry_dofs_and_reuses_its_geometry():
    # a state keeps u on the pair's geometry dofs; a step starting from that u reuses the
    # state's geometry object, any other u (or a state of the earlier full-size form, or a
    # float32 u) gets the geometry computed afresh, equal to the pair's own
    surface, n = bar_surface()
    pair = RigidContactPair(surface, PlaneObstacle([0.0, -1e-3], [0.3, 1.0]), n)
    con = LevelSetContact(pair, kappa=4e7)
    rng = np.random.default_rng(2)
    u = rng.standard_normal(n) * 1e-4
    state = con.initial_state(u, np.zeros(n))
    assert same_bytes(state.u_geometry, u[pair.geometry_dofs])
    assert con._geometry_from(state, u.copy()) is state.geometry
    moved = u.copy()
    moved[pair.geometry_dofs[-1]] += 1e-9
    assert same_bytes(con._geometry_from(state, moved).gap, pair.geometry(moved).gap)
    older = dataclasses.replace(state, u_geometry=u.copy())  # full-size: not compared
    assert con._geometry_from(older, u) is not state.geometry
    u32 = u.astype(np.float32)
    same32 = dataclasses.replace(state, u_geometry=u32[pair.geometry_dofs])
    assert con._geometry_from(same32, u32) is state.geometry  # compared by the gather path


def test_stack_active_kept_patterns_equal_a_fresh_stacking():
    # reference: stack_active without a cache (the rows stacked afresh at every call)
    rng = np.random.default_rng(2)
    m, w, n = 6, 3, 30
    cols = np.sort(rng.choice(n, (m, w), replace=False), axis=1)
    template = csr_pattern(cols.ravel().astype(np.int32),
                           np.arange(0, m * w + 1, w, dtype=np.int32), (m, n))  # fmt: skip

    class Trial:
        def __init__(self, matrix, active):
            self.matrix, self.active, self.rhs = matrix, active, rng.standard_normal(m)

    cache: dict = {}
    sets = [rng.random(m) < 0.5 for _ in range(3)]
    for step in range(12):  # the sets come back: kept patterns
        tr = Trial(csr_with_data(template, rng.standard_normal(m * w)), sets[step % 3])
        g_a, rhs_a, idx = stack_active([tr], n, cache)
        ref, ref_rhs, ref_idx = stack_active([tr], n)
        for arr in ("data", "indices", "indptr"):
            assert same_bytes(getattr(g_a, arr), getattr(ref, arr))
        assert same_bytes(rhs_a, ref_rhs) and same_bytes(idx[0], ref_idx[0])
        again = stack_active([tr], n, cache)  # the same trial: the same objects
        assert again[0] is g_a and again[1] is rhs_a and not rhs_a.flags.writeable
    assert len(cache["patterns"]) == 3


@pytest.mark.parametrize("zeros", [False, True])
def test_scaled_entries_equal_numpy(zeros):
    # reference: the numpy lines of _make_b (scaled entries, their zeros dropped)
    rng = np.random.default_rng(5)
    data = rng.standard_normal(50)
    if zeros:
        data[[3, 7, 20]] = [0.0, -0.0, 0.0]
    w = -rng.random(50)
    ref = data * w
    keep_ref = ref != 0.0
    for before in (keep_ref, ~keep_ref, keep_ref[:-1]):
        out, keep, same, every = scaled_entries(data, w, before)
        assert same_bytes(out, ref[keep_ref]) and same_bytes(keep, keep_ref)
        assert every == bool(keep_ref.all())
        assert same == (before.shape == keep_ref.shape and np.array_equal(before, keep_ref))


def test_geometry_dofs_out_of_range_rejected():
    surface, n = bar_surface()
    pair = RigidContactPair(surface, PlaneObstacle([0.0, 0.0], [0.0, 1.0]), n)
    pair.geometry_dofs = np.array([0, n])  # a pair that names a dof outside the system
    with pytest.raises(ValueError, match="geometry_dofs"):
        LevelSetContact(pair, kappa=1.0)
