"""The operators of a coupled system as the integrators use them: mass, forces, tangents, energies.

Linear blocks (every term's model declares ``is_linear``) use the assembled weighted stiffness,
computed once, so a force evaluation is a sparse mat-vec. Nonlinear block terms call their
model's ``internal_force(u, state, weight) -> (f, trial_state)`` with the committed state of the
term and, when a tangent is asked for, ``tangent(u, state, weight)`` (capability ``"tangent"``
of :mod:`arlequin.contract`) or, with ``tangent="initial"``, the model's ``stiffness(weight)``
(a modified Newton iteration: the documented alternative for models without a tangent).

Energies of nonlinear blocks: the integrators accumulate the work of the internal forces; a block
whose every term's model offers the optional members ``stored_energy_of_state(state, weight)``
and ``plastic_dissipation(state, weight)`` (:mod:`arlequin.contract`, :class:`DynamicModel`)
also reports its stored energy and its plastic dissipation from the committed states
(:meth:`SystemOperators.stored_and_dissipated`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import scipy.sparse as sp

from ...contract import (
    CapabilityError,
    ConstraintError,
    ContractError,
    DynamicModel,
    capabilities,
    check_protocol,
    is_linear,
)
from ...linalg.csr import CsrProduct
from ...linalg.timing import SWITCH
from ...problem.system import Block, BlockTerm, CoupledSystem

__all__ = ["TANGENTS", "SystemOperators", "as_system", "as_vector"]

#: How nonlinear terms provide their tangent: their own consistent tangent, or the initial
#: (small-strain) stiffness.
TANGENTS = ("consistent", "initial")


def as_system(system: Any) -> CoupledSystem:
    """A :class:`CoupledSystem` from itself, from an object with a ``system()`` method (an
    ``ArlequinProblem``), or from a single model (one block named ``"model"``, weight 1)."""
    if isinstance(system, CoupledSystem):
        return system
    make = getattr(system, "system", None)
    if callable(make):
        return make()
    if isinstance(system, DynamicModel):
        return CoupledSystem([Block("model", system, [BlockTerm(system)])])
    raise ContractError(
        f"expected a CoupledSystem, an ArlequinProblem or a model, got {type(system).__name__}"
    )


def as_vector(x: Any, system: CoupledSystem, what: str) -> np.ndarray:
    """Global vector (n,) from None (zeros), an array (n,) or a dict {block name: block vector}.

    Raises
    ------
    ValueError
        On a size mismatch or non-finite values, naming ``what``.
    """
    n = system.n_dofs
    if x is None:
        return np.zeros(n)
    if isinstance(x, Mapping):
        out = system.dofmap.assemble(x, what)
    else:
        out = np.asarray(x, dtype=float).ravel().copy()
        if out.size != n:
            raise ValueError(f"{what} has {out.size} values, expected {n} (the system's dofs)")
    bad = np.nonzero(~np.isfinite(out))[0]
    if bad.size:
        raise ValueError(
            f"{what} has {bad.size} non-finite value(s), first {out[bad[0]]} at global dof "
            f"{int(bad[0])}"
        )
    return out


class SystemOperators:
    """Mass, internal force and tangent of a :class:`CoupledSystem` for the integrators.

    Parameters
    ----------
    system : CoupledSystem
    lumped : bool
        Row-sum lumped weighted mass (explicit scheme) or consistent weighted mass.
    tangent : {"consistent", "initial"}
        Tangent of nonlinear terms (see the module docstring). With ``"consistent"`` a nonlinear
        model without the ``"tangent"`` capability is refused when a tangent is first needed.
    with_mass : bool
        Assemble the mass (False for the quasi-static solver, which has none: the consistent
        mass of the 3D sphere's eighth at 31,722 dofs takes 5.5 s to assemble).

    Attributes
    ----------
    mass : ndarray (n,), sparse (n, n) or None
        Weighted mass (kg); None without ``with_mass``.
    inv_mass : ndarray (n,) or None
        Inverse lumped mass (1/kg).
    stiffness : sparse (n, n)
        Stiffness of the linear blocks (N/m), zero blocks for the nonlinear ones.
    block_linear : list of bool
    linear : bool
        Every block linear.
    """

    def __init__(
        self,
        system: CoupledSystem,
        lumped: bool,
        tangent: str = "consistent",
        with_mass: bool = True,
    ) -> None:
        if tangent not in TANGENTS:
            raise ValueError(f"tangent must be one of {TANGENTS}, got {tangent!r}")
        self.system = system
        self.blocks = list(system.blocks)
        self.dofmap = system.dofmap
        self.n = int(system.n_dofs)
        self.lumped = bool(lumped)
        self.tangent_kind = tangent
        for b in self.blocks:
            for t in b.terms:
                check_protocol(t.model, DynamicModel, f"the model of block {b.name!r}")
        self.block_linear = [all(is_linear(t.model) for t in b.terms) for b in self.blocks]
        self.linear = all(self.block_linear)
        self.offsets = self.dofmap.offsets
        self.block_of_dof = self.dofmap.block_of_dof
        self.names = [b.name for b in self.blocks]
        mass = system.mass(lumped=self.lumped) if with_mass else None
        self.mass = mass
        if self.lumped and with_mass:
            mass = np.asarray(mass, dtype=float)
            bad = np.nonzero(~(mass > 0.0))[0]
            if bad.size:
                j = int(bad[0])
                b = self.blocks[int(self.block_of_dof[j])]
                raise ConstraintError(
                    f"lumped weighted mass must be positive, got {mass[j]:.3e} kg at dof "
                    f"{j - b.offset} of block {b.name!r} ({bad.size} such dofs): check the "
                    "partition weights (epsilon > 0) and the density"
                )
            self.inv_mass = 1.0 / mass
        else:
            self.inv_mass = None
        kb = []
        for b, lin in zip(self.blocks, self.block_linear):
            kb.append(system.block_stiffness(b) if lin else sp.csr_matrix((b.n_dofs, b.n_dofs)))
        self.stiffness = sp.block_diag(kb, format="csr")
        self._nonlinear_terms = [
            (bi, ti, t)
            for bi, (b, lin) in enumerate(zip(self.blocks, self.block_linear))
            if not lin
            for ti, t in enumerate(b.terms)
        ]

    # ------------------------------------------------------------------ capabilities
    def check_tangents(self, what: str) -> None:
        """Raise :class:`CapabilityError` if a nonlinear term has no consistent tangent and the
        operators were built with ``tangent="consistent"`` (``what`` names the computation)."""
        if self.tangent_kind != "consistent":
            return
        for _, _, term in self._nonlinear_terms:
            if "tangent" not in capabilities(term.model):
                raise CapabilityError(
                    f"{what} needs the consistent tangent of every nonlinear model, and "
                    f"{type(term.model).__name__} has none: use the explicit scheme, or "
                    "newton='initial' (modified Newton with the model's initial stiffness)"
                )

    # ------------------------------------------------------------------ states
    def initial_states(self) -> dict[str, list[Any]]:
        """One state per block term (None for linear models)."""
        out: dict[str, list[Any]] = {}
        for b, lin in zip(self.blocks, self.block_linear):
            states = []
            for t in b.terms:
                init = getattr(t.model, "initial_state", None)
                states.append(init(t.weight) if callable(init) and not lin else None)
            out[b.name] = states
        return out

    # ------------------------------------------------------------------ forces
    @staticmethod
    def _term_u(b, t, u: np.ndarray) -> np.ndarray:
        ub = u[b.dofs]
        return ub if t.transfer is None else t.transfer @ ub

    def internal_force(
        self, u: np.ndarray, states: Mapping[str, list[Any]], tangent: bool = False,
        dt: float | None = None, blocks: Sequence[int] | None = None,
    ) -> tuple[np.ndarray, dict[str, list[Any]], sp.csr_matrix | None]:  # fmt: skip
        """Internal force (N) at ``u`` from the committed ``states``; ``dt`` (s) is the step that
        leads to ``u``, passed to the models whose ``uses_time_step`` is True (rate-dependent
        laws, bulk viscosity; None at the initial time).

        ``blocks`` (indices) restricts the evaluation to those blocks (the force is zero on the
        others and their states are the committed ones): a subcycling integrator evaluates its
        slow blocks only at their own steps. Not combined with ``tangent``.

        Returns
        -------
        f : ndarray, shape (n,)
        trial_states : dict
            Block name -> list of trial states (committed by the integrator once the step is
            accepted).
        tangent : sparse (n, n) or None
            Tangent (N/m) when ``tangent`` is True (see the ``tangent`` parameter of the class).
        """
        timer = SWITCH.timer
        f, terms = self._linear_force(u, tangent, blocks)
        trial = {name: list(s) for name, s in states.items()}
        if not terms:
            return f, trial, (self.stiffness if tangent else None)
        if tangent:
            self.check_tangents("a tangent of the coupled system")
        kt_blocks: dict[int, sp.csr_matrix] = {}
        for bi, ti, term, dofs, name, uses_dt in self._force_terms(terms):
            ub = u[dofs]
            p = term.transfer
            ut = ub if p is None else p @ ub
            state = states[name][ti]
            tic = timer.clock() if timer is not None else 0.0
            if uses_dt:
                ft, new_state = term.model.internal_force(ut, state, term.weight, dt=dt)
            else:
                ft, new_state = term.model.internal_force(ut, state, term.weight)
            if timer is not None:
                timer.kernel += timer.clock() - tic
            trial[name][ti] = new_state
            ft = ft if p is None else p.T @ ft
            # ±ft added or subtracted in place (a + (−b) is a − b: the same floats, no temporary)
            if term.sign == 1:
                f[dofs] += ft
            elif term.sign == -1:
                f[dofs] -= ft
            else:
                f[dofs] += term.sign * ft
            if tangent:
                kb = self._term_tangent(term, ut, state, dt, uses_dt)
                kt_blocks[bi] = kb if bi not in kt_blocks else kt_blocks[bi] + kb
        kt_full = None
        if tangent:
            blocks = [
                kt_blocks.get(bi, sp.csr_matrix((b.n_dofs, b.n_dofs)))
                for bi, b in enumerate(self.blocks)
            ]
            kt_full = (self.stiffness + sp.block_diag(blocks, format="csr")).tocsr()
        return f, trial, kt_full

    def _linear_force(
        self, u: np.ndarray, tangent: bool, blocks: Sequence[int] | None
    ) -> tuple[np.ndarray, list]:
        """The assembled (linear) part of :meth:`internal_force` (of ``blocks`` only, if given)
        and the nonlinear terms left to evaluate (block index, term index, term)."""
        timer = SWITCH.timer
        tic = timer.clock() if timer is not None else 0.0
        if blocks is not None:
            if tangent:
                raise ValueError("internal_force: a tangent is assembled for every block")
            idx, k_rows, terms = self._rows_of(tuple(blocks))
            f = np.zeros(u.shape)
            if k_rows is not None:
                f[idx] = k_rows(u)
        else:
            # the assembled (linear) part; nothing to multiply when every term is nonlinear
            f = self._stiffness_times(u) if self.stiffness.nnz else np.zeros(u.shape)
            terms = self._nonlinear_terms
        if timer is not None:
            timer.linear_algebra += timer.clock() - tic
        return f, terms

    def _term_tangent(
        self, term: Any, ut: np.ndarray, state: Any, dt: float | None, uses_dt: bool
    ) -> sp.csr_matrix:
        """The signed tangent (N/m) of one nonlinear term at its displacement ``ut`` from its
        committed ``state``, on its block's dofs (the consistent one, or the initial stiffness
        with ``tangent="initial"``)."""
        if self.tangent_kind == "consistent":
            if uses_dt:  # rates: the same dt
                kt = term.model.tangent(ut, state, term.weight, dt=dt)
            else:
                kt = term.model.tangent(ut, state, term.weight)
            kt = sp.csr_matrix(kt)
        else:
            kt = sp.csr_matrix(term.model.stiffness(term.weight))
        p = term.transfer
        return term.sign * (kt if p is None else (p.T @ kt @ p))

    def _force_terms(self, terms: list) -> list[tuple]:
        """``terms`` (block index, term index, term) with their block's dofs (a slice), name
        and whether the model takes the step (``uses_time_step``), kept for each of the
        operators' own lists of terms (the blocks' properties cost a few µs a step)."""
        cache = self.__dict__.setdefault("_force_terms_cache", {})
        entry = cache.get(id(terms))
        if entry is None or entry[0] is not terms:
            found = [
                (bi, ti, t, self.blocks[bi].dofs, self.blocks[bi].name,
                 bool(getattr(t.model, "uses_time_step", False)))
                for bi, ti, t in terms
            ]  # fmt: skip
            entry = cache[id(terms)] = (terms, found)  # the list kept: its id stays its own
        return entry[1]

    def _rows_of(self, blocks: tuple[int, ...]):
        """The dofs of ``blocks``, the product with the rows of the linear stiffness on them
        (None if they are empty) and their nonlinear terms (cached by the tuple of block
        indices)."""
        cache = self.__dict__.setdefault("_rows_cache", {})
        if blocks not in cache:
            idx = np.concatenate(
                [np.arange(self.offsets[b], self.offsets[b + 1]) for b in sorted(set(blocks))]
            ) if blocks else np.zeros(0, dtype=np.int64)  # fmt: skip
            terms = [(bi, ti, t) for bi, ti, t in self._nonlinear_terms if bi in blocks]
            rows = self.stiffness[idx].tocsr()
            # compiled (CsrProduct: the floats of ``rows @ u``), None when nothing to multiply
            cache[blocks] = (idx, CsrProduct(rows) if rows.nnz else None, terms)
        return cache[blocks]

    def _stiffness_times(self, u: np.ndarray) -> np.ndarray:
        """K u (N) with the linear stiffness, compiled (:class:`~arlequin.linalg.csr.CsrProduct`,
        the floats of ``K @ u``), built on first use and again if the matrix is replaced."""
        product = self.__dict__.get("_stiffness_product")
        if product is None or product[0] is not self.stiffness:
            product = self.__dict__["_stiffness_product"] = (
                self.stiffness,
                CsrProduct(self.stiffness),
            )
        return product[1](u)

    def initial_stiffness(self) -> sp.csr_matrix:
        """Block-diagonal weighted stiffness of every block (N/m): the linear stiffness, and the
        models' ``stiffness`` (small-strain initial tangent) for nonlinear blocks."""
        return self.system.stiffness()

    # ------------------------------------------------------------------ per-block reductions
    def block_sums(self, x: np.ndarray) -> np.ndarray:
        """Per-block sums Σ_{j∈b} x_j, shape (n_blocks,) (numpy's segmented sums, those of
        :meth:`block_dots` on its products)."""
        if not self.n:
            return np.zeros(len(self.blocks))
        return np.add.reduceat(x, self.offsets[:-1])

    def block_dots(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Per-block dot products Σ_{j∈b} x_j y_j, shape (n_blocks,)."""
        if not self.n:
            return np.zeros(len(self.blocks))
        # the products in a buffer kept between calls (several a step): no new n-array each
        if np.shape(x) != np.shape(y):
            return np.add.reduceat(x * y, self.offsets[:-1])
        buf = self.__dict__.get("_dots_buffer")
        if buf is None or buf.shape != np.shape(x) or np.result_type(x, y) != buf.dtype:
            buf = self.__dict__["_dots_buffer"] = np.empty(np.shape(x), np.result_type(x, y))
        np.multiply(x, y, out=buf)
        return np.add.reduceat(buf, self.offsets[:-1])

    def mass_times(self, x: np.ndarray) -> np.ndarray:
        """M x (N·s²/m × x)."""
        return self.mass * x if self.lumped else self.mass @ x

    def kinetic(self, v: np.ndarray) -> np.ndarray:
        """α-weighted kinetic energy per block (J) with the integrator's mass."""
        return 0.5 * self.block_dots(v, self.mass_times(v))

    def stored_and_dissipated(
        self, states: Mapping[str, list[Any]], internal_work: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Stored energy and plastic dissipation per nonlinear block (J) from committed states.

        A nonlinear block whose every term's model has the optional members
        ``stored_energy_of_state(state, weight)`` and ``plastic_dissipation(state, weight)``
        (found with ``getattr``, see :class:`arlequin.contract.DynamicModel`) gets
        Σ_terms sign × those; the others (and a model that raises ``ValueError`` there, e.g.
        :class:`FiniteStrainJ2` with bulk viscosity) keep ``internal_work`` as their stored
        energy and no dissipation. Linear blocks: 0 and 0 (their ½ uᵀK u is added by the caller).
        """
        stored = np.zeros(len(self.blocks))
        dissipated = np.zeros(len(self.blocks))
        for bi, (b, lin) in enumerate(zip(self.blocks, self.block_linear)):
            if lin:
                continue
            parts = self._block_energy_parts(b, states[b.name])
            if parts is None:
                stored[bi] = internal_work[bi]
            else:
                stored[bi], dissipated[bi] = parts
        return stored, dissipated

    @staticmethod
    def _block_energy_parts(b: Block, states: list[Any]) -> tuple[float, float] | None:
        stored = dissipated = 0.0
        for t, state in zip(b.terms, states):
            psi = getattr(t.model, "stored_energy_of_state", None)
            dis = getattr(t.model, "plastic_dissipation", None)
            if not (callable(psi) and callable(dis)) or state is None:
                return None
            try:
                stored += t.sign * float(psi(state, t.weight))
                dissipated += t.sign * float(dis(state, t.weight))
            except ValueError:
                return None
        return stored, dissipated

    def strain_linear(self, u: np.ndarray) -> np.ndarray:
        """½ uᵀ K u per block (J) for the linear blocks (0 for the others)."""
        ku = self._stiffness_times(u) if u.dtype == np.float64 and u.ndim == 1 else \
            self.stiffness @ u  # compiled for a vector of floats: scipy's floats  # fmt: skip
        return 0.5 * self.block_dots(u, ku)
