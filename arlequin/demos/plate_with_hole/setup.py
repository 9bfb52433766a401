"""From a configuration to the problem of the plate with a hole: meshes, models, supports, load.

The quarter plate [0, W]² minus the quarter disc r < a has two symmetry lines, x = 0 (u_x = 0)
and y = 0 (u_y = 0), held on every model; the traction (S, 0) acts on x = W (the coarse
model's edge in the Arlequin run), the hole and y = W are free.

Models:

``arlequin``  a coarse linear-elastic model of the whole plate (the quasi-uniform mesh of
              :func:`~.meshes.plate_mesh`), and a J2 patch: the coarse cells in the square
              [0, R]² (R the grid line at or below ``patch_radius``) refined ``levels`` times,
              the hole nodes projected onto the circle (nested overlap), glued in its
              outermost layer of coarse cells (ramp weights from ``edge_weight`` on its outer
              edge, coarse mediator, L2 by default).
``mono``      the whole coarse mesh refined ``levels`` times, J2 everywhere: uniformly fine at
              the patch's resolution.
``graded``    one conforming mesh (:func:`~.meshes.graded_plate_mesh`): the patch's cells
              with the J2 model, the rest a tensor grid refined along the patch only, with the
              elastic model (one block, two terms, :class:`ZonedPlate`).
"""

from __future__ import annotations

import logging
import warnings
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sp
import skfem

from ...coupling.exactness import ExactnessWarning
from ...coupling.gluing import Patch
from ...coupling.weights import RampWeights
from ...models import IsotropicElastic, J2Material, LinearElastic
from ...problem.adapt import AdaptivePatch
from ...problem.arlequin_problem import ArlequinProblem
from ...problem.system import Block, BlockTerm, CoupledSystem
from ..adaptive_options import adaptive_patch
from .meshes import graded_plate_mesh, hole_nodes, plate_mesh, refine_projected, square_radius

if TYPE_CHECKING:  # annotations only: the configuration runs this module
    from .config import PlateWithHoleConfig

__all__ = [
    "DENSITY",
    "PlateSetup",
    "ZonedPlate",
    "area",
    "build",
    "j2_factory",
    "loaded_edge_average",
]

logger = logging.getLogger(__name__)

#: Steel's density (kg/m³): recorded with the materials, unused by a quasi-static run.
DENSITY = 7850.0


class _FrozenElastic:
    """A linear-elastic term inside a nonlinear block: its weighted stiffness assembled once,
    the internal force K u and the tangent K."""

    is_linear = True

    def __init__(self, model: LinearElastic, weight: np.ndarray) -> None:
        self.model = model
        self.matrix = sp.csr_matrix(model.stiffness(weight))

    def __getattr__(self, name: str) -> Any:
        return getattr(self.model, name)

    def internal_force(self, u: np.ndarray, state=None, weight=None):
        return self.matrix @ u, state

    def tangent(self, u: np.ndarray, state=None, weight=None) -> sp.csr_matrix:
        return self.matrix

    def initial_state(self, weight=None) -> None:
        return None


class ZonedPlate:
    """One plane-strain mesh: the J2 model on the ``zone`` cells, linear elastic on the others
    (its stiffness, weighted by the other cells' indicator, assembled once). The block
    ``"coarse"`` has two terms: the elastic one, and the J2 model on the zone's sub-mesh through
    the restriction of the block's dofs to the zone's nodes (its ``transfer``). Duck-types the
    part of :class:`~arlequin.ArlequinProblem` that the solvers and the writers use."""

    def __init__(self, mesh: skfem.MeshQuad, zone: np.ndarray, j2_model: Any,
                 elastic: LinearElastic) -> None:  # fmt: skip
        self.mesh, self.zone = mesh, np.asarray(zone)
        self.elastic = elastic
        sub, nodes = mesh.restrict(self.zone, return_mapping=True)
        self.j2 = j2_model(sub)
        nq = elastic.scalar_basis().dx.shape[1]
        outside = np.ones((mesh.nelements, nq))
        outside[self.zone] = 0.0
        self.outside = outside
        rows = np.arange(2 * nodes.size)
        cols = (2 * np.asarray(nodes)[:, None] + np.arange(2)[None, :]).ravel()
        self.transfer = sp.csr_matrix((np.ones(rows.size), (rows, cols)),
                                      shape=(rows.size, elastic.n_dofs))  # fmt: skip
        self.problem = ArlequinProblem(elastic, [])
        self._system: CoupledSystem | None = None

    def add_dirichlet(self, block: str, where, components=None, **kwargs: Any) -> None:
        """Prescribe displacements on the plate's nodes (as ``ArlequinProblem.add_dirichlet``)."""
        self.problem.add_dirichlet(block, where, components=components, **kwargs)

    def add_traction(self, traction, where=None) -> None:
        """A traction (Pa) on the plate's boundary facets selected by ``where``."""
        self.problem.add_traction(traction, where=where)

    def system(self) -> CoupledSystem:
        """One block ``"coarse"``: the elastic term outside the zone and the J2 term."""
        if self._system is None:
            base = self.problem.system()
            terms = [BlockTerm(_FrozenElastic(self.elastic, self.outside), self.outside),
                     BlockTerm(self.j2, None, self.transfer)]  # fmt: skip
            self._system = CoupledSystem([Block("coarse", self.elastic, terms)],
                                         base.constraints, base.load)  # fmt: skip
        return self._system

    def field_layout(self):
        """The plate's mesh and its cell data for a results folder."""
        return self.problem.field_layout()


@dataclass
class PlateSetup:
    """What a run needs besides its configuration.

    Attributes
    ----------
    problem : ArlequinProblem or ZonedPlate
    plastic_model : SmallStrainJ2
        The J2 model (the patch's, the fine mesh's or the graded mesh's zone).
    plastic_block : str
        Its block (``"patch0"`` or ``"coarse"``).
    plastic_term : int
        Its term in the block (its state: ``solver.states[block][term]``).
    loaded_model : model
        The model whose edge x = W carries the traction (the displacement is read there).
    coarse : skfem.MeshQuad
        The coarse mesh (drawn under the plastic zone).
    n_elements : int
        Cells of the run (every model's).
    patch_fraction : float
        The J2 region's share of the plate's area (1 for ``mono``).
    zone_cells : ndarray or None
        Graded: the zone's cells in the mesh (the J2 sub-mesh's cell k is ``zone_cells[k]``).
    adapt : AdaptivePatch or None
        With ``adaptive``: the patch that grows from its seed, the coarse ring at the hole
        (refined with the hole's new nodes on the circle, as the fixed patch).
    """

    problem: Any
    plastic_model: Any
    plastic_block: str
    plastic_term: int
    loaded_model: Any
    coarse: skfem.MeshQuad
    n_elements: int
    patch_fraction: float
    zone_cells: np.ndarray | None = None
    adapt: AdaptivePatch | None = None

    def follow(self, adapt: AdaptivePatch) -> None:
        """After a growth: the problem, the J2 model, the cell count and the patch's share of
        the plate of the grown patch."""
        self.problem = adapt.problem
        self.plastic_model = self.problem.patches[0].model
        mesh = self.plastic_model.mesh
        self.n_elements = int(self.coarse.nelements + mesh.nelements)
        self.patch_fraction = area(mesh) / area(self.coarse)


def j2_factory(config: PlateWithHoleConfig):
    """The J2 model of a mesh (small strain with B-bar: plain bilinear cells lock under
    isochoric plastic flow)."""
    material = J2Material(config.young, config.poisson, DENSITY, config.yield_stress,
                          config.hardening)  # fmt: skip

    def make(mesh):
        if config.material == "finite-strain":
            from ...models import FiniteStrainJ2

            return FiniteStrainJ2(mesh, material, kind="plane_strain")
        from ...models import SmallStrainJ2

        return SmallStrainJ2(mesh, material, kind="plane_strain", bbar=True)

    return make


def area(mesh: Any) -> float:
    """The area (m²) of a quadrilateral mesh (shoelace formula)."""
    p = mesh.p[:, mesh.t]
    x, y = p[0], p[1]
    return float(0.5 * np.abs(np.sum(x * np.roll(y, -1, axis=0) - y * np.roll(x, -1, axis=0),
                                     axis=0)).sum())  # fmt: skip


def build(config: PlateWithHoleConfig) -> PlateSetup:
    """The problem of ``config`` (supports, and the traction at λ = 1: the final load S)."""
    a, w, lv = config.radius, config.width, config.levels
    coarse, lines = plate_mesh(a, config.n_theta, config.n_radial, w, config.block)
    if config.adaptive:  # the seed: the coarse cells on the hole (its first ring)
        cells = np.nonzero(np.isin(coarse.t, hole_nodes(coarse, a)).any(axis=0))[0]
    else:
        cells = np.nonzero(square_radius(coarse) <= config.patch_square * (1.0 + 1e-12))[0]
    make_j2 = j2_factory(config)
    elastic = IsotropicElastic(config.young, config.poisson, DENSITY)
    kind = "plane_strain"
    total = area(coarse)
    zone = None
    if config.model == "mono":
        plastic = make_j2(refine_projected(coarse, lv, a))
        problem = ArlequinProblem(plastic, [])
        blocks, block, loaded, n_el = ["coarse"], "coarse", plastic, plastic.mesh.nelements
        fraction, term = 1.0, 0
    elif config.model == "graded":
        mesh, zone = graded_plate_mesh(coarse, lines, a, lv, cells)
        problem = ZonedPlate(mesh, zone, make_j2, LinearElastic(mesh, elastic, kind))
        plastic, blocks, block, term = problem.j2, ["coarse"], "coarse", 1
        loaded, n_el = problem.elastic, mesh.nelements
        fraction = area(plastic.mesh) / total
    else:
        plastic = make_j2(refine_projected(coarse, lv, a, cells=cells))
        # the gluing band: the patch's outermost layers of coarse cells
        band = config.gluing_rings * config.coarse_size
        weights = RampWeights(edge=config.edge_weight)
        patch = Patch(plastic, gluing_width=band, coupling=config.coupling, weights=weights,
                      overlap_method="nested")  # fmt: skip
        problem = ArlequinProblem(LinearElastic(coarse, elastic, kind), [patch])
        with warnings.catch_warnings(record=True) as caught:
            # the coarse mediator on the curved band does not reproduce a uniform stress
            # exactly (ExactnessWarning): a patch-test condition, not this problem's; logged
            warnings.simplefilter("always", ExactnessWarning)
            problem.couplings  # noqa: B018
        for warning in caught:
            logger.info("%s", warning.message)
        blocks, block, term = ["coarse", "patch0"], "patch0", 0
        loaded = problem.model("coarse")
        n_el = coarse.nelements + plastic.mesh.nelements
        fraction = area(plastic.mesh) / total
    tol = 1e-9 * a
    for name in blocks:
        problem.add_dirichlet(name, lambda x: np.isclose(x[0], 0.0, atol=tol), components=[0])
        problem.add_dirichlet(name, lambda x: np.isclose(x[1], 0.0, atol=tol), components=[1])
    s = config.load
    problem.add_traction(np.array([s, 0.0]), where=lambda x: np.isclose(x[0], w, atol=tol))
    adapt = _adaptive_patch(config, coarse, make_j2) if config.adaptive else None
    return PlateSetup(problem, plastic, block, term, loaded, coarse, int(n_el), float(fraction),
                      zone, adapt)  # fmt: skip


def _adaptive_patch(config: PlateWithHoleConfig, coarse: Any, make_j2: Any) -> AdaptivePatch:
    """The adaptation of the seed patch (the options of ``config``): new cells refined with the
    hole's new nodes on the circle, as the seed."""
    a, levels = config.radius, config.levels
    return adaptive_patch(
        config,
        model_factory=make_j2,
        levels=levels,
        refine=lambda cells: refine_projected(coarse, levels, a, cells=cells),
        # grow when the plastic zone comes within one coarse cell of the band (a load step
        # moves the front by several fine cells: closer, it would enter the band and the step
        # be computed again)
        band_cells=2**levels,
        closure=fill_notches(coarse),
        # the band's outer half, where α_f < 1/2, yields spuriously where the coarse stress
        # is 0.85 σy (the multipliers' forces on a vanishing fine stiffness): disregarded
        band_weight=0.5,
    )


def fill_notches(mesh: Any):
    """The adaptive patch's closure: the coarse cells outside the patch whose neighbours
    across two opposite edges, or across three of their four edges, are in it join it, until
    none is (a notch or a slot one cell wide, whose band would fold onto itself). A cell in
    a re-entrant corner (two adjacent edges) stays out: filling those, iterated, gives back the
    bounding rectangle of any staircase, and the patch would not follow the 45° shear bands."""
    t2f, f2t = mesh.t2f, mesh.f2t
    # the cell across each of a cell's four edges (-1 on the plate's boundary); t2f lists a
    # quad's edges in turn round it, so edges 0 and 2, 1 and 3 are opposite
    across = np.where(f2t[0, t2f] == np.arange(mesh.nelements), f2t[1, t2f], f2t[0, t2f])

    def closure(mask: np.ndarray) -> np.ndarray:
        mask = mask.copy()
        while True:
            inside = (across >= 0) & mask[np.maximum(across, 0)]
            add = (inside[0] & inside[2]) | (inside[1] & inside[3]) | (inside.sum(axis=0) >= 3)
            add &= ~mask
            if not add.any():
                return mask
            mask |= add

    return closure


def loaded_edge_average(setup: PlateSetup, system: Any, width: float) -> np.ndarray:
    """The row vector e with e · u the mean x-displacement (m) of the edge x = W: the nodal
    forces of a unit x traction on that edge over its length."""
    model = setup.loaded_model
    mesh = model.mesh
    bf = mesh.boundary_facets()
    mid = mesh.p[:, mesh.facets[:, bf]].mean(axis=1)
    edge = bf[np.isclose(mid[0], width, atol=1e-9 * width)]
    f = model.traction_vector(edge, np.array([1.0, 0.0]))
    e = np.zeros(system.n_dofs)
    e[system.block("coarse").dofs] = f / f.sum()
    return e
