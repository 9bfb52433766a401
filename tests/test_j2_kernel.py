"""The compiled J2 kernels (models/plasticity/j2_kernel.py, planar;
models/plasticity/j2_kernel_3d.py, hexahedra) against the numpy reference path.

Both evaluate the same formulas (Q1 kinematics with F-bar, b_e − 1 without round-off, the
exponential-map return, the bulk viscosity, the consistent force), one point by point and one
with arrays, so they must agree to round-off: 1e-12 relative to the largest entry of each output
on random displacements and random committed states (elastic, plastic and mixed cells). The
bound, 1e-13, is issue 30's; measured at most 3.3e-14 (the nodal force with bulk viscosity).
"""

from __future__ import annotations

import numpy as np
import pytest
import skfem
from _meshes import perturb

from arlequin.contract import StateError
from arlequin.models import (
    CallableHardening,
    FiniteStrainJ2,
    InvertedElementError,
    J2Material,
    JohnsonCookHardening,
    VoceHardening,
)

COPPER = J2Material(117e9, 0.35, 8930.0, 0.4e9, 0.1e9)  # Taylor-bar copper (DESIGN §4)
MATERIALS = {
    "linear": COPPER,
    "voce": J2Material.with_law(117e9, 0.35, 8930.0, VoceHardening(0.4e9, 0.2e9, 8.0, 0.05e9)),
    "johnson-cook-rate": J2Material.with_law(
        117e9, 0.35, 8930.0, JohnsonCookHardening(0.4e9, 0.3e9, 0.4, c=0.02)
    ),
}
RTOL = 1e-13


def mesh(n: int = 4, seed: int = 1, dim: int = 2) -> skfem.Mesh:
    if dim == 3:  # 3 × 3 × 4 distorted hexahedra
        m = skfem.MeshHex.init_tensor(*[np.linspace(0.0, 3.2e-3, 4)] * 2,
                                      np.linspace(0.0, 4e-3, 5))  # fmt: skip
        return perturb(m, 3.2e-3 / 3, 0.2, seed)
    m = skfem.MeshQuad.init_tensor(np.linspace(0.0, 3.2e-3, n + 1), np.linspace(0.0, 4e-3, n + 2))
    return perturb(m, 3.2e-3 / n, 0.25, seed)


def pair(kind, name, fbar=True, **kwargs):
    m = mesh(dim=3 if kind == "3d" else 2)
    mat = MATERIALS[name]
    return (FiniteStrainJ2(m, mat, kind, fbar, backend="numpy", **kwargs),
            FiniteStrainJ2(m, mat, kind, fbar, backend="numba", **kwargs))  # fmt: skip


def random_u(model, amplitude, seed, compress=0.0):
    """Random nodal displacement (strains ~ amplitude) plus an axial compression."""
    rng = np.random.default_rng(seed)
    u = amplitude * 1e-3 * rng.uniform(-1, 1, model.n_dofs)
    axis = model.dim - 1  # z in axisymmetry (r, z) and in 3D
    u[model.nodal_dofs()[axis]] -= compress * model.mesh.p[axis]
    return u


def assert_same(a, b, what):
    fa, sa = a
    fb, sb = b
    for name, x, y in [
        ("force", fa, fb),
        ("cp_inv", sa.cp_inv, sb.cp_inv),
        ("eqps", sa.eqps, sb.eqps),
        ("kirchhoff", sa.kirchhoff, sb.kirchhoff),
        ("jacobian", sa.jacobian, sb.jacobian),
        ("plastic_work", sa.plastic_work, sb.plastic_work),
        ("viscous_work", sa.viscous_work, sb.viscous_work),
    ]:
        scale = max(np.abs(x).max(), 1e-300)
        err = np.abs(x - y).max() / scale
        assert err <= RTOL, f"{what}: {name} differs by {err:.2e} (relative)"


@pytest.mark.parametrize("kind", ["axisymmetric", "plane_strain", "3d"])
@pytest.mark.parametrize("name", sorted(MATERIALS))
@pytest.mark.parametrize("fbar", [True, False])
def test_kernel_equals_numpy_on_random_states(kind, name, fbar):
    ref, fast = pair(kind, name, fbar)
    dt = 1e-7
    # elastic (strains 1e-9 and 1e-4), mixed and fully plastic evaluations from the virgin state
    for amplitude, compress in [(1e-9, 0.0), (1e-4, 0.0), (2e-3, 2e-3), (0.05, 0.2)]:
        u = random_u(ref, amplitude, seed=3, compress=compress)
        a, b = ref.internal_force(u, dt=dt), fast.internal_force(u, dt=dt)
        assert_same(a, b, f"first step, strain ~{amplitude}")
        plastic = a[1].eqps > 0
        if amplitude >= 2e-3:
            assert plastic.any()
    # a second step from a committed plastic state, unloading in part of the mesh (mixed)
    u1 = random_u(ref, 0.05, seed=4, compress=0.2)
    s1 = ref.internal_force(u1, dt=dt)[1]
    if kind == "3d":  # a slight pull-back plus noise: 3D points all flow on the planar recipe
        u2 = 0.999 * u1 + random_u(ref, 0.002, seed=5)
    else:
        u2 = u1 + random_u(ref, 0.01, seed=5, compress=-0.01)
    a, b = ref.internal_force(u2, s1, dt=dt), fast.internal_force(u2, s1, dt=dt)
    assert_same(a, b, "second step")
    grew = a[1].eqps > s1.eqps
    assert grew.any() and not grew.all()  # both branches at once


@pytest.mark.parametrize("kind", ["axisymmetric", "plane_strain", "3d"])
def test_kernel_equals_numpy_with_bulk_viscosity_and_weight(kind):
    ref, fast = pair(kind, "linear", bulk_viscosity=True)
    assert ref.uses_time_step and fast.uses_time_step
    rng = np.random.default_rng(2)
    alpha = rng.uniform(0.1, 1.0, ref.shape)
    u1 = random_u(ref, 0.02, seed=6, compress=0.1)
    s1 = ref.internal_force(u1, weight=alpha, dt=1e-7)[1]
    u2 = u1 + random_u(ref, 0.001, seed=7, compress=0.01)  # compressing further: q > 0
    a = ref.internal_force(u2, s1, weight=alpha, dt=1e-8)
    b = fast.internal_force(u2, s1, weight=alpha, dt=1e-8)
    assert_same(a, b, "bulk viscosity")
    assert ref.viscous_dissipation(a[1], alpha) > 0.0


@pytest.mark.parametrize("kind", ["axisymmetric", "3d"])
def test_kernel_and_numpy_agree_on_the_smallest_strains(kind):
    # b_e − 1 is assembled without forming 1 + ε: the force stays linear in u down to 1e-15
    ref, fast = pair(kind, "linear")
    u = random_u(ref, 1.0, seed=8)
    f1 = fast.internal_force(1e-6 * u)[0]
    for scale in [1e-9, 1e-12]:
        for model in (ref, fast):
            f = model.internal_force(scale * 1e-6 * u)[0]
            assert np.allclose(f, scale * f1, rtol=0, atol=1e-5 * scale * np.abs(f1).max())


@pytest.mark.parametrize("kind", ["plane_strain", "3d"])
def test_kernel_reports_an_inverted_cell_by_id(kind):
    _, fast = pair(kind, "linear")
    p = fast.mesh.p
    corner = int(np.argmax(p.sum(axis=0)))  # the top-right corner node: in one cell only
    cell = int(np.nonzero((fast.mesh.t == corner).any(axis=0))[0][0])
    u = np.zeros(fast.n_dofs)
    u[fast.nodal_dofs()[:, corner]] = -4e-3  # pushed across the cell's diagonal
    with pytest.raises(InvertedElementError, match=f"cell {cell}: det F <= 0 \\(1 such cells\\)"):
        fast.internal_force(u)


@pytest.mark.parametrize("kind", ["axisymmetric", "3d"])
def test_kernel_on_one_thread_and_on_all_is_the_same(kind, monkeypatch):
    # the cells are independent: below PARALLEL_MIN_CELLS the kernel runs on the calling thread,
    # above it on all of numba's threads, and the outputs are the same bit for bit
    import numba

    from arlequin.models.plasticity import j2_kernel

    ref, fast = pair(kind, "linear", bulk_viscosity=True)
    u1 = random_u(ref, 0.02, seed=6, compress=0.1)
    s1 = ref.internal_force(u1, dt=1e-7)[1]
    u2 = u1 + random_u(ref, 0.001, seed=7, compress=0.01)
    threads = numba.get_num_threads()
    results = []
    for threshold in (10**9, 0):
        monkeypatch.setattr(j2_kernel, "PARALLEL_MIN_CELLS", threshold)
        f, s = fast.internal_force(u2, s1, dt=1e-8)
        results.append([f.copy()] + [x.copy() for x in vars(s).values()])
        assert numba.get_num_threads() == threads  # restored after a serial call
    for a, b in zip(*results, strict=True):
        assert np.array_equal(a, b)


def test_kernel_never_writes_over_a_state_still_referenced():
    # the compiled path reuses the arrays of states nothing references any more: a committed
    # state, or a view of one of its arrays, must survive any number of later evaluations
    _, fast = pair("axisymmetric", "linear")
    u = random_u(fast, 0.05, seed=4, compress=0.2)
    s1 = fast.internal_force(u)[1]
    kept = {k: v.copy() for k, v in vars(s1).items()}
    view = fast.internal_force(0.5 * u, s1)[1].eqps[1:]  # the state dropped, a view kept
    view_before = view.copy()
    s = s1
    for k in range(6):
        s = fast.internal_force((1.0 + 0.01 * k) * u, s)[1]
    for k, v in vars(s1).items():
        assert np.array_equal(v, kept[k]), k
    assert np.array_equal(view, view_before)
    # and once nothing references them, the arrays are reused rather than allocated
    del s, view
    pooled = {id(a) for arrays in fast._state_pool._sets for a in arrays}
    s2 = fast.internal_force(u, s1)[1]
    assert id(s2.cp_inv) in pooled


def test_backend_choice():
    m = mesh()
    user = J2Material.with_law(
        117e9, 0.35, 8930.0, CallableHardening(lambda e, r: 4e8 + 1e8 * e, lambda e, r: 1e8 + 0 * e)
    )
    assert FiniteStrainJ2(m, COPPER).backend == "numba"  # planar + built-in law
    assert FiniteStrainJ2(m, user).backend == "numpy"  # user callable: numpy only
    with pytest.raises(ValueError, match="backend='numba' needs"):
        FiniteStrainJ2(m, user, backend="numba")
    with pytest.raises(ValueError, match="backend must be one of"):
        FiniteStrainJ2(m, COPPER, backend="cuda")
    hexes = skfem.MeshHex.init_tensor(*[np.linspace(0, 1e-3, 2)] * 3)
    assert FiniteStrainJ2(hexes, COPPER).backend == "numba"  # the hexahedral kernel


def test_callable_law_matches_the_built_in_one():
    # the same linear law as a user callable (numpy path, Newton) and built in (the kernel)
    m = mesh()
    user = J2Material.with_law(
        117e9, 0.35, 8930.0,
        CallableHardening(lambda e, r: 0.4e9 + 0.1e9 * e, lambda e, r: 0.1e9 + 0.0 * e),
    )  # fmt: skip
    a = FiniteStrainJ2(m, user, "axisymmetric")
    b = FiniteStrainJ2(m, COPPER, "axisymmetric")
    u = random_u(a, 0.05, seed=9, compress=0.2)
    assert_same(a.internal_force(u), b.internal_force(u), "callable vs built-in")


def test_return_map_failure_is_a_state_error():
    # a user law that returns NaN once the point flows: reported, never propagated
    bad = J2Material.with_law(
        117e9, 0.35, 8930.0,
        CallableHardening(lambda e, r: np.where(e > 0, np.nan, 0.4e9), lambda e, r: 0.0 * e),
    )  # fmt: skip
    model = FiniteStrainJ2(mesh(), bad, "plane_strain")
    u = random_u(model, 0.05, seed=10, compress=0.2)
    with pytest.raises(StateError, match="plastic multiplier not converged"):
        model.internal_force(u)


@pytest.mark.parametrize(
    "geometry, model, n",
    [("axisymmetric", "mono", 5), ("axisymmetric", "arlequin", 10), ("3d", "arlequin", 8)],
)
def test_warm_up_compiles_every_signature_the_taylor_bar_uses(geometry, model, n):
    # the demos' wall clocks start after warm_up: a signature compiled (or loaded) inside the
    # clock cost the 3D Arlequin bar 21 s of its 237 s with a cold cache (FiniteStrainJ2 passes
    # the weight as a read-only view, which the warm-up once passed writeable: another type)
    from arlequin.demos.taylor_bar import run_taylor_bar
    from arlequin.models.plasticity.j2_kernel import planar_j2_kernel, warm_up
    from arlequin.models.plasticity.j2_kernel_3d import solid_j2_kernel, warm_up_solid

    warm_up_solid() if geometry == "3d" else warm_up()
    kernel = solid_j2_kernel if geometry == "3d" else planar_j2_kernel
    before = list(kernel.signatures)
    run_taylor_bar(model=model, elements_radial=n, geometry=geometry, t_end=3e-8)
    assert kernel.signatures == before


@pytest.mark.parametrize("dim, nen", [(2, 4), (3, 8)])
def test_cell_force_assembly_is_bincount_bit_for_bit(dim, nen):
    # the kernels' nodal assembly replaced np.bincount over the (component, node, cell)
    # arrays: the same additions in the same order, so the same floats (not merely close)
    from arlequin.models.plasticity.j2_kernel import assemble_cell_forces, assembly_dofs

    rng = np.random.default_rng(3)
    ne, n_nodes = 57, 40
    nodes = rng.integers(0, n_nodes, size=(ne, nen))  # shared nodes, in any order
    cell_dofs = np.stack([dim * nodes + i for i in range(dim)], axis=-1)  # (ne, nen, dim)
    fe = rng.standard_normal((dim, nen, ne)) * 10.0 ** rng.integers(-8, 8, size=(dim, nen, ne))
    flags = np.zeros(ne, dtype=np.int64)
    f = np.full(dim * n_nodes + 3, np.nan)  # overwritten, trailing dofs of no cell included
    assert assemble_cell_forces(assembly_dofs(cell_dofs), fe, flags, f) == 0
    by_component = np.transpose(cell_dofs, (2, 1, 0))  # the model's (dim, nen, ne) layout
    expected = np.bincount(by_component.ravel(), weights=fe.ravel(), minlength=f.size)
    assert np.array_equal(f, expected)
    flags[[4, 30]] = (1, 2)
    assert assemble_cell_forces(assembly_dofs(cell_dofs), fe, flags, f) == 2


def test_compiled_critical_step_is_the_numpy_estimate_bit_for_bit():
    # the numba backend's critical step computes the cell sizes in one compiled pass: the same
    # operations as Q1Kinematics.cell_sizes (the numpy backend's), so the same float, on a
    # distorted mesh and on the reference one
    mesh = skfem.MeshQuad.init_tensor(np.linspace(0, 3.2e-3, 7), np.linspace(0, 10e-3, 19))
    compiled = FiniteStrainJ2(mesh, COPPER, backend="numba")
    reference = FiniteStrainJ2(mesh, COPPER, backend="numpy")
    rng = np.random.default_rng(5)
    for scale in (0.0, 2e-5, 1e-4):
        u = rng.standard_normal(compiled.n_dofs) * scale
        assert compiled.critical_time_step(u) == reference.critical_time_step(u)
    crushed = np.zeros(compiled.n_dofs)
    crushed[compiled.nodal_dofs()[1]] = -0.5 * mesh.p[1]  # half as tall: a smaller step
    assert compiled.critical_time_step(crushed) == reference.critical_time_step(crushed)
    assert compiled.critical_time_step(crushed) < compiled.critical_time_step(0.0 * crushed)
    # a cell collapsed to a point (0/0): NaN from both, not a skipped cell
    collapsed = np.zeros(compiled.n_dofs)
    nodes = mesh.t[:, 0]
    dofs = compiled.nodal_dofs()
    for k in range(4):
        collapsed[dofs[:, nodes[k]]] = mesh.p[:, nodes[0]] - mesh.p[:, nodes[k]]
    with np.errstate(invalid="ignore"):
        assert np.isnan(reference.critical_time_step(collapsed))
    assert np.isnan(compiled.critical_time_step(collapsed))


@pytest.mark.parametrize("kind", ["axisymmetric", "plane_strain"])
def test_planar_states_keep_zero_out_of_plane_shear_through_pool_reuse(kind):
    # the planar kernel leaves C_p⁻¹'s and τ's out-of-plane shear unwritten: the model's pool
    # hands out fresh arrays of zeros or arrays only this kernel wrote. Ten evaluations (the
    # states dropped, so their arrays are written over), each against the numpy path: every
    # component as there (zeros included), the shear exactly zero
    numpy_model, numba_model = pair(kind, "linear")
    state_np = state_nb = numba_model.initial_state()
    for k in range(10):
        u = random_u(numba_model, 0.05, seed=40 + k, compress=0.02 * k)
        ref = numpy_model.internal_force(u, state_np)
        out = numba_model.internal_force(u, state_nb)
        assert_same(ref, out, f"{kind} evaluation {k}")
        for field in (out[1].cp_inv, out[1].kirchhoff):
            for i, j in ((0, 2), (2, 0), (1, 2), (2, 1)):
                assert not np.any(field[i, j])
        if k % 3 == 2:  # commit now and then: a state held while others are recycled
            state_np, state_nb = ref[1], out[1]


def test_thread_scratch_slots_start_on_their_own_cache_lines():
    # numpy's arrays are 16-byte aligned: per-thread scratch slots of 192 bytes then shared
    # their boundary cache lines, and the threads' writes to them (several per cell) made the
    # planar kernel up to 1.6 times slower on two threads (false sharing, measured in one
    # process). Each slot must start on a 128-byte boundary (two lines: the adjacent-line
    # prefetcher) and the kernels' scratch shapes keep at least the rows they index.
    from arlequin.models.plasticity.j2_kernel import scratch, thread_slots
    from arlequin.models.plasticity.j2_kernel_3d import solid_scratch
    from arlequin.models.plasticity.j2_tangent_kernel import tangent_scratch

    for shape in [(4, 6), (8, 19), (9, 8, 3), (4, 3, 3), (3, 3, 3, 3), (33, 32)]:
        slots = thread_slots(shape)
        assert slots.flags.c_contiguous and slots.dtype == np.float64
        assert slots.shape[0] >= 1 and slots.shape[1] >= shape[0]
        assert slots.shape[2:] == shape[1:]
        for t in range(slots.shape[0]):
            assert slots[t].ctypes.data % 128 == 0
    for arrays, shapes in [
        (scratch(4, 4), [(4, 10), (4, 4, 3), (4, 4)]),
        (solid_scratch(8, 8), [(8, 19), (9, 8, 3), (4, 3, 3)]),
        (tangent_scratch(4, 4, 2), [(4, 19), (4, 4, 4), (4, 3, 3), (3, 3, 3, 3), (3, 3, 4, 2),
                                    (9, 8)]),
    ]:  # fmt: skip
        for a, s in zip(arrays, shapes, strict=True):
            assert a.shape[1] >= s[0] and a.shape[2:] == s[1:]
            assert all(a[t].ctypes.data % 128 == 0 for t in range(a.shape[0]))
