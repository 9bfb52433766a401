"""Which documented exactness conditions a patch breaks (docs/theory.md §3), and the warning.

A uniform stress is reproduced exactly by the discrete Arlequin problem under condition A (a
nested patch with the fine mediator) or condition B (ramp weights whose gradient is one constant
vector over the part of the gluing zone each mediator function sees). :func:`exactness_failures`
checks them on a built :class:`~arlequin.coupling.gluing.PatchCoupling`; the coupling raises one
:class:`ExactnessWarning` per broken condition.
"""

from __future__ import annotations

import logging
from typing import Any, Protocol

import numpy as np
from skfem import Basis

from ..geometry.reference import scalar_element_for
from .fields import scalar_at_quadrature

__all__ = ["ExactnessWarning", "GluedPatch", "exactness_failures", "unheld_band_cells"]


class GluedPatch(Protocol):
    """What the checks read of a patch's coupling: a built
    :class:`~arlequin.coupling.gluing.PatchCoupling` (whose module imports this one, so the
    checks name its members, not its class)."""

    name: str
    mediator: str
    overlap: Any
    coarse_model: Any
    fine_model: Any
    weights: Any
    gluing_cells: np.ndarray
    fine_gluing_cells: np.ndarray

    def _fine_nodal(self, which: str) -> np.ndarray: ...


logger = logging.getLogger(__name__)


class ExactnessWarning(UserWarning):
    """The patch breaks a documented exactness condition: a uniform stress state is not
    reproduced exactly (the message names the condition and a setting that meets it)."""


def exactness_failures(pc: GluedPatch) -> list[str]:
    """The exactness conditions of docs/theory.md this patch breaks ([] if none).

    First, band cells the mediator does not hold (:func:`_unheld_cells`); then the uniform
    stress conditions:

    Condition A: a nested patch with the fine mediator (whose space contains the coarse one
    on S_g), weights constant outside S_g. Condition B: ramp weights whose gradient ∇α_c is
    one constant vector over the part of S_g each mediator function sees (straight bands,
    no function meeting two bands), so that σ·∇α_c lies in the mediator space. User weights
    are not checked (logged).
    """
    return _unheld_cells(pc) + _uniform_stress_failures(pc)


def unheld_band_cells(pc: GluedPatch) -> np.ndarray:
    """Patch cells of the gluing band that their own weight does not hold: nodal weights with
    α_fine = 0 at every vertex (a nested tetrahedral patch's staircase edge), shape (n,) int.

    Such cells carry no stiffness; the coarse mediator constrains only the coarse-scale part
    of the band's patch field, so under it their fine-scale modes deform freely under the
    multipliers' forces (docs/theory.md, "The band's fine-scale modes"). The fine mediator
    holds every patch dof of the band.
    """
    if pc.weights.mode != "nodal":
        return np.zeros(0, dtype=np.int64)
    band = np.asarray(pc.fine_gluing_cells)
    held = np.any(pc._fine_nodal("fine")[pc.fine_model.mesh.t[:, band]] > 0.0, axis=0)
    return band[~held]


def _unheld_cells(pc: GluedPatch) -> list[str]:
    """The warning for :func:`unheld_band_cells` under the coarse mediator."""
    if pc.mediator != "coarse":
        return []
    unheld = unheld_band_cells(pc)
    if unheld.size == 0:
        return []
    fmesh = pc.fine_model.mesh
    x = ", ".join(f"{c:.4g}" for c in fmesh.p[:, fmesh.t[:, unheld[0]]].mean(axis=1))
    return [
        f"{unheld.size} patch cell(s) of the gluing band have α_fine = 0 at every vertex (the "
        f"first at x = ({x}) m) and the coarse mediator does not hold their fine-scale modes: "
        "they deform freely under the multipliers (a plastic patch yields there, measured 12 "
        "to 90 times the single fine mesh's plastic strain); use mediator='fine' (what the "
        "default 'auto' takes here) or weights whose α_fine is positive on every band cell"
    ]


def _uniform_stress_failures(pc: GluedPatch) -> list[str]:
    """Conditions A and B of docs/theory.md §3 (a uniform stress reproduced exactly)."""
    nested = pc.overlap.method == "nested"
    same_space = (
        nested and pc.fine_model.mesh.nelements == np.unique(pc.overlap.coarse_cells).size
    )  # the patch is the coarse mesh itself: both mediators are the fine space
    fine_mediator = pc.mediator == "fine" or same_space
    if nested and fine_mediator:
        return []  # condition A
    name = type(pc.weights).__name__
    if name == "ConstantWeights":
        return [
            "constant weights reproduce a uniform stress exactly only on a nested patch "
            "with the fine mediator (condition A of docs/theory.md; measured errors 1e-3 to "
            "4e-2 otherwise): use weights='ramp' with straight bands, or mediator='fine' "
            "on a nested patch"
        ]
    if name != "RampWeights":
        logger.info("%s: exactness of user weights %s not checked", pc.name, name)
        return []
    return _ramp_failures(pc)


def _ramp_failures(pc: GluedPatch) -> list[str]:
    """Condition B for ramp weights: one weight gradient per mediator function."""
    imesh = pc.overlap.integration_mesh
    cells = pc.gluing_cells
    # P1 gradients are constant on a simplex: one point each (a million integration cells of
    # a non-nested 3D patch); bilinear ones vary: order 2
    simplex = imesh.t.shape[0] == imesh.dim() + 1
    basis = Basis(imesh, scalar_element_for(imesh), elements=cells, intorder=1 if simplex else 2)
    nodal = pc.overlap.fine_transfer @ pc._fine_nodal("coarse")
    grad = scalar_at_quadrature(basis, nodal, gradient=True)  # (d, nc, nq)
    scale = float(np.max(np.abs(grad))) if grad.size else 0.0
    if scale == 0.0:
        return []
    coarse = pc.mediator == "coarse"
    owner = pc.overlap.coarse_cells[cells] if coarse else pc.overlap.fine_cells[cells]
    mesh = pc.coarse_model.mesh if coarse else pc.fine_model.mesh
    nodes = mesh.t[:, owner]  # (n_v, n_gc): the mediator functions over each gluing cell
    n_v, n_gc = nodes.shape
    node_of = nodes.ravel()
    cell_of = np.tile(np.arange(n_gc), n_v)
    lo = np.full((grad.shape[0], mesh.nvertices), np.inf)
    hi = np.full((grad.shape[0], mesh.nvertices), -np.inf)
    g_min, g_max = grad.min(axis=2), grad.max(axis=2)  # (d, n_gc)
    for i in range(grad.shape[0]):
        np.minimum.at(lo[i], node_of, g_min[i, cell_of])
        np.maximum.at(hi[i], node_of, g_max[i, cell_of])
    spread = np.max(np.where(np.isfinite(lo), hi - lo, 0.0), axis=0)
    bad = np.nonzero(spread > 1e-6 * scale)[0]
    if bad.size == 0:
        return []
    worst = int(bad[np.argmax(spread[bad])])
    x = ", ".join(f"{c:.4g}" for c in mesh.p[:, worst])
    which = "coarse" if coarse else "fine"
    return [
        f"{bad.size} {which} mediator function(s) see different gradients of the ramp "
        f"weight on the gluing zone (the worst at x = ({x}) m: the band turns a corner, is "
        "curved, or one function meets two bands), so σ·∇α_c is not in the mediator space "
        "(condition B of docs/theory.md) and a uniform stress is not reproduced exactly"
        + (
            " (with the coarse mediator on a non-nested 3D patch whose band turns edges, the "
            "error reached the size of the solution itself)"
            if coarse and pc.overlap.method != "nested" and mesh.dim() == 3
            else ""
        )
        + ": use mediator='fine' (exact on a nested patch, condition A; on a non-nested one "
        "far closer), or straight bands whose "
        f"{which} mediator functions each meet a single band"
    ]
