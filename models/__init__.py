"""Single-mesh physics models, shipped as ``arlequin.models``.

Models know nothing about Arlequin coupling: each assembled quantity takes an optional weight
evaluated at quadrature points (the energy partition weight α, default 1). They are written
against :mod:`arlequin.contract` (the protocols and shared errors), the only part of the core
they import besides its pure helpers (dof layout, reference elements, facet geometry).

Modules: ``elastic`` (small-strain linear elasticity), ``hardening`` (isotropic hardening
laws), ``j2`` (the J2 material point), ``kinematics`` (finite-strain Q1 kinematics, F-bar),
``j2_kernel`` (the compiled planar kernel), ``elastoplastic`` (finite-strain J2 model),
``small_strain_j2`` (small-strain J2 with its consistent tangent),
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
from .plasticity.small_strain_j2 import (
    SMALL_STRAIN_KINDS,
    ReturnResult,
    SmallStrainJ2,
    SmallStrainState,
    consistent_tangent,
    from_mandel,
    small_strain_return,
    to_mandel,
)

__all__ = [
    "BACKENDS",
    "HARDENING_LAWS",
    "KINDS",
    "SMALL_STRAIN_KINDS",
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
    "ReturnResult",
    "RigidContactPair",
    "SignoriniContact",
    "SmallStrainJ2",
    "SmallStrainState",
    "SphereObstacle",
    "VoceHardening",
    "acoustic_impedance",
    "consistent_tangent",
    "element_critical_step",
    "from_mandel",
    "hencky_j2_return",
    "hencky_strain",
    "j2_return_map",
    "j2_update",
    "make_hardening",
    "scalar_element_for",
    "small_strain_return",
    "to_mandel",
]
