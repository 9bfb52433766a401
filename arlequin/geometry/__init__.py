"""Geometry: reference elements, facet geometry, point location, exact intersections and
clipping, mesh checks and regions (boxes, level sets, closed surfaces).

The lowest layer of the core: it imports nothing else from :mod:`arlequin` but the contract, and
the models may use its pure helpers (:mod:`~arlequin.geometry.reference`,
:mod:`~arlequin.geometry.facets`, :mod:`~arlequin.geometry.meshcheck`).
"""
