"""From a configuration to the problem of a pressure vessel: meshes, models, supports, loads.

The quarter section (:mod:`arlequin.demos.pressure_vessel.meshes`) has two symmetry lines:
x = 0 (the sphere's axis, the cylinder's vertical plane: u_x = 0) and y = 0 (the equator or the
horizontal plane: u_y = 0), held on every model; the sphere's eighth in 3D has three symmetry
planes x_i = 0 (u_i = 0). The bore carries the pressure, a traction
−P n on its facets (n the outward normal of the faceted bore), or a prescribed radial
displacement U e_r on its nodes (on every model that reaches it).
"""

from __future__ import annotations

import logging
import warnings
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from ...coupling.exactness import ExactnessWarning
from ...coupling.gluing import Patch
from ...models import FiniteStrainJ2, IsotropicElastic, J2Material, LinearElastic
from ...problem.adapt import AdaptivePatch
from ...problem.arlequin_problem import ArlequinProblem
from ..adaptive_options import adaptive_patch
from .meshes import VesselMeshes, refine_projected, vessel_meshes

if TYPE_CHECKING:  # annotations only: the configuration runs this module
    from .config import PressureVesselConfig

__all__ = ["DENSITY", "VesselSetup", "build"]

logger = logging.getLogger(__name__)

#: Steel's density (kg/m³): recorded with the materials, unused by a quasi-static run.
DENSITY = 7850.0


@dataclass
class VesselSetup:
    """What a run needs besides its configuration.

    Attributes
    ----------
    problem : ArlequinProblem
        The coarse model and its patch (``arlequin``), or the fine model alone (``mono``).
    meshes : VesselMeshes
    plastic_block : str
        The block of the J2 model (``"patch0"`` or ``"coarse"`` for mono).
    plastic_model : model
    kind : str
        ``"axisymmetric"`` (sphere) or ``"plane_strain"`` (cylinder).
    outer_node, inner_node : tuple of (block, node)
        Where the outer and inner radial displacements are read: the nodes at (b, 0) and
        (a, 0) of the model that carries them.
    bore_blocks : list of str
        The blocks whose bore nodes are prescribed under ``inner_displacement``.
    adapt : AdaptivePatch or None
        With ``adaptive``: the patch that grows from its one-ring seed (its rings refined
        with the bore's new nodes on the circle, as the fixed patch).
    """

    problem: ArlequinProblem
    meshes: VesselMeshes
    plastic_block: str
    plastic_model: Any
    kind: str
    outer_node: tuple[str, int]
    inner_node: tuple[str, int]
    bore_blocks: list[str]
    adapt: AdaptivePatch | None = None

    def follow(self, adapt: AdaptivePatch) -> None:
        """After a growth: the problem, the J2 model, the meshes and the inner node of the
        grown patch."""
        self.problem = adapt.problem
        self.plastic_model = self.problem.patches[0].model
        mesh = self.plastic_model.mesh
        self.meshes = replace(self.meshes, patch=mesh)
        a = float(np.linalg.norm(self.meshes.coarse.p, axis=0).min())
        self.inner_node = ("patch0", _node_at(mesh, (a,) + (0.0,) * (mesh.dim() - 1)))


def _plastic_model(config: PressureVesselConfig, mesh: Any, kind: str) -> Any:
    material = J2Material(config.young, config.poisson, DENSITY, config.yield_stress,
                          config.hardening)  # fmt: skip
    if config.material == "finite-strain":
        return FiniteStrainJ2(mesh, material, kind=kind)
    from ...models import SmallStrainJ2

    # mean dilatation (B-bar): full integration locks under isochoric plastic flow
    return SmallStrainJ2(mesh, material, kind=kind, bbar=True)


def _node_at(mesh: Any, x: tuple[float, float]) -> int:
    d = np.linalg.norm(mesh.p - np.asarray(x, dtype=float)[:, None], axis=0)
    i = int(np.argmin(d))
    if d[i] > 1e-9 * np.ptp(mesh.p):
        raise ValueError(f"no node at x = {x} (nearest at {d[i]:.3g} m)")
    return i


def _on_bore(a: float):
    # facet midpoints (chords lie inside the circle) and nodes (on it) of the bore
    return lambda x: np.linalg.norm(x, axis=0) <= a * (1.0 + 1e-9)


def _whole_rings(mesh: Any):
    """The adaptive patch's closure: every coarse cell whose centre lies within the outermost
    ring of the cells given (the patch stays a set of rings, its gluing band a ring)."""
    radius = np.linalg.norm(mesh.p[:, mesh.t].mean(axis=1), axis=0)

    def closure(mask: np.ndarray) -> np.ndarray:
        return mask | (radius <= radius[mask].max() * (1.0 + 1e-9))

    return closure


def build(config: PressureVesselConfig) -> VesselSetup:
    """The problem of ``config`` (supports and the load at λ = 1: the final pressure, or the
    final bore displacement)."""
    a, b = config.inner, config.outer
    kind = {2: "axisymmetric" if config.shape == "sphere" else "plane_strain", 3: "3d"}[config.dim]
    meshes = vessel_meshes(a, b, config.coarse, config.fine, config.patch_radius, config.model,
                           config.dim)  # fmt: skip
    origin = (0.0,) * (config.dim - 1)
    if config.model == "mono":
        plastic = _plastic_model(config, meshes.mono, kind)
        problem = ArlequinProblem(plastic, [])
        blocks, plastic_block = ["coarse"], "coarse"
        outer = ("coarse", _node_at(meshes.mono, (b, *origin)))
        inner = ("coarse", _node_at(meshes.mono, (a, *origin)))
    else:
        elastic = IsotropicElastic(config.young, config.poisson, DENSITY)
        coarse = LinearElastic(meshes.coarse, elastic, kind)
        plastic = _plastic_model(config, meshes.patch, kind)
        # the gluing band: the patch's outermost coarse ring; nested although the bore's new
        # nodes sit on the circle, off the coarse chords
        problem = ArlequinProblem(
            coarse,
            [Patch(plastic, gluing_width=meshes.ring_width, overlap_method="nested")],
        )
        with warnings.catch_warnings(record=True) as caught:
            # the coarse mediator on a curved band does not reproduce a uniform stress
            # exactly (ExactnessWarning): a patch-test condition, not this problem's; logged
            warnings.simplefilter("always", ExactnessWarning)
            problem.couplings  # noqa: B018
        for w in caught:
            logger.info("%s", w.message)
        blocks, plastic_block = ["coarse", "patch0"], "patch0"
        outer = ("coarse", _node_at(meshes.coarse, (b, *origin)))
        inner = ("patch0", _node_at(meshes.patch, (a, *origin)))
    for block in blocks:
        for axis in range(config.dim):  # the symmetry planes x_i = 0: u_i = 0
            problem.add_dirichlet(
                block, lambda x, i=axis: np.isclose(x[i], 0.0, atol=1e-12 * b), [axis]
            )
    pressure, u_bore = config.load_pressure, config.inner_displacement
    if pressure is not None:
        problem.add_traction(lambda x, n: -pressure * n, where=_on_bore(a))
    else:
        for block in blocks:
            problem.add_dirichlet(
                block, _on_bore(a), value=lambda x: u_bore * x / np.linalg.norm(x, axis=0)
            )
    adapt = None
    if config.adaptive:
        coarse_mesh, levels = meshes.coarse, meshes.levels
        adapt = adaptive_patch(
            config,
            model_factory=lambda mesh: _plastic_model(config, mesh, kind),
            levels=levels,
            refine=lambda cells: refine_projected(coarse_mesh, levels, (a,), cells),
            # grow when the plastic zone comes within one coarse ring of the band (a load
            # step moves the front by several fine cells: closer, it would enter the band and
            # the step be computed again)
            band_cells=2**levels,
            closure=_whole_rings(coarse_mesh),
        )
    return VesselSetup(problem, meshes, plastic_block, plastic, kind, outer, inner, blocks, adapt)
