"""The sliding block's set-up: a configuration -> the mesh, the model, the loading, the contact
with friction and the exact solution (:func:`build`)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import skfem

from ...models import (
    ContactSurface,
    CoulombContact,
    IsotropicElastic,
    LevelSetContact,
    LinearElastic,
    PlaneObstacle,
    RigidContactPair,
)
from ...problem.system import Block, BlockTerm, CoupledSystem
from ...solvers import RayleighDamping, SmoothStep

if TYPE_CHECKING:
    from .config import SlidingBlockConfig

__all__ = ["Loading", "SlidingBlockSetup", "build"]


@dataclass
class Loading:
    """A loading's force, initial state and exact solution.

    Attributes
    ----------
    load : callable
        ``load(t)``: the external force vector (N, shape (n,)) at the integrator's time t (s).
    u0, v0 : ndarray, shape (n,)
        Initial displacement (m) and velocity (m/s) of the integration.
    ramp : float
        Duration of the load ramp before the reported t = 0 (s; 0 with the pressure loading).
    launch : float
        Velocity (m/s) added along x to every node at the end of the ramp (0: none; the
        pressure launch is in ``v0``).
    a_exact : float
        The exact mean acceleration along x after the launch or the ramp (m/s²).
    t_stop : float or None
        The exact stop time after the launch (s), None when the block does not stop.
    t_run : float
        Simulated time after the launch or the ramp (s).
    """

    load: Callable[[float], np.ndarray]
    u0: np.ndarray
    v0: np.ndarray
    ramp: float
    launch: float
    a_exact: float
    t_stop: float | None
    t_run: float


@dataclass
class SlidingBlockSetup:
    """The block, its contact with the plane and its loading, ready to integrate.

    Attributes
    ----------
    config : SlidingBlockConfig
    dim : int
    mesh : skfem.Mesh
    model : LinearElastic
    system : CoupledSystem
    contact : CoulombContact or LevelSetContact
        The contact with the plane (named ``"plane"``).
    loading : Loading
    mass_x : ndarray, shape (n_nodes,)
        The lumped masses of the x dofs (kg).
    bottom_x : ndarray of int
        The x dofs of the contact nodes.
    c_d, c_s : float
        Dilatational and shear wave speeds (m/s).
    damping : RayleighDamping or None
    """

    config: SlidingBlockConfig
    dim: int
    mesh: Any
    model: LinearElastic
    system: CoupledSystem
    contact: Any
    loading: Loading
    mass_x: np.ndarray
    bottom_x: np.ndarray
    c_d: float
    c_s: float
    damping: RayleighDamping | None

    @property
    def t_total(self) -> float:
        """The integration's end time (s): the ramp and the run after it."""
        return self.loading.ramp + self.loading.t_run


def build(config: SlidingBlockConfig) -> SlidingBlockSetup:
    """The set-up of a (checked) configuration."""
    mesh, model, mat = _block(config)
    c_d, c_s = config.wave_speeds
    xi = config.damping_ratio
    rayleigh = (RayleighDamping.from_ratio(xi, 0.5 * math.pi * c_s / config.height) if xi
                else None)  # fmt: skip
    if config.gravity is None:
        loading = _pressure_loading(config, mesh, model, c_d)
    else:
        loading = _gravity_loading(config, model, c_d)
    system = CoupledSystem([Block("block", model, [BlockTerm(model)])], load=loading.load)
    contact, surf = _contact(config, mesh, mat, system)
    dim = config.dim
    mass = system.mass(lumped=True)
    return SlidingBlockSetup(
        config=config, dim=dim, mesh=mesh, model=model, system=system, contact=contact,
        loading=loading, mass_x=mass[0::dim], bottom_x=dim * surf.nodes, c_d=c_d, c_s=c_s,
        damping=rayleigh,
    )  # fmt: skip


def _block(config: SlidingBlockConfig) -> tuple[Any, LinearElastic, IsotropicElastic]:
    """The mesh (2n × n plane-strain quadrilaterals or 2n × 2n × n hexahedra), its model and
    material."""
    n = int(config.elements)
    mat = IsotropicElastic(config.young, config.poisson, config.density)
    lat = np.linspace(0.0, config.width, 2 * n + 1)
    z = np.linspace(0.0, config.height, n + 1)
    if config.dim == 2:
        mesh = skfem.MeshQuad.init_tensor(lat, z)
        model = LinearElastic(mesh, mat, kind="plane_strain")
    else:
        mesh = skfem.MeshHex.init_tensor(lat, lat, z)
        model = LinearElastic(mesh, mat, kind="3d")
    return mesh, model, mat


def _pressure_loading(config: SlidingBlockConfig, mesh: Any, model: LinearElastic,
                      c_d: float) -> Loading:  # fmt: skip
    """The top pressure p, from the exact static state under p, launched at t = 0."""
    dim, height, width = config.dim, config.height, config.width
    pressure, poisson, young = config.load_pressure, config.poisson, config.young
    velocity, friction = config.launch_velocity, config.friction
    top = mesh.facets_satisfying(lambda p: np.isclose(p[-1], height), boundaries_only=True)
    traction = np.zeros(dim)
    traction[-1] = -pressure
    f_top = model.traction_vector(top, traction)

    def load(t: float) -> np.ndarray:
        return f_top

    # the exact static state under p, laterally free (uniform stress σ_zz = −p)
    if dim == 2:
        e_zz = -pressure * (1 - poisson**2) / young
        e_lat = pressure * poisson * (1 + poisson) / young
    else:
        e_zz, e_lat = -pressure / young, pressure * poisson / young
    x = mesh.p
    u0 = np.zeros(model.n_dofs)
    v0 = np.zeros(model.n_dofs)
    for k in range(dim - 1):
        u0[k::dim] = e_lat * (x[k] - 0.5 * width)
    u0[dim - 1 :: dim] = e_zz * x[-1]
    v0[0::dim] = velocity
    a_exact = -friction * pressure / (config.density * height)
    t_stop = velocity / -a_exact if friction > 0 else None
    t_run = _run_time(config, t_stop, c_d)
    return Loading(load, u0, v0, 0.0, 0.0, a_exact, t_stop, t_run)


def _gravity_loading(config: SlidingBlockConfig, model: LinearElastic, c_d: float) -> Loading:
    """Gravity on the incline, ramped from rest, and the launch at V at the end of the ramp."""
    dim, gravity, friction = config.dim, config.gravity, config.friction
    th = math.radians(config.incline)
    g_vec = np.zeros(dim)
    g_vec[0], g_vec[-1] = gravity * math.sin(th), -gravity * math.cos(th)
    f_g = model.body_force_vector(config.density * g_vec)
    ramp = config.ramp_duration
    smooth = SmoothStep(ramp)

    def load(t: float) -> np.ndarray:
        return smooth(t) * f_g

    slide = gravity * (math.sin(th) - friction * math.cos(th))
    launch = config.launch_velocity
    t_stop = None
    if launch > 0.0:
        # launched: v(t) = V + slide t while it slides (slide < 0: it decelerates and stops)
        a_exact = slide
        if slide < 0.0:
            t_stop = launch / -slide
    else:
        a_exact = max(slide, 0.0)  # at rest: it sticks unless the incline beats the friction
    t_run = _run_time(config, t_stop, c_d) if launch > 0.0 else (
        config.t_end if config.t_end is not None else 200.0 * config.height / c_d)  # fmt: skip
    zeros = np.zeros(model.n_dofs)
    return Loading(load, zeros, zeros.copy(), ramp, launch, a_exact, t_stop, t_run)


def _run_time(config: SlidingBlockConfig, t_stop: float | None, c_d: float) -> float:
    """Simulated time after a launch: ``t_end``, else 1.3 × the stop time, else 200 H/c_d."""
    t_end = config.t_end
    return 1.3 * t_stop if t_end is None and t_stop else (t_end or 200 * config.height / c_d)


def _contact(config: SlidingBlockConfig, mesh: Any, mat: IsotropicElastic,
             system: CoupledSystem) -> tuple[Any, ContactSurface]:  # fmt: skip
    """The level-set contact of the bottom nodes with the plane, with Coulomb friction μ > 0."""
    dim = config.dim
    surf = ContactSurface(mesh, where=lambda p: p[-1] < 1e-9 * config.height,
                          offset=system.dofmap["block"])  # fmt: skip
    normal = np.zeros(dim)
    normal[-1] = 1.0
    pair = RigidContactPair(surf, PlaneObstacle(np.zeros(dim), normal), system.dofmap)
    friction = config.friction
    con = (CoulombContact(pair, friction, material=mat, name="plane") if friction > 0
           else LevelSetContact(pair, material=mat, name="plane"))  # fmt: skip
    return con, surf
