"""One patch glued to the coarse model: its coupling (the patch's description, :class:`Patch`,
lives in :mod:`arlequin.coupling.patches` and is re-exported here).

:class:`PatchCoupling` builds, for one patch, everything that ties it to the coarse model: the
overlap (the shared integration mesh, :mod:`arlequin.coupling.overlap`), the classification of the
patch boundary (on the coarse boundary, or interior), the gluing zone (a band along the interior
boundary), the partition weights at every quadrature point (:mod:`arlequin.coupling.weights`) and
the coupling matrices (:mod:`arlequin.coupling.mediators`). All quantities are SI.
"""

from __future__ import annotations

import logging
import warnings
from collections.abc import Callable
from functools import cached_property
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..geometry.facets import distance_to_facets, facet_coordinates, outward_normals
from ..geometry.locate import cell_centroids, cell_sizes, locate_points
from .exactness import ExactnessWarning, exactness_failures, unheld_band_cells
from .fields import scalar_at_quadrature
from .mediators import CouplingMatrices, MediatorError, coupling_matrices
from .overlap import Overlap, build_overlap, check_meshes
from .patches import Patch, resolve_mediator
from .weights import PartitionWeights, check_partition_of_unity

__all__ = [
    "PatchCoupling"
]  # Patch: arlequin.coupling.patches, ExactnessWarning: arlequin.coupling.exactness


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
        check_meshes(cmesh, fmesh)  # before the boundary classification uses both meshes
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
        self._fine_gluing_zone()
        self._surely_covered: np.ndarray | None = None
        trim = self.weights.mode in ("nodal", "cell")
        self.overlap: Overlap = build_overlap(
            cmesh, fmesh, patch.overlap_method, patch.boundary_tol,
            pair_filter=self._pieces_needed if trim else None,
        )  # fmt: skip
        #: α_coarse beyond the band (ε), carried by the coarse cells themselves where the
        #: overlap is trimmed (0 otherwise: the integration cells carry all of α_coarse)
        self.coarse_floor = self._floor() if self.overlap.trimmed else 0.0
        self.gluing_cells = np.nonzero(self._fine_gluing_mask[self.overlap.fine_cells])[0]
        if self.gluing_cells.size == 0:
            raise MediatorError(
                f"empty gluing zone for {self.name}: it does not overlap the coarse mesh"
            )
        self.integration_model = coarse_model.with_mesh(self.overlap.integration_mesh)
        self._evaluate_weights()
        #: the mediator space in use, "coarse" or "fine" (``patch.mediator`` resolved)
        self.mediator = resolve_mediator(patch.mediator, unheld_band_cells(self).size)
        length = patch.length if patch.length is not None else self.default_h1_length()
        self.coupling: CouplingMatrices = coupling_matrices(
            self.overlap,
            self.gluing_cells,
            self.n_components,
            patch.coupling,
            length,
            self.mediator,
            self.axisymmetric,
        )
        self.exactness_failures = exactness_failures(self)
        for failure in self.exactness_failures:
            warnings.warn(f"{self.name}: {failure}", ExactnessWarning, stacklevel=3)

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

    def _fine_gluing_zone(self) -> None:
        fmesh = self.fine_model.mesh
        centroids = cell_centroids(fmesh)
        self._distance_cache: dict = {}
        self._fine_values: dict = {}
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
        self._fine_gluing_mask = fine_gluing
        self.fine_gluing_cells = np.nonzero(fine_gluing)[0]

    # ------------------------------------------------------------------ trimmed overlaps
    def _floor(self) -> float:
        """α_coarse beyond the gluing band (m): the weights' value at twice the band width."""
        x = np.zeros((self.fine_model.mesh.dim(), 1))
        d = np.array([2.0 * self.gluing_width])
        return float(np.asarray(self.weights.alpha_coarse(x, d, self.gluing_width)).ravel()[0])

    def _weighted_fine_cells(self) -> np.ndarray:
        """Patch cells on which α_coarse is not the floor somewhere, shape (n_fine_cells,) bool.

        The integration cells inside them carry α_coarse − floor ≠ 0 (nodal weights: a vertex
        value differs; cell weights: the cell's value does).
        """
        fmesh = self.fine_model.mesh
        floor = self._floor()
        if self.weights.mode == "nodal":
            return np.any(self._fine_nodal("coarse")[fmesh.t] != floor, axis=0)
        return self._fine_cell_values("coarse") != floor

    def _pieces_needed(self, fine_cells: np.ndarray, coarse_cells: np.ndarray) -> np.ndarray:
        """Which candidate pairs (patch cell, coarse cell) the overlap must intersect.

        A coarse cell C that surely lies inside the patch gets α_coarse = floor = ε on itself
        (its own term) and α_coarse − ε on the integration cells, which vanishes outside the
        patch cells that see the band (:meth:`_weighted_fine_cells`): only those pieces of C
        are cut. Every piece of the other coarse cells is cut (partly covered cells need the
        whole overlap, −α_fine on it). C surely lies inside when its centroid c is inside the
        patch and farther than its circumradius about c, r_C = max |v − c|, from every facet of
        the patch's boundary (the distance is 1-Lipschitz, so no point of C reaches a facet).
        """
        cmesh, fmesh = self.coarse_model.mesh, self.fine_model.mesh
        cand = np.unique(coarse_cells)
        c = cell_centroids(cmesh)[:, cand]
        r = np.max(np.linalg.norm(cmesh.p[:, cmesh.t[:, cand]] - c[:, None, :], axis=0), axis=0)
        cap = float(r.max()) * (1.0 + 1e-9)
        far = self.distance(c, cap) > r * (1.0 + 1e-9)
        if self.outer_facets.size:
            outer = facet_coordinates(fmesh, self.outer_facets)
            far &= distance_to_facets(c, outer, cap=cap) > r * (1.0 + 1e-9)
        far[far] = locate_points(fmesh, c[:, far], tol=0.0).inside
        self._surely_covered = np.zeros(cmesh.nelements, dtype=bool)
        self._surely_covered[cand[far]] = True
        return self._weighted_fine_cells()[fine_cells] | ~self._surely_covered[coarse_cells]

    # ------------------------------------------------------------------ weights
    def _fine_nodal(self, which: str) -> np.ndarray:
        """α_which at the patch's nodes (nodal weights), shape (n_fine_nodes,), cached."""
        key = ("nodal", which)
        if key not in self._fine_values:
            fn = self.weights.alpha_coarse if which == "coarse" else self.weights.alpha_fine
            fmesh = self.fine_model.mesh
            self._fine_values[key] = np.asarray(
                fn(fmesh.p, self._node_distance(fmesh), self.gluing_width), dtype=float
            )
        return self._fine_values[key]

    def _fine_cell_values(self, which: str) -> np.ndarray:
        """α_which of the patch's cells (cell weights, at their centroids), cached."""
        key = ("cell", which)
        if key not in self._fine_values:
            fn = self.weights.alpha_coarse if which == "coarse" else self.weights.alpha_fine
            fmesh = self.fine_model.mesh
            self._fine_values[key] = np.asarray(
                fn(cell_centroids(fmesh), self._centroid_distance(fmesh), self.gluing_width),
                dtype=float,
            )
        return self._fine_values[key]

    def _weights_at(self, basis, which: str, overlap: bool = False) -> np.ndarray:
        """α_which at the quadrature points of a scalar cell basis, shape (n_elems, n_qp).

        On the patch mesh (``overlap=False``) nodal weights are the ramp's nodal values
        interpolated by the patch's first-order functions, cell weights the value at each
        cell's centroid. On the integration mesh (``overlap=True``) they are the same
        functions of the patch carried over (the patch's nodal values through the fine
        transfer, each patch cell's value on its pieces), so that α_coarse + α_fine = 1 holds
        between the two models' weights exactly wherever the ramp is not linear on a patch
        cell, and no distance is computed at the integration mesh's many nodes.
        """
        mode = self.weights.mode
        if mode == "nodal":
            nodal = self._fine_nodal(which)
            if overlap:
                nodal = self.overlap.fine_transfer @ nodal
            return scalar_at_quadrature(basis, nodal)
        if mode == "cell":
            per_cell = self._fine_cell_values(which)
            if overlap:
                per_cell = per_cell[self.overlap.fine_cells]
            return np.repeat(per_cell[:, None], basis.dx.shape[1], axis=1)
        fn = self.weights.alpha_coarse if which == "coarse" else self.weights.alpha_fine
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
        alpha_c = self._weights_at(ibasis, "coarse", overlap=True)
        alpha_f = self._weights_at(ibasis, "fine", overlap=True)
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
        covered = i_measure >= (1.0 - 1e-9) * c_measure
        if self._surely_covered is not None and self.overlap.trimmed:
            covered |= self._surely_covered  # inside the patch, its pieces trimmed
        return covered

    def coarse_overlap_weight(self) -> np.ndarray:
        """Weight of the coarse model's term on the integration cells, shape (n_I, n_qp).

        α_coarse − floor on the cells of fully covered coarse cells (which carry the floor
        themselves, see :attr:`coarse_floor`; floor 0 unless the overlap is trimmed), −α_fine
        on those of partly covered ones (see :attr:`covered_coarse_cells`).
        """
        covered = self.covered_coarse_cells[self.overlap.coarse_cells]
        inside = self.alpha_coarse_overlap
        if self.coarse_floor:
            inside = inside - self.coarse_floor
        return np.where(covered[:, None], inside, -self.alpha_fine_overlap)

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
