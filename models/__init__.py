"""Single-mesh physics models, shipped as ``arlequin.models``.

Models know nothing about Arlequin coupling: each assembled quantity takes an optional weight
evaluated at quadrature points (the energy partition weight α, default 1). They are written
against :mod:`arlequin.contract` (the protocols and shared errors), the only part of the core
they import besides its pure helpers (dof layout, reference elements, facet geometry).

Modules: ``elastic`` (small-strain linear elasticity), ``hardening`` (isotropic hardening
laws), ``j2`` (the J2 material point), ``kinematics`` (finite-strain Q1 kinematics, F-bar),
``j2_kernel`` (the compiled planar kernel), ``elastoplastic`` (finite-strain J2 model),
``obstacles`` (rigid level-set obstacles), ``contact_geometry`` (contact surfaces and pairs),
``contact`` (the level-set Signorini–Moreau contact model and the Signorini baseline),
``friction`` (Coulomb friction in the level-set model).
"""

from .contact.friction import CoulombContact, FrictionState
from .contact.geometry import (
    ContactGeometry,
    ContactPair,
    ContactSurface,
    DeformableContactPair,
    RigidContactPair,
)
from .contact.level_set import (
    ContactConvergenceError,
    ContactHistory,
    ContactRecord,
    ContactState,
    LevelSetContact,
    SignoriniContact,
    acoustic_impedance,
)
from .contact.obstacles import LevelSetObstacle, Obstacle, PlaneObstacle, SphereObstacle
from .elastic import (
    KINDS,
    IsotropicElastic,
    LinearElastic,
    element_critical_step,
    scalar_element_for,
)
from .plasticity.finite_strain_j2 import BACKENDS, BulkViscosity, FiniteStrainJ2
from .plasticity.hardening import (
    HARDENING_LAWS,
    CallableHardening,
    Hardening,
    JohnsonCookHardening,
    LinearHardening,
    VoceHardening,
    make_hardening,
)
from .plasticity.j2 import (
    InvertedElementError,
    J2Material,
    PlasticState,
    hencky_j2_return,
    hencky_strain,
    j2_return_map,
    j2_update,
)
from .plasticity.kinematics import Q1Kinematics

__all__ = [
    "BACKENDS",
    "HARDENING_LAWS",
    "KINDS",
    "BulkViscosity",
    "CallableHardening",
    "ContactConvergenceError",
    "ContactGeometry",
    "ContactHistory",
    "ContactPair",
    "ContactRecord",
    "ContactState",
    "ContactSurface",
    "CoulombContact",
    "DeformableContactPair",
    "FiniteStrainJ2",
    "FrictionState",
    "Hardening",
    "InvertedElementError",
    "IsotropicElastic",
    "J2Material",
    "JohnsonCookHardening",
    "LevelSetContact",
    "LevelSetObstacle",
    "LinearElastic",
    "LinearHardening",
    "Obstacle",
    "PlaneObstacle",
    "PlasticState",
    "Q1Kinematics",
    "RigidContactPair",
    "SignoriniContact",
    "SphereObstacle",
    "VoceHardening",
    "acoustic_impedance",
    "element_critical_step",
    "hencky_j2_return",
    "hencky_strain",
    "j2_return_map",
    "j2_update",
    "make_hardening",
    "scalar_element_for",
]
