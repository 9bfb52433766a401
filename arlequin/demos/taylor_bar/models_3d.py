"""The 3D Taylor bar: a quarter bar of hexahedra, one finite-strain mesh or the Arlequin pair.

The quarter x, y ≥ 0 of the bar (:mod:`arlequin.demos.taylor_bar.meshes_3d`) with the symmetry
conditions u_x = 0 on x = 0 and u_y = 0 on y = 0. :class:`MonoBar3D` is one finite-strain J2
mesh of 8-node F-bar hexahedra over the whole quarter; :class:`ArlequinBar3D` a coarse
linear-elastic quarter bar plus a nested finite-strain patch over the impacted end (the coarse
cells below ``patch_length`` refined, their new lateral nodes moved onto the cylinder), glued by
the mediator in a band of coarse layers at the patch's top, as the axisymmetric
:class:`~arlequin.demos.taylor_bar.models.ArlequinBar` (same weights, weight floor, mediator space
without the symmetry components). The wall z = 0 is the level-set contact on the impact face and
the lower lateral surface.

Energies, masses and forces are those of the quarter (a quarter of the full bar's). Both classes
give the recorder the same view as the axisymmetric ones: the length and footprint radius of a
displacement, the energies, the field frames and the final picture. SI units.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
import skfem

from ...coupling.patches import Patch, select_cells
from ...models import (
    ContactSurface,
    CoulombContact,
    FiniteStrainJ2,
    J2Material,
    LevelSetContact,
    LinearElastic,
    PlaneObstacle,
    RigidContactPair,
)
from ...problem.arlequin_problem import ArlequinProblem
from ...problem.system import Block, BlockTerm, CoupledSystem, LinearConstraint
from .meshes import ArlequinBarSizes
from .meshes_3d import patch_levels, quarter_bar_mesh, refined_bar_mesh
from .models import LATERAL_CONTACT, ArlequinBarView

__all__ = [
    "ArlequinBar3D",
    "MonoBar3D",
    "check_arlequin_sizes_3d",
]


def _wall(mesh, offset, dofmap, material, radius, lateral, friction) -> LevelSetContact:
    """The level-set wall z = 0 on the impact face and the lateral surface below ``lateral``."""
    h_min = float(np.min(np.linalg.norm(np.diff(mesh.p[:, mesh.facets[:2]], axis=1), axis=0)))
    tol = 1e-9 * radius

    def on_wall_side(x):  # facet midpoints: the lateral ones sit a sagitta inside r = R
        return (x[2] < tol) | ((np.hypot(x[0], x[1]) > radius - 0.25 * h_min) & (x[2] < lateral))

    surface = ContactSurface(mesh, where=on_wall_side, offset=offset)
    wall = PlaneObstacle(np.zeros(3), np.array([0.0, 0.0, 1.0]))
    pair = RigidContactPair(surface, wall, dofmap)
    if friction > 0.0:
        return CoulombContact(pair, friction, material=material, name="wall")
    return LevelSetContact(pair, material=material, name="wall")


def _surface_cells(cmesh: skfem.MeshHex, surface: Any, length: float) -> np.ndarray:
    """The coarse cells inside a closed surface, checked to hold the impact face's cells."""
    cells = select_cells(cmesh, surface=surface)
    at_face = np.nonzero(cmesh.p[2, cmesh.t].min(axis=0) < 1e-9 * length)[0]
    missing = np.setdiff1d(at_face, cells)
    if missing.size:
        raise ValueError(f"the patch surface must enclose the impact face z = 0 (the wall acts "
                         f"on the patch): {missing.size} of the {at_face.size} coarse cells on "
                         f"it have their centroid outside")  # fmt: skip
    return cells


class _Quarter:
    """What the single-mesh and the Arlequin 3D bars share: measures, frames, the picture."""

    radius: float
    fine_mesh: skfem.MeshHex
    model: FiniteStrainJ2

    def _locate(self, mesh: skfem.MeshHex, fine_mesh: skfem.MeshHex, length: float) -> None:
        """The top node on the axis of ``mesh`` (the length) and the impact face's nodes of
        ``fine_mesh`` (the footprint)."""
        tol = 1e-9 * self.radius
        p = mesh.p
        on_axis = (np.abs(p[0]) < tol) & (np.abs(p[1]) < tol)
        self._axis_top = int(np.nonzero(on_axis & (p[2] > length - 1e-9 * length))[0][0])
        self._face = np.nonzero(fine_mesh.p[2] < tol)[0]

    def initial_velocity(self, velocity: float) -> np.ndarray:
        """The system's initial velocity (m/s): −``velocity`` along z on every node."""
        v0 = np.zeros(self.system.dofmap.n_dofs)
        for name in self.system.dofmap:
            v0[self.system.dofmap[name].component_dofs(2)] = -velocity
        return v0

    def lumped_mass(self) -> np.ndarray:
        """The system's lumped (α-weighted) mass (kg per dof; its sum is 3 × the quarter's)."""
        return np.asarray(self.system.mass(lumped=True))

    def fine_state(self, integ) -> Any:
        """The finite-strain model's quadrature state (``PlasticState``) in the integrator."""
        return integ.states[self.fine_block][0]

    def _footprint(self, uf: np.ndarray) -> float:
        x = self.fine_mesh.p[:, self._face] + uf.reshape(-1, 3).T[:, self._face]
        return float(np.hypot(x[0], x[1]).max())

    def render(self, u, state, path: str, title: str) -> None:
        """The picture of the final state (PNG at ``path``), pyvista off-screen."""
        from .render_3d import render_taylor_bar_3d

        render_taylor_bar_3d(self, u, state, path, title)


def _symmetry_rows(dofs: np.ndarray, p: np.ndarray, tol: float, n_dofs: int, offset: int = 0):
    """Rows of u_x = 0 on x = 0 and u_y = 0 on y = 0 (a CSR matrix, n_dofs columns)."""
    cols = np.concatenate([dofs[0, np.abs(p[0]) < tol], dofs[1, np.abs(p[1]) < tol]]) + offset
    return sp.csr_matrix((np.ones(cols.size), (np.arange(cols.size), cols)),
                         shape=(cols.size, n_dofs))  # fmt: skip


class MonoBar3D(_Quarter):
    """One finite-strain J2 mesh (F-bar hexahedra) over the quarter bar (block ``"bar"``).

    Parameters
    ----------
    length, radius : float
        L and R (m).
    elements_radial : int
        Cells across the radius of the O-grid (≥ 2).
    material : J2Material
    fbar, backend, bulk_viscosity
        As :class:`~arlequin.models.FiniteStrainJ2`.
    mesh : skfem.MeshHex, optional
        Another mesh of the quarter bar instead (a refined one: :func:`refined_bar_mesh`).
    friction : float
        Coulomb μ against the wall (0: frictionless).
    """

    fine_block = "bar"
    #: the fine cells of a graded mesh (set when the mesh is one; None for a uniform mesh)
    graded_fine_elements: int | None = None

    def __init__(self, length, radius, elements_radial, material: J2Material, fbar=True,
                 backend="auto", bulk_viscosity=None, mesh=None,
                 friction: float = 0.0) -> None:  # fmt: skip
        if mesh is None:
            mesh = quarter_bar_mesh(length, radius, elements_radial)
        self.radius = radius
        self.mesh = self.fine_mesh = mesh
        self.model = FiniteStrainJ2(mesh, material, "3d", fbar, backend=backend,
                                    bulk_viscosity=bulk_viscosity)  # fmt: skip
        bar = self.model
        rows = _symmetry_rows(bar.nodal_dofs(), mesh.p, 1e-9 * radius, bar.n_dofs)
        self.system = CoupledSystem([Block("bar", bar, [BlockTerm(bar)])],
                                    [LinearConstraint(rows, None, name="symmetry",
                                                      kind="dirichlet")])  # fmt: skip
        self.contact = _wall(
            mesh,
            self.system.dofmap["bar"],
            self.system.dofmap,
            material.elastic,
            radius,
            LATERAL_CONTACT * length,
            friction,
        )
        self._locate(mesh, mesh, length)
        self.n_elements = int(mesh.nelements)
        #: layers along z
        self.elements_axial = int(np.unique(np.round(mesh.p[2] / (1e-9 * length))).size - 1)

    def measures(self, u: np.ndarray) -> tuple[float, float]:
        """(length, footprint radius) of a displacement (m)."""
        return float(self.mesh.p[2, self._axis_top] + u[3 * self._axis_top + 2]), \
            self._footprint(u)  # fmt: skip

    def energies(self, integ, e: dict) -> dict[str, float]:
        """Stored (elastic), plastic and viscous energies of the quarter (J)."""
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
        state = self.fine_state(integ)
        point = {"displacement": integ.u.reshape(-1, 3), "velocity": integ.v.reshape(-1, 3)}
        cell = {"plastic_strain": state.eqps.mean(axis=1),
                "von_mises": state.von_mises.mean(axis=1)}  # fmt: skip
        return {"bar": (point, cell)}


def check_arlequin_sizes_3d(s: ArlequinBarSizes) -> int:
    """The refinement levels of the 3D Arlequin bar's patch (2^levels = s.ratio).

    Raises
    ------
    ValueError
        Unless the ratio is a power of two and the coarse O-grid has at least 4 cells across
        the radius.
    """
    levels = patch_levels(s.ratio)
    if s.coarse_radial < 4:
        # coarser, the O-grid's chords lie too far inside the cylinder for the patch's
        # lateral nodes (on it) to be located in the coarse cells
        raise ValueError(f"the 3D Arlequin bar needs at least 4 coarse cells across the "
                         f"radius, got {s.coarse_radial} (coarse size "
                         f"{s.coarse_size:.4g} m): refine the coarse size")  # fmt: skip
    return levels


class ArlequinBar3D(ArlequinBarView, _Quarter):
    """The coarse linear-elastic quarter bar plus the nested finite-strain J2 patch.

    Blocks ``"coarse"`` and ``"patch"``; symmetry conditions on both (and dropped from the
    mediator space, as the axis conditions of the axisymmetric bar); the wall on the patch.

    Parameters
    ----------
    length, radius : float
        L and R (m).
    sizes : ArlequinBarSizes
        ``coarse_radial`` the O-grid's cells across the radius, ``coarse_axial`` its layers,
        ``ratio`` a power of two (fine cells per coarse edge), ``patch_rows`` and ``band_rows``
        coarse layers.
    material, weights, mediator, coupling, epsilon, fbar, backend, bulk_viscosity, friction
        As :class:`~arlequin.demos.taylor_bar.models.ArlequinBar`.
    """

    fine_block = "patch"
    coarse_block = "coarse"

    def __init__(self, length, radius, sizes: ArlequinBarSizes, material: J2Material,
                 weights="ramp", mediator="fine", coupling="H1", epsilon=1e-3, fbar=True,
                 backend="auto", bulk_viscosity=None, friction: float = 0.0,
                 surface: Any = None) -> None:  # fmt: skip
        s = sizes
        levels = check_arlequin_sizes_3d(s)
        self.sizes, self.radius = s, radius
        cmesh = quarter_bar_mesh(length, radius, s.coarse_radial, s.coarse_axial)
        if surface is None:
            z_top = s.patch_length * (1 + 1e-9)
            cells = select_cells(cmesh, box=((-1.0, -1.0, -1.0), (1.0, 1.0, z_top)))
        else:
            cells = _surface_cells(cmesh, surface, length)
        self.patch_cells = cells
        fmesh = refined_bar_mesh(cmesh.restrict(cells), radius, levels)
        self.coarse_mesh, self.fine_mesh = cmesh, fmesh
        self.coarse = LinearElastic(cmesh, material.elastic, kind="3d")
        self.model = FiniteStrainJ2(fmesh, material, "3d", fbar, backend=backend,
                                    bulk_viscosity=bulk_viscosity)  # fmt: skip
        # nested, the patch's lateral nodes moved onto the cylinder a sagitta outside the
        # coarse cells: the coarse functions are extrapolated there (build_overlap)
        patch = Patch(self.model, gluing_width=s.gluing_width, weights=weights, epsilon=epsilon,
                      coupling=coupling, mediator=mediator, overlap_method="nested",
                      name="patch")  # fmt: skip
        self.problem = ArlequinProblem(self.coarse, [patch], mediator_dirichlet="drop")
        tol = 1e-9 * radius
        for block in ("coarse", "patch"):
            self.problem.add_dirichlet(block, lambda x: np.abs(x[0]) < tol, components=[0])
            self.problem.add_dirichlet(block, lambda x: np.abs(x[1]) < tol, components=[1])
        self.system = self.problem.system()
        self.coupling = self.problem.couplings[0]
        self.layout = self.problem.field_layout()
        dm = self.system.dofmap
        # the wall's lateral reach stays below the gluing band: below the lowest coarse node
        # of a cell left out of the patch, less the band's width
        outside = np.setdiff1d(np.arange(cmesh.nelements), cells)
        z_out = cmesh.p[2, cmesh.t[:, outside]].min() if outside.size else length
        lateral = min(LATERAL_CONTACT * length, z_out - s.gluing_width)
        if lateral <= 0.0:
            raise ValueError(f"the patch leaves the coarse cells at z = {z_out:.4g} m, within "
                             f"the gluing width {s.gluing_width:.4g} m of the impact face: "
                             f"enlarge the patch")  # fmt: skip
        self.contact = _wall(fmesh, dm["patch"], dm, material.elastic, radius, lateral,
                             friction)  # fmt: skip
        self._c, self._f = dm["coarse"].slice, dm["patch"].slice
        self._locate(cmesh, fmesh, length)
        tol_z = 1e-9 * length
        cp = cmesh.p
        self.band_cells = self.coupling.fine_gluing_cells
        z_cells = cp[2, cmesh.t].max(axis=0)
        #: the top of the patch (m): its highest coarse node (patch_length unless a surface)
        self.patch_top = float(cp[2, cmesh.t[:, cells]].max())
        self.drawn_coarse_cells = np.nonzero(z_cells > z_out - s.gluing_width + tol_z)[0]
        self.n_elements = int(cmesh.nelements + fmesh.nelements)
        self.coarse_elements = int(cmesh.nelements)
        self.fine_elements = int(fmesh.nelements)
        #: p: the patch's share of the fine elements of a uniform mesh at its resolution
        self.patch_fraction = cells.size / cmesh.nelements

    def measures(self, u: np.ndarray) -> tuple[float, float]:
        """(length from the coarse model's top node on the axis, footprint radius from the
        patch's impact face) (m)."""
        uc, uf = self.split(u)
        return float(self.coarse_mesh.p[2, self._axis_top] + uc[3 * self._axis_top + 2]), \
            self._footprint(uf)  # fmt: skip
