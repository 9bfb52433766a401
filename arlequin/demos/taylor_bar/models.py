"""The two ways of modelling the Taylor bar: one finite-strain mesh, or the Arlequin pair.

:class:`MonoBar` is one axisymmetric Q1 F-bar mesh over the whole bar. :class:`ArlequinBar` is
the source paper's Figure 2: a coarse linear-elastic model of the whole bar and a refined
finite-strain J2 patch over the impacted end (a nested refinement of the coarse cells it
covers), glued through the mediator in a band of coarse rows at the top of the patch, with the
partition weights ramped across the band and the rigid wall acting on the patch only.

Under the patch, below the band, the coarse model keeps the weight floor ε (α_coarse = ε,
α_fine = 1 − ε, default ε = 1e-3): it is a free linear-elastic bar of ε-weighted stiffness and
mass, hanging from the band. Linear, it cannot blow up or invert a cell (it has no such notion),
and it sees no wall, so it creates no spurious contact; it carries ε of its share of the
energies, all accounted for in the balance. Its motion there has no physical meaning (it is not
glued), so the pictures draw the coarse cells above the band's lower edge only. Removing those
coarse cells instead would give the same answer up to O(ε) and save little: they are linear,
a sparse product per step.

Both models carry u_r = 0 on the axis, and so does the mediator space
(``ArlequinProblem(..., mediator_dirichlet="drop")``): with the fine mediator, whose rows tie
every patch dof of the band to the coarse field, the rows of u_r on the axis would repeat the
axis conditions (linearly dependent rows), and with either mediator they would carry the axis
reactions, which oscillate from step to step in an explicit run.

Both classes give the recorder (:mod:`arlequin.demos.taylor_bar.record`) the same view: the
length and footprint radius of a displacement, the energies of the models, the field frames
and the final picture. SI units.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
import skfem

from ...models import (
    HARDENING_LAWS,
    ContactSurface,
    CoulombContact,
    FiniteStrainJ2,
    J2Material,
    LevelSetContact,
    LinearElastic,
    PlaneObstacle,
    RigidContactPair,
    make_hardening,
)
from ...problem.arlequin_problem import ArlequinProblem, Patch
from ...problem.system import Block, BlockTerm, CoupledSystem, LinearConstraint
from .meshes import ArlequinBarSizes, taylor_bar_mesh

__all__ = ["LAW_DEFAULTS", "ArlequinBar", "ArlequinBarView", "MonoBar", "hardening_parameters"]

#: Part of the lateral surface, from the impact face, that the wall may meet (it folds onto the
#: wall as the mushroom forms), as a fraction of the bar length.
LATERAL_CONTACT = 0.3


#: Default parameters of each hardening law (Pa, dimensionless, 1/s); σ_y0 and H come from
#: ``yield_stress`` and ``hardening`` for every law.
LAW_DEFAULTS: dict[str, dict[str, float]] = {
    "linear": {},
    "voce": {"voce_saturation": 0.1e9, "voce_rate": 10.0},
    "johnson-cook": {"jc_b": 0.292e9, "jc_n": 0.31, "jc_c": 0.0, "jc_reference_rate": 1.0},
}


def hardening_parameters(law: str, yield_stress: float, hardening: float, **params: float):
    """The :class:`~arlequin.models.Hardening` of a law name and the CLI's parameters.

    ``linear``: σ_y0 + H ε̄p; ``voce``: σ_y0 + Q(1 − e^{−b ε̄p}) + H ε̄p (``voce_saturation`` Q,
    ``voce_rate`` b); ``johnson-cook``: (σ_y0 + B ε̄p^n)(1 + C ln(ε̄̇p/ε̄̇0)) (``jc_b``, ``jc_n``,
    ``jc_c``, ``jc_reference_rate``; H unused).
    """
    if law not in HARDENING_LAWS:
        raise ValueError(f"hardening law must be one of {HARDENING_LAWS}, got {law!r}")
    p = {**LAW_DEFAULTS[law], **{k: v for k, v in params.items() if v is not None}}
    unknown = set(p) - set(LAW_DEFAULTS[law])
    if unknown:
        raise ValueError(f"parameters {sorted(unknown)} do not belong to the {law} law")
    if law == "linear":
        return make_hardening("linear", yield_stress=yield_stress, modulus=hardening)
    if law == "voce":
        return make_hardening("voce", yield_stress=yield_stress, saturation=p["voce_saturation"],
                              rate=p["voce_rate"], modulus=hardening)  # fmt: skip
    return make_hardening("johnson-cook", a=yield_stress, b=p["jc_b"], n=p["jc_n"], c=p["jc_c"],
                          reference_rate=p["jc_reference_rate"])  # fmt: skip


def _wall(mesh, offset, dofmap, material, tol, lateral, radius,
          friction: float = 0.0) -> LevelSetContact:  # fmt: skip
    """The level-set wall z = 0 on the impact face and the lower lateral surface of a mesh
    (Coulomb friction μ = ``friction`` if positive; μ = 0: the frictionless model)."""

    def on_wall_side(x):
        return (x[1] < tol) | ((x[0] > radius - tol) & (x[1] < lateral))

    surface = ContactSurface(mesh, where=on_wall_side, offset=offset, axisymmetric=True)
    wall = PlaneObstacle(np.zeros(2), np.array([0.0, 1.0]))
    pair = RigidContactPair(surface, wall, dofmap)
    if friction > 0.0:
        return CoulombContact(pair, friction, material=material, name="wall")
    return LevelSetContact(pair, material=material, name="wall")


class MonoBar:
    """One finite-strain J2 mesh over the whole bar (block ``"bar"``).

    Parameters
    ----------
    length, radius : float
        L and R (m).
    elements_radial : int
        Cells across the radius (of the uniform mesh).
    mesh : skfem.MeshQuad, optional
        Another mesh of the bar instead (the graded one).
    material : J2Material
    fbar, backend, bulk_viscosity
        As :class:`~arlequin.models.FiniteStrainJ2`.
    """

    fine_block = "bar"
    #: the fine cells of a graded mesh (set when the mesh is one; None for a uniform mesh)
    graded_fine_elements: int | None = None

    def __init__(self, length, radius, elements_radial, material: J2Material, fbar=True,
                 backend="auto", bulk_viscosity=None, mesh=None,
                 friction: float = 0.0) -> None:  # fmt: skip
        if mesh is None:
            mesh = taylor_bar_mesh(length, radius, elements_radial)
        self.mesh = self.fine_mesh = mesh
        self.model = FiniteStrainJ2(mesh, material, "axisymmetric", fbar, backend=backend,
                                    bulk_viscosity=bulk_viscosity)  # fmt: skip
        bar = self.model
        tol = 1e-9 * radius
        p = mesh.p
        axis = np.nonzero(p[0] < tol)[0]
        dofs = bar.nodal_dofs()
        rows = sp.csr_matrix((np.ones(axis.size), (np.arange(axis.size), dofs[0, axis])),
                             shape=(axis.size, bar.n_dofs))  # fmt: skip
        self.system = CoupledSystem(
            [Block("bar", bar, [BlockTerm(bar)])],
            [LinearConstraint(rows, None, name="axis", kind="dirichlet")],
        )
        self.contact = _wall(mesh, self.system.dofmap["bar"], self.system.dofmap,
                             material.elastic, tol, LATERAL_CONTACT * length, radius,
                             friction)  # fmt: skip
        self._axis_top = int(np.nonzero((p[0] < tol) & (p[1] > length - tol))[0][0])
        self._face = np.nonzero(p[1] < tol)[0]
        self._r, self._z = dofs[0], dofs[1]
        self.n_elements = int(mesh.nelements)

    def initial_velocity(self, velocity: float) -> np.ndarray:
        """The system's initial velocity (m/s): −``velocity`` along z on every node."""
        v0 = np.zeros(self.system.dofmap.n_dofs)
        v0[self._z] = -velocity
        return v0

    def lumped_mass(self) -> np.ndarray:
        """The lumped mass (kg per dof)."""
        return self.model.mass(lumped=True)

    def fine_state(self, integ) -> Any:
        """The finite-strain model's quadrature state (``PlasticState``) in the integrator."""
        return integ.states["bar"][0]

    def measures(self, u: np.ndarray) -> tuple[float, float]:
        """(length, footprint radius) of a displacement (m)."""
        x = self.model.current_coordinates(u)
        return float(x[1, self._axis_top]), float(x[0, self._face].max())

    def energies(self, integ, e: dict) -> dict[str, float]:
        """Stored (elastic), plastic and viscous energies and the coupling work (J); ``e`` is
        ``integ.energies()`` (unused on one mesh)."""
        state = self.fine_state(integ)
        return {
            "elastic": self.model.elastic_energy_of_state(state),
            "plastic_dissipation": self.model.plastic_dissipation(state),
            "viscous_dissipation": self.model.viscous_dissipation(state),
            "coupling_work": 0.0,
        }

    def series_meshes(self) -> dict[str, Any]:
        """Series name -> reference mesh of the field series the run writes."""
        return {"bar": self.mesh}

    def frame(self, integ) -> dict[str, tuple[dict, dict]]:
        """Series name -> (point data, cell data) of one field frame at the integrator's time."""
        u, v, state = integ.u, integ.v, self.fine_state(integ)
        pad = np.zeros(self.mesh.nvertices)
        point = {
            "displacement": np.column_stack([u[self._r], u[self._z], pad]),
            "velocity": np.column_stack([v[self._r], v[self._z], pad]),
        }
        cell = {
            "plastic_strain": state.eqps.mean(axis=1),
            "von_mises": state.von_mises.mean(axis=1),
        }
        return {"bar": (point, cell)}

    def render(self, u, state, path: str, title: str) -> None:
        """The picture of the final state (PNG at ``path``), pyvista off-screen."""
        from .render import render_taylor_bar

        render_taylor_bar(self.model, u, state, path, title)


class ArlequinBarView:
    """What the Arlequin bars (axisymmetric and 3D) show the recorder alike: the split of a
    system vector, the weighted energies, the field frames and the band's plastic strain.

    Needs ``self._c``, ``self._f`` (the blocks' slices), ``coupling``, ``model``, ``layout``,
    ``system``, ``coarse_mesh``, ``fine_mesh``, ``band_cells`` and ``fine_state``.
    """

    def split(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The coarse and the patch parts of a system vector ``u``."""
        return u[self._c], u[self._f]

    def energies(self, integ, e: dict) -> dict[str, float]:
        """Weighted energies of both models and the net work of the coupling forces (J);
        ``e`` is ``integ.energies()``."""
        state = self.fine_state(integ)
        alpha = self.coupling.alpha_fine
        return {
            "elastic": e["strain"]["coarse"] + self.model.elastic_energy_of_state(state, alpha),
            "plastic_dissipation": self.model.plastic_dissipation(state, alpha),
            "viscous_dissipation": self.model.viscous_dissipation(state, alpha),
            "coupling_work": float(sum(e["coupling_work"].values())),
        }

    def series_meshes(self) -> dict[str, Any]:
        """Series name -> reference mesh of the field series the run writes."""
        return {"coarse": self.coarse_mesh, "patch": self.fine_mesh}

    def frame(self, integ) -> dict[str, tuple[dict, dict]]:
        """Series name -> (point data, cell data) of one field frame at the integrator's time."""
        frames = self.layout.frame(self.system.dofmap, integ.u, integ.v, integ.multipliers)
        state = self.fine_state(integ)
        frames["patch"][1]["plastic_strain"] = state.eqps.mean(axis=1)
        frames["patch"][1]["von_mises"] = state.von_mises.mean(axis=1)
        return frames

    def band_plastic_strain(self, state) -> float:
        """Largest ε̄p at the quadrature points of the gluing band's fine cells."""
        return float(np.asarray(state.eqps)[self.band_cells].max())


class ArlequinBar(ArlequinBarView):
    """The coarse linear-elastic bar plus the refined finite-strain J2 patch (module docstring).

    Blocks ``"coarse"`` and ``"patch"``; u_r = 0 on the axis of both; the wall on the patch's
    impact face and lower lateral surface.

    Parameters
    ----------
    length, radius : float
        L and R (m).
    sizes : ArlequinBarSizes
    material : J2Material
        The patch's material; the coarse model uses its elastic part.
    weights, mediator, coupling, epsilon
        As :class:`~arlequin.Patch`.
    fbar, backend, bulk_viscosity
        As :class:`~arlequin.models.FiniteStrainJ2`.
    """

    fine_block = "patch"
    coarse_block = "coarse"

    def __init__(self, length, radius, sizes: ArlequinBarSizes, material: J2Material,
                 weights="ramp", mediator="fine", coupling="H1", epsilon=1e-3, fbar=True,
                 backend="auto", bulk_viscosity=None, friction: float = 0.0) -> None:  # fmt: skip
        s = sizes
        self.sizes = s
        n_f, rows_f = s.coarse_radial * s.ratio, s.patch_rows * s.ratio
        tensor = skfem.MeshQuad.init_tensor
        cmesh = tensor(np.linspace(0.0, radius, s.coarse_radial + 1),
                       np.linspace(0.0, length, s.coarse_axial + 1))  # fmt: skip
        fmesh = tensor(np.linspace(0.0, radius, n_f + 1),
                       np.linspace(0.0, s.patch_length, rows_f + 1))  # fmt: skip
        self.coarse_mesh, self.fine_mesh = cmesh, fmesh
        self.coarse = LinearElastic(cmesh, material.elastic, kind="axisymmetric")
        self.model = FiniteStrainJ2(fmesh, material, "axisymmetric", fbar, backend=backend,
                                    bulk_viscosity=bulk_viscosity)  # fmt: skip
        patch = Patch(self.model, gluing_width=s.gluing_width, weights=weights, epsilon=epsilon,
                      coupling=coupling, mediator=mediator, overlap_method="nested",
                      name="patch")  # fmt: skip
        # both models have u_r = 0 on the axis: the mediator space too (module docstring)
        self.problem = ArlequinProblem(self.coarse, [patch], mediator_dirichlet="drop")
        tol = 1e-9 * radius
        for block in ("coarse", "patch"):
            self.problem.add_dirichlet(block, lambda x: x[0] < tol, components=[0])
        self.system = self.problem.system()
        self.coupling = self.problem.couplings[0]
        self.layout = self.problem.field_layout()
        dm = self.system.dofmap
        # the wall's lateral reach stays below the gluing band
        lateral = min(LATERAL_CONTACT * length, s.patch_length - s.gluing_width)
        self.contact = _wall(fmesh, dm["patch"], dm, material.elastic, tol, lateral, radius,
                             friction)  # fmt: skip
        self._c = dm["coarse"].slice
        self._f = dm["patch"].slice
        self._cz = dm["coarse"].component_dofs(1)
        self._fz = dm["patch"].component_dofs(1)
        cp = cmesh.p
        self._axis_top = int(np.nonzero((cp[0] < tol) & (cp[1] > length - tol))[0][0])
        self._face = np.nonzero(fmesh.p[1] < tol)[0]
        self.band_cells = self.coupling.fine_gluing_cells
        # coarse cells drawn in the pictures: those reaching above the band's lower edge
        z_cells = cmesh.p[1, cmesh.t].max(axis=0)
        self.drawn_coarse_cells = np.nonzero(
            z_cells > s.patch_length - s.gluing_width + 1e-9 * length
        )[0]
        self.n_elements = int(cmesh.nelements + fmesh.nelements)
        self.coarse_elements = int(cmesh.nelements)
        self.fine_elements = int(fmesh.nelements)
        #: p: the patch's share of the fine elements of a uniform mesh at its resolution
        self.patch_fraction = s.patch_rows / s.coarse_axial

    def initial_velocity(self, velocity: float) -> np.ndarray:
        """The system's initial velocity (m/s): −``velocity`` along z on every node."""
        v0 = np.zeros(self.system.dofmap.n_dofs)
        v0[self._cz] = -velocity
        v0[self._fz] = -velocity
        return v0

    def lumped_mass(self) -> np.ndarray:
        """The coupled system's lumped, α-weighted mass (kg; its sum is the bar's mass)."""
        return np.asarray(self.system.mass(lumped=True))

    def fine_state(self, integ) -> Any:
        """The finite-strain model's quadrature state (``PlasticState``) in the integrator."""
        return integ.states["patch"][0]

    def measures(self, u: np.ndarray) -> tuple[float, float]:
        """(length from the coarse model's top node on the axis, footprint radius from the
        patch's impact face) (m)."""
        uc, uf = self.split(u)
        length = self.coarse_mesh.p[1, self._axis_top] + uc[2 * self._axis_top + 1]
        r = self.fine_mesh.p[0, self._face] + uf[2 * self._face]
        return float(length), float(r.max())

    def render(self, u, state, path: str, title: str) -> None:
        """The picture of the final state (PNG at ``path``), pyvista off-screen."""
        from .render import render_arlequin_bar

        render_arlequin_bar(self, u, state, path, title)
