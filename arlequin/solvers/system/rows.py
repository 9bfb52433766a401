"""Constraint rows as the integrators use them: stacked equality rows, active unilateral rows.

Equality rows (:class:`~arlequin.problem.system.LinearConstraint`) are fixed for the whole run and
stacked once (:class:`EqualityRows`). Unilateral rows (contact) change inside each step; the
integrators stack the active ones with :func:`stack_active` and key their cached factorisations
by the *content* of those rows (:func:`rows_key`), never by object identity.
"""

from __future__ import annotations

import hashlib
import logging
from collections.abc import Sequence
from typing import Any

import numpy as np
import scipy.sparse as sp

from ...contract import csr_pattern, csr_with_data, same_pattern
from ...linalg.block_sums import kind_block_powers, scattered_block_powers, touched_index
from ...linalg.csr import (
    PARALLEL_MIN_NNZ,
    CsrProduct,
    csr_times,
    csr_times_subtract_scaled,
    subtract_scaled_transposed,
)
from ...linalg.factor import factor_checked
from ...linalg.timing import energy_products_done, timer_start
from ...linalg.vector_updates import subtract_scaled_at
from ...problem.system import LinearConstraint
from .operators import SystemOperators

logger = logging.getLogger(__name__)

__all__ = [
    "EqualityRows",
    "consistent_initial_state",
    "rows_key",
    "rows_times",
    "scatter_active",
    "stack_active",
    "subtract_transposed",
    "transposed",
    "transposed_times",
    "unilateral_block_power",
    "unilateral_block_powers",
]


def rows_key(mat: sp.csr_matrix) -> bytes:
    """A digest of a sparse matrix's shape, pattern and values (a factorisation cache key)."""
    mat = sp.csr_matrix(mat)
    h = hashlib.blake2b(digest_size=16)
    h.update(np.asarray(mat.shape, dtype=np.int64).tobytes())
    for arr in (mat.indptr, mat.indices, mat.data):
        h.update(np.ascontiguousarray(arr).tobytes())
    return h.digest()


def stack_active(trials: Sequence, n: int, cache: dict | None = None):
    """Active rows of the unilateral constraints' trials.

    Parameters
    ----------
    trials : sequence of ConstraintTrial
    n : int
        Number of global dofs.
    cache : dict, optional
        The caller's cache (one per integrator): the same matrices with the same active rows
        (most steps) give the same stacked rows without rebuilding them.

    Returns
    -------
    g_a : csr_matrix, shape (m_A, n)
        The active rows stacked.
    rhs_a : ndarray, shape (m_A,)
        Their right-hand sides.
    idx : list of ndarray of int
        The active row indices of each constraint.
    """
    if not trials:
        return sp.csr_matrix((0, n)), np.zeros(0), []
    # the same matrices with the same active rows (most steps): the same stacked rows, the
    # same active indices, and the same right-hand sides when the trials' are the same arrays
    # (a velocity-level contact's zeros); the cache keeps what it returns read-only
    key = tuple((id(tr.matrix), tr.active.tobytes()) for tr in trials)
    if cache is not None and cache.get("key") == key:
        idx = cache["idx"]
        if all(tr.rhs is r for tr, r in zip(trials, cache["rhs_of"])):
            return cache["g_a"], cache["rhs_a"], list(idx)
        return cache["g_a"], _active_rhs(trials, idx), list(idx)
    idx = [np.nonzero(tr.active)[0] for tr in trials]
    rhs_a = _active_rhs(trials, idx)
    mats = [tr.matrix if getattr(tr.matrix, "format", None) == "csr" else
            sp.csr_matrix(tr.matrix) for tr in trials]  # fmt: skip
    g_a = _stacked_rows(trials, mats, idx, n, cache)
    if cache is not None:
        # the matrices and right-hand sides are kept alive with the key so that their ids
        # cannot be reused
        for a in (*idx, rhs_a):
            a.flags.writeable = False
        cache.update(key=key, g_a=g_a, matrices=[tr.matrix for tr in trials], idx=idx,
                     rhs_of=[tr.rhs for tr in trials], rhs_a=rhs_a)  # fmt: skip
        idx = list(idx)
    return g_a, rhs_a, idx


def _stacked_rows(
    trials: Sequence, mats: Sequence[sp.csr_matrix], idx: Sequence[np.ndarray], n: int,
    cache: dict | None,
) -> sp.csr_matrix:  # fmt: skip
    """The active rows ``idx`` of the CSR matrices ``mats`` (the trials'), stacked (m_A, n):
    from a kept pattern of :func:`stack_active`'s cache when the matrices' index arrays and
    active rows are those of one, else gathered (and their pattern kept when shared)."""
    # new matrices on the same patterns (index arrays, shared while a deforming contact's
    # points keep their facets: csr_pattern) with the same active rows: the stacked rows'
    # pattern and the gathers kept, only the entries taken (no scipy constructor a step)
    pattern_key = tuple((id(m.indices), id(m.indptr), a.tobytes())
                        for m, a in zip(mats, (tr.active for tr in trials)))  # fmt: skip
    # a few patterns kept, the most recent last: the active rows go back and forth between a
    # few sets while the statuses settle (a Taylor bar: 44 sets in 80 changes over 755 steps),
    # and a new set cost 0.18 ms a step in the run, most of it in two scipy constructors
    patterns = cache.setdefault("patterns", {}) if cache is not None else None
    entry = patterns.pop(pattern_key, None) if patterns is not None else None
    if entry is not None:
        patterns[pattern_key] = entry  # the most recent again
        return csr_with_data(entry[0], np.concatenate([m.data[p] for m, p in zip(mats, entry[1])]))
    data, indices, indptr, pos = _stack_rows(mats, idx, n)
    shape = (indptr.size - 1, n)
    # a template only for read-only index arrays (csr_pattern's: never changed), kept with
    # the index arrays so that their ids cannot be reused
    shared = all(not m.indices.flags.writeable and not m.indptr.flags.writeable
                 for m in mats)  # fmt: skip
    if patterns is not None and shared:
        template = csr_pattern(indices, indptr, shape)
        patterns[pattern_key] = (template, pos, [(m.indices, m.indptr) for m in mats])
        if len(patterns) > _KEPT_PATTERNS:
            del patterns[next(iter(patterns))]  # the least recently used
        return csr_with_data(template, data)
    return sp.csr_matrix((data, indices, indptr), shape=shape)


def _active_rhs(trials: Sequence, idx: Sequence[np.ndarray]) -> np.ndarray:
    """The right-hand sides of the trials' active rows ``idx``, stacked, shape (m_A,)."""
    return np.concatenate([np.asarray(tr.rhs, dtype=float)[act] for tr, act in zip(trials, idx)])


def _stack_rows(mats: Sequence[sp.csr_matrix], idx: Sequence[np.ndarray], n: int):
    """The CSR arrays of ``sp.vstack([m[i] for m, i in zip(mats, idx)], format="csr")``
    (data, indices, indptr), in a few vectorised gathers: scipy's row indexing and stacking
    took twice as long (0.14 against 0.07 ms a step of the ball impact, whose deformable
    pair's rows change every step), and the positions of its entries in each matrix's arrays.
    """
    data, indices, counts, positions = [], [], [], []
    for mat, act in zip(mats, idx):
        start = mat.indptr[act]
        cnt = mat.indptr[act + 1] - start
        # positions of the selected rows' entries: each row's start repeated along the row
        offsets = np.cumsum(cnt) - cnt
        pos = np.repeat(start - offsets, cnt) + np.arange(int(cnt.sum()))
        data.append(mat.data[pos])
        indices.append(mat.indices[pos])
        counts.append(cnt)
        positions.append(pos)
    cnt = np.concatenate(counts)
    indptr = np.zeros(cnt.size + 1, dtype=np.int64)
    np.cumsum(cnt, out=indptr[1:])
    index_dtype = np.int32 if max(n, int(indptr[-1])) < np.iinfo(np.int32).max else np.int64
    return (np.concatenate(data), np.concatenate(indices).astype(index_dtype, copy=False),
            indptr.astype(index_dtype, copy=False), positions)  # fmt: skip


_KEPT_PATTERNS = 16  # stacked-row patterns kept by stack_active's cache


def scatter_active(values: np.ndarray, idx: Sequence[np.ndarray], sizes: Sequence[int]):
    """Split stacked active multipliers into full per-constraint vectors (zeros elsewhere)."""
    out, start = [], 0
    for act, m in zip(idx, sizes):
        full = np.zeros(m)
        full[act] = values[start : start + act.size]
        start += act.size
        out.append(full)
    return out


_TRANSPOSED: list[Any] = [None, None]  # the last rows given to transposed() and their transpose


def transposed(g: sp.csr_matrix) -> sp.csr_matrix:
    """Gᵀ as CSR, cached for the last G (the stacked active rows change rarely; building the
    transpose object at each product cost about 45 µs, a tenth of a Taylor bar step). The cache
    holds G itself, so its identity cannot be reused by another object, and stacked rows are
    never modified in place. Its products sum in the same order as ``g.T @ x`` (by increasing
    row of G), so results are unchanged bit for bit."""
    if _TRANSPOSED[0] is not g:
        _TRANSPOSED[0], _TRANSPOSED[1] = g, g.T.tocsr()
    return _TRANSPOSED[1]


def transposed_times(g: sp.csr_matrix, lam: np.ndarray) -> np.ndarray:
    """``Gᵀ λ`` (n,) of CSR rows G (m, n) without duplicate entries and multipliers λ (m,).

    One weighted ``bincount`` over G's arrays: the entries of each column summed from zero in
    the order of increasing row, each product ``G_ij λ_i`` as in the CSR product with
    :func:`transposed` (the same numbers bit for bit), without the transpose a deformable
    contact's rows, new at every step, needed (a quarter of a millisecond a step of the ball
    impact).
    """
    weights = g.data * np.repeat(lam, np.diff(g.indptr))
    return np.bincount(g.indices, weights, minlength=g.shape[1])


def _compiled_rows(g: sp.csr_matrix, *vectors: np.ndarray) -> bool:
    """Whether the compiled row kernels take G and these vectors as they are (float64 values,
    contiguous float64 vectors of G's sizes)."""
    if g.data.dtype != np.float64:
        return False
    for x in vectors:  # a loop, not all() of a generator (see vector_updates._compiled)
        if not (x.dtype == np.float64 and x.ndim == 1 and x.flags.c_contiguous):
            return False
    return True


def rows_times(g: sp.csr_matrix, x: np.ndarray) -> np.ndarray:
    """``G x`` (m,) of CSR rows G (m, n): scipy's product bit for bit
    (:func:`~arlequin.linalg.csr.csr_times`), without its Python-level checks (a few µs, each
    status iteration of a contact step)."""
    if not (_compiled_rows(g, x) and x.shape == (g.shape[1],)):
        return g @ x
    y = np.empty(g.shape[0])
    csr_times(g.indptr, g.indices, g.data, x, y)
    return y


def subtract_transposed(g: sp.csr_matrix, lam: np.ndarray, scale: np.ndarray, v: np.ndarray,
                        scratch: np.ndarray) -> None:  # fmt: skip
    """``v −= scale ⊙ (Gᵀ λ)`` in place for CSR rows G (m, n), multipliers λ (m,) and a scale
    (n,) (M⁻¹): the bits of ``v -= scale * transposed_times(g, lam)`` on G's columns alone
    (:func:`~arlequin.linalg.csr.subtract_scaled_transposed`); ``scratch`` (n,) zeros, left
    zeros."""
    n = g.shape[1]
    sizes = lam.shape == (g.shape[0],) and v.shape == scale.shape == scratch.shape == (n,)
    if not (sizes and _compiled_rows(g, lam, scale, v, scratch)):
        push = transposed_times(g, lam)
        push *= scale
        v -= push
        return
    subtract_scaled_transposed(g.indptr, g.indices, g.data, lam, scale, v, scratch)


def unilateral_block_power(
    ops: SystemOperators, g: sp.csr_matrix, lam: np.ndarray, x: np.ndarray
) -> np.ndarray:
    """Per-block −λ·(G_b x_b) of unilateral rows G (m, n) with multipliers λ (m,)."""
    if g.shape[0] == 0:
        return np.zeros(len(ops.blocks))
    return -ops.block_dots(transposed(g) @ lam, x)


def _vectors(xs: Sequence[np.ndarray], n: int, what: str) -> tuple[np.ndarray, np.ndarray]:
    """The first and last of one or two vectors as contiguous float64 arrays (n,) (the arrays
    themselves when they are: the common case, tested without a conversion call)."""
    if not 1 <= len(xs) <= 2:
        raise ValueError(f"{what}: one or two vectors, got {len(xs)}")
    x1, x2 = xs[0], xs[-1]
    ok = (n,)
    if (type(x1) is np.ndarray and type(x2) is np.ndarray and x1.shape == ok and x2.shape == ok
            and x1.dtype == x2.dtype == np.float64 and x1.flags.c_contiguous
            and x2.flags.c_contiguous):  # fmt: skip
        return x1, x2  # the integrators' own vectors: no conversion
    x1, x2 = np.ascontiguousarray(x1, dtype=float), np.ascontiguousarray(x2, dtype=float)
    if x1.shape != ok or x2.shape != ok:
        raise ValueError(f"{what}: vectors of shape ({n},), got {x1.shape} and {x2.shape}")
    return x1, x2


def unilateral_block_powers(
    ops: SystemOperators, g: sp.csr_matrix, lam: np.ndarray, xs: Sequence[np.ndarray]
) -> np.ndarray:
    """:func:`unilateral_block_power` for one or two vectors x (n,), shape (len(xs), n_blocks),
    on the dofs the rows touch only (the same powers up to round-off: the force Gᵀλ is summed
    on those dofs alone), in one compiled pass
    (:func:`~arlequin.linalg.block_sums.scattered_block_powers`: the floats of
    ``np.bincount`` for the force and :func:`signed_block_sums` for each vector)."""
    nb = len(ops.blocks)
    x1, x2 = _vectors(xs, ops.n, "unilateral_block_powers")
    out = np.zeros((len(xs), nb))
    if g.shape[0] == 0:
        return out
    # the touched dofs of the last rows (the same object while the active rows are: most
    # steps of a Taylor bar), as transposed() keeps its transpose, or of their pattern (the
    # same read-only index arrays: csr_pattern's, a deforming contact's new rows each step)
    last = _TOUCHED[0]
    if not (last is g or (last is not None and same_pattern(last, g))):
        cols, inv = np.unique(g.indices, return_inverse=True)
        row_of = np.repeat(np.arange(g.shape[0]), np.diff(g.indptr))
        index = touched_index(cols, ops.block_of_dof[cols])
        _TOUCHED[0], _TOUCHED[1] = g, (cols, inv, row_of, *index)
    cols, inv, row_of, idx, block = _TOUCHED[1]
    tic = timer_start()
    scattered_block_powers(np.ascontiguousarray(g.data, dtype=float),
                           np.ascontiguousarray(lam, dtype=float), row_of, inv, cols.size, x1,
                           x2, len(xs), idx, block, out)  # fmt: skip
    energy_products_done(tic)
    return out


_TOUCHED: list[Any] = [None, None]  # the last rows of unilateral_block_powers, their dofs


def _rate(c: LinearConstraint, t: float, h: float, order: int = 1) -> np.ndarray:
    """d^order g / dt^order by centred differences with step h (zero for constant data)."""
    if not callable(c.rhs):
        return np.zeros(c.n_rows)
    if order == 1:
        return (c.g(t + h) - c.g(t - h)) / (2.0 * h)
    return (c.g(t + h) - 2.0 * c.g(t) + c.g(t - h)) / (h * h)


class EqualityRows:
    """The equality constraints of a system stacked: ``B`` (m×n), levels, kinds, right-hand sides.

    Attributes
    ----------
    constraints : list of LinearConstraint
    matrix : csr_matrix, shape (m, n)
    slices : dict
        Constraint name -> rows.
    displacement : ndarray of bool, shape (m,)
        Rows at displacement level (the others are at velocity level).
    coupling : ndarray of bool, shape (m,)
        Rows of kind ``"coupling"``.
    cols : ndarray of int
        Global dofs touched by the rows; ``matrix_cols = matrix[:, cols]``.
    """

    def __init__(self, constraints: Sequence[LinearConstraint], ops: SystemOperators) -> None:
        self.constraints = list(constraints)
        n = ops.n
        self.n = n
        names = [c.name for c in self.constraints]
        if len(set(names)) != len(names):
            raise ValueError(f"constraint names must be unique, got {names}")
        mats = [sp.csr_matrix(c.matrix) for c in self.constraints]
        for c, mat in zip(self.constraints, mats):
            if mat.shape[1] != n:
                raise ValueError(f"constraint {c.name!r} has {mat.shape[1]} columns, expected {n}")
        self.matrix = sp.vstack(mats, format="csr") if mats else sp.csr_matrix((0, n))
        self.matrix.sum_duplicates()
        self.m = int(self.matrix.shape[0])
        self.slices: dict[str, slice] = {}
        start = 0
        disp, coup = [], []
        for c in self.constraints:
            self.slices[c.name] = slice(start, start + c.n_rows)
            start += c.n_rows
            disp.append(np.full(c.n_rows, c.level == "displacement"))
            coup.append(np.full(c.n_rows, c.kind == "coupling"))
        self.displacement = np.concatenate(disp) if disp else np.zeros(0, dtype=bool)
        self.all_displacement = bool(self.displacement.all())  # every row: displacement level
        self.coupling = np.concatenate(coup) if coup else np.zeros(0, dtype=bool)
        self.cols = np.unique(self.matrix.indices) if self.m else np.zeros(0, dtype=np.int64)
        self.matrix_cols = self.matrix[:, self.cols].tocsr() if self.m else sp.csr_matrix((0, 0))
        self.matrix_cols_t = self.matrix_cols.T.tocsr()
        # B and Bᵀ on the touched dofs as compiled products (scipy's floats, without its
        # dispatch: the explicit impulse multiplies by them at every step)
        self.times = CsrProduct(self.matrix_cols)
        # the touched dofs as the compiled products' column map (uint32: no wraparound test)
        self.cols_u32 = np.ascontiguousarray(self.cols, dtype=np.uint32) \
            if self.cols.size and self.cols.max() < 2**32 else None  # fmt: skip
        self.transpose_times = CsrProduct(self.matrix_cols_t)
        self.block_of_col = ops.block_of_dof[self.cols]
        self.n_blocks = len(ops.blocks)
        # per-block row products in one mat-vec: row (b m + i) holds row i of B on block b's dofs
        if self.m:
            coo = self.matrix_cols.tocoo()
            self._stacked = sp.csr_matrix(
                (coo.data, (self.block_of_col[coo.col] * self.m + coo.row, coo.col)),
                shape=(self.n_blocks * self.m, self.cols.size),
            )
        self._coupling_f = self.coupling.astype(float)
        self._by_kind: tuple[np.ndarray, np.ndarray] | None = None
        self._constant = all(not callable(c.rhs) for c in self.constraints)
        self._g0 = self._g(0.0) if self._constant else None

    def _g(self, t: float) -> np.ndarray:
        parts = [c.g(t) for c in self.constraints]
        return np.concatenate(parts) if parts else np.zeros(0)

    def g(self, t: float) -> np.ndarray:
        """Stacked right-hand sides at time t (s), shape (m,)."""
        return self._g0 if self._g0 is not None else self._g(t)

    @property
    def time_dependent(self) -> bool:
        return not self._constant

    def rate(self, t: float, h: float, order: int = 1) -> np.ndarray:
        """Stacked d^order g/dt^order at t (centred differences, step h)."""
        if self._constant:
            return np.zeros(self.m)
        parts = [_rate(c, t, h, order) for c in self.constraints]
        return np.concatenate(parts) if parts else np.zeros(0)

    def split(self, lam: np.ndarray) -> dict[str, np.ndarray]:
        """Stacked multipliers -> {constraint name: multipliers}."""
        return {name: lam[s].copy() for name, s in self.slices.items()}

    def block_powers(self, lam: np.ndarray, x_cols: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per-block −λ·(B_b x_b) for the coupling rows and for the other rows.

        Parameters
        ----------
        lam : ndarray, shape (m,)
            Multipliers (N).
        x_cols : ndarray, shape (len(cols),)
            A velocity (m/s) or displacement increment (m) on :attr:`cols`.

        Returns
        -------
        coupling, other : ndarray, shape (n_blocks,)
            Power (W) or work (J) of the constraint forces −Bᵀλ on each block.
        """
        nb = self.n_blocks
        if self.m == 0:
            return np.zeros(nb), np.zeros(nb)
        rb = (self._stacked @ x_cols).reshape(nb, self.m) * lam
        pc = -(rb * self._coupling_f).sum(axis=1)
        po = -rb.sum(axis=1) - pc
        return pc, po

    def subtract_at_cols(self, v: np.ndarray, scale: np.ndarray, x: np.ndarray) -> None:
        """``v[self.cols] −= scale ⊙ x`` in place (v (n,), scale and x on the touched dofs):
        the equality rows' impulse M⁻¹ Bᵀλ, one compiled pass bit for bit the numpy line
        (:func:`~arlequin.linalg.vector_updates.subtract_scaled_at`)."""
        k = self.cols.shape
        fast = (v.shape == (self.n,) and scale.shape == x.shape == k and v.flags.c_contiguous
                and v.dtype == scale.dtype == x.dtype == np.float64)  # fmt: skip
        if not fast:
            v[self.cols] -= scale * x
            return
        subtract_scaled_at(v, self.cols, np.ascontiguousarray(scale), np.ascontiguousarray(x))

    def subtract_impulse(self, v: np.ndarray, scale: np.ndarray, lam: np.ndarray) -> None:
        """``v[self.cols] −= scale ⊙ (Bᵀλ)`` in place (v (n,), scale on the touched dofs, λ
        (m,)): the equality rows' impulse M⁻¹ Bᵀλ, one compiled pass
        (:func:`~arlequin.linalg.csr.csr_times_subtract_scaled`), the floats of
        ``subtract_at_cols(v, scale, transpose_times(lam))`` without the product's vector."""
        a = self.transpose_times
        fast = (a.nnz < PARALLEL_MIN_NNZ and v.shape == (self.n,) and v.flags.c_contiguous
                and scale.shape == self.cols.shape and lam.shape == (self.m,)
                and v.dtype == scale.dtype == lam.dtype == np.float64
                and scale.flags.c_contiguous and lam.flags.c_contiguous)  # fmt: skip
        if not fast:
            self.subtract_at_cols(v, scale, a(lam))
            return
        csr_times_subtract_scaled(a._indptr, a._indices, a._data, lam, self.cols, scale, v)

    def add_block_powers(self, lam: np.ndarray, vs: Sequence[np.ndarray], out: np.ndarray) -> None:
        """Accumulate into ``out`` (len(vs), 2, n_blocks) the powers ``−Σ_{j∈b} x_j
        (B_cᵀλ_c)_j`` of the coupling rows (``out[i, 0]``) and of the others (``out[i, 1]``)
        for one or two vectors x (n,) of ``vs``: one compiled pass over the touched dofs
        (:func:`~arlequin.linalg.block_sums.kind_block_powers`; a zero ``out`` receives the
        floats of each kind's Bᵀλ summed alone, then
        :func:`~arlequin.linalg.block_sums.signed_block_sums` for each vector and kind)."""
        x1, x2 = _vectors(vs, self.n, "add_block_powers")
        if out.shape != (len(vs), 2, self.n_blocks):
            raise ValueError(f"add_block_powers: out of shape ({len(vs)}, 2, {self.n_blocks}), "
                             f"got {out.shape}")  # fmt: skip
        if self.m == 0:
            return
        if self._by_kind is None:
            # the rows' kinds and the touched dofs with their blocks; Bᵀ is the transpose
            # product's (its rows' entries by increasing row of B, as each kind's Bᵀ alone)
            other = np.ascontiguousarray(~self.coupling, dtype=np.uint8)
            has = np.array([other.size - other.sum() > 0, other.sum() > 0], dtype=np.uint8)
            self._by_kind = (other, has)
            self._block_sums = touched_index(self.cols, self.block_of_col)
        other, has = self._by_kind
        idx, block = self._block_sums
        a = self.transpose_times
        tic = timer_start()
        kind_block_powers(a._indptr, a._indices, a._data, other,
                          np.ascontiguousarray(lam, dtype=float), x1, x2, len(vs), has, idx,
                          block, out)  # fmt: skip
        energy_products_done(tic)

    def row_name(self, i: int) -> str:
        """Description of stacked row ``i`` for error messages."""
        for name, sl in self.slices.items():
            if sl.start <= i < sl.stop:
                return f"row {i - sl.start} of constraint {name!r}"
        return f"row {i}"


def _project(
    rows: EqualityRows, ops: SystemOperators, x: np.ndarray, sel: np.ndarray, target: np.ndarray
) -> np.ndarray:
    """Mass-metric projection of x onto {y: B[sel] y = target}."""
    b = rows.matrix[np.nonzero(sel)[0]]
    if b.shape[0] == 0:
        return x
    r = target - b @ x
    if not np.any(r):
        return x
    if ops.lumped:
        s = (b @ sp.diags(ops.inv_mass) @ b.T).tocsc()
        lu = factor_checked(s, "the initial-condition projection matrix B M⁻¹ Bᵀ", spd=True)
        return x + ops.inv_mass * (b.T @ lu.solve(r))
    mat = sp.bmat([[ops.mass, b.T], [b, None]], format="csc")
    lu = factor_checked(mat, "the initial-condition projection saddle point")
    sol = lu.solve(np.concatenate([np.zeros(x.size), r]))
    return x + sol[: x.size]


def consistent_initial_state(
    rows: EqualityRows, ops: SystemOperators, t: float, h: float, u: np.ndarray, v: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """u and v projected (mass metric) onto the equality rows at time t (s).

    ``B u = g(t)`` for displacement rows; ``B v = ġ(t)`` (centred differences of step h, s) for
    them and ``B v = g(t)`` for velocity rows. The size of each correction is logged.
    """
    u_new = _project(rows, ops, u, rows.displacement, rows.g(t))
    vt = np.where(rows.displacement, rows.rate(t, h), rows.g(t))
    v_new = _project(rows, ops, v, np.ones(rows.m, dtype=bool), vt)
    for what, old, new in (("displacement", u, u_new), ("velocity", v, v_new)):
        change = float(np.linalg.norm(new - old))
        scale = max(float(np.linalg.norm(old)), 1e-300)
        if change > 1e-12 * scale:
            logger.info(
                "initial %s projected onto the constraints (change %.3e, relative %.3e)",
                what,
                change,
                change / scale,
            )
    return u_new, v_new
