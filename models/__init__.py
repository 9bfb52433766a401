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

__all__ = [
    "KINDS",
    "ContactConvergenceError",
    "ContactSurface",
    "DeformableContactPair",
    "IsotropicElastic",
    "LevelSetContact",
    "LevelSetObstacle",
    "LinearElastic",
    "Obstacle",
    "PlaneObstacle",
    "RigidContactPair",
    "SignoriniContact",
    "SphereObstacle",
    "acoustic_impedance",
    "scalar_element_for",
]
