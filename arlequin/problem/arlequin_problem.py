"""An Arlequin problem: a coarse model, refined patches, weights, mediators, loads and supports.

Usage
-----
>>> problem = ArlequinProblem(coarse_model, [Patch(fine_model, gluing_width=0.1)])
>>> problem.add_dirichlet("coarse", where=lambda x: x[0] < 1e-12)
>>> problem.add_traction([1e6, 0.0], where=lambda x: x[0] > 1 - 1e-12)
>>> result = arlequin.solve_static(problem)

Models are any objects following :class:`arlequin.problem.system.Model` (``arlequin.models``
provides them); the core never imports them. All quantities are SI.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..contract import ContractError, Model, check_protocol
from ..coupling.band_plasticity import BandPlasticity, band_plasticity
from ..coupling.gluing import Patch, PatchCoupling
from ..coupling.overlap import OverlapError
from ..dofs import DofMap
from ..geometry.locate import cell_centroids, locate_points
from ..io.layout import BlockFields, FieldLayout
from .system import Block, BlockTerm, CoupledSystem, LinearConstraint

__all__ = ["ArlequinProblem", "Patch", "PatchCoupling", "von_mises_of"]

logger = logging.getLogger(__name__)


def _facet_midpoints(mesh, facets: np.ndarray) -> np.ndarray:
    return mesh.p[:, mesh.facets[:, facets]].mean(axis=1)


@dataclass
class _Load:
    kind: str  # "body" or "traction"
    value: Any
    where: Callable[[np.ndarray], np.ndarray] | None
    amplitude: Callable[[float], float] | None
    blocks: Sequence[str] | None


@dataclass
class _Dirichlet:
    block: str
    where: Callable[[np.ndarray], np.ndarray]
    components: Sequence[int] | None
    value: Any
    amplitude: Callable[[float], float] | None
    level: str


def von_mises_of(sigma: np.ndarray) -> np.ndarray:
    """√(3/2) ‖dev σ‖ (Pa) of tensors (3, 3, …)."""
    dev = sigma - np.einsum("ii...->...", sigma)[None, None] / 3.0 * np.eye(3)[:, :, None, None]
    return np.sqrt(1.5 * np.einsum("ij...,ij...->...", dev, dev))


@dataclass
class ArlequinProblem:
    """A coarse model plus refined patches, coupled by Lagrange-multiplier mediators.

    Parameters
    ----------
    coarse : Model
        The model of the whole structure.
    patches : sequence of Patch
        Non-overlapping refined patches.
    mediator_dirichlet : {"auto", "keep", "drop"}
        ``"drop"``: remove the mediator functions carried by dofs that a Dirichlet condition of
        the carrier model (the coarse one for a coarse mediator, the patch for a fine one)
        prescribes, so that the multiplier space is the trace of the constrained spaces. Use it
        when both models carry the same condition in the gluing zone (a symmetry plane through
        the band): the rows would otherwise repeat the conditions (exactly so with a fine
        mediator: linearly dependent rows, whose multipliers drift in the null direction, to
        1e14 on a thick sphere, and load the supports with spurious reactions) and carry
        their reactions. ``"auto"`` (default): ``"drop"`` for the patches glued by the fine
        mediator, ``"keep"`` for the coarse one.
    """

    coarse: Any
    patches: Sequence[Patch] = field(default_factory=list)
    mediator_dirichlet: str = "auto"

    def __post_init__(self) -> None:
        check_protocol(self.coarse, Model, "the coarse model")
        self.patches = list(self.patches)
        for i, p in enumerate(self.patches):
            if not isinstance(p, Patch):
                raise ContractError(
                    f"patch {i} is a {type(p).__name__}; wrap its model in arlequin.Patch(model, "
                    "gluing_width=...)"
                )
        self._loads: list[_Load] = []
        self._dirichlet: list[_Dirichlet] = []
        self._couplings: list[PatchCoupling] | None = None
        self._names = ["coarse"] + [p.name or f"patch{i}" for i, p in enumerate(self.patches)]
        if len(set(self._names)) != len(self._names):
            raise ValueError(f"block names must be unique, got {self._names}")
        self._check_patches_disjoint()
        if self.mediator_dirichlet not in ("auto", "keep", "drop"):
            raise ValueError(
                "mediator_dirichlet must be 'auto', 'keep' or 'drop', got "
                f"{self.mediator_dirichlet!r}"
            )

    # ------------------------------------------------------------------ set-up
    def with_patches(self, patches: Sequence[Patch]) -> ArlequinProblem:
        """A new problem with the same coarse model, ``mediator_dirichlet``, supports and loads
        on other patches (the same number, their blocks named as this problem's: the supports
        and loads given per block apply to the new patches' meshes, their selectors evaluated
        there). Adaptive patches (:mod:`arlequin.problem.adapt`) grow a patch this way."""
        patches = list(patches)
        if len(patches) != len(self.patches):
            raise ValueError(f"with_patches needs {len(self.patches)} patches, got {len(patches)}")
        named = [replace(p, name=p.name or self._names[i + 1]) for i, p in enumerate(patches)]
        new = ArlequinProblem(self.coarse, named, self.mediator_dirichlet)
        new._loads, new._dirichlet = list(self._loads), list(self._dirichlet)
        return new

    @property
    def block_names(self) -> list[str]:
        return list(self._names)

    def _check_patches_disjoint(self) -> None:
        for i, a in enumerate(self.patches):
            for j in range(i + 1, len(self.patches)):
                b = self.patches[j]
                ma, mb = a.model.mesh, b.model.mesh
                if ma.dim() != mb.dim():
                    raise ValueError(
                        f"mismatched dimensions: patch {i} is {ma.dim()}D, patch {j} is {mb.dim()}D"
                    )
                lo = np.maximum(ma.p.min(axis=1), mb.p.min(axis=1))
                hi = np.minimum(ma.p.max(axis=1), mb.p.max(axis=1))
                if np.any(lo >= hi):
                    continue
                loc = locate_points(ma, cell_centroids(mb), tol=0.0)
                loc2 = locate_points(mb, cell_centroids(ma), tol=0.0)
                if loc.inside.any() or loc2.inside.any():
                    raise OverlapError(
                        f"patches {self._names[i + 1]} and {self._names[j + 1]} overlap; "
                        "overlapping patches are not supported (merge them into one patch)"
                    )

    @property
    def couplings(self) -> list[PatchCoupling]:
        """Per-patch overlap, weights and coupling matrices (built on first use)."""
        if self._couplings is None:
            self._couplings = [
                PatchCoupling(self.coarse, p, self._names[i + 1])
                for i, p in enumerate(self.patches)
            ]
        return self._couplings

    def model(self, block: str) -> Any:
        """The model of a block (``"coarse"`` or a patch name)."""
        if block not in self._names:
            raise ValueError(f"unknown block {block!r}; blocks are {self._names}")
        i = self._names.index(block)
        return self.coarse if i == 0 else self.patches[i - 1].model

    def add_dirichlet(
        self,
        block: str,
        where: Callable[[np.ndarray], np.ndarray],
        components: Sequence[int] | None = None,
        value: float | np.ndarray | Callable[[np.ndarray], np.ndarray] = 0.0,
        amplitude: Callable[[float], float] | None = None,
        level: str = "displacement",
    ) -> None:
        """Prescribe displacements (m) (``level="velocity"``: velocities, m/s) on a block's nodes.

        Parameters
        ----------
        block : str
            ``"coarse"`` or a patch name.
        where : callable
            Predicate on node coordinates (dim, n_nodes) -> (n_nodes,) bool.
        components : sequence of int, optional
            Components to prescribe (default all).
        value : float, ndarray (dim,) or callable
            Prescribed value; a callable takes node coordinates (dim, n) and returns (dim, n).
        amplitude : callable, optional
            Time factor a(t); the prescribed value is a(t) * value.
        """
        model = self.model(block)
        nodes = np.nonzero(np.asarray(where(model.mesh.p), dtype=bool))[0]
        if nodes.size == 0:
            raise ValueError(f"Dirichlet condition on {block!r} selects no node")
        self._dirichlet.append(_Dirichlet(block, where, components, value, amplitude, level))

    def add_body_force(
        self,
        force: Any,
        amplitude: Callable[[float], float] | None = None,
        blocks: Sequence[str] | None = None,
    ) -> None:
        """Body force density (N/m³), split between the models by the partition weights.

        ``force`` is a constant vector or a callable of x (dim, n_elems, n_qp).

        Raises
        ------
        ValueError
            For a constant force with the wrong number of components or a non-finite value.
        """
        self._check_vector(force, "body force (N/m^3)")
        self._check_blocks(blocks)
        self._loads.append(_Load("body", force, None, amplitude, blocks))

    def _check_vector(self, value: Any, what: str) -> None:
        if callable(value):
            return
        vec = np.asarray(value, dtype=float).ravel()
        d = int(self.coarse.n_components)
        if vec.size != d:
            raise ValueError(f"{what} must have {d} components, got {vec.tolist()}")
        if not np.all(np.isfinite(vec)):
            raise ValueError(f"{what} must be finite, got {vec.tolist()}")

    def _check_blocks(self, blocks: Sequence[str] | None) -> None:
        for b in blocks or ():
            if b not in self._names:
                raise ValueError(f"unknown block {b!r}; blocks are {self._names}")

    def add_traction(
        self,
        traction: Any,
        where: Callable[[np.ndarray], np.ndarray] | None = None,
        amplitude: Callable[[float], float] | None = None,
        blocks: Sequence[str] | None = None,
    ) -> None:
        """Traction (Pa) on the physical boundary, split by the partition weights in the overlap.

        Applied on the boundary facets (of the coarse mesh and of each patch mesh, on the coarse
        boundary) whose midpoints satisfy ``where`` (default: the whole boundary). ``traction``
        is a constant vector or a callable of (x, n) returning (dim, n_facets, n_qp).

        Raises
        ------
        ValueError
            For a constant traction with the wrong number of components or a non-finite value,
            or a selector ``where`` that matches no boundary facet of the coarse mesh nor of
            any patch (an interior line, a typo in a coordinate).
        """
        self._check_vector(traction, "traction (Pa)")
        self._check_blocks(blocks)
        if where is not None:
            meshes = [self.coarse.mesh] + [p.model.mesh for p in self.patches]
            if not any(self._facets(m, where).size for m in meshes):
                raise ValueError(
                    "the traction selector `where` matches no boundary facet of the coarse mesh "
                    "or of any patch (it is evaluated at facet midpoints, shape (dim, n)): "
                    "tractions act on the physical boundary only"
                )
        self._loads.append(_Load("traction", traction, where, amplitude, blocks))

    # ------------------------------------------------------------------ assembly
    def _load_vectors(self, load: _Load) -> dict[str, np.ndarray]:
        out: dict[str, np.ndarray] = {}
        want = set(self._names if load.blocks is None else load.blocks)
        cmodel = self.coarse
        if "coarse" in want:
            if load.kind == "body":
                # as the stiffness and mass: the coarse cells' own weights, then the overlaps'
                f = cmodel.body_force_vector(load.value, weight=self._coarse_own_weight())
                for pc in self.couplings:
                    f = f + pc.coarse_transfer.T @ pc.integration_model.body_force_vector(
                        load.value, weight=pc.coarse_overlap_weight()
                    )
            else:
                # the whole boundary, less α_fine on the overlap's facets there (every piece
                # of a coarse cell on the boundary is kept, also in a trimmed overlap)
                f = cmodel.traction_vector(self._facets(cmodel.mesh, load.where), load.value)
                for pc in self.couplings:
                    imodel = pc.integration_model
                    facets = self._filter(imodel.mesh, pc.integration_boundary_facets(), load.where)
                    corr = imodel.traction_vector(
                        facets, load.value, weight=pc.weight_function("fine")
                    )
                    f = f - pc.coarse_transfer.T @ corr
            out["coarse"] = f
        for pc in self.couplings:
            if pc.name not in want:
                continue
            fmodel = pc.fine_model
            if load.kind == "body":
                out[pc.name] = fmodel.body_force_vector(load.value, weight=pc.alpha_fine)
            else:
                facets = self._filter(fmodel.mesh, pc.outer_facets, load.where)
                out[pc.name] = fmodel.traction_vector(
                    facets, load.value, weight=pc.weight_function("fine")
                )
        return out

    @staticmethod
    def _facets(mesh, where) -> np.ndarray:
        return ArlequinProblem._filter(mesh, mesh.boundary_facets(), where)

    @staticmethod
    def _filter(mesh, facets: np.ndarray, where) -> np.ndarray:
        if where is None or facets.size == 0:
            return facets
        return facets[np.asarray(where(_facet_midpoints(mesh, facets)), dtype=bool)]

    def _coarse_own_weight(self) -> np.ndarray:
        """Weight of the coarse model's own term at its quadrature points, (n_elems, n_qp): 1,
        except on the coarse cells a patch covers (0, or the floor a trimmed overlap leaves
        them: :attr:`PatchCoupling.coarse_floor`)."""
        own = np.ones(self.coarse.mesh.nelements)
        for pc in self.couplings:
            own[pc.covered_coarse_cells] = pc.coarse_floor
        return np.repeat(own[:, None], self.coarse.scalar_basis().dx.shape[1], axis=1)

    def system(self) -> CoupledSystem:
        """The coupled algebraic system (blocks, coupling and Dirichlet constraints, loads)."""
        couplings = self.couplings
        coarse_terms = [BlockTerm(self.coarse, self._coarse_own_weight())]
        # the coarse model inside each overlap, on the overlap's integration cells
        coarse_terms += [
            BlockTerm(pc.integration_model, pc.coarse_overlap_weight(), pc.coarse_transfer, 1.0)
            for pc in couplings
        ]
        blocks = [Block("coarse", self.coarse, coarse_terms)]
        blocks += [
            Block(pc.name, pc.fine_model, [BlockTerm(pc.fine_model, pc.alpha_fine)])
            for pc in couplings
        ]
        dofmap = self.dofmap()
        n = dofmap.n_dofs

        constraints: list[LinearConstraint] = []
        for pc in couplings:
            cm = pc.coupling
            rows = dofmap.embed("coarse", cm.coarse) - dofmap.embed(pc.name, cm.fine)
            kept = np.nonzero(self.mediator_rows(pc))[0]
            rows = rows.tocsr()[kept]
            # a fine mediator's functions are the patch's own on the band: its dofs, one per
            # row, are where the rows are square (the explicit scheme's impulse basis)
            pivots = (dofmap[pc.name].slice.start + np.asarray(cm.mediator_dofs)[kept]
                      if cm.mediator == "fine" else None)  # fmt: skip
            constraints.append(LinearConstraint(rows.tocsr(), None, f"coupling:{pc.name}",
                                                kind="coupling", pivot_dofs=pivots))  # fmt: skip
        for k, bc in enumerate(self._dirichlet):
            constraints.append(self._dirichlet_rows(bc, dofmap, k))

        parts = []
        for load in self._loads:
            full = dofmap.assemble(self._load_vectors(load), "load vector")
            parts.append((full, load.amplitude))

        def load_fn(t: float, parts=parts, n=n) -> np.ndarray:
            f = np.zeros(n)
            for vec, amp in parts:
                f += vec if amp is None else float(amp(t)) * vec
            return f

        # unloaded: no load function, so that an explicit step does not build and test a
        # vector of zeros at every step
        return CoupledSystem(blocks, constraints, load_fn if parts else None,
                             band_plasticity=self.band_plasticity)  # fmt: skip

    def field_layout(self) -> FieldLayout:
        """What a results folder shows of this problem: each block's mesh with its cell-mean
        partition weight ``alpha``, and the multiplier field of each mediator on the nodes of
        the model whose space carries it."""
        cbasis = self.coarse.scalar_basis()
        c_measure = cbasis.dx.sum(axis=1)
        # the coarse cells' weighted measure: their own term's, then the overlaps'
        coarse_share = (self._coarse_own_weight() * cbasis.dx).sum(axis=1)
        blocks = []
        multipliers = {}
        for pc in self.couplings:
            ibasis = pc.integration_model.scalar_basis()
            coarse_share += np.bincount(
                pc.overlap.coarse_cells,
                weights=(pc.coarse_overlap_weight() * ibasis.dx).sum(axis=1),
                minlength=coarse_share.size,
            )
            fdx = pc.fine_model.scalar_basis().dx
            alpha = (pc.alpha_fine * fdx).sum(axis=1) / fdx.sum(axis=1)
            blocks.append(
                BlockFields(pc.name, pc.fine_model.mesh, pc.n_components, {"alpha": alpha})
            )
            carrier = "coarse" if pc.coupling.mediator == "coarse" else pc.name
            keep = self.mediator_rows(pc)
            multipliers[f"coupling:{pc.name}"] = (carrier, pc.coupling.mediator_dofs[keep])
        coarse = BlockFields(
            "coarse",
            self.coarse.mesh,
            int(self.coarse.n_components),
            {"alpha": coarse_share / c_measure},
        )
        return FieldLayout([coarse, *blocks], multipliers)

    def coarse_yield_ratio(self, u: np.ndarray, yield_stress: float | None = None) -> float | None:
        """The largest von Mises stress of the coarse model outside every patch over the
        smallest initial yield stress of the patches' materials (or ``yield_stress``, Pa), at
        the global displacement ``u`` (m); None when the coarse model gives no stress
        (``stress_at_quadrature``) or no yield stress is known (given, or a patch model's
        ``yield_stress``, :class:`arlequin.contract.SupportsCellStates`). Above 1, the plastic
        zone has outgrown the patches."""
        stress = getattr(self.coarse, "stress_at_quadrature", None)
        yields = [
            float(np.min(p.model.yield_stress(None)))
            for p in self.patches
            if callable(getattr(p.model, "yield_stress", None))
        ]
        if yield_stress is not None:
            yields = [float(yield_stress)]
        if stress is None or not yields:
            return None
        outside = np.ones(self.coarse.mesh.nelements, dtype=bool)
        for pc in self.couplings:
            outside[pc.overlap.coarse_cells] = False
        if not outside.any():
            return 0.0
        vm = von_mises_of(stress(u[self.dofmap()["coarse"].slice])[:, :, outside])
        return float(vm.max() / min(yields))

    def band_plasticity(self, states: dict[str, list[Any]]) -> list[BandPlasticity]:
        """Plastic flow in each J2 patch's gluing band for the blocks' ``states`` (name -> the
        terms' states): :func:`arlequin.coupling.band_plasticity.band_plasticity` of every
        patch whose model tells its plastic strain."""
        bands = (band_plasticity(pc, (states.get(pc.name) or [None])[0]) for pc in self.couplings)
        return [band for band in bands if band is not None]

    def mediator_rows(self, pc: PatchCoupling) -> np.ndarray:
        """Boolean mask of the mediator functions of ``pc`` kept as coupling rows (all of them,
        unless ``mediator_dirichlet="drop"``, or ``"auto"`` with the fine mediator)."""
        dofs = np.asarray(pc.coupling.mediator_dofs)
        mode = self.mediator_dirichlet
        if mode == "keep" or (mode == "auto" and pc.coupling.mediator == "coarse"):
            return np.ones(dofs.size, dtype=bool)
        carrier = "coarse" if pc.coupling.mediator == "coarse" else pc.name
        model = self.model(carrier)
        d = int(model.n_components)
        fixed = np.zeros(int(model.n_dofs), dtype=bool)
        for bc in self._dirichlet:
            if bc.block != carrier or bc.level != "displacement":
                continue
            nodes = np.nonzero(np.asarray(bc.where(model.mesh.p), dtype=bool))[0]
            comps = range(d) if bc.components is None else bc.components
            for c in comps:
                fixed[d * nodes + c] = True
        return ~fixed[dofs]

    def dofmap(self) -> DofMap:
        """The dof layout of the coupled system: the coarse block, then one block per patch."""
        return DofMap.of_models({name: self.model(name) for name in self._names})

    def _dirichlet_rows(self, bc: _Dirichlet, dofmap: DofMap, k: int) -> LinearConstraint:
        model = self.model(bc.block)
        mesh = model.mesh
        nodes = np.nonzero(np.asarray(bc.where(mesh.p), dtype=bool))[0]
        d = int(model.n_components)
        comps = list(range(d)) if bc.components is None else list(bc.components)
        if any(c < 0 or c >= d for c in comps):
            raise ValueError(f"Dirichlet components must lie in [0, {d}), got {comps}")
        dofs = dofmap[bc.block].node_dofs(nodes, comps).T.ravel()
        n = dofmap.n_dofs
        if callable(bc.value):
            vals = (
                np.asarray(bc.value(mesh.p[:, nodes]), dtype=float).reshape(d, -1)[comps].T.ravel()
            )
        else:
            v = np.broadcast_to(np.asarray(bc.value, dtype=float).reshape(-1), (d,))
            vals = np.tile(v[comps], nodes.size)
        rows = sp.csr_matrix(
            (np.ones(dofs.size), (np.arange(dofs.size), dofs)), shape=(dofs.size, n)
        )
        rhs = (
            vals
            if bc.amplitude is None
            else (lambda t, vals=vals, a=bc.amplitude: float(a(t)) * vals)
        )
        return LinearConstraint(
            rows, rhs, f"dirichlet:{bc.block}:{k}", level=bc.level, kind="dirichlet"
        )
