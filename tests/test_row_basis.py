"""The explicit scheme's impulse basis (arlequin/solvers/dynamics/row_basis.py).

Exact references: rows B and T⁻¹B are the same constraint, so the M-orthogonal projection of any
velocity onto them is the same (to round-off), and the multipliers of B are Tᵀ times those of
T⁻¹B; a nested fine mediator's T⁻¹R_O is the interpolation of the coarse field at the band's
fine nodes (sparse), a non-nested one's is an L2 projection (dense: the rows stay as they are).
An explicit run with the rows rewritten is the run with the rows as assembled, to round-off.
"""

from __future__ import annotations

import copy
import math
import pickle
from dataclasses import replace

import numpy as np
import pytest
import scipy.sparse as sp

from arlequin.demos.ball_impact import STEEL
from arlequin.demos.ball_impact.setup import ImpactBodies, ball_sizes
from arlequin.demos.patch_test import build_patch_test_problem
from arlequin.problem.system import CoupledSystem, LinearConstraint
from arlequin.solvers import solve
from arlequin.solvers.dynamics.row_basis import ImpulseBasis, Multipliers
from arlequin.solvers.system.operators import SystemOperators

R = 0.01


def _without_pivots(system: CoupledSystem) -> CoupledSystem:
    cons = [replace(c, pivot_dofs=None) for c in system.constraints]
    return CoupledSystem(system.blocks, cons, system.load)


def _project(rows, minv, v):
    """v − M⁻¹BᵀΛ with B M⁻¹Bᵀ Λ = B v (dense: the reference), and Λ."""
    b = rows.matrix.toarray()
    lam = np.linalg.solve(b @ (minv[:, None] * b.T), b @ v)
    return v - minv * (b.T @ lam), lam


@pytest.fixture(scope="module")
def ball():
    # the ball on its block, coarse π R/40 and one level: two fine-mediator bands, the axis
    # rows of both bodies (single-dof rows through the bands), the block's base
    sizes = ball_sizes(R, 0.25 * math.pi * R / 10, 0.25 * math.pi * R / 20, 0.4 * R)
    return ImpactBodies("arlequin", sizes, R, 0.04, 0.04, STEEL, STEEL)


def test_nested_fine_mediator_rows_in_their_pivot_basis(ball):
    system = ball.system
    ops = SystemOperators(system, lumped=True)
    basis = ImpulseBasis(system.constraints, ops)
    assert basis.reduced == ["ball.coupling:patch", "block.coupling:patch"]
    minv = ops.inv_mass
    for name in basis.reduced:
        sl = basis.rows.slices[name]
        red = basis.rows.matrix[sl].tocsr()
        # identity on the pivot dofs, a sparse interpolation elsewhere (at most the 4 nodes
        # of a coarse cell), which holds a rigid translation along the axis: the rows vanish
        piv = next(c.pivot_dofs for c in system.constraints if c.name == name)
        assert np.array_equal(red[:, piv].toarray(), np.eye(sl.stop - sl.start))
        assert red.nnz / red.shape[0] <= 1 + 4
        along_axis = np.zeros(ops.n)
        along_axis[1::2] = 1.0  # (u_r, u_z) per node in every block
        assert np.abs(red @ along_axis).max() <= 1e-12
    rng = np.random.default_rng(0)
    v = rng.standard_normal(ops.n)
    v_orig, lam_orig = _project(basis.original, minv, v)
    v_red, lam_red = _project(basis.rows, minv, v)
    # the same corrected velocity (the condition number of the assembled rows' B M⁻¹Bᵀ is
    # about 1e6 here: round-off of that order times 1e-16)
    assert np.abs(v_red - v_orig).max() <= 1e-10 * np.abs(v_orig).max()
    back = basis.to_original(lam_red)
    assert np.abs(back - lam_orig).max() <= 1e-9 * np.abs(lam_orig).max()
    # the lazy mapping gives the same, per constraint
    mult = basis.multipliers(lam_red)
    assert isinstance(mult, Multipliers)
    for name, sl in basis.original.slices.items():
        np.testing.assert_allclose(mult[name], lam_orig[sl], rtol=0,
                                   atol=1e-9 * np.abs(lam_orig).max())  # fmt: skip
    # axis rows of the patches carried the coupling's share: their multipliers differ
    assert basis.affects("ball.dirichlet:patch:1") and not basis.affects("block.dirichlet:coarse:2")


def test_multipliers_mapping_copies_and_pickles_as_a_plain_dict(ball):
    system = ball.system
    ops = SystemOperators(system, lumped=True)
    basis = ImpulseBasis(system.constraints, ops)
    lam = np.random.default_rng(1).standard_normal(basis.rows.m)
    mult = basis.multipliers(lam)
    mult["contact"] = np.ones(3)
    plain = copy.copy(mult)
    assert type(plain) is dict and set(plain) == set(mult) and "contact" in plain
    again = pickle.loads(pickle.dumps(mult))
    assert type(again) is dict
    for k in plain:
        np.testing.assert_array_equal(again[k], plain[k])
    name = basis.reduced[0]
    np.testing.assert_array_equal(mult.in_scheme_basis(name), lam[basis.rows.slices[name]])
    with pytest.raises(KeyError):
        mult["nope"]


def test_many_samples_convert_in_one_solve_to_the_numbers_of_each(ball):
    # a per-step history keeps the scheme's stacked multipliers and converts k steps at once:
    # bit for bit each step's own conversion, for every constraint (the axis rows that the
    # single-dof elimination touches included)
    ops = SystemOperators(ball.system, lumped=True)
    basis = ImpulseBasis(ball.system.constraints, ops)
    lam = np.random.default_rng(4).standard_normal((7, basis.rows.m))
    batch = basis.to_original(lam)
    for k in range(lam.shape[0]):
        np.testing.assert_array_equal(batch[k], basis.to_original(lam[k]))
    mults = [basis.multipliers(x) for x in lam]
    stacked = np.vstack([m.stacked_in_scheme_basis() for m in mults])
    np.testing.assert_array_equal(stacked, lam)
    for name in basis.original.slices:
        assert mults[0].converted(name)
        got = mults[-1].to_original(name, stacked)
        for k, m in enumerate(mults):
            np.testing.assert_array_equal(got[k], m[name])
    mults[0]["contact"] = np.ones(3)
    assert not mults[0].converted("contact") and not mults[0].converted("nope")


def test_taylor_multiplier_history_converts_by_chunks_to_the_per_step_numbers(ball):
    # MultiplierHistory keeps the scheme's multipliers and converts them by chunks: the same
    # float32 rows as converting each step (its former way), across chunk boundaries and
    # through a checkpoint's state and restore
    from types import SimpleNamespace

    from arlequin.demos.taylor_bar.record import MultiplierHistory

    ops = SystemOperators(ball.system, lumped=True)
    basis = ImpulseBasis(ball.system.constraints, ops)
    name = "ball.dirichlet:patch:1"  # converted through the single-dof rows
    hist = MultiplierHistory(name)
    hist.chunk = 4
    lam = np.random.default_rng(5).standard_normal((11, basis.rows.m))
    expected = []
    for k, x in enumerate(lam):
        m = basis.multipliers(x)
        expected.append(np.asarray(m[name], dtype=np.float32))
        hist(SimpleNamespace(multipliers=m))
        if k == 5:  # a checkpoint mid-chunk, restored into a new history
            again = MultiplierHistory(name)
            again.chunk = 4
            again.restore(pickle.loads(pickle.dumps(hist.state())))
            hist = again
    got = hist.array()
    assert got.dtype == np.float32 and not got.flags.writeable
    np.testing.assert_array_equal(got, np.vstack(expected))
    # a plain dict of multipliers (no rewritten rows): kept as given
    plain = MultiplierHistory("c")
    for x in lam[:3]:
        plain(SimpleNamespace(multipliers={"c": x[:5]}))
    np.testing.assert_array_equal(plain.array(), lam[:3, :5].astype(np.float32))
    assert not plain.array().flags.writeable  # one block, handed out read-only too


@pytest.mark.parametrize("dim", ["2", "axi", "3"])
@pytest.mark.parametrize("coupling", ["L2", "H1"])
def test_patch_test_rows_nested_reduce_nonnested_stay(dim, coupling):
    for mesh in ("nested", "nonnested") if dim == "2" else ("nested",):
        problem, _ = build_patch_test_problem(dim, coupling, "ramp", "fine", mesh, seed=2)
        system = problem.system()
        ops = SystemOperators(system, lumped=True)
        basis = ImpulseBasis(system.constraints, ops)
        coupling_names = [c.name for c in system.constraints if c.kind == "coupling"]
        if mesh == "nested":
            assert basis.reduced == coupling_names
        else:
            # the coarse functions are not in the fine space: T⁻¹R_O is dense, rows kept
            assert basis.reduced == [] and basis.rows is basis.original
        v = np.random.default_rng(3).standard_normal(ops.n)
        v_orig, lam_orig = _project(basis.original, ops.inv_mass, v)
        v_red, lam_red = _project(basis.rows, ops.inv_mass, v)
        assert np.abs(v_red - v_orig).max() <= 1e-10 * np.abs(v_orig).max()
        assert np.abs(basis.to_original(lam_red) - lam_orig).max() <= \
            1e-8 * np.abs(lam_orig).max()  # fmt: skip


def test_coarse_mediator_has_no_pivots():
    problem, _ = build_patch_test_problem("2", "H1", "ramp", "coarse", "nested", seed=2)
    assert all(c.pivot_dofs is None for c in problem.system().constraints)


def test_explicit_run_is_the_run_with_the_rows_as_assembled(ball):
    # the ball on the block for 400 steps from the impact: with the rows in their pivot
    # basis and as assembled (pivots removed), the same motion, contact and works
    kw = dict(t_end=400 * 2.0e-8, v0=ball.initial_velocity(1.0), constraints=[ball.contact])
    runs = []
    for system in (ball.system, _without_pivots(ball.system)):
        runs.append(solve(system, "explicit", dt=2.0e-8, **kw))
    red, orig = runs
    assert red.u.shape == orig.u.shape and red.times[-1] == orig.times[-1]
    scale_u = np.abs(orig.u).max()
    assert np.abs(red.u - orig.u).max() <= 1e-9 * scale_u
    assert np.abs(red.v - orig.v).max() <= 1e-9 * np.abs(orig.v).max()
    for name, lam in orig.multipliers.items():
        scale = max(np.abs(lam).max(), 1e-300)
        assert np.abs(red.multipliers[name] - lam).max() <= 1e-7 * scale, name
    # the energies block by block: the coupling work stays at round-off of the kinetic
    # energy in both (the rows hold at every step), the others agree
    ke = max(np.abs(v).max() for v in orig.kinetic.values())
    for what in ("kinetic", "strain", "coupling_work", "constraint_work"):
        a, b = getattr(red, what), getattr(orig, what)
        for block in b:
            assert np.abs(a[block] - b[block]).max() <= 1e-9 * ke, (what, block)


def test_pivot_dofs_are_checked():
    rows = sp.csr_matrix(np.eye(3, 5))
    with pytest.raises(ValueError, match="pivot_dofs of constraint 'c' must be 3 integer"):
        LinearConstraint(rows, None, "c", pivot_dofs=np.array([0, 1]))
    with pytest.raises(ValueError, match=r"distinct dofs in \[0, 5\)"):
        LinearConstraint(rows, None, "c", pivot_dofs=np.array([0, 1, 1]))
    with pytest.raises(ValueError, match=r"distinct dofs in \[0, 5\)"):
        LinearConstraint(rows, None, "c", pivot_dofs=np.array([0, 1, 5]))
