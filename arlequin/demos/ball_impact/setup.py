"""The bodies of the ball-impact demo: the ball (and the block) as Arlequin pairs or single meshes.

``arlequin`` (:class:`ArlequinBodies`): each body is a coarse linear-elastic model of the whole
body plus a nested refined patch at the contact zone (:mod:`arlequin.demos.ball_impact.meshes`),
glued by the fine mediator in a band of two coarse cells at the patch's edge, ramp weights (L2
coupling: on a nested patch the fine mediator ties the band's fine dofs to the coarse field
whatever the coupling, and the H1 rows make the impulse solve 2.2 times slower: measured 175 s
against 78 s for the same results to 1e-6 on the rigid-wall run at 13 cells per contact
radius; the coarse mediator is 2.6 times faster still but inexact on this curved band, −3.9%
on the peak force);
the block's patch is finite-strain J2 in the plastic regime. ``mono``: one mesh per body with
the fine size everywhere, the block finite-strain J2 in the whole block in the plastic regime.
All bodies carry u_r = 0 on the axis (and so does the mediator space); the block's base is on
rollers (u_z = 0). The contact (level set, optionally Coulomb friction) acts between the ball's
surface nodes below the gluing band and the block's top facets below the band (or the rigid
plane z = 0 with ``rigid_wall``). SI units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...models import (
    ContactSurface,
    CoulombContact,
    DeformableContactPair,
    FiniteStrainJ2,
    IsotropicElastic,
    J2Material,
    LevelSetContact,
    LinearElastic,
    PlaneObstacle,
    RigidContactPair,
)
from ...problem.adapt import AdaptivePatch
from ...problem.adapt_bodies import BodyAdaptation
from ...problem.arlequin_problem import ArlequinProblem, Patch
from ...problem.bodies import MultiBodyProblem
from .meshes import GROWTH, ball_patch_mesh, block_mesh, block_patch_mesh, half_disk_mesh
from .zoned import ZonedBody

__all__ = ["ARC", "BallSizes", "ImpactBodies", "ResolvedInputs", "ball_sizes", "mono_cells"]

#: Length of the ball's O-grid cells along its arc, per 1/n (m per m of radius).
ARC = 0.25 * math.pi


@dataclass(frozen=True)
class BallSizes:
    """Resolved mesh sizes (m) and counts of a ball-impact set-up.

    ``n`` is the ball's O-grid parameter at the coarse size, ``levels`` the patches' nested
    refinements (fine size = coarse / 2^levels), ``reach`` the patches' radius around the
    contact point, ``gluing`` the gluing band width (two coarse cells), ``zone`` the radius of
    the contact surfaces (inside the patches, below the bands).
    """

    coarse: float
    fine: float
    n: int
    levels: int
    reach: float
    gluing: float
    zone: float
    block_reach: float = 0.0

    @property
    def block_patch(self) -> float:
        """The block patch's radius (m): ``block_reach``, or the ball's ``reach``."""
        return self.block_reach or self.reach


def ball_sizes(radius: float, coarse_size: float, fine_size: float, reach: float,
               block_reach: float | None = None) -> BallSizes:  # fmt: skip
    """The sizes of the patches from the requested ones (m): the coarse size rounded to the
    ball's O-grid, the fine size to a power-of-two refinement of it; ``block_reach`` the
    block patch's radius if it differs from the ball's ``reach``."""
    n = max(2, math.ceil(ARC * radius / coarse_size - 1e-9))
    coarse = ARC * radius / n
    levels = max(1, round(math.log2(coarse / fine_size)))
    gluing = 2.0 * coarse
    zone = reach - gluing - coarse
    if zone <= coarse:
        raise ValueError(f"patch_size={reach:.4g} m leaves no contact zone below the gluing band "
                         f"(two coarse cells of {coarse:.4g} m): give patch_size > "
                         f"{4 * coarse:.4g} m")  # fmt: skip
    return BallSizes(coarse, coarse / 2**levels, n, levels, reach, gluing, zone,
                     float(block_reach or 0.0))  # fmt: skip


def mono_cells(sizes: BallSizes, block_radius: float, block_height: float,
               rigid_wall: bool) -> int:  # fmt: skip
    """Cells of the uniformly fine (``mono``) meshes of both bodies at ``sizes.fine``."""
    n_f = sizes.n * 2**sizes.levels
    cells = 6 * n_f**2
    if not rigid_wall:
        cells += math.ceil(block_radius / sizes.fine) * math.ceil(block_height / sizes.fine)
    return int(cells)


@dataclass(frozen=True)
class ResolvedInputs:
    """The inputs of a run with the defaults that depend on others resolved (SI units).

    ``velocity`` (m/s), ``radius`` (R, m), ``block_radius``, ``block_height`` (m), the
    materials, ``fine`` (the requested fine size before rounding, m), ``sizes`` (the rounded
    sizes and the patches' radii), ``coarse_step_ratio`` (M), and ``record``: the inputs
    recorded in ``results.json`` and the JSON (plain JSON, the materials as objects of their
    named fields); ``adapt``: the adaptive patch's options (``adapt_threshold``,
    ``adapt_buffer``, ``adapt_every``, ``max_patch_fraction``), None for a fixed patch.
    """

    regime: str
    model: str
    velocity: float
    radius: float
    block_radius: float
    block_height: float
    ball_material: IsotropicElastic
    block_material: IsotropicElastic | J2Material
    fine: float
    sizes: BallSizes
    friction: float
    rigid_wall: bool
    coarse_step_ratio: int
    t_end: float | None
    record: dict[str, Any]
    adapt: dict[str, Any] | None = None

    @property
    def plastic(self) -> bool:
        """The plastic regime (the block's patch finite-strain J2)."""
        return self.regime == "plastic"

    @property
    def block_size(self) -> float:
        """The block's smaller dimension (m; infinite against the rigid wall)."""
        return math.inf if self.rigid_wall else min(self.block_radius, self.block_height)


def _axis(x: np.ndarray, tol: float) -> np.ndarray:
    return x[0] < tol


class ImpactBodies:
    """The ball (and the block) of one model, with their contact (module docstring).

    Parameters
    ----------
    model : {"arlequin", "mono", "mono-zoned", "graded"}
        ``mono-zoned``: the uniform meshes with J2 only in the block's patch region (the cells
        whose centre lies within ``sizes.block_patch`` of the contact point), elastic elsewhere;
        ``graded``: one conforming mesh per body, the fine size at the contact point growing by
        :data:`~arlequin.demos.ball_impact.meshes.GROWTH` a cell away from it (the ball's graded
        O-grid), the same laws as ``mono-zoned``.
    sizes : BallSizes
    ball_radius, block_radius, block_height : float
        R, R_B, H_B (m).
    ball_material : IsotropicElastic
    block_material : IsotropicElastic or J2Material
        J2Material: the plastic regime (finite-strain J2 in the block's patch, or in the whole
        block with ``mono``).
    rigid_wall : bool
        The ball against the rigid plane z = 0 instead of the block.
    friction : float
        Coulomb coefficient (0: frictionless).
    seed : float, optional
        The block patch's radius (m) when it adapts (the coarse mesh stays uniform to
        ``sizes.block_patch``): the seed of :meth:`adaptation`.
    """

    def __init__(self, model: str, sizes: BallSizes, ball_radius: float, block_radius: float,
                 block_height: float, ball_material: IsotropicElastic,
                 block_material: IsotropicElastic | J2Material, rigid_wall: bool = False,
                 friction: float = 0.0, seed: float | None = None) -> None:  # fmt: skip
        self.model = model
        self.sizes = s = sizes
        big = float(ball_radius)
        self.radius = big
        self.tol = tol = 1e-9 * big
        self.plastic = isinstance(block_material, J2Material)
        bodies: dict[str, Any] = {}
        self.meshes: dict[str, Any] = {}
        if model == "graded":
            ball_coarse = half_disk_mesh(big, 0, pole_spacing=s.fine, uniform=s.reach)
        else:
            ball_coarse = half_disk_mesh(big, s.n if model == "arlequin" else s.n * 2**s.levels)
        self.zoned: ZonedBody | None = None
        if model == "arlequin":
            ball_fine = ball_patch_mesh(ball_coarse, big, s.reach, s.levels)
            bodies["ball"] = self._pair(ball_coarse, ball_fine, ball_material, ball_material)
            self.meshes.update({"ball.coarse": ball_coarse, "ball.patch": ball_fine})
        else:
            bodies["ball"] = self._single(ball_coarse, ball_material)
            self.meshes["ball.coarse"] = ball_coarse
        if not rigid_wall:
            elastic = block_material.elastic if self.plastic else block_material
            if model == "arlequin":
                bc = block_mesh(block_radius, block_height, s.coarse, uniform=s.block_patch)
                bf = block_patch_mesh(bc, s.block_patch if seed is None else seed, s.levels)
                bodies["block"] = self._pair(bc, bf, elastic, block_material)
                self.meshes.update({"block.coarse": bc, "block.patch": bf})
            else:
                # mono, mono-zoned: uniformly fine; graded: fine at the contact, growing away
                growth = GROWTH if model == "graded" else 1.0
                bc = block_mesh(block_radius, block_height, s.fine, growth=growth,
                                uniform=s.block_patch)  # fmt: skip
                if self.plastic and model in ("mono-zoned", "graded"):
                    centres = bc.p[:, bc.t].mean(axis=1)
                    zone_cells = np.nonzero(np.hypot(centres[0], centres[1]) < s.block_patch)[0]
                    self.zoned = ZonedBody(bc, zone_cells, block_material)
                    self.zoned.add_dirichlet("coarse", lambda x: _axis(x, tol), components=[0])
                    bodies["block"] = self.zoned
                else:
                    bodies["block"] = self._single(bc, block_material)
                self.meshes["block.coarse"] = bc
            bodies["block"].add_dirichlet("coarse", lambda x: x[1] < -block_height + tol,
                                          components=[1])  # fmt: skip
        self.problem = MultiBodyProblem(bodies)
        contact_block = "patch" if model == "arlequin" else "coarse"
        self.ball_block = f"ball.{contact_block}"
        self.block_block = None if rigid_wall else f"block.{contact_block}"
        self.zone = s.zone if model == "arlequin" else s.reach - s.gluing - s.coarse
        self._rigid, self._friction, self._ball_material = rigid_wall, friction, ball_material
        self._bind(self.problem)
        blocks = list(self.system.dofmap)
        self.slow_blocks = tuple(b for b in ("ball.coarse", "block.coarse")
                                 if model == "arlequin" and b in blocks)  # fmt: skip

    def _bind(self, problem: MultiBodyProblem, system: Any = None, contact: Any = None) -> None:
        """The system, layout, contact and measures of ``problem`` (this set-up's, or the one
        an adaptive block patch grew to: its ``system`` and ``contact`` already built)."""
        self.problem = problem
        # an assembled system caches its blocks' mass: the integrator's is reused
        self.system = problem.system() if system is None else system
        self.layout = problem.field_layout()
        for name, body in problem.bodies.items():
            if isinstance(body, ArlequinProblem) and body.patches:
                self.meshes[f"{name}.patch"] = body.patches[0].model.mesh
        if contact is None:
            self.contact = self.contact_for(problem)
        else:
            self.contact, self.pair = contact, contact.pair
        dm = self.system.dofmap
        self._ball_z = np.concatenate([dm[b].component_dofs(1) for b in dm
                                       if b.startswith("ball.")])  # fmt: skip
        mass = np.asarray(self.system.mass(lumped=True))
        self._ball_mass = mass[self._ball_z]
        self.ball_mass = float(self._ball_mass.sum())
        self.slave_r = self.pair.slave.positions(np.zeros(dm.n_dofs))[0]
        if self.block_block is not None:
            bm = self.meshes[self.block_block]
            self._pole = int(np.nonzero((bm.p[0] < self.tol) & (bm.p[1] > -self.tol))[0][0])
        #: the block patch's cells in its gluing band (empty without an Arlequin block)
        self.band_cells = np.zeros(0, dtype=np.int64)
        if self.model == "arlequin" and self.block_block is not None:
            self.band_cells = np.asarray(problem.bodies["block"].couplings[0].fine_gluing_cells)
        self.n_elements = int(sum(m.nelements for m in self.meshes.values()))
        self.fine_elements = int(sum(m.nelements for k, m in self.meshes.items()
                                     if k.endswith(".patch")))  # fmt: skip

    def contact_for(self, problem: MultiBodyProblem) -> Any:
        """The contact between the bodies of ``problem`` (on its dof map): the ball's surface
        nodes below its gluing band against the block's top facets below the band (or the
        rigid plane). Also kept as :attr:`pair`."""
        s, big, tol = self.sizes, self.radius, self.tol
        dm = problem.system().dofmap
        zone = self.zone
        meshes = {f"{n}.patch": b.patches[0].model.mesh for n, b in problem.bodies.items()
                  if isinstance(b, ArlequinProblem) and b.patches}  # fmt: skip
        meshes = {**self.meshes, **meshes}

        def on_ball(x):
            return (np.hypot(x[0], x[1] - big) > big - 0.05 * s.fine) & (np.hypot(x[0], x[1])
                                                                          < zone)  # fmt: skip

        slave = ContactSurface(meshes[self.ball_block], where=on_ball, offset=dm[self.ball_block],
                               axisymmetric=True)  # fmt: skip
        if self._rigid:
            pair = RigidContactPair(slave, PlaneObstacle(np.zeros(2), np.array([0.0, 1.0])), dm)
        else:
            master = ContactSurface(meshes[self.block_block],
                                    where=lambda x: (x[1] > -tol) & (x[0] < zone),
                                    offset=dm[self.block_block], axisymmetric=True)  # fmt: skip
            pair = DeformableContactPair(slave, master, dm)
        # κ = η = the impedance ρc of the ball (LevelSetContact's default from a material)
        self.pair = pair
        if self._friction > 0:
            return CoulombContact(pair, self._friction, material=self._ball_material,
                                  name="contact")  # fmt: skip
        return LevelSetContact(pair, material=self._ball_material, name="contact")

    def regrow(self, problem: MultiBodyProblem, system: Any = None, contact: Any = None) -> None:
        """Follow an adaptive block patch that grew: ``problem`` is the new set-up, ``system``
        and ``contact`` (:meth:`contact_for`) those the run already built on it, if given."""
        self._bind(problem, system, contact)

    def adaptation(self, threshold: float, buffer: int, every: int, max_fraction: float) -> Any:
        """The adaptive block patch (:class:`~arlequin.problem.adapt_bodies.BodyAdaptation`
        of an :class:`~arlequin.AdaptivePatch`), its contact rebuilt on each grown problem."""
        patch = AdaptivePatch(threshold=threshold, buffer=buffer, every=every,
                              max_fraction=max_fraction)  # fmt: skip
        return BodyAdaptation(patch, "block", constraints=lambda p: [self.contact_for(p)])

    def _pair(self, cmesh, fmesh, coarse_material, fine_material) -> ArlequinProblem:
        coarse = LinearElastic(cmesh, coarse_material, kind="axisymmetric")
        fine = (FiniteStrainJ2(fmesh, fine_material, "axisymmetric", True)
                if isinstance(fine_material, J2Material)
                else LinearElastic(fmesh, fine_material, kind="axisymmetric"))  # fmt: skip
        patch = Patch(fine, gluing_width=self.sizes.gluing, coupling="L2", mediator="fine",
                      overlap_method="nested", name="patch")  # fmt: skip
        problem = ArlequinProblem(coarse, [patch], mediator_dirichlet="drop")
        for block in ("coarse", "patch"):
            problem.add_dirichlet(block, lambda x: _axis(x, self.tol), components=[0])
        return problem

    def _single(self, mesh, material) -> ArlequinProblem:
        model = (FiniteStrainJ2(mesh, material, "axisymmetric", True)
                 if isinstance(material, J2Material)
                 else LinearElastic(mesh, material, kind="axisymmetric"))  # fmt: skip
        problem = ArlequinProblem(model, [])
        problem.add_dirichlet("coarse", lambda x: _axis(x, self.tol), components=[0])
        return problem

    # ------------------------------------------------------------------ measures
    def initial_velocity(self, velocity: float) -> np.ndarray:
        """−``velocity`` (m/s) along z on every node of the ball, the block at rest."""
        v0 = np.zeros(self.system.dofmap.n_dofs)
        v0[self._ball_z] = -velocity
        return v0

    def ball_velocity(self, v: np.ndarray) -> float:
        """The ball's mean velocity along z (m/s): its momentum over its mass."""
        return float(self._ball_mass @ v[self._ball_z]) / self.ball_mass

    def contact_force(self, multipliers: dict) -> float:
        """The contact force between the bodies (N), ≥ 0 in compression."""
        lam = multipliers.get("contact")
        if lam is None or not np.size(lam):
            return 0.0
        m = self.pair.n_points
        return float(-(np.asarray(lam)[:m] * self.pair.weights).sum())

    def dent_depth(self, u: np.ndarray) -> float:
        """Depth of the block's top surface on the axis below z = 0 (m; 0 with a rigid wall)."""
        if self.block_block is None:
            return 0.0
        dofs = self.system.dofmap[self.block_block]
        return float(-u[dofs.offset + 2 * self._pole + 1])

    def plastic_part(self) -> tuple[Any, str, int, Any, Any] | None:
        """The block's finite-strain J2 term: (model, block name, term index, weight, transfer
        from the block's dofs), or None in the elastic regime."""
        if not self.plastic or self.block_block is None:
            return None
        if self.zoned is not None:
            return self.zoned.j2, self.block_block, 1, None, self.zoned.transfer
        term = self.system.block(self.block_block).terms[0]
        return term.model, self.block_block, 0, term.weight, None

    def block_energies(self, u: np.ndarray, states: dict,
                       energies: dict | None = None) -> tuple[float, float]:  # fmt: skip
        """(elastic energy, plastic dissipation) (J) of the block carrying the J2 law.

        ``energies``: the integrator's
        :meth:`~arlequin.solvers.dynamics.base.Integrator.energies` at the same state, if the
        caller has them. When the J2 law is its block's only term (no zoned body: not
        ``mono-zoned`` or ``graded``) and has no bulk viscosity, the block's
        ``stored`` and ``dissipation`` there are these numbers (the same calls on the same
        state): taken from them rather than computed twice.
        """
        part = self.plastic_part()
        if part is None:
            return 0.0, 0.0
        model, block, index, weight, _ = part
        terms = self.system.block(block).terms
        if (energies is not None and self.zoned is None
                and not getattr(model, "bulk_viscosity", None)
                and len(terms) == 1 and terms[0].sign == 1):  # fmt: skip
            return energies["stored"][block], energies["dissipation"][block]
        ub = u[self.system.dofmap[block].slice]
        state = states[block][index]
        # the committed state is the one at u: its own τ gives ψ (no kinematics)
        elastic = model.elastic_energy_of_state(state, weight)
        if self.zoned is not None:
            k = self.system.block(block).terms[0].model.stiffness_matrix
            elastic += 0.5 * float(ub @ (k @ ub))
        return elastic, model.plastic_dissipation(state, weight)

    def plastic_strain(self, states: dict) -> tuple[Any, np.ndarray] | None:
        """(the J2 mesh, its cell-mean ε̄p) or None."""
        part = self.plastic_part()
        if part is None:
            return None
        model, block, index, _, _ = part
        return model.mesh, states[block][index].eqps.mean(axis=1)

    def j2_displacement(self, u: np.ndarray) -> np.ndarray:
        """The J2 mesh's displacement dofs (m) from the system's ``u``."""
        _, block, _, _, transfer = self.plastic_part()
        ub = u[self.system.dofmap[block].slice]
        return ub if transfer is None else transfer @ ub
