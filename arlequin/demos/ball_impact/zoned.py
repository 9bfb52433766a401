"""One mesh, two laws: finite-strain J2 on the cells of a zone, linear elastic on the others.

The block of the ``mono-zoned`` and ``graded`` references of the ball impact: one conforming
mesh (uniformly fine, or graded), the J2 model on the sub-mesh of the zone's cells (a term of
the block through the selection of its nodes' dofs), the linear-elastic model on the whole mesh
weighted by the indicator of the other cells, so that every cell has exactly one law. The
elastic term's weighted stiffness is assembled once (:class:`FrozenLinear`). Duck-types the part
of :class:`~arlequin.ArlequinProblem` that :class:`~arlequin.MultiBodyProblem` uses (``system``,
``field_layout``, ``model``, ``add_dirichlet``). SI units.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp

from ...models import FiniteStrainJ2, J2Material, LinearElastic
from ...problem.arlequin_problem import ArlequinProblem
from ...problem.system import Block, BlockTerm, CoupledSystem

__all__ = ["FrozenLinear", "ZonedBody"]


class FrozenLinear:
    """A linear model whose weighted stiffness is assembled once: the internal force of a
    linear term inside a nonlinear block (whose terms the integrators evaluate one by one)."""

    def __init__(self, model: Any, weight: Any) -> None:
        self.model = model
        self.stiffness_matrix = sp.csr_matrix(model.stiffness(weight))

    def __getattr__(self, name: str) -> Any:
        return getattr(self.model, name)

    def internal_force(self, u: np.ndarray, state=None, weight=None):
        """K(α) u (N) with the stiffness assembled at construction, and the unchanged state."""
        return self.stiffness_matrix @ u, state


class ZonedBody:
    """One axisymmetric mesh: finite-strain J2 on ``zone`` cells, linear elastic elsewhere.

    Parameters
    ----------
    mesh : skfem.MeshQuad
    zone : ndarray of int
        The J2 cells.
    material : J2Material
        The J2 law; the other cells use its elastic part.
    """

    def __init__(self, mesh, zone: np.ndarray, material: J2Material) -> None:
        zone = np.unique(np.asarray(zone, dtype=np.int64))
        if zone.size == 0:
            raise ValueError("the J2 zone of a zoned body selects no cell")
        self.mesh = mesh
        self.zone_cells = zone
        self.elastic = LinearElastic(mesh, material.elastic, kind="axisymmetric")
        sub, nodes = mesh.restrict(zone, return_mapping=True)
        self.zone_mesh = sub
        self.j2 = FiniteStrainJ2(sub, material, "axisymmetric", True)
        nq = self.elastic.scalar_basis().dx.shape[1]
        outside = np.ones((mesh.nelements, nq))
        outside[zone] = 0.0
        self.outside = outside
        rows = np.arange(2 * nodes.size)
        cols = (2 * np.asarray(nodes)[:, None] + np.arange(2)[None, :]).ravel()
        #: the J2 sub-mesh's dofs from the mesh's (node-interleaved, 2 per node)
        self.transfer = sp.csr_matrix((np.ones(rows.size), (rows, cols)),
                                      shape=(rows.size, self.elastic.n_dofs))  # fmt: skip
        self.problem = ArlequinProblem(self.elastic, [])

    def model(self, block: str = "coarse") -> Any:
        """The mesh's elastic model (the block's dof owner)."""
        return self.problem.model(block)

    def add_dirichlet(self, block: str, where, components=None, **kwargs: Any) -> None:
        """As :meth:`ArlequinProblem.add_dirichlet` on the whole mesh."""
        self.problem.add_dirichlet(block, where, components=components, **kwargs)

    def system(self) -> CoupledSystem:
        """One block ``"coarse"`` with the elastic and the J2 terms, the problem's rows."""
        base = self.problem.system()
        terms = [BlockTerm(FrozenLinear(self.elastic, self.outside), self.outside),
                 BlockTerm(self.j2, None, self.transfer)]  # fmt: skip
        return CoupledSystem([Block("coarse", self.elastic, terms)], base.constraints, base.load)

    def field_layout(self):
        """The mesh's fields (as the single-model problem's)."""
        return self.problem.field_layout()
