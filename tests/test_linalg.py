"""The integrators' sparse factorisation (arlequin/integrators/linalg.py) against dense solves."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from arlequin.contract import ConstraintError
from arlequin.integrators.linalg import ScaledLU


def _spd_with_isolated_rows(n: int, isolated: np.ndarray, seed: int = 0) -> sp.csr_matrix:
    rng = np.random.default_rng(seed)
    a = rng.standard_normal((n, n))
    a = a @ a.T + n * np.eye(n)
    a[isolated, :] = 0.0
    a[:, isolated] = 0.0
    a[isolated, isolated] = rng.uniform(1.0, 1e6, isolated.size)  # rows of mixed units
    return sp.csr_matrix(a)


@pytest.mark.parametrize("isolated", [[0, 3, 7], [5], list(range(12))])
def test_scaled_lu_solves_rows_of_mixed_units(isolated):
    idx = np.asarray(isolated)
    mat = _spd_with_isolated_rows(12, idx)
    lu = ScaledLU(mat, "test matrix", spd=True)
    rhs = np.random.default_rng(1).standard_normal((12, 3))
    # exact up to round-off: the dense solve of the same matrix
    assert np.allclose(lu.solve(rhs), np.linalg.solve(mat.toarray(), rhs), rtol=1e-12, atol=0)
    assert np.allclose(lu.solve(rhs[:, 0]), np.linalg.solve(mat.toarray(), rhs[:, 0]),
                       rtol=1e-12, atol=0)  # fmt: skip


def test_dependent_rows_are_refused():
    mat = _spd_with_isolated_rows(6, np.array([0])).tolil()
    mat[5, :] = mat[4, :]
    mat[:, 5] = mat[:, 4]  # rows 4 and 5 equal: singular
    with pytest.raises(ConstraintError, match="linearly dependent"):
        ScaledLU(mat.tocsr(), "test matrix", names=lambda i: f"row {i}", spd=True)
