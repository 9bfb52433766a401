"""The explicit step's optional timers and the per-step shortcuts of issue 30.

The shortcuts must give the same numbers bit for bit as the code they replace (their
references are computed here on the same data); the timers must only count.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from arlequin.contract import ConstraintError
from arlequin.linalg.impulses import ImpulseSolver
from arlequin.linalg.timing import SWITCH, StepTimer
from arlequin.linalg.vector_updates import (
    interpolated,
    scaled_plus,
    subtract_scaled_at,
    sum_of_squares,
    work_products,
)
from arlequin.solvers.system.rows import (
    rows_times,
    subtract_transposed,
    transposed,
    transposed_times,
)


def _random_rows(rng, m: int, n: int, duplicates: bool) -> sp.csr_matrix:
    nnz = int(rng.integers(1, 4 * m + 2))
    rows, cols = rng.integers(0, m, nnz), rng.integers(0, n, nnz)
    data = rng.standard_normal(nnz) * 10.0 ** rng.integers(-6, 7, nnz)
    if not duplicates:
        return sp.csr_matrix((data, (rows, cols)), shape=(m, n))
    # a CSR with duplicate, unsorted entries (rows grouped, columns as drawn)
    order = np.argsort(rows, kind="stable")
    indptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=m))])
    return sp.csr_matrix((data[order], cols[order], indptr), shape=(m, n))


@pytest.mark.parametrize("duplicates", [False, True])
def test_row_products_are_the_scipy_ones_bit_for_bit(duplicates):
    # references: the CSR product with the cached transpose (transposed_times replaced it),
    # scipy's CSR product (rows_times) and the bincount path that subtract_transposed replaces
    # in the explicit step (v -= M⁻¹ Gᵀλ)
    rng = np.random.default_rng(31)
    for _ in range(100):
        m, n = int(rng.integers(1, 30)), int(rng.integers(1, 200))
        g = _random_rows(rng, m, n, duplicates)
        lam = rng.standard_normal(m) * 1e4
        assert np.array_equal(transposed_times(g, lam), transposed(g) @ lam)
        x = rng.standard_normal(n)
        assert np.array_equal(rows_times(g, x), g @ x)
        minv = rng.uniform(0.5, 2.0, n) * 10.0 ** rng.integers(-3, 4, n)
        v = rng.standard_normal(n)
        v[: n // 3] = 0.0
        expected = v.copy()
        push = transposed_times(g, lam)
        push *= minv
        expected -= push
        scratch = np.zeros(n)
        subtract_transposed(g, lam, minv, v, scratch)
        assert np.array_equal(v, expected)
        assert not scratch.any()  # left zeros for the next call


def test_dense_active_rows_factor_refuses_dependent_rows():
    # two copies of one contact row (no equality rows): S_AA is singular to round-off; the
    # dense Cholesky must report it as the sparse factorisation did, not return huge impulses
    class _NoRows:
        m = 0

    solver = ImpulseSolver(_NoRows(), np.full(6, 2.0))
    row = np.array([0.0, 1.0, 0.0, 0.3, 0.0, 0.0])
    g = sp.csr_matrix(np.vstack([row, row]))
    with pytest.raises(ConstraintError, match="dependent"):
        solver.solve(np.zeros(0), g, np.ones(2))
    # dependent to 1e-8 of the entries: a positive pivot of ~1e-16 of its row's diagonal
    g = sp.csr_matrix(np.vstack([row, row + np.array([0.0, 0.0, 0.0, 0.0, 0.0, 1e-8])]))
    with pytest.raises(ConstraintError, match="dependent"):
        solver.solve(np.zeros(0), g, np.ones(2))
    # an active row without entries (on a wall: the diagonal path)
    g = sp.csr_matrix(np.vstack([row, np.zeros(6)]))
    with pytest.raises(ConstraintError, match="empty row 1"):
        solver.solve(np.zeros(0), g, np.ones(2))
    # rows on distinct dofs: diagonal, x = (1 / d) r as the sparse factorisation's diagonal path
    g = sp.csr_matrix(np.array([[0.0, 2.0, 0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, -3.0, 0.0, 0.0]]))
    _, lam = solver.solve(np.zeros(0), g, np.array([1.0, -2.0]))
    assert np.array_equal(lam, (1.0 / np.array([8.0, 18.0])) * np.array([1.0, -2.0]))
    # independent rows: the impulses solve G M⁻¹ Gᵀ Λ = r
    g = sp.csr_matrix(np.vstack([row, [1.0, 0.0, 0.0, 0.0, 0.0, 2.0]]))
    _, lam = solver.solve(np.zeros(0), g, np.array([1.0, -2.0]))
    s = (g @ sp.diags(np.full(6, 2.0)) @ g.T).toarray()
    np.testing.assert_allclose(s @ lam, [1.0, -2.0], rtol=1e-14)


def test_compiled_vector_updates_are_the_numpy_lines_bit_for_bit():
    # references: the numpy lines each compiled pass replaced in the explicit step
    rng = np.random.default_rng(32)
    for n in (0, 1, 7, 1000):
        x, y, z, w = (rng.standard_normal(n) * 10.0 ** rng.integers(-9, 9, n) for _ in range(4))
        alpha, share = 3.7e-8, 0.4999
        ref = alpha * x
        ref += y
        assert scaled_plus(alpha, x, y).tobytes() == ref.tobytes()
        ref = y - x
        ref *= share
        ref += x
        assert interpolated(x, y, share).tobytes() == ref.tobytes()
        f = z + w
        f *= 0.5
        ref = (x - y) * f
        assert work_products(x, y, z, w, np.empty(n)).tobytes() == ref.tobytes()
        if n:
            cols = rng.choice(n, n // 2 + 1, replace=False)
            got, ref = z.copy(), z.copy()
            ref[cols] -= x[: cols.size] * y[: cols.size]
            subtract_scaled_at(got, cols, x[: cols.size].copy(), y[: cols.size].copy())
            assert got.tobytes() == ref.tobytes()
    # other layouts take the numpy lines themselves
    x = np.arange(10.0)[::2]
    np.testing.assert_array_equal(scaled_plus(2.0, x, x), 3.0 * x)


def test_sum_of_squares_of_the_finite_check():
    # reference: the BLAS dot it replaced (another summation order: equal to round-off), and
    # every non-finite case the check must see (NaN, ±inf, an overflow of the sum)
    rng = np.random.default_rng(33)
    x = rng.standard_normal(26_814)
    assert sum_of_squares(x) == pytest.approx(float(x @ x), rel=1e-13)
    for bad in (np.nan, np.inf, -np.inf):
        y = x.copy()
        y[12_345] = bad
        assert not np.isfinite(sum_of_squares(y))
    assert sum_of_squares(np.full(9, 1e200)) == np.inf  # each square 1e400: overflow
    assert sum_of_squares(np.zeros(0)) == 0.0
    # u and v of the check in one call: the sum of the two (each in its own order)
    z = rng.standard_normal(1_000)
    assert sum_of_squares(x, z) == sum_of_squares(x) + sum_of_squares(z)
    y = z.copy()
    y[3] = np.nan
    assert not np.isfinite(sum_of_squares(x, y))
    assert sum_of_squares(x, z, z) == pytest.approx(float(x @ x + 2 * z @ z), rel=1e-13)


def test_dense_active_rows_beside_unshared_equality_rows():
    # equality rows on dofs 0-1 and active rows on dofs 3-5 (a wall away from a symmetry
    # axis): the active block is solved alone, densely, and the equality rows by their factor
    class _Rows:
        m = 1
        cols = np.array([0, 1])
        matrix_cols = sp.csr_matrix(np.array([[1.0, -1.0]]))
        matrix = sp.csr_matrix(np.array([[1.0, -1.0, 0.0, 0.0, 0.0, 0.0]]))

        @staticmethod
        def row_name(i):
            return f"row {i}"

    minv = np.full(6, 2.0)
    solver = ImpulseSolver(_Rows(), minv)
    g = sp.csr_matrix(np.array([[0.0, 0.0, 0.0, 1.0, 0.5, 0.0], [0.0, 0.0, 0.0, 0.0, 1.0, 1.0]]))
    lam_e, lam_a = solver.solve(np.array([3.0]), g, np.array([1.0, -2.0]))
    np.testing.assert_allclose(lam_e, [3.0 / 4.0], rtol=1e-15)  # B M⁻¹ Bᵀ = 4
    s_aa = (g @ sp.diags(minv) @ g.T).toarray()
    np.testing.assert_allclose(s_aa @ lam_a, [1.0, -2.0], rtol=1e-14)
    # a non-finite right-hand side gives non-finite impulses (the step's finite-state check
    # then fails it), not an error from the LAPACK wrapper
    _, bad = solver.solve(np.array([3.0]), g, np.array([np.nan, 1.0]))
    assert not np.isfinite(bad).any()


def test_block_sums_are_the_segmented_sums_of_block_dots():
    # reference: SystemOperators.block_dots, whose per-block sums of x ⊙ y block_sums makes on
    # the products formed beforehand (the explicit step's internal work)
    from arlequin.solvers.system.operators import SystemOperators

    ops = SystemOperators.__new__(SystemOperators)
    ops.n, ops.blocks, ops.offsets = 7, ["a", "b"], np.array([0, 3, 7])
    rng = np.random.default_rng(34)
    x, y = rng.standard_normal((2, 7))
    assert ops.block_sums(x * y).tobytes() == ops.block_dots(x, y).tobytes()


def test_timer_is_off_by_default_and_restored_after_its_context():
    assert SWITCH.timer is None
    with StepTimer() as outer:
        assert SWITCH.timer is outer
        with StepTimer() as inner:
            assert SWITCH.timer is inner
        assert SWITCH.timer is outer
    assert SWITCH.timer is None


@pytest.mark.parametrize("clock", ["wall", "thread"])
def test_timer_splits_the_steps_of_an_explicit_run(clock):
    from arlequin.demos.two_bars import run_two_bars

    plain = run_two_bars(integrator="explicit")
    with StepTimer(clock=clock) as timer:
        timed = run_two_bars(integrator="explicit")
    rep = timer.report()
    # the first step apart; the others all counted (the run's steps from its recorded times)
    assert rep["steps"] == len(timed.t) - 2
    assert rep["first_step_seconds"] >= 0.0
    assert rep["linear_algebra_seconds"] > 0.0
    assert rep["kernel_seconds"] == 0.0  # linear models: no model's internal force call
    assert rep["other_seconds"] == pytest.approx(
        rep["step_seconds"] - rep["linear_algebra_seconds"]
    )
    assert 0.0 <= rep["overhead_share"] <= 1.0
    # the energy bookkeeping's products (the coupling's powers here) are a part of the
    # linear algebra
    assert 0.0 < rep["energy_products_seconds"] <= rep["linear_algebra_seconds"]
    # so are the step's compiled vector updates (the kick, the predictor, the check's Σx²)
    assert 0.0 < rep["vector_updates_seconds"]
    assert (rep["energy_products_seconds"] + rep["vector_updates_seconds"]
            <= rep["linear_algebra_seconds"] * (1 + 1e-12))  # fmt: skip
    # the timers change nothing in the run
    assert np.array_equal(plain.contact_pressure, timed.contact_pressure)
    assert np.array_equal(plain.total_energy, timed.total_energy)


def test_block_dots_with_its_buffer_equal_the_plain_products():
    from arlequin.demos.two_bars import TwoBarsConfig
    from arlequin.demos.two_bars.setup import TwoBarsSetup
    from arlequin.problem.system import Block, BlockTerm, CoupledSystem
    from arlequin.solvers.system.operators import SystemOperators

    bodies = TwoBarsSetup(TwoBarsConfig()).impact("levelset").bodies
    system = CoupledSystem([Block(f"bar{i}", b, [BlockTerm(b)]) for i, b in enumerate(bodies)])
    ops = SystemOperators(system, lumped=True)
    rng = np.random.default_rng(1)
    for _ in range(3):
        x, y = rng.standard_normal(ops.n), rng.standard_normal(ops.n)
        # reference: the products summed per block by reduceat, as before the buffer
        assert np.array_equal(ops.block_dots(x, y), np.add.reduceat(x * y, ops.offsets[:-1]))


def test_timer_refuses_an_unknown_clock():
    with pytest.raises(ValueError, match="clock"):
        StepTimer(clock="cpu")
