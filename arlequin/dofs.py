"""The dof layout: one place that knows where each model's degrees of freedom live.

Within a model, dofs are interleaved by node (scikit-fem's ``ElementVector`` ordering)::

    local dof = n_components * node + component

A coupled system stacks the models' dof vectors in blocks, in order; a :class:`DofMap` holds the
blocks (name, offset, size, components) and converts between nodes, local dofs and global dofs.
Overlap transfers, coupling matrices, Dirichlet rows, contact rows and the demos all go through
it. Its numbering convention, :func:`node_dofs`, is part of the model contract
(:mod:`arlequin.contract`), where the models import it from.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .contract import node_dofs

__all__ = ["DofBlock", "DofMap", "node_dofs", "vector_operator"]


def vector_operator(scalar: sp.spmatrix, n_components: int) -> sp.csr_matrix:
    """The operator acting on interleaved vector fields from one acting on nodal scalars.

    ``scalar`` maps nodal values of one mesh to nodal values of another, shape (m, n); the result
    maps interleaved vector fields, shape (n_components m, n_components n).
    """
    a = sp.csr_matrix(scalar)
    d = int(n_components)
    if d == 1:
        return a
    # kron(scalar, I_d) built from the CSR arrays (scipy's kron goes through COO: 3 s for the
    # 16M entries of a 200k-tetrahedron overlap's transfer): row d·i + c holds row i's entries
    # at columns d·j + c, in the same order, so the result is kron's entry for entry
    m, n = a.shape
    counts = np.repeat(np.diff(a.indptr), d)
    indptr = np.zeros(d * m + 1, dtype=np.int64)
    np.cumsum(counts, out=indptr[1:])
    row = np.repeat(np.arange(d * m), counts)
    src = a.indptr[row // d] + (np.arange(indptr[-1]) - indptr[row])
    indices = d * a.indices[src].astype(np.int64) + row % d
    return sp.csr_matrix((a.data[src], indices, indptr), shape=(d * m, d * n))


@dataclass(frozen=True)
class DofBlock:
    """One model's slice of a global dof vector.

    Attributes
    ----------
    name : str
    offset : int
        First global dof.
    size : int
        Number of dofs.
    n_components : int
        Components per node (the block has ``size // n_components`` nodes).
    """

    name: str
    offset: int
    size: int
    n_components: int = 1

    @property
    def slice(self) -> slice:
        """Global dofs of the block as a slice."""
        return slice(self.offset, self.offset + self.size)

    @property
    def stop(self) -> int:
        return self.offset + self.size

    @property
    def n_nodes(self) -> int:
        return self.size // self.n_components

    def node_dofs(self, nodes, components=None) -> np.ndarray:
        """Global dofs of the block's nodes, shape (n_components', len(nodes))."""
        return node_dofs(nodes, self.n_components, components, self.offset)

    def component_dofs(self, component: int) -> np.ndarray:
        """Global dofs of one displacement component at every node, shape (n_nodes,)."""
        return self.node_dofs(np.arange(self.n_nodes), [component])[0]


class DofMap(Mapping[str, DofBlock]):
    """Blocks of a global dof vector, in order.

    Parameters
    ----------
    blocks : iterable of (name, size, n_components)
        One entry per model; offsets follow from the order.

    Examples
    --------
    >>> dm = DofMap([("coarse", 6, 2), ("patch0", 4, 2)])
    >>> dm["patch0"].offset, dm.n_dofs
    (6, 10)
    >>> dm["patch0"].node_dofs([1]).ravel().tolist()
    [8, 9]
    """

    def __init__(self, blocks: Iterable[tuple[str, int, int]]) -> None:
        self._blocks: dict[str, DofBlock] = {}
        offset = 0
        for name, size, n_components in blocks:
            if name in self._blocks:
                raise ValueError(f"block names must be unique, got {name!r} twice")
            size, n_components = int(size), int(n_components)
            if n_components < 1 or size % n_components:
                raise ValueError(
                    f"block {name!r}: {size} dofs is not a multiple of {n_components} components"
                )
            self._blocks[name] = DofBlock(name, offset, size, n_components)
            offset += size
        self.n_dofs = offset
        self._offsets = np.array([b.offset for b in self._blocks.values()] + [offset], np.int64)

    @classmethod
    def of_models(cls, models: Mapping[str, object]) -> DofMap:
        """A map from {name: model}; models give ``n_dofs`` and (optionally) ``n_components``."""
        return cls(
            (name, int(m.n_dofs), int(getattr(m, "n_components", 1))) for name, m in models.items()
        )

    # Mapping interface
    def __getitem__(self, name: str) -> DofBlock:
        try:
            return self._blocks[name]
        except KeyError:
            raise KeyError(f"no block named {name!r}; blocks are {list(self._blocks)}") from None

    def __iter__(self) -> Iterator[str]:
        return iter(self._blocks)

    def __len__(self) -> int:
        return len(self._blocks)

    def __repr__(self) -> str:
        parts = ", ".join(f"{b.name}[{b.offset}:{b.stop}]" for b in self._blocks.values())
        return f"DofMap({parts})"

    @property
    def offsets(self) -> np.ndarray:
        """Block offsets followed by n_dofs, shape (n_blocks + 1,)."""
        return self._offsets

    @property
    def block_of_dof(self) -> np.ndarray:
        """Block index of every global dof, shape (n_dofs,)."""
        return np.repeat(np.arange(len(self)), np.diff(self._offsets))

    def split(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """Global vector (n_dofs,) -> {block name: view of its slice}."""
        return {b.name: x[b.slice] for b in self._blocks.values()}

    def assemble(self, parts: Mapping[str, np.ndarray], what: str = "vector") -> np.ndarray:
        """{block name: block vector} -> global vector (missing blocks are zero)."""
        out = np.zeros(self.n_dofs)
        for name, val in parts.items():
            b = self[name]
            val = np.asarray(val, dtype=float).ravel()
            if val.size != b.size:
                raise ValueError(
                    f"{what} for block {name!r} has {val.size} values, expected {b.size}"
                )
            out[b.slice] = val
        return out

    def embed(self, name: str, local: sp.spmatrix) -> sp.csr_matrix:
        """Rows acting on one block's dofs, shape (m, size) -> rows on the global vector."""
        b = self[name]
        local = sp.csr_matrix(local)
        if local.shape[1] != b.size:
            raise ValueError(
                f"rows for block {name!r} have {local.shape[1]} columns, expected {b.size}"
            )
        coo = local.tocoo()
        return sp.csr_matrix(
            (coo.data, (coo.row, coo.col + b.offset)), shape=(local.shape[0], self.n_dofs)
        )
