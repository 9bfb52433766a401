"""The explicit scheme's impulse basis of the equality rows.

Rows B and T B (T invertible) are the same constraint: the corrected velocity
v = v* − M⁻¹BᵀΛ that satisfies them is the M-orthogonal projection of v* onto it whatever the
basis; only the multipliers change, Λ = TᵀΛ'. A constraint that names pivot dofs
(:attr:`~arlequin.problem.system.LinearConstraint.pivot_dofs`: one per row, touched by no other row,
the rows square and invertible there) is written in the basis where it is the identity on
them. With its rows R = [T | R_O | R_J] on the pivot dofs F, the other dofs O and the dofs J
that single-dof homogeneous rows S fix (a symmetry axis, a support; s_j their entries),

    R' = T⁻¹ (R − R_J D_s⁻¹ S) = [I | P | 0],    P = T⁻¹ R_O,

kept only where P is sparse: the fine mediator of a nested patch, whose coarse functions lie
in the fine space, gives the interpolation of the coarse field at the band's fine nodes (about
3 entries a row in 2D), so that the rows say v_F = −P v_O. P is computed by sparse solves and
checked by its residual T P − R_O; a constraint whose P is not sparse (a non-nested patch, a
coarse mediator) keeps its rows. The impulse matrix of R' is diagonal plus low rank
(:class:`~arlequin.linalg.factor.DiagonalLowRankSolver`), where R's was as dense as the
band's Gram matrix squared.

The multipliers of the original rows are Λ_R = T⁻ᵀΛ'_R and Λ_S = Λ'_S − D_s⁻¹ R_JᵀΛ_R, computed
when they are asked for (:class:`Multipliers`): a run that reads only some of them (its contact
force at every step, everything at the records) never pays the others' solves.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator, MutableMapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...problem.system import LinearConstraint
from ..system.operators import SystemOperators
from ..system.rows import EqualityRows

__all__ = ["ImpulseBasis", "Multipliers"]

logger = logging.getLogger(__name__)

#: Entries of P = T⁻¹R_O below this fraction of their column's largest are round-off zeros.
_DROP = 1e-12
#: Largest residual |T P − R_O| accepted, against the largest |R_O|.
_RESIDUAL = 1e-11
#: P is kept if it has at most this many times R_O's entries (a nested mediator's P has
#: fewer: the interpolation at a node against the couplings with every node around it).
_DENSITY = 1.0
#: Work bound of computing P (columns of R_O times entries of T's factors).
_WORK = 2e10


@dataclass(frozen=True)
class _Reduced:
    """One constraint rewritten: its rows' slice, T's factors, and the single-dof rows it
    eliminated (their stacked row indices and R_J D_s⁻¹ on them)."""

    name: str
    rows: slice
    t_lu: Any
    single_rows: np.ndarray
    r_j_scaled: sp.csr_matrix  # (m_c, len(single_rows)): R_J D_s⁻¹, one column per single row


def _homogeneous(c: LinearConstraint) -> bool:
    return not callable(c.rhs) and not np.any(c.g(0.0))


class ImpulseBasis:
    """The equality rows of a system, each constraint with pivot dofs in its identity basis
    (module docstring).

    Parameters
    ----------
    constraints : sequence of LinearConstraint
    ops : SystemOperators

    Attributes
    ----------
    original : EqualityRows
        The rows as given (the basis the multipliers are reported in).
    rows : EqualityRows
        The rows the scheme uses: the same constraints, names and slices, the reduced ones
        rewritten (homogeneous, the level of the original).
    reduced : list of str
        The names of the rewritten constraints.
    """

    def __init__(self, constraints: Sequence[LinearConstraint], ops: SystemOperators) -> None:
        constraints = list(constraints)
        self.original = EqualityRows(constraints, ops)
        self._reduced: list[_Reduced] = []
        candidates = [c for c in constraints if c.pivot_dofs is not None and c.n_rows
                      and _homogeneous(c)]  # fmt: skip
        if not candidates:
            self.rows = self.original
            self.reduced: list[str] = []
            self._affected: frozenset[str] = frozenset()
            return
        orig = self.original
        b = orig.matrix.tocsr()
        b.eliminate_zeros()
        n = b.shape[1]
        counts = np.bincount(b.indices, minlength=n)
        # single-dof homogeneous rows (supports, a symmetry axis): their dofs can be eliminated
        # from the other rows of the same level
        nnz = np.diff(b.indptr)
        g0 = orig.g(0.0)
        constant = np.concatenate([np.full(c.n_rows, not callable(c.rhs)) for c in constraints])
        single = (nnz == 1) & (g0 == 0.0) & constant
        pivoted_rows = np.zeros(orig.m, dtype=bool)
        for c in candidates:
            pivoted_rows[orig.slices[c.name]] = True
        single &= ~pivoted_rows
        single_rows = np.nonzero(single)[0]
        single_col = b.indices[b.indptr[single_rows]]
        # the first single row of each dof (duplicates keep their own multipliers)
        _, first = np.unique(single_col, return_index=True)
        single_rows, single_col = single_rows[first], single_col[first]
        row_of_col = np.full(n, -1, dtype=np.int64)
        row_of_col[single_col] = single_rows
        new: dict[str, LinearConstraint] = {}
        for c in candidates:
            red = self._reduce(c, b, counts, row_of_col, orig)
            if red is None:
                continue
            con, info = red
            new[c.name] = con
            self._reduced.append(info)
        self.reduced = [r.name for r in self._reduced]
        if not new:
            self.rows = orig
            self._affected = frozenset()
            return
        self.rows = EqualityRows([new.get(c.name, c) for c in constraints], ops)
        owner = np.concatenate([np.full(c.n_rows, k) for k, c in enumerate(constraints)])
        affected = set(self.reduced)
        for r in self._reduced:
            affected.update(constraints[k].name for k in np.unique(owner[r.single_rows]))
        self._affected = frozenset(affected)

    # ------------------------------------------------------------------ construction
    def _reduce(self, c: LinearConstraint, b: sp.csr_matrix, counts: np.ndarray,
                row_of_col: np.ndarray, orig: EqualityRows):  # fmt: skip
        """(the rewritten constraint, its :class:`_Reduced`) or None (reason logged)."""
        sl = orig.slices[c.name]
        rc = b[sl].tocsr()
        m = rc.shape[0]
        piv = np.asarray(c.pivot_dofs, dtype=np.int64)
        own = np.bincount(rc.indices, minlength=b.shape[1])
        if np.any(counts[piv] != own[piv]) or np.any(row_of_col[piv] >= 0):
            logger.debug("constraint %r: its pivot dofs are touched by other rows", c.name)
            return None
        level = "displacement" if c.level == "displacement" else "velocity"
        same_level = orig.displacement if level == "displacement" else ~orig.displacement
        coo = rc.tocoo()
        srow = row_of_col[coo.col]
        on_j = (srow >= 0) & same_level[np.maximum(srow, 0)]
        is_piv = np.zeros(b.shape[1], dtype=bool)
        is_piv[piv] = True
        on_f = is_piv[coo.col]
        on_o = ~on_j & ~on_f
        pos = np.full(b.shape[1], -1, dtype=np.int64)
        pos[piv] = np.arange(m)
        t = sp.csc_matrix((coo.data[on_f], (coo.row[on_f], pos[coo.col[on_f]])), shape=(m, m))
        o_cols = np.unique(coo.col[on_o])
        opos = np.full(b.shape[1], -1, dtype=np.int64)
        opos[o_cols] = np.arange(o_cols.size)
        r_o = sp.csc_matrix((coo.data[on_o], (coo.row[on_o], opos[coo.col[on_o]])),
                            shape=(m, o_cols.size))  # fmt: skip
        try:
            t_lu = spla.splu(t)
        except RuntimeError:
            logger.debug("constraint %r: singular on its pivot dofs", c.name)
            return None
        udiag = np.abs(t_lu.U.diagonal())
        if udiag.min() <= 1e-13 * udiag.max():
            logger.debug("constraint %r: numerically singular on its pivot dofs", c.name)
            return None
        if o_cols.size * (t_lu.L.nnz + t_lu.U.nnz) > _WORK:
            logger.debug("constraint %r: P too costly to compute (%d columns)", c.name,
                         o_cols.size)  # fmt: skip
            return None
        p = _sparse_solve(t_lu, r_o, max_nnz=int(_DENSITY * r_o.nnz))
        if p is None:
            logger.debug("constraint %r: T⁻¹R_O is not sparse", c.name)
            return None
        scale = np.abs(r_o.data).max() if r_o.nnz else 1.0
        resid = t @ p - r_o
        if resid.nnz and np.abs(resid.data).max() > _RESIDUAL * scale:
            logger.debug("constraint %r: T P − R_O = %.3e of R_O", c.name,
                         np.abs(resid.data).max() / scale)  # fmt: skip
            return None
        # R' = [I | P | 0] on (F, O, J)
        pc = p.tocoo()
        n = b.shape[1]
        rows = np.concatenate([np.arange(m), pc.row])
        cols = np.concatenate([piv, o_cols[pc.col]])
        vals = np.concatenate([np.ones(m), pc.data])
        reduced = sp.csr_matrix((vals, (rows, cols)), shape=(m, n))
        # R_J D_s⁻¹ on the single rows it eliminated
        j_rows = srow[on_j]
        j_vals = coo.data[on_j] / b.data[b.indptr[j_rows]]
        singles, jpos = np.unique(j_rows, return_inverse=True)
        r_j = sp.csr_matrix((j_vals, (coo.row[on_j], jpos)), shape=(m, singles.size))
        logger.info("constraint %r in its pivot basis: %d rows, P with %.2f entries a row "
                    "on %d dofs, %d single-dof rows eliminated", c.name, m, p.nnz / max(m, 1),
                    o_cols.size, singles.size)  # fmt: skip
        con = LinearConstraint(reduced, None, c.name, level=c.level, kind=c.kind)
        return con, _Reduced(c.name, sl, t_lu, singles, r_j)

    # ------------------------------------------------------------------ multipliers
    def to_original(self, lam: np.ndarray) -> np.ndarray:
        """Stacked multipliers in the scheme's basis -> in the original rows' basis: shape
        (m,), or (k, m) for k samples (one solve for all of them, the same numbers as k
        calls)."""
        x = np.asarray(lam, dtype=float)
        if x.ndim == 2:  # the samples as the columns of the solves and products
            return self._columns_to_original(x.T).T
        return self._columns_to_original(x)

    def _columns_to_original(self, lam: np.ndarray) -> np.ndarray:
        """:meth:`to_original` of multipliers (m,) or of k columns (m, k)."""
        out = np.array(lam, dtype=float, copy=True)
        for r in self._reduced:
            lam_r = r.t_lu.solve(np.ascontiguousarray(lam[r.rows]), trans="T")
            out[r.rows] = lam_r
            if r.single_rows.size:
                out[r.single_rows] -= r.r_j_scaled.T @ lam_r
        return out

    def multipliers(self, lam: np.ndarray) -> dict[str, np.ndarray] | Multipliers:
        """The per-constraint multipliers (N) of stacked ones in the scheme's basis: a plain
        dict without rewritten rows, a lazy :class:`Multipliers` otherwise."""
        if not self._reduced:
            return self.original.split(lam)
        return Multipliers(self, lam)

    def affects(self, name: str) -> bool:
        """Whether the multipliers of constraint ``name`` differ between the two bases."""
        return name in self._affected


def _sparse_solve(lu, rhs: sp.csc_matrix, max_nnz: int) -> sp.csr_matrix | None:
    """T⁻¹ rhs with its round-off zeros dropped, by chunks of columns; None past max_nnz."""
    m, k = rhs.shape
    chunk = max(1, int(4e6 // max(m, 1)))
    parts = []
    total = 0
    for start in range(0, k, chunk):
        block = rhs[:, start : start + chunk].toarray()
        x = lu.solve(block)
        big = np.abs(x).max(axis=0)
        x[np.abs(x) <= _DROP * big[None, :]] = 0.0
        part = sp.csc_matrix(x)
        total += part.nnz
        if total > max_nnz:
            return None
        parts.append(part)
    return sp.hstack(parts, format="csr") if parts else sp.csr_matrix((m, 0))


class Multipliers(MutableMapping):
    """Constraint name -> multipliers (N) in the original rows' basis, converted on access
    from the scheme's (:class:`ImpulseBasis`); other entries (the unilateral constraints') are
    set and read as in a dict. A copy or a pickle is a plain dict of every entry."""

    def __init__(self, basis: ImpulseBasis, lam: np.ndarray) -> None:
        self._basis = basis
        self._lam = lam
        self._extra: dict[str, np.ndarray] = {}
        self._full: np.ndarray | None = None

    def __getitem__(self, name: str) -> np.ndarray:
        if name in self._extra:
            return self._extra[name]
        sl = self._basis.original.slices[name]  # KeyError for an unknown name
        if not self._basis.affects(name):
            return self._lam[sl].copy()
        if self._full is None:
            self._full = self._basis.to_original(self._lam)
        return self._full[sl].copy()

    def in_scheme_basis(self, name: str) -> np.ndarray:
        """A constraint's multipliers as the scheme computed them (no conversion)."""
        if name in self._extra:
            return self._extra[name]
        return self._lam[self._basis.original.slices[name]].copy()

    def converted(self, name: str) -> bool:
        """Whether ``self[name]`` is converted from the stacked multipliers in the scheme's
        basis (:meth:`stacked_in_scheme_basis`), rather than set as an entry."""
        return name not in self._extra and name in self._basis.original.slices

    def stacked_in_scheme_basis(self) -> np.ndarray:
        """Every equality row's multiplier (m,) as the scheme computed them (a copy)."""
        return self._lam.copy()

    def to_original(self, name: str, stacked: np.ndarray) -> np.ndarray:
        """Constraint ``name``'s multipliers (N) from stacked ones in the scheme's basis, (m,)
        or (k, m) for k samples: the numbers of ``self[name]`` for each. A per-step history
        keeps :meth:`stacked_in_scheme_basis` and converts many steps in one solve, rather
        than a triangular solve pair at each step (41 µs of an Arlequin Taylor bar's step)."""
        sl = self._basis.original.slices[name]
        x = np.asarray(stacked, dtype=float)
        if not self._basis.affects(name):
            return x[..., sl].copy()
        return self._basis.to_original(x)[..., sl]

    def __setitem__(self, name: str, value: np.ndarray) -> None:
        self._extra[name] = value

    def __delitem__(self, name: str) -> None:
        del self._extra[name]

    def __iter__(self) -> Iterator[str]:
        yield from self._basis.original.slices
        yield from (k for k in self._extra if k not in self._basis.original.slices)

    def __len__(self) -> int:
        return len(set(self._basis.original.slices) | set(self._extra))

    def __copy__(self) -> dict[str, np.ndarray]:
        return dict(self.items())

    def __reduce__(self):
        return (dict, (dict(self.items()),))
