"""One patch glued to the coarse model: its coupling (the patch's description, :class:`Patch`,
lives in :mod:`arlequin.patches` and is re-exported here).

:class:`PatchCoupling` builds, for one patch, everything that ties it to the coarse model: the
overlap (the shared integration mesh, :mod:`arlequin.overlap`), the classification of the patch
boundary (on the coarse boundary, or interior), the gluing zone (a band along the interior
boundary), the partition weights at every quadrature point (:mod:`arlequin.weights`) and the
coupling matrices (:mod:`arlequin.coupling`). All quantities are SI.
"""

from __future__ import annotations

import logging
import warnings
from collections.abc import Callable
from functools import cached_property
from typing import Any

import numpy as np
import scipy.sparse as sp
from skfem import Basis

from .coupling import CouplingMatrices, MediatorError, coupling_matrices
from .geometry import distance_to_facets, facet_coordinates, outward_normals
from .locate import cell_centroids, cell_sizes, locate_points
from .overlap import Overlap, build_overlap
from .patches import Patch
from .reference import scalar_element_for
from .system import BlockTerm
from .weights import PartitionWeights, check_partition_of_unity

__all__ = ["ExactnessWarning", "PatchCoupling"]  # Patch: arlequin.patches (imported here too)


class ExactnessWarning(UserWarning):
    """The patch breaks a documented exactness condition: a uniform stress state is not
    reproduced exactly (the message names the condition and a setting that meets it)."""

logger = logging.getLogger(__name__)


class PatchCoupling:
    """Everything computed for one patch: overlap, weights, gluing zone, coupling matrices.

    Built by :class:`ArlequinProblem`; exposed for post-processing and tests.
    """

    def __init__(self, coarse_model: Any, patch: Patch, name: str) -> None:
        self.patch = patch
        self.name = name
        self.coarse_model = coarse_model
        self.fine_model = patch.model
        self.weights: PartitionWeights = patch.weights  # type: ignore[assignment]
        cmesh, fmesh = coarse_model.mesh, patch.model.mesh
        self.overlap: Overlap = build_overlap(
            cmesh, fmesh, patch.overlap_method, patch.boundary_tol
        )
        self.n_components = int(coarse_model.n_components)
        if int(patch.model.n_components) != self.n_components:
            raise ValueError(
                f"mismatched dimensions: coarse model has {self.n_components} displacement "
                f"components, patch {name} has {patch.model.n_components}"
            )
        if coarse_model.kind != patch.model.kind:
            raise ValueError(
                f"mismatched kinematics: coarse kind={coarse_model.kind!r}, "
                f"patch kind={patch.model.kind!r}"
            )
        self.axisymmetric = coarse_model.kind == "axisymmetric"
        self._classify_boundary()
        self._gluing_zone()
        self.integration_model = coarse_model.with_mesh(self.overlap.integration_mesh)
        self._evaluate_weights()
        length = patch.length if patch.length is not None else self.default_h1_length()
        self.coupling: CouplingMatrices = coupling_matrices(
            self.overlap,
            self.gluing_cells,
            self.n_components,
            patch.coupling,
            length,
            patch.mediator,
            self.axisymmetric,
        )
        self.exactness_failures = self._diagnose_exactness()
        for failure in self.exactness_failures:
            warnings.warn(f"{self.name}: {failure}", ExactnessWarning, stacklevel=3)

    # ------------------------------------------------------------------ exactness
    def _diagnose_exactness(self) -> list[str]:
        """The exactness conditions of docs/theory.md this patch breaks ([] if none).

        Condition A: a nested patch with the fine mediator (whose space contains the coarse one
        on S_g), weights constant outside S_g. Condition B: ramp weights whose gradient ∇α_c is
        one constant vector over the part of S_g each mediator function sees (straight bands,
        no function meeting two bands), so that σ·∇α_c lies in the mediator space. User weights
        are not checked (logged).
        """
        nested = self.overlap.method == "nested"
        same_space = nested and self.fine_model.mesh.nelements == np.unique(
            self.overlap.coarse_cells
        ).size  # the patch is the coarse mesh itself: both mediators are the fine space
        fine_mediator = self.patch.mediator == "fine" or same_space
        if nested and fine_mediator:
            return []  # condition A
        name = type(self.weights).__name__
        if name == "ConstantWeights":
            return [
                "constant weights reproduce a uniform stress exactly only on a nested patch "
                "with the fine mediator (condition A of docs/theory.md; measured errors 1e-3 to "
                "4e-2 otherwise): use weights='ramp' with straight bands, or mediator='fine' "
                "on a nested patch"
            ]
        if name != "RampWeights":
            logger.info("%s: exactness of user weights %s not checked", self.name, name)
            return []
        return self._diagnose_ramp()

    def _diagnose_ramp(self) -> list[str]:
        """Condition B for ramp weights: one weight gradient per mediator function."""
        imesh = self.overlap.integration_mesh
        cells = self.gluing_cells
        basis = Basis(imesh, scalar_element_for(imesh), elements=cells, intorder=2)
        nodal = self.weights.alpha_coarse(imesh.p, self._node_distance(imesh), self.gluing_width)
        grad = np.asarray(basis.interpolate(np.asarray(nodal, dtype=float)).grad)  # (d, nc, nq)
        scale = float(np.max(np.abs(grad))) if grad.size else 0.0
        if scale == 0.0:
            return []
        coarse = self.patch.mediator == "coarse"
        owner = self.overlap.coarse_cells[cells] if coarse else self.overlap.fine_cells[cells]
        mesh = self.coarse_model.mesh if coarse else self.fine_model.mesh
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
            + (" (with the coarse mediator on a non-nested 3D patch whose band turns edges, the "
               "error reached the size of the solution itself)" if coarse and
               self.overlap.method != "nested" and mesh.dim() == 3 else "")
            + ": use mediator='fine' (exact on a nested patch, condition A; on a non-nested one "
            "far closer), or straight bands whose "
            f"{which} mediator functions each meet a single band"
        ]

    def default_h1_length(self) -> float:
        """Default H1 coupling length ℓ (m): the mean coarse cell size on the gluing zone.

        Cell size = (cell measure)^(1/dim). A length of the order of the gluing width (the other
        common choice) weights the strain term so heavily that waves reflect at the band: in the
        1D wave check (ratio 4 and 8, band of 10 coarse cells, pulses of 10 cells) ℓ = the band
        width reflects 1.7e-4 and 2.5e-4 of the incident energy, ℓ = one coarse cell 3.0e-5 and
        4.5e-5 (docs/dynamics.md). Patch tests are exact for any ℓ.
        """
        parents = np.unique(self.overlap.coarse_cells[self.gluing_cells])
        dx = self.coarse_model.scalar_basis().dx.sum(axis=1)[parents]
        dim = self.coarse_model.mesh.dim()
        if self.axisymmetric:
            # the measure carries 2π r: use the cell's plane area instead
            c = cell_centroids(self.coarse_model.mesh)[0, parents]
            dx = dx / (2.0 * np.pi * np.maximum(c, 1e-300))
        return float(np.mean(dx ** (1.0 / dim)))

    # ------------------------------------------------------------------ geometry
    def on_coarse_boundary(self, x: np.ndarray) -> np.ndarray:
        """Whether points x (dim, n) lie on the coarse mesh's boundary (within boundary_tol h)."""
        cmesh = self.coarse_model.mesh
        dist = distance_to_facets(x, self._coarse_facets)
        loc = locate_points(cmesh, x, tol=max(self.patch.boundary_tol, 1e-6))
        h = np.where(loc.cells >= 0, self._coarse_h[np.maximum(loc.cells, 0)], self._coarse_h.max())
        return dist <= self.patch.boundary_tol * h

    def facets_on_coarse_boundary(self, mesh, facets: np.ndarray) -> np.ndarray:
        """Which boundary facets of a patch-side mesh lie on the coarse boundary, (n_f,) bool.

        A facet does when its midpoint is within ``boundary_tol`` × the local coarse cell size
        h of the coarse boundary *and* the point at that distance beyond the midpoint, along
        the facet's outward normal, lies outside the coarse mesh. The second test does not
        depend on the patch's cell size: an interior facet that meets the coarse boundary at a
        vertex (a strip patch spanning the domain) has its probe inside the coarse mesh
        whatever the mesh ratio, and faceted curved boundaries (patch nodes projected onto the
        true curve, off the coarse facets by much less than h) are still recognised.
        """
        facets = np.asarray(facets, dtype=np.int64)
        mid = mesh.p[:, mesh.facets[:, facets]].mean(axis=1)
        on = self.on_coarse_boundary(mid)
        if not on.any():
            return on
        cmesh = self.coarse_model.mesh
        near = np.nonzero(on)[0]
        loc = locate_points(cmesh, mid[:, near], tol=max(self.patch.boundary_tol, 1e-6))
        h = np.where(loc.cells >= 0, self._coarse_h[np.maximum(loc.cells, 0)], self._coarse_h.max())
        probe = mid[:, near] + self.patch.boundary_tol * h * outward_normals(mesh, facets[near])
        on[near] = ~locate_points(cmesh, probe, tol=0.0).inside
        return on

    def _classify_boundary(self) -> None:
        fmesh = self.fine_model.mesh
        self._coarse_facets = facet_coordinates(self.coarse_model.mesh)
        self._coarse_h = cell_sizes(self.coarse_model.mesh)
        bfacets = fmesh.boundary_facets()
        on = self.facets_on_coarse_boundary(fmesh, bfacets)
        self.outer_facets = bfacets[on]
        self.interior_facets = bfacets[~on]
        self._interior_coords = facet_coordinates(fmesh, self.interior_facets)

    def distance(self, x: np.ndarray, cap: float | None = None) -> np.ndarray:
        """Distance (m) from points x (dim, ...) to the patch's interior boundary, shape (...).

        With ``cap``, distances beyond it are lower bounds above it (weights saturate there).
        """
        shape = x.shape[1:]
        flat = x.reshape(x.shape[0], -1)
        return distance_to_facets(flat, self._interior_coords, cap=cap).reshape(shape)

    def _cached_distance(self, kind: str, mesh, points) -> np.ndarray:
        """Capped distances of a mesh's nodes or centroids, computed once per mesh (the cache
        holds the mesh, so that its id cannot be reused by another one)."""
        key = (kind, id(mesh))
        hit = self._distance_cache.get(key)
        if hit is None or hit[0] is not mesh:
            hit = (mesh, self.distance(points(mesh), self._distance_cap))
            self._distance_cache[key] = hit
        return hit[1]

    def _node_distance(self, mesh) -> np.ndarray:
        return self._cached_distance("nodes", mesh, lambda m: m.p)

    def _centroid_distance(self, mesh) -> np.ndarray:
        return self._cached_distance("cells", mesh, cell_centroids)

    def _centroids_within(
        self, mesh, centroids: np.ndarray, d_nodes: np.ndarray, width: float
    ) -> np.ndarray:
        """Cells whose centroid lies within ``width`` of the interior boundary, shape (n_cells,).

        The distance is 1-Lipschitz, so the vertex distances bound the centroid's:
        max_v (d_v − |c − v|) ≤ d_c ≤ min_v (d_v + |c − v|). Only the cells these bounds leave
        undecided (a thin layer along the band's inner edge) need the exact centroid distance.
        """
        r = np.linalg.norm(mesh.p[:, mesh.t] - centroids[:, None, :], axis=0)  # (n_v, n_cells)
        dv = d_nodes[mesh.t]
        lower = np.max(dv - r, axis=0)
        upper = np.min(dv + r, axis=0)
        inside = upper < width
        undecided = ~inside & (lower < width)
        if np.any(undecided):
            exact = self.distance(centroids[:, undecided], self._distance_cap)
            inside[np.nonzero(undecided)[0][exact < width]] = True
        return inside

    def _gluing_zone(self) -> None:
        fmesh = self.fine_model.mesh
        centroids = cell_centroids(fmesh)
        self._distance_cache: dict = {}
        # distances only matter up to the band width (weights saturate beyond it): exact up to
        # the width plus one fine cell, lower bounds beyond
        self._distance_cap = (
            None
            if self.patch.gluing_width is None
            else float(self.patch.gluing_width) + float(cell_sizes(fmesh).max())
        )
        if self.patch.gluing_region is not None:
            fine_gluing = np.asarray(self.patch.gluing_region(centroids), dtype=bool)
            d_nodes = (
                self._node_distance(fmesh)
                if self.interior_facets.size
                else np.zeros(fmesh.nvertices)
            )
            width = float(d_nodes[fmesh.t[:, fine_gluing]].max()) if fine_gluing.any() else 0.0
        else:
            if self.interior_facets.size == 0:
                raise MediatorError(
                    f"empty gluing zone for {self.name}: the patch boundary has no part inside the "
                    "coarse domain (give a gluing_region instead of a gluing_width)"
                )
            w = float(self.patch.gluing_width)
            d_nodes = self._node_distance(fmesh)
            fine_gluing = self._centroids_within(fmesh, centroids, d_nodes, w)
            # snap: the band's inner edge goes through the outer vertices of the selected cells
            width = float(d_nodes[fmesh.t[:, fine_gluing]].max()) if fine_gluing.any() else 0.0
            if fine_gluing.any() and abs(width - w) > 1e-9 * w:
                logger.info("%s: gluing width %.6g m snapped to %.6g m", self.name, w, width)
        if not fine_gluing.any() or width <= 0.0:
            raise MediatorError(
                f"empty gluing zone for {self.name}: no patch cell lies within the gluing band "
                f"(gluing_width={self.patch.gluing_width})"
            )
        self.gluing_width = width
        self.fine_gluing_cells = np.nonzero(fine_gluing)[0]
        self.gluing_cells = np.nonzero(fine_gluing[self.overlap.fine_cells])[0]
        if self.gluing_cells.size == 0:
            raise MediatorError(
                f"empty gluing zone for {self.name}: it does not overlap the coarse mesh"
            )

    # ------------------------------------------------------------------ weights
    def _weights_at(self, basis, which: str) -> np.ndarray:
        """α_which at the quadrature points of a scalar cell basis, shape (n_elems, n_qp)."""
        mesh = basis.mesh
        fn = self.weights.alpha_coarse if which == "coarse" else self.weights.alpha_fine
        mode = self.weights.mode
        if mode == "nodal":
            nodal = fn(mesh.p, self._node_distance(mesh), self.gluing_width)
            return np.asarray(basis.interpolate(np.asarray(nodal, dtype=float)))
        if mode == "cell":
            c = cell_centroids(mesh)
            per_cell = np.asarray(
                fn(c, self._centroid_distance(mesh), self.gluing_width), dtype=float
            )
            return np.repeat(per_cell[:, None], basis.dx.shape[1], axis=1)
        x = np.asarray(basis.global_coordinates())
        return np.broadcast_to(
            fn(x, self.distance(x, self._distance_cap), self.gluing_width), basis.dx.shape
        ).copy()

    def weight_function(self, which: str) -> Callable[[np.ndarray], np.ndarray]:
        """Pointwise α_which(x) for x (dim, ...) (used on boundary facets)."""
        fn = self.weights.alpha_coarse if which == "coarse" else self.weights.alpha_fine
        return lambda x: fn(x, self.distance(x, self._distance_cap), self.gluing_width)

    def _evaluate_weights(self) -> None:
        ibasis = self.integration_model.scalar_basis()
        alpha_c = self._weights_at(ibasis, "coarse")
        alpha_f = self._weights_at(ibasis, "fine")
        check_partition_of_unity(alpha_c, alpha_f, np.asarray(ibasis.mapping.F(ibasis.X)))
        self.alpha_fine_overlap = alpha_f
        self.alpha_coarse_overlap = alpha_c
        self.alpha_fine = self._weights_at(self.fine_model.scalar_basis(), "fine")

    # ------------------------------------------------------------------ operators
    @cached_property
    def coarse_transfer(self) -> sp.csr_matrix:
        """Vector transfer coarse dofs -> integration-mesh dofs."""
        return self.overlap.vector_transfer("coarse", self.n_components)

    @cached_property
    def covered_coarse_cells(self) -> np.ndarray:
        """Coarse cells entirely covered by the integration mesh (boolean, (n_coarse_cells,)).

        On these the coarse model's terms are integrated on the overlap cells only, with weight
        α_coarse; on partly covered cells (non-nested overlaps) the overlap part −α_fine is
        subtracted from the full-cell integral. Never subtracting on fully covered cells keeps
        the weighted coarse operators positive even where Gauss quadrature is not exact
        (distorted quadrilaterals) and α_coarse = ε is small.
        """
        cmesh = self.coarse_model.mesh
        imodel = self.integration_model
        i_measure = np.bincount(
            self.overlap.coarse_cells,
            weights=imodel.scalar_basis().dx.sum(axis=1),
            minlength=cmesh.nelements,
        )
        c_measure = self.coarse_model.scalar_basis().dx.sum(axis=1)
        # >=: a patch whose nodes were projected onto a convex curved boundary can cover a
        # coarse cell by more than its measure; subtracting there would give a negative weight
        return i_measure >= (1.0 - 1e-9) * c_measure

    def coarse_overlap_term(self) -> BlockTerm:
        """The coarse model's contribution inside the overlap, integrated on the overlap cells.

        Weight α_coarse on the overlap cells of fully covered coarse cells, −α_fine on those of
        partly covered ones (see :attr:`covered_coarse_cells`).
        """
        covered = self.covered_coarse_cells[self.overlap.coarse_cells]
        weight = np.where(covered[:, None], self.alpha_coarse_overlap, -self.alpha_fine_overlap)
        return BlockTerm(self.integration_model, weight, self.coarse_transfer, 1.0)

    def fine_term(self) -> BlockTerm:
        """The patch model's term of its block, weighted by α_fine at its quadrature points."""
        return BlockTerm(self.fine_model, self.alpha_fine)

    def integration_boundary_facets(self) -> np.ndarray:
        """Boundary facets of the integration mesh that lie on the coarse mesh's boundary.

        Nested overlaps: the patch's outer facets (the integration mesh is the patch mesh).
        Intersection meshes give every cell its own nodes, so each of their facets is a
        "boundary" facet: those on the coarse boundary are the pieces of the patch's outer
        facets, i.e. the facets whose vertices and centroid all lie on an outer facet (within
        1e-9 of the facet's size).
        """
        imesh = self.overlap.integration_mesh
        if self.overlap.method == "nested":
            return self.outer_facets
        bf = imesh.boundary_facets()
        if self.outer_facets.size == 0:
            return bf[:0]
        fmesh = self.fine_model.mesh
        # only the cells of I inside a fine cell with an outer facet can have one
        with_outer = np.zeros(fmesh.nelements, dtype=bool)
        with_outer[fmesh.f2t[0, self.outer_facets]] = True
        bf = bf[with_outer[self.overlap.fine_cells[imesh.f2t[0, bf]]]]
        outer = facet_coordinates(fmesh, self.outer_facets)
        verts = imesh.facets[:, bf]  # (n_v, n_f)
        x = imesh.p[:, verts]  # (dim, n_v, n_f)
        size = np.max(np.linalg.norm(x - x[:, :1], axis=0), axis=0)  # (n_f,)
        if imesh.dim() == 1:
            size = cell_sizes(fmesh).min() * np.ones(bf.size)
        cap = 1e-9 * float(size.max()) if size.size else 0.0  # exact below it: all we need
        d = distance_to_facets(x.reshape(imesh.dim(), -1), outer, cap=cap).reshape(verts.shape)
        # and its centroid: a 3D facet whose vertices lie on two outer faces meeting at an
        # edge (an interior face of a corner cell) has its centroid off both
        dc = distance_to_facets(x.mean(axis=1), outer, cap=cap)
        on = np.all(d <= 1e-9 * size[None, :], axis=0) & (dc <= 1e-9 * size)
        return bf[on]
