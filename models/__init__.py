"""Single-mesh physics models, shipped as ``arlequin.models``.

Models know nothing about Arlequin coupling: each assembled quantity takes an optional weight
evaluated at quadrature points (the energy partition weight α, default 1). They are written
against :mod:`arlequin.contract` (the protocols and shared errors), the only part of the core
they import besides its pure helpers (dof layout, reference elements, facet geometry).

Modules: ``elastic`` (small-strain linear elasticity), ``elastoplastic`` (finite-strain J2),
``obstacles`` (rigid level-set obstacles), ``contact_geometry`` (contact surfaces and pairs),
``contact`` (the level-set Signorini–Moreau contact model and the Signorini baseline).
"""

from .contact import (
    ContactConvergenceError,
    ContactHistory,
    ContactRecord,
    ContactState,
    LevelSetContact,
    SignoriniContact,
    acoustic_impedance,
)
from .contact_geometry import (
    ContactGeometry,
    ContactPair,
    ContactSurface,
    DeformableContactPair,
    RigidContactPair,
)
from .elastic import (
    KINDS,
    IsotropicElastic,
    LinearElastic,
    element_critical_step,
    scalar_element_for,
)
from .elastoplastic import (
    FiniteStrainJ2,
    InvertedElementError,
    J2Material,
    PlasticState,
    hencky_j2_return,
)
from .obstacles import LevelSetObstacle, Obstacle, PlaneObstacle, SphereObstacle

__all__ = [
    "KINDS",
    "ContactConvergenceError",
    "ContactGeometry",
    "ContactHistory",
    "ContactPair",
    "ContactRecord",
    "ContactState",
    "ContactSurface",
    "DeformableContactPair",
    "FiniteStrainJ2",
    "InvertedElementError",
    "IsotropicElastic",
    "J2Material",
    "LevelSetContact",
    "LevelSetObstacle",
    "LinearElastic",
    "Obstacle",
    "PlaneObstacle",
    "PlasticState",
    "RigidContactPair",
    "SignoriniContact",
    "SphereObstacle",
    "acoustic_impedance",
    "element_critical_step",
    "hencky_j2_return",
    "scalar_element_for",
]
