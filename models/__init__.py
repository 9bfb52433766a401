"""Single-mesh physics models, shipped as ``arlequin.models``.

Models know nothing about Arlequin coupling: each assembled quantity takes an optional weight
evaluated at quadrature points (the energy partition weight α, default 1).
"""

from .contact import (
    ContactConvergenceError,
    ContactSurface,
    DeformableContactPair,
    LevelSetContact,
    LevelSetObstacle,
    Obstacle,
    PlaneObstacle,
    RigidContactPair,
    SignoriniContact,
    SphereObstacle,
    acoustic_impedance,
)
from .elastic import KINDS, IsotropicElastic, LinearElastic, scalar_element_for
from .elastoplastic import (
    FiniteStrainJ2,
    InvertedElementError,
    J2Material,
    PlasticState,
    hencky_j2_return,
)

__all__ = [
    "KINDS",
    "ContactConvergenceError",
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
    "hencky_j2_return",
    "scalar_element_for",
]
