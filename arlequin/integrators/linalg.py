"""Sparse factorisations of the integrators' constraint and saddle-point matrices.

The matrices mix rows of very different units (stiffness N/m, mass kg, constraint rows of m² for
L2 coupling): :class:`ScaledLU` scales them symmetrically before SuperLU and turns (numerical)
singularity into a :class:`~arlequin.contract.ConstraintError` that names the offending row.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..contract import ConstraintError

__all__ = ["ScaledLU", "factor_checked"]


class ScaledLU:
    """Sparse LU (SuperLU) of a symmetric matrix after symmetric diagonal scaling ``D A D``.

    ``D_ii = |A_ii|^{-1/2}``; rows with a zero diagonal (multiplier rows of a saddle point) get
    the inverse norm of their scaled row, so that stiffness, mass and constraint rows of very
    different units become commensurate. A pivot below ``1e-14`` of the largest one (after
    scaling) means linearly dependent rows: :class:`ConstraintError`.

    Parameters
    ----------
    mat : sparse, shape (N, N)
    what : str
        Name of the matrix for the error message.
    names : callable, optional
        Row index -> description, for the error message.
    spd : bool
        Symmetric positive definite: symmetric ordering, diagonal pivots.
    """

    def __init__(
        self,
        mat: sp.spmatrix,
        what: str,
        names: Callable[[int], str] | None = None,
        spd: bool = False,
    ) -> None:
        mat = sp.csr_matrix(mat)
        n = mat.shape[0]
        self.shape = mat.shape
        self._inv_diag: np.ndarray | None = None
        if _is_diagonal(mat):
            # independent rows (a wall, a symmetry axis): no factorisation, one division
            dg = mat.diagonal()
            scale = np.max(np.abs(dg)) if n else 0.0
            small = np.nonzero(~(np.abs(dg) > 1e-14 * scale))[0] if n else np.zeros(0, int)
            if small.size:
                i = int(small[0])
                where = f" ({names(i)})" if names is not None else ""
                raise ConstraintError(f"{what} has an empty row {i}{where}")
            self._inv_diag = 1.0 / dg
            return
        diag = np.abs(mat.diagonal())
        d = np.zeros(n)
        nz = diag > 0.0
        d[nz] = 1.0 / np.sqrt(diag[nz])
        if not np.all(nz):
            scaled_cols = sp.csr_matrix(mat[~nz] @ sp.diags(d))
            norms = np.sqrt(np.asarray(scaled_cols.multiply(scaled_cols).sum(axis=1)).ravel())
            bad = np.nonzero(norms == 0.0)[0]
            if bad.size:
                i = int(np.nonzero(~nz)[0][bad[0]])
                where = f" ({names(i)})" if names is not None else ""
                raise ConstraintError(f"{what} has an empty row {i}{where}")
            d[~nz] = 1.0 / norms
        self.d = d
        scaled = sp.csc_matrix(sp.diags(d) @ mat @ sp.diags(d))
        try:
            if spd:
                self.lu = spla.splu(scaled, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0)
            else:
                self.lu = spla.splu(scaled)
        except RuntimeError as exc:
            raise ConstraintError(
                f"{what} is singular ({exc}): the constraint rows are linearly dependent"
            ) from exc
        piv = np.abs(self.lu.U.diagonal())
        tiny = np.nonzero(~(piv > 1e-14 * piv.max()))[0] if piv.size else np.zeros(0, int)
        if tiny.size:
            where = ""
            if names is not None:
                where = f" (near {names(int(self.lu.perm_c[tiny[0]]) if spd else int(tiny[0]))})"
            raise ConstraintError(
                f"{what} is numerically singular: {tiny.size} pivot(s) below 1e-14 of the "
                f"largest after scaling{where}; the constraint rows are linearly dependent (e.g. "
                "a Dirichlet condition on dofs that the mediator rows already tie, or duplicate "
                "rows)"
            )

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solve A x = rhs; rhs of shape (N,) or (N, k)."""
        if self._inv_diag is not None:
            inv = self._inv_diag if rhs.ndim == 1 else self._inv_diag[:, None]
            return inv * rhs
        d = self.d if rhs.ndim == 1 else self.d[:, None]
        return d * self.lu.solve(np.ascontiguousarray(d * rhs))


def _is_diagonal(mat: sp.csr_matrix) -> bool:
    """True if the CSR matrix has no stored entry off its diagonal (zeros pruned)."""
    mat = mat.copy()
    mat.eliminate_zeros()
    rows = np.repeat(np.arange(mat.shape[0]), np.diff(mat.indptr))
    return bool(np.all(mat.indices == rows))


def factor_checked(
    mat: sp.spmatrix, what: str, names: Callable[[int], str] | None = None, spd: bool = False
) -> ScaledLU | None:
    """:class:`ScaledLU` of a square sparse matrix (None if it is empty)."""
    if mat.shape[0] == 0:
        return None
    return ScaledLU(mat, what, names, spd)
