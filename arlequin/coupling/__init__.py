"""Coupling: what ties one patch to its coarse model.

The overlap and its integration mesh (:mod:`~arlequin.coupling.overlap`), the partition weights
(:mod:`~arlequin.coupling.weights`), the mediator spaces and L2/H1 coupling matrices
(:mod:`~arlequin.coupling.mediators`), the gluing of one patch (:mod:`~arlequin.coupling.gluing`),
the exactness conditions (:mod:`~arlequin.coupling.exactness`), patch descriptions and nested
refinement (:mod:`~arlequin.coupling.patches`) and fields evaluated across meshes
(:mod:`~arlequin.coupling.fields`). Built on :mod:`arlequin.geometry`; knows nothing of solvers.
"""
