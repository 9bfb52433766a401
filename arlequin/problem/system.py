"""The algebraic view of a coupled problem that the integrators see.

An integrator never sees meshes: it sees a :class:`CoupledSystem`, i.e. a global displacement
vector made of per-model blocks, block-diagonal (weighted) mass and stiffness, internal and
external forces, and a list of constraints. Arlequin mediator equations, Dirichlet conditions and
prescribed velocities are :class:`LinearConstraint` rows ``B u = g(t)``; contact enters as
unilateral constraint objects (see :mod:`arlequin.solvers`). Units are SI.

Shapes: ``n`` is the total number of dofs (sum over blocks), ``m`` a constraint's row count.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..contract import Model, StateError
from ..dofs import DofMap

__all__ = [
    "Block",
    "BlockTerm",
    "CoupledSystem",
    "LinearConstraint",
    "Model",  # re-exported from arlequin.contract
    "StateError",  # re-exported from arlequin.contract
]


@dataclass(frozen=True)
class LinearConstraint:
    """Equality constraint rows ``B u = g(t)`` (``level="displacement"``) or ``B v = g(t)``
    (``level="velocity"``).

    Attributes
    ----------
    matrix : scipy.sparse.csr_matrix, shape (m, n)
        The constraint rows B on the global dof vector.
    rhs : callable or ndarray or None
        g(t) with shape (m,); ``None`` means zero. Callables take the time t (s).
    name : str
        For reports (``"coupling:patch0"``, ``"dirichlet"``...).
    level : {"displacement", "velocity"}
    kind : str
        ``"coupling"`` (Arlequin mediator rows: their work is the coupling work),
        ``"dirichlet"`` or ``"other"``.
    pivot_dofs : ndarray of int, shape (m,), optional
        A hint for the explicit scheme: global dofs, one per row, on which the rows form an
        invertible square matrix T and which no other row touches (single-dof supports
        aside). The scheme may then write the rows in the basis where they are the identity
        on those dofs, T⁻¹B (the same constraint, the same corrected velocities), whose impulse
        matrix is diagonal plus low rank
        (:mod:`arlequin.solvers.dynamics.row_basis`); the fine mediator of a nested patch gives its
        band's fine dofs. Rows whose T⁻¹B is not sparse keep their own basis.
    """

    matrix: sp.csr_matrix
    rhs: Callable[[float], np.ndarray] | np.ndarray | None = None
    name: str = "constraint"
    level: str = "displacement"
    kind: str = "other"
    pivot_dofs: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.level not in ("displacement", "velocity"):
            raise ValueError(
                f"constraint level must be 'displacement' or 'velocity', got {self.level!r}"
            )
        if self.pivot_dofs is not None:
            piv = np.asarray(self.pivot_dofs)
            if piv.shape != (self.n_rows,) or not np.issubdtype(piv.dtype, np.integer):
                raise ValueError(
                    f"pivot_dofs of constraint {self.name!r} must be {self.n_rows} integer dofs "
                    f"(one per row), got an array of shape {piv.shape} and dtype {piv.dtype}"
                )
            n = int(self.matrix.shape[1])
            if piv.size and (piv.min() < 0 or piv.max() >= n or np.unique(piv).size != piv.size):
                raise ValueError(f"pivot_dofs of constraint {self.name!r} must be distinct dofs "
                                 f"in [0, {n})")  # fmt: skip

    @property
    def n_rows(self) -> int:
        return int(self.matrix.shape[0])

    def g(self, t: float) -> np.ndarray:
        """Right-hand side at time ``t`` (s), shape (m,)."""
        if self.rhs is None:
            return np.zeros(self.n_rows)
        if callable(self.rhs):
            return np.asarray(self.rhs(t), dtype=float).reshape(self.n_rows)
        return np.asarray(self.rhs, dtype=float).reshape(self.n_rows)


@dataclass
class BlockTerm:
    """A weighted contribution of one model to its block.

    The block's internal force is ``sum(sign * P.T @ model.internal_force(P @ u_block, weight))``
    over its terms. ``P`` (None = identity) maps the block's dofs to the term model's dofs; the
    coarse model of an Arlequin problem has a term on its own mesh (weight 1 outside the
    patches) and, per patch, a term on the overlap's integration mesh
    (:meth:`~arlequin.coupling.gluing.PatchCoupling.coarse_overlap_weight`), so that the net weight
    inside the overlap is α_coarse, integrated exactly on the overlap cells. An array weight is kept
    as a read-only copy: models may then check and broadcast it once for all steps.
    """

    model: Any
    weight: Any = None
    transfer: sp.csr_matrix | None = None
    sign: float = 1.0

    def __post_init__(self) -> None:
        if isinstance(self.weight, np.ndarray):
            w = np.array(self.weight, dtype=float)
            w.setflags(write=False)
            self.weight = w

    def _lift(self, a: sp.spmatrix) -> sp.csr_matrix:
        if self.transfer is None:
            return self.sign * sp.csr_matrix(a)
        p = self.transfer
        return self.sign * (p.T @ a @ p).tocsr()

    def stiffness(self) -> sp.csr_matrix:
        """The term's weighted stiffness lifted to its block (N/m)."""
        return self._lift(self.model.stiffness(self.weight))

    def mass(self) -> sp.csr_matrix:
        """The term's weighted consistent mass lifted to its block (kg)."""
        return self._lift(self.model.mass(self.weight, lumped=False))


@dataclass
class Block:
    """One model's slice of the global dof vector.

    Attributes
    ----------
    name : str
        ``"coarse"``, ``"patch0"``...
    model : Model
        The model that owns the block's dofs (its mesh defines them).
    terms : list of BlockTerm
        Weighted contributions (see :class:`BlockTerm`).
    offset : int
        First global dof of the block.
    """

    name: str
    model: Any
    terms: list[BlockTerm]
    offset: int = 0

    @property
    def n_dofs(self) -> int:
        return int(self.model.n_dofs)

    @property
    def dofs(self) -> slice:
        return slice(self.offset, self.offset + self.n_dofs)


@dataclass
class CoupledSystem:
    """Global system: blocks, constraints and loads.

    Attributes
    ----------
    blocks : list of Block
    constraints : list of LinearConstraint
        Equality rows (and unilateral constraint objects, see :mod:`arlequin.contract`).
    load : callable
        ``load(t) -> (n,)`` external force vector (N) at time t (s), already weighted.
    dofmap : DofMap
        The blocks' dof layout (set on construction).
    band_plasticity : callable or None
        ``band_plasticity(states) -> list`` of the problem that built the system: plastic flow
        in its J2 patches' gluing bands (:meth:`ArlequinProblem.band_plasticity`), which the
        solvers watch; None for a system built by hand.
    """

    blocks: list[Block]
    constraints: list[LinearConstraint] = field(default_factory=list)
    load: Callable[[float], np.ndarray] | None = None
    band_plasticity: Callable[[dict[str, list[Any]]], list[Any]] | None = None

    def __post_init__(self) -> None:
        self.dofmap = DofMap(
            (b.name, b.n_dofs, int(getattr(b.model, "n_components", 1))) for b in self.blocks
        )
        for block in self.blocks:
            block.offset = self.dofmap[block.name].offset
        self._cache: dict[str, Any] = {}
        # block name -> (system, its block) that owns the block's operators (a body's own
        # system in a multi-body problem: kept when another body's patch grows, its operators
        # with it)
        self._sources: dict[str, tuple[CoupledSystem, Block]] = {}

    def share_block(self, name: str, source: CoupledSystem, block: Block) -> None:
        """Take block ``name``'s weighted operators (and :meth:`block_memo` values) from
        ``source``'s ``block`` (the same terms), computed there once for every system that
        shares it."""
        self._sources[name] = (source, block)

    def block_memo(self, block: Block, key: str, compute: Callable[[], Any]) -> Any:
        """A value of one block that depends on its terms only (its stiffness, its mass, their
        critical step...): ``compute()`` once per block and ``key``, shared with the systems the
        block comes from (:meth:`share_block`)."""
        full = f"{key}:{block.name}"
        if full not in self._cache:
            src = self._sources.get(block.name)
            if src is not None:
                self._cache[full] = src[0].block_memo(src[1], key, compute)
            else:
                self._cache[full] = compute()
        return self._cache[full]

    @property
    def n_dofs(self) -> int:
        return self.dofmap.n_dofs

    def block(self, name: str) -> Block:
        """The block named ``name``."""
        for b in self.blocks:
            if b.name == name:
                return b
        raise KeyError(f"no block named {name!r}; blocks are {[b.name for b in self.blocks]}")

    def split(self, u: np.ndarray) -> dict[str, np.ndarray]:
        """Global vector -> {block name: block vector}."""
        return self.dofmap.split(u)

    # ------------------------------------------------------------------ operators
    def block_stiffness(self, block: Block) -> sp.csr_matrix:
        """Weighted stiffness of one block (linear models), shape (n_b, n_b)."""
        return self.block_memo(block, "K", lambda: sum(
            (t.stiffness() for t in block.terms[1:]), block.terms[0].stiffness()
        ).tocsr())  # fmt: skip

    def block_mass(self, block: Block) -> sp.csr_matrix:
        """Weighted consistent mass of one block, shape (n_b, n_b)."""
        return self.block_memo(block, "M", lambda: sum(
            (t.mass() for t in block.terms[1:]), block.terms[0].mass()
        ).tocsr())  # fmt: skip

    def stiffness(self) -> sp.csr_matrix:
        """Block-diagonal weighted stiffness, shape (n, n) (N/m)."""
        return sp.block_diag([self.block_stiffness(b) for b in self.blocks], format="csr")

    def mass(self, lumped: bool = False):
        """Weighted mass (kg): sparse (n, n), or its row sums (n,) when ``lumped``.

        Row sums of the weighted consistent mass are ∫ α ρ φ_j ≥ 0, the weighted lumped mass.
        """
        m = sp.block_diag([self.block_mass(b) for b in self.blocks], format="csr")
        if lumped:
            return np.asarray(m.sum(axis=1)).ravel()
        return m

    def external_force(self, t: float = 0.0) -> np.ndarray:
        """External force at time t (s), shape (n,) (N)."""
        if self.load is None:
            return np.zeros(self.n_dofs)
        return np.asarray(self.load(t), dtype=float)

    def constraint_matrix(self, kinds: Sequence[str] | None = None) -> sp.csr_matrix:
        """All (or the selected kinds of) constraint rows stacked, shape (m_total, n)."""
        rows = [c.matrix for c in self.constraints if kinds is None or c.kind in kinds]
        if not rows:
            return sp.csr_matrix((0, self.n_dofs))
        return sp.vstack(rows, format="csr")

    def constraint_rhs(self, t: float, kinds: Sequence[str] | None = None) -> np.ndarray:
        """The right-hand sides g(t) of the equality constraints at time ``t`` (s), stacked."""
        parts = [c.g(t) for c in self.constraints if kinds is None or c.kind in kinds]
        return np.concatenate(parts) if parts else np.zeros(0)

    # ------------------------------------------------------------------ energies
    def strain_energies(self, u: np.ndarray) -> dict[str, float]:
        """α-weighted strain energy ½ uᵀK u per block (J), linear models."""
        out = {}
        for b in self.blocks:
            ub = u[b.dofs]
            out[b.name] = 0.5 * float(ub @ (self.block_stiffness(b) @ ub))
        return out

    def kinetic_energies(self, v: np.ndarray, lumped: bool = False) -> dict[str, float]:
        """α-weighted kinetic energy ½ vᵀM v per block (J)."""
        out = {}
        for b in self.blocks:
            vb = v[b.dofs]
            mb = self.block_mass(b)
            if lumped:
                out[b.name] = 0.5 * float(np.asarray(mb.sum(axis=1)).ravel() @ (vb * vb))
            else:
                out[b.name] = 0.5 * float(vb @ (mb @ vb))
        return out
