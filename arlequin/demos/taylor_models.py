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

Both classes give the recorder (:mod:`arlequin.demos.taylor_record`) the same view: the
length and footprint radius of a displacement, the energies of the models, the field frames
and the final picture. SI units.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import scipy.sparse as sp
import skfem

from ..models import (
    ContactSurface,
    FiniteStrainJ2,
    J2Material,
    LevelSetContact,
    LinearElastic,
    PlaneObstacle,
    RigidContactPair,
)
from ..problem import ArlequinProblem, Patch
from ..system import Block, BlockTerm, CoupledSystem, LinearConstraint

__all__ = ["ArlequinBar", "ArlequinBarSizes", "MonoBar", "arlequin_bar_sizes", "taylor_bar_mesh"]

#: Part of the lateral surface, from the impact face, that the wall may meet (it folds onto the
#: wall as the mushroom forms), as a fraction of the bar length.
LATERAL_CONTACT = 0.3


def taylor_bar_mesh(length: float, radius: float, elements_radial: int) -> skfem.MeshQuad:
    """Meridional (r, z) Q1 mesh of the bar: ``elements_radial`` cells across the radius and
    round(L / h) along the axis, h = R / elements_radial (nearly square cells), z ∈ [0, L]."""
    n_r = int(elements_radial)
    n_z = max(1, round(length / (radius / n_r)))
    return skfem.MeshQuad.init_tensor(np.linspace(0.0, radius, n_r + 1),
                                      np.linspace(0.0, length, n_z + 1))  # fmt: skip


def _wall(mesh, offset, dofmap, material, tol, lateral, radius) -> LevelSetContact:
    """The level-set wall z = 0 on the impact face and the lower lateral surface of a mesh."""

    def on_wall_side(x):
        return (x[1] < tol) | ((x[0] > radius - tol) & (x[1] < lateral))

    surface = ContactSurface(mesh, where=on_wall_side, offset=offset, axisymmetric=True)
    wall = PlaneObstacle(np.zeros(2), np.array([0.0, 1.0]))
    return LevelSetContact(RigidContactPair(surface, wall, dofmap), material=material,
                           name="wall")  # fmt: skip


class MonoBar:
    """One finite-strain J2 mesh over the whole bar (block ``"bar"``).

    Parameters
    ----------
    length, radius : float
        L and R (m).
    elements_radial : int
        Cells across the radius.
    material : J2Material
    fbar, backend, bulk_viscosity
        As :class:`~arlequin.models.FiniteStrainJ2`.
    """

    fine_block = "bar"

    def __init__(self, length, radius, elements_radial, material: J2Material, fbar=True,
                 backend="auto", bulk_viscosity=None) -> None:  # fmt: skip
        mesh = taylor_bar_mesh(length, radius, elements_radial)
        self.mesh = mesh
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
                             material.elastic, tol, LATERAL_CONTACT * length, radius)  # fmt: skip
        self._axis_top = int(np.nonzero((p[0] < tol) & (p[1] > length - tol))[0][0])
        self._face = np.nonzero(p[1] < tol)[0]
        self._r, self._z = dofs[0], dofs[1]
        self.n_elements = int(mesh.nelements)
        self.fine_weight = None

    def initial_velocity(self, velocity: float) -> np.ndarray:
        v0 = np.zeros(self.system.dofmap.n_dofs)
        v0[self._z] = -velocity
        return v0

    def lumped_mass(self) -> np.ndarray:
        return self.model.mass(lumped=True)

    def fine_state(self, integ) -> Any:
        return integ.states["bar"][0]

    def measures(self, u: np.ndarray) -> tuple[float, float]:
        """(length, footprint radius) of a displacement (m)."""
        x = self.model.current_coordinates(u)
        return float(x[1, self._axis_top]), float(x[0, self._face].max())

    def energies(self, integ) -> dict[str, float]:
        """Stored (elastic), plastic and viscous energies and the coupling work (J)."""
        state = self.fine_state(integ)
        u = integ.u
        return {
            "elastic": self.model.stored_energy(u, state),
            "plastic_dissipation": self.model.plastic_dissipation(state),
            "viscous_dissipation": self.model.viscous_dissipation(state),
            "coupling_work": 0.0,
        }

    def series_meshes(self) -> dict[str, Any]:
        return {"bar": self.mesh}

    def frame(self, integ) -> dict[str, tuple[dict, dict]]:
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

    def fine_displacement(self, u: np.ndarray) -> np.ndarray:
        return u

    def render(self, u, state, path: str, title: str) -> None:
        from .render import render_taylor_bar

        render_taylor_bar(self.model, u, state, path, title)


class ArlequinBarSizes:
    """The nested meshes of :class:`ArlequinBar`, snapped to coarse cell edges (SI units).

    Attributes
    ----------
    coarse_radial, coarse_axial : int
        Coarse cells across the radius and along the bar.
    ratio : int
        Fine cells per coarse cell edge (k = coarse size / fine size).
    patch_rows, band_rows : int
        Coarse rows under the patch and in the gluing band (the band is the top of the patch).
    coarse_size, fine_size : float
        Cell edges across the radius (m).
    patch_length, gluing_width : float
        The snapped patch length and band width (m).
    """

    def __init__(self, coarse_radial, coarse_axial, ratio, patch_rows, band_rows, length,
                 radius) -> None:  # fmt: skip
        self.coarse_radial, self.coarse_axial, self.ratio = coarse_radial, coarse_axial, ratio
        self.patch_rows, self.band_rows = patch_rows, band_rows
        self.coarse_size = radius / coarse_radial
        self.fine_size = self.coarse_size / ratio
        self.axial_size = length / coarse_axial  # coarse cell height
        self.patch_length = patch_rows * self.axial_size
        self.gluing_width = band_rows * self.axial_size

    def as_dict(self) -> dict[str, Any]:
        return {
            "coarse_radial": self.coarse_radial, "coarse_axial": self.coarse_axial,
            "ratio": self.ratio, "patch_rows": self.patch_rows, "band_rows": self.band_rows,
            "coarse_size": self.coarse_size, "fine_size": self.fine_size,
            "patch_length": self.patch_length, "gluing_width": self.gluing_width,
        }  # fmt: skip


def _smallest_divisor(n: int) -> int | None:
    for k in range(2, n + 1):
        if n % k == 0:
            return k
    return None


def arlequin_bar_sizes(
    length: float,
    radius: float,
    fine_radial: int,
    coarse_size: float | None = None,
    patch_length: float | None = None,
    gluing_width: float | None = None,
) -> ArlequinBarSizes:
    """Snap the Arlequin bar's sizes to nested meshes.

    Parameters
    ----------
    length, radius : float
        L and R (m).
    fine_radial : int
        Fine cells across the radius (fine size R / fine_radial).
    coarse_size : float, optional
        Coarse cell edge across the radius (m), a multiple k ≥ 1 of the fine size; default the
        smallest multiple k ≥ 2 that divides ``fine_radial`` (2 for an even count).
    patch_length : float, optional
        Patch length from the impact face (m), rounded to whole coarse rows; default 0.9 L.
    gluing_width : float, optional
        Gluing band width (m), rounded to whole coarse rows (at least one); default two rows.

    Raises
    ------
    ValueError
        If the coarse size is not a multiple of the fine size, if the patch does not leave at
        least one coarse row above it, or if the band does not leave at least one patch row
        under it.
    """
    n_f = int(fine_radial)
    fine = radius / n_f
    if coarse_size is None:
        k = _smallest_divisor(n_f)
        if k is None:
            raise ValueError(
                f"with 1 fine cell across the radius the coarse cells cannot be larger; give "
                f"more fine cells (got fine size {fine} m)"
            )
    else:
        if not (math.isfinite(coarse_size) and coarse_size > 0.0):
            raise ValueError(f"coarse_size must be positive and finite, got {coarse_size}")
        ratio = coarse_size / fine
        k = round(ratio)
        if k < 1 or abs(ratio - k) > 1e-6 * ratio or n_f % k:
            raise ValueError(
                f"coarse_size must be a multiple of the fine size dividing the radius: got "
                f"coarse_size={coarse_size} m, fine size {fine} m (ratio {ratio:.6g}) with "
                f"{n_f} fine cells across the radius"
            )
    n_rc = n_f // k
    n_zc = max(1, round(length / (radius / n_rc)))
    hz = length / n_zc
    if patch_length is None:
        patch_length = 0.9 * length
    if not (math.isfinite(patch_length) and 0.0 < patch_length < length):
        raise ValueError(
            f"patch_length must lie in (0, L = {length}) m, got patch_length={patch_length}"
        )
    rows = round(patch_length / hz)
    if rows < 2 or rows > n_zc - 1:
        raise ValueError(
            f"patch_length={patch_length} m gives {rows} coarse rows of {hz:.4g} m; the patch "
            f"needs at least 2 rows and must leave at least one of the {n_zc} rows above it"
        )
    if gluing_width is None:
        band = 2
    else:
        if not (math.isfinite(gluing_width) and gluing_width > 0.0):
            raise ValueError(f"gluing_width must be positive and finite, got {gluing_width}")
        band = max(1, round(gluing_width / hz))
    if band >= rows:
        raise ValueError(
            f"gluing_width={gluing_width} m gives a band of {band} coarse rows of {hz:.4g} m, "
            f"the whole patch of {rows} rows; the band must leave patch rows under it"
        )
    return ArlequinBarSizes(n_rc, n_zc, k, rows, band, length, radius)


class ArlequinBar:
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

    def __init__(self, length, radius, sizes: ArlequinBarSizes, material: J2Material,
                 weights="ramp", mediator="coarse", coupling="H1", epsilon=1e-3, fbar=True,
                 backend="auto", bulk_viscosity=None) -> None:  # fmt: skip
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
        self.problem = ArlequinProblem(self.coarse, [patch])
        tol = 1e-9 * radius
        for block in ("coarse", "patch"):
            self.problem.add_dirichlet(block, lambda x: x[0] < tol, components=[0])
        self.system = self.problem.system()
        self.coupling = self.problem.couplings[0]
        self.layout = self.problem.field_layout()
        self._drop_axis_mediator_rows(tol)
        self.fine_weight = self.coupling.alpha_fine
        dm = self.system.dofmap
        # the wall's lateral reach stays below the gluing band
        lateral = min(LATERAL_CONTACT * length, s.patch_length - s.gluing_width)
        self.contact = _wall(fmesh, dm["patch"], dm, material.elastic, tol, lateral, radius)
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

    def _drop_axis_mediator_rows(self, tol: float) -> None:
        """Remove the mediator functions of u_r on the axis.

        Both displacement spaces have u_r = 0 on the axis, so the multiplier space is taken
        with the same condition (the trace of the constrained spaces): the rows of those
        mediator functions would otherwise duplicate the axis conditions (exactly so for the
        fine mediator, whose rows tie every band dof) and carry their reactions, which
        oscillate from step to step in an explicit run.
        """
        pc = self.coupling
        carrier = self.coarse_mesh if pc.coupling.mediator == "coarse" else self.fine_mesh
        med = np.asarray(pc.coupling.mediator_dofs)
        keep = ~((med % 2 == 0) & (carrier.p[0, med // 2] < tol))
        name = f"coupling:{pc.name}"
        for i, con in enumerate(self.system.constraints):
            if con.name == name:
                self.system.constraints[i] = dataclasses.replace(
                    con, matrix=con.matrix[np.nonzero(keep)[0]].tocsr()
                )
        block, dofs = self.layout.multipliers[name]
        self.layout.multipliers[name] = (block, dofs[keep])

    def initial_velocity(self, velocity: float) -> np.ndarray:
        v0 = np.zeros(self.system.dofmap.n_dofs)
        v0[self._cz] = -velocity
        v0[self._fz] = -velocity
        return v0

    def lumped_mass(self) -> np.ndarray:
        """The coupled system's lumped, α-weighted mass (kg; its sum is the bar's mass)."""
        return np.asarray(self.system.mass(lumped=True))

    def fine_state(self, integ) -> Any:
        return integ.states["patch"][0]

    def fine_displacement(self, u: np.ndarray) -> np.ndarray:
        return u[self._f]

    def measures(self, u: np.ndarray) -> tuple[float, float]:
        """(length from the coarse model's top node on the axis, footprint radius from the
        patch's impact face) (m)."""
        uc, uf = u[self._c], u[self._f]
        length = self.coarse_mesh.p[1, self._axis_top] + uc[2 * self._axis_top + 1]
        r = self.fine_mesh.p[0, self._face] + uf[2 * self._face]
        return float(length), float(r.max())

    def energies(self, integ) -> dict[str, float]:
        """Weighted energies of both models and the net work of the coupling forces (J)."""
        state = self.fine_state(integ)
        uf = integ.u[self._f]
        e = integ.energies()
        alpha = self.fine_weight
        return {
            "elastic": e["strain"]["coarse"] + self.model.stored_energy(uf, state, alpha),
            "plastic_dissipation": self.model.plastic_dissipation(state, alpha),
            "viscous_dissipation": self.model.viscous_dissipation(state, alpha),
            "coupling_work": float(sum(e["coupling_work"].values())),
        }

    def series_meshes(self) -> dict[str, Any]:
        return {"coarse": self.coarse_mesh, "patch": self.fine_mesh}

    def frame(self, integ) -> dict[str, tuple[dict, dict]]:
        frames = self.layout.frame(self.system.dofmap, integ.u, integ.v, integ.multipliers)
        state = self.fine_state(integ)
        frames["patch"][1]["plastic_strain"] = state.eqps.mean(axis=1)
        frames["patch"][1]["von_mises"] = state.von_mises.mean(axis=1)
        return frames

    def band_plastic_strain(self, state) -> float:
        """Largest ε̄p at the quadrature points of the gluing band's fine cells."""
        return float(np.asarray(state.eqps)[self.band_cells].max())

    def render(self, u, state, path: str, title: str) -> None:
        from .render import render_arlequin_bar

        render_arlequin_bar(self, u, state, path, title)
