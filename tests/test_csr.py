"""The compiled CSR product (arlequin/linalg/csr.py) against scipy's ``A @ x``.

The explicit loop's linear forces go through it (and its power sums through block_sums.py),
and the issue-30 rule is that the histories do not change: so the products must be scipy's
floats bit for bit (the same additions in the same order), not merely close, on the serial and
on the threaded path.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import skfem
from skfem.models.elasticity import lame_parameters, linear_elasticity

from arlequin.linalg import csr
from arlequin.linalg.csr import CsrProduct


def random_csr(seed: int) -> sp.csr_matrix:
    """Random CSR with empty rows, unsorted column indices and duplicate entries."""
    rng = np.random.default_rng(seed)
    n_rows, n_cols, nnz = 300, 250, 4000
    rows = np.sort(rng.integers(0, n_rows, nnz))
    rows[rows % 7 == 3] = 0  # some empty rows
    cols = rng.integers(0, n_cols, nnz)
    values = rng.standard_normal(nnz) * 10.0 ** rng.integers(-6, 6, nnz)
    indptr = np.searchsorted(rows, np.arange(n_rows + 1))
    a = sp.csr_matrix((values, cols, indptr), shape=(n_rows, n_cols))
    assert not a.has_sorted_indices  # stored order kept: duplicates and unsorted columns
    return a


@pytest.mark.parametrize("threaded", [False, True])
def test_product_is_scipys_bit_for_bit(threaded, monkeypatch):
    if threaded:
        monkeypatch.setattr(csr, "PARALLEL_MIN_NNZ", 0)
    rng = np.random.default_rng(7)
    for seed in range(3):
        a = random_csr(seed)
        x = rng.standard_normal(a.shape[1])
        assert np.array_equal(CsrProduct(a)(x), a @ x)
    # an assembled stiffness (skfem, int32 indices, sorted), as the explicit loop multiplies
    m = skfem.MeshQuad.init_tensor(*[np.linspace(0.0, 1.0, 21)] * 2)
    basis = skfem.Basis(m, skfem.ElementVector(skfem.ElementQuad1()))
    k = skfem.asm(linear_elasticity(*lame_parameters(1e9, 0.3)), basis).tocsr()
    x = rng.standard_normal(k.shape[1])
    assert np.array_equal(CsrProduct(k)(x), k @ x)


def test_product_of_gathered_vectors_is_the_product_of_their_gather():
    # the explicit impulse's B (v + u/Δt) on the rows' dofs: the sum formed inside the product,
    # the floats of the gathers, the division, the sum and the product made apart
    rng = np.random.default_rng(8)
    a = random_csr(4)
    n = 1000
    cols = np.sort(rng.choice(n, a.shape[1], replace=False))
    x, z = rng.standard_normal(n), rng.standard_normal(n) * 1e-3
    dt = 3.7e-9
    product = CsrProduct(a)
    expected = a @ (x[cols] + z[cols] / dt)
    assert np.array_equal(product.times_gathered(cols.astype(np.uint32), x, z, dt), expected)
    with pytest.raises(ValueError, match="cols must be uint32"):
        product.times_gathered(cols, x, z, dt)
    # the compiled loop reads x and z unchecked: vectors too short are refused first
    with pytest.raises(ValueError, match="x and z must be vectors"):
        product.times_gathered(cols.astype(np.uint32), x[: cols.max()], z[: cols.max()], dt)


def test_product_keeps_its_own_copy_and_checks_the_vector():
    a = random_csr(3)
    product = CsrProduct(a)
    x = np.ones(a.shape[1])
    expected = a @ x
    a.data[:] = 0.0  # a later change of the matrix is not seen (documented)
    assert np.array_equal(product(x), expected)
    with pytest.raises(ValueError, match=r"x must have shape \(250,\)"):
        product(np.ones(a.shape[1] + 1))


def test_signed_block_sums_are_the_bincount_sums():
    # the explicit loop's per-block powers −Σ_{j∈b} f_j x_j over the touched dofs, compiled:
    # the same additions in the same order as a weighted bincount, so the same floats
    from arlequin.linalg.block_sums import signed_block_sums, touched_index

    rng = np.random.default_rng(11)
    n, n_blocks = 500, 4
    block_of_dof = np.repeat(np.arange(n_blocks), n // n_blocks)
    dofs = np.sort(rng.choice(n, 120, replace=False))
    f = rng.standard_normal(dofs.size)
    x = rng.standard_normal(n)
    idx, block = touched_index(dofs, block_of_dof[dofs])
    out = np.zeros(n_blocks)
    signed_block_sums(f, x, idx, block, out)
    expected = -np.bincount(block_of_dof[dofs], f * x[dofs], minlength=n_blocks)
    assert np.array_equal(out, expected)
    # dofs in any order (blocks interleaved) and a non-zero start: the kernel's register sums
    # make the subtractions of the plain loop ``out[block[k]] -= f_k x_idx[k]``, in its order
    shuffled = rng.permutation(dofs.size)
    idx, block = touched_index(dofs[shuffled], block_of_dof[dofs[shuffled]])
    start = rng.standard_normal(n_blocks)
    out = start.copy()
    signed_block_sums(f[shuffled], x, idx, block, out)
    expected = start.copy()
    for k in range(idx.size):
        expected[block[k]] -= f[shuffled][k] * x[idx[k]]
    assert np.array_equal(out, expected)


@pytest.mark.parametrize("kinds", ["both", "coupling only", "others only"])
def test_kind_block_powers_are_the_per_kind_products_and_sums(kinds):
    # the equality rows' powers of both kinds for two vectors in one compiled pass: the bits of
    # the code it replaced (each kind's Bᵀλ by CsrProduct, then signed_block_sums per vector)
    from arlequin.linalg.block_sums import kind_block_powers, signed_block_sums, touched_index
    from arlequin.linalg.csr import CsrProduct

    rng = np.random.default_rng(12)
    m, n, n_blocks = 60, 400, 3
    b = sp.random(m, n, density=0.03, random_state=rng, format="csr")
    cols = np.unique(b.indices)
    b_cols = b[:, cols].tocsr()
    coupling = {"both": rng.random(m) < 0.6, "coupling only": np.ones(m, bool),
                "others only": np.zeros(m, bool)}[kinds]  # fmt: skip
    block_of_dof = np.repeat(np.arange(n_blocks), -(-n // n_blocks))[:n]
    lam, x1, x2 = rng.standard_normal(m), rng.standard_normal(n), rng.standard_normal(n)
    idx, block = touched_index(cols, block_of_dof[cols])
    expected = np.zeros((2, 2, n_blocks))
    for kind, rows in enumerate((np.nonzero(coupling)[0], np.nonzero(~coupling)[0])):
        if rows.size:
            force = CsrProduct(b_cols[rows].T.tocsr())(lam[rows])
            for i, x in enumerate((x1, x2)):
                signed_block_sums(force, x, idx, block, expected[i, kind])
    bt = b_cols.T.tocsr()
    other = (~coupling).astype(np.uint8)
    has = np.array([coupling.any(), (~coupling).any()], dtype=np.uint8)
    out = np.zeros((2, 2, n_blocks))
    kind_block_powers(bt.indptr.astype(np.int64), bt.indices.astype(np.uint32), bt.data, other,
                      lam, x1, x2, 2, has, idx, block, out)  # fmt: skip
    assert np.array_equal(out, expected)
    one = np.zeros((1, 2, n_blocks))  # one vector: x2 not read
    kind_block_powers(bt.indptr.astype(np.int64), bt.indices.astype(np.uint32), bt.data, other,
                      lam, x1, x1, 1, has, idx, block, one)  # fmt: skip
    assert np.array_equal(one[0], expected[0])


def test_scattered_block_powers_are_the_bincount_force_and_sums():
    # a few active rows' powers for two vectors in one compiled pass: the bits of
    # np.bincount for the force Gᵀλ on the touched dofs, then signed_block_sums per vector
    from arlequin.linalg.block_sums import scattered_block_powers, signed_block_sums, touched_index

    rng = np.random.default_rng(13)
    m, n, n_blocks = 9, 300, 4
    g = sp.random(m, n, density=0.02, random_state=rng, format="csr")
    lam, x1, x2 = rng.standard_normal(m), rng.standard_normal(n), rng.standard_normal(n)
    cols, inv = np.unique(g.indices, return_inverse=True)
    row_of = np.repeat(np.arange(m), np.diff(g.indptr))
    block_of_dof = np.repeat(np.arange(n_blocks), n // n_blocks)
    idx, block = touched_index(cols, block_of_dof[cols])
    force = np.bincount(inv, g.data * lam[row_of], minlength=cols.size)
    expected = np.zeros((2, n_blocks))
    for i, x in enumerate((x1, x2)):
        signed_block_sums(force, x, idx, block, expected[i])
    out = np.zeros((2, n_blocks))
    scattered_block_powers(g.data, lam, row_of, inv, cols.size, x1, x2, 2, idx, block, out)
    assert np.array_equal(out, expected)


def test_csr_times_subtract_scaled_is_the_product_then_the_update():
    # the equality rows' impulse v[cols] −= M⁻¹ Bᵀλ in one compiled pass: the bits of the
    # product's vector (CsrProduct, scipy's floats) and then the indexed update
    from arlequin.linalg.csr import csr_times_subtract_scaled

    rng = np.random.default_rng(14)
    n, m = 300, 40
    bt = sp.random(120, m, density=0.08, random_state=rng, format="csr")
    cols = np.sort(rng.choice(n, 120, replace=False))
    scale, lam, v = rng.uniform(0.5, 2.0, 120), rng.standard_normal(m), rng.standard_normal(n)
    expected = v.copy()
    expected[cols] -= scale * (bt @ lam)
    product = CsrProduct(bt)
    got = v.copy()
    csr_times_subtract_scaled(product._indptr, product._indices, product._data, lam, cols,
                              scale, got)  # fmt: skip
    assert got.tobytes() == expected.tobytes()
