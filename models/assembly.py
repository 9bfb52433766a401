"""Assembly of per-cell matrices into a CSR pattern computed once, with a scatter map.

For a mesh of ``n_cells`` cells of ``nen`` nodes and ``dim`` dofs a node, numbered node-major
(global dof ``dim · node + i``, local dof ``dim · a + i``), :class:`CellPattern` computes once:

* the CSR structure (``indptr``, ``indices``) of the assembled (n_dofs, n_dofs) matrix,
  columns sorted within each row, no duplicates: a read-only template
  (:func:`arlequin.contract.csr_pattern`) that every assembled matrix shares
  (:func:`arlequin.contract.csr_with_data`, no sort, no sum of duplicates);
* the scatter map by node blocks: ``base[e, a, b]`` the position in the CSR data array of the
  entry (dim · t[e, a], dim · t[e, b]), and ``row_stride[n]`` the number of entries in a row of
  node n, so that the local entry (dim · a + i, dim · b + j) of cell e goes to
  ``base[e, a, b] + i · row_stride[t[e, a]] + j`` (``dim²`` times less memory than the full map,
  :meth:`CellPattern.scatter_map`, which the numpy reference path uses);
* a colouring of the cells (no two cells of a colour share a node), so that a compiled kernel adds
  the cells of one colour in parallel without a race.

:meth:`CellPattern.assemble` sums dense local matrices (n_cells, nd, nd) with the compiled
:func:`scatter_add`; :meth:`CellPattern.assemble_reference` is its numpy reference
(``np.add.at`` on the full map), ``tests/test_assembly.py`` compares them. numba compiles on
first call (cached on disk).
"""

from __future__ import annotations

import numba as nb
import numpy as np
import scipy.sparse as sp

from arlequin.contract import csr_pattern, csr_with_data

__all__ = ["CellPattern", "colour_cells", "scatter_add"]


@nb.njit(cache=True)
def colour_cells(cells, n_nodes):
    """Greedy colouring of the cells (n_cells, nen) by shared nodes: colour of each cell (int64),
    the lowest one no cell met earlier through one of its nodes has (node bit masks, 64 colours
    a word, as many words as needed)."""
    n_cells, nen = cells.shape
    words = 1
    used = np.zeros((n_nodes, words), dtype=np.uint64)
    colour = np.empty(n_cells, dtype=np.int64)
    for e in range(n_cells):
        c = -1
        w = 0
        while c < 0:
            if w == words:  # every colour of the current words taken: one more word
                grown = np.zeros((n_nodes, words + 1), dtype=np.uint64)
                grown[:, :words] = used
                used = grown
                words += 1
            taken = np.uint64(0)
            for a in range(nen):
                taken |= used[cells[e, a], w]
            if taken != np.uint64(0xFFFFFFFFFFFFFFFF):
                bit = 0
                while (taken >> np.uint64(bit)) & np.uint64(1):
                    bit += 1
                c = 64 * w + bit
            else:
                w += 1
        colour[e] = c
        mask = np.uint64(1) << np.uint64(c % 64)
        for a in range(nen):
            used[cells[e, a], c // 64] |= mask
    return colour


@nb.njit(parallel=True, cache=True)
def scatter_add(data, cells, base, row_stride, order, colour_ptr, local):
    """data[map] += local, cell by cell: the cells of each colour in parallel (no race)."""
    nen = cells.shape[1]
    dim = local.shape[1] // nen
    for c in range(colour_ptr.size - 1):
        for k in nb.prange(colour_ptr[c], colour_ptr[c + 1]):
            e = order[k]
            for a in range(nen):
                stride = row_stride[cells[e, a]]
                for b in range(nen):
                    p = base[e, a, b]
                    for i in range(dim):
                        for j in range(dim):
                            data[p + i * stride + j] += local[e, dim * a + i, dim * b + j]
    return data


class CellPattern:
    """The CSR pattern, scatter map and cell colouring of a cell dof table, computed once.

    Parameters
    ----------
    cells : ndarray of int, shape (n_cells, nen)
        Nodes of each cell.
    dim : int
        Dofs a node (global dof ``dim · node + i``).
    n_nodes : int
        Number of nodes (rows: ``dim · n_nodes``).
    """

    def __init__(self, cells: np.ndarray, dim: int, n_nodes: int) -> None:
        cells = np.ascontiguousarray(cells, dtype=np.int64)
        ne, nen = cells.shape
        self.cells, self.dim, self.n_dofs = cells, int(dim), int(dim) * int(n_nodes)
        key = (cells[:, :, None] * n_nodes + cells[:, None, :]).ravel()
        unique, inverse = np.unique(key, return_inverse=True)
        node_row, node_col = np.divmod(unique, n_nodes)
        nptr = np.searchsorted(node_row, np.arange(n_nodes + 1))
        row_len = np.diff(nptr)  # nodes in each node row
        d = self.dim
        self.row_stride = d * row_len  # entries in a dof row of each node
        indptr = np.zeros(self.n_dofs + 1, dtype=np.int64)
        np.cumsum(np.repeat(self.row_stride, d), out=indptr[1:])
        columns = (d * node_col[:, None] + np.arange(d)).ravel()  # a node row's dof columns
        starts = np.repeat(d * nptr[:-1], d)  # where each dof row's columns start in `columns`
        lengths = np.diff(indptr)
        pick = np.repeat(starts - indptr[:-1], lengths) + np.arange(indptr[-1])
        index_dtype = np.int32 if max(self.n_dofs, indptr[-1]) < 2**31 else np.int64
        shape = (self.n_dofs, self.n_dofs)
        self.template = csr_pattern(
            columns[pick].astype(index_dtype), indptr.astype(index_dtype), shape
        )
        self.nnz = int(indptr[-1])
        first = np.repeat(cells, nen, axis=1).ravel()  # node a of each (e, a, b)
        self.base = (indptr[d * first] + d * (inverse.ravel() - nptr[first])).reshape(ne, nen, nen)
        colour = colour_cells(cells, int(n_nodes))
        self.order = np.argsort(colour, kind="stable")
        self.colour_ptr = np.searchsorted(colour[self.order], np.arange(colour.max() + 2))
        self.n_colours = int(colour.max()) + 1

    def scatter_map(self) -> np.ndarray:
        """Position in the CSR data array of each local entry, int64 (n_cells, nd, nd)."""
        d = self.dim
        ij = np.arange(d)
        stride = self.row_stride[self.cells]  # (ne, nen)
        full = (self.base[:, :, None, :, None] + ij[None, None, :, None, None]
                * stride[:, :, None, None, None] + ij[None, None, None, None, :])  # fmt: skip
        ne, nen = self.cells.shape
        return full.reshape(ne, nen * d, nen * d)

    def matrix(self, data: np.ndarray) -> sp.csr_matrix:
        """The CSR matrix of the entries ``data`` (nnz,) on this pattern (shared index arrays)."""
        return csr_with_data(self.template, data)

    def assemble(self, local: np.ndarray) -> sp.csr_matrix:
        """Σ over cells of the local matrices (n_cells, nd, nd), compiled."""
        data = np.zeros(self.nnz)
        scatter_add(data, self.cells, self.base, self.row_stride, self.order, self.colour_ptr,
                    np.ascontiguousarray(local, dtype=float))  # fmt: skip
        return self.matrix(data)

    def assemble_reference(self, local: np.ndarray) -> sp.csr_matrix:
        """:meth:`assemble` by ``np.add.at`` on :meth:`scatter_map` (the numpy reference)."""
        data = np.zeros(self.nnz)
        np.add.at(data, self.scatter_map(), local)
        return self.matrix(data)
