"""Finite-strain J2 elastoplasticity (Simo 1992), total Lagrangian, with an optional weight.

Its consistent tangent: :mod:`arlequin.models.plasticity.j2_tangent` (numpy) and
:mod:`arlequin.models.plasticity.j2_tangent_kernel` (numba).

The model ties together the Q1 kinematics with F-bar (:mod:`~.kinematics`), the J2 material
point (:mod:`~.j2`: Hencky elasticity, exponential-map return, any law of :mod:`~.hardening`)
and, for the built-in laws, the compiled kernels that fuse them (``backend="numba"``, the
default there: :mod:`~.j2_kernel` for planar cells, :mod:`~.j2_kernel_3d` for hexahedra). The
numpy path (``backend="numpy"``) is the reference the kernels are tested against.

Optional artificial bulk viscosity (off by default): on compression a pressure
q = ρ (c_quad ℓ² ε̇_v² − c_lin ℓ c_d ε̇_v) (ε̇_v = J̄̇/J̄ from the step, ρ = ρ₀/J̄, ℓ the cell size)
is added to the stress; its work is accumulated in the state (``viscous_work``) like the plastic
work (``plastic_work``), so that energy balances can count both.

Units: SI (m, kg, s, Pa, N). Quadrature-point arrays have shape (components…, n_elems, n_qp).
The model knows nothing about Arlequin: ``weight`` (α at quadrature points, default 1) scales
every integrand.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from skfem import Basis, Mesh

from arlequin.contract import CellStates, StateError

from ..elastic import LinearElastic, WeightLike, element_critical_step

# the compiled kernels' modules at import (a function-level import at every evaluation cost
# several µs); numba compiles or loads each kernel on its first call only
from . import j2_kernel, j2_kernel_3d
from .array_pool import ArrayPool
from .j2 import (
    InvertedElementError,
    J2Material,
    PlasticState,
    hencky_j2_return,
    hencky_strain,
    j2_return_map,
)
from .kinematics import KINDS, Q1Kinematics  # noqa: F401  (KINDS re-exported)

__all__ = [
    "BACKENDS",
    "BulkViscosity",
    "FiniteStrainJ2",
    "InvertedElementError",
    "J2Material",
    "PlasticState",
    "hencky_j2_return",
]

#: Backends of the internal force: the compiled kernel (planar cells) and the numpy reference.
BACKENDS = ("auto", "numba", "numpy")


@dataclass(frozen=True)
class BulkViscosity:
    """Artificial bulk viscosity (LS-DYNA's defaults): q = ρ (c_quad ℓ² ε̇_v² − c_lin ℓ c_d ε̇_v)
    on compression. Both coefficients dimensionless, ≥ 0."""

    linear: float = 0.06
    quadratic: float = 1.5

    def __post_init__(self) -> None:
        for name in ("linear", "quadratic"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0.0):
                raise ValueError(f"bulk viscosity coefficient {name} must be >= 0, got {v}")


class FiniteStrainJ2(CellStates):
    """Finite-strain J2 elastoplastic model with F-bar on one Q1 mesh (explicit dynamics).

    Parameters
    ----------
    mesh : skfem.MeshQuad or skfem.MeshHex
        Reference (undeformed) mesh, in m. Axisymmetric meshes use (r, z) = (x[0], x[1]).
    material : J2Material
    kind : {"axisymmetric", "plane_strain", "3d"}
        Default ``"axisymmetric"`` for quads and ``"3d"`` for hexahedra.
    fbar : bool
        Use the F-bar deformation gradient (default). Without it, isochoric plastic flow
        locks the bilinear cells.
    backend : {"auto", "numba", "numpy"}
        ``auto``: the compiled kernel for planar cells with a built-in hardening law, numpy
        otherwise (3D cells, user hardening callables).
    bulk_viscosity : BulkViscosity or bool, optional
        Artificial bulk viscosity (True: the default coefficients).
    validate, allow_seams : bool
        Mesh checks (see :class:`~arlequin.models.LinearElastic`).

    Notes
    -----
    Quadrature: 2×2 (2×2×2) Gauss points; F-bar uses the cell's mean dilatation J̄. Dofs are
    interleaved by node (``dim * node + component``); :meth:`mass` and :meth:`stiffness`
    (small-strain elastic, for stable-step estimates) come from a
    :class:`~arlequin.models.LinearElastic` on the same mesh and quadrature. Capabilities
    (:mod:`arlequin.contract`): ``"critical_time_step"`` in the current configuration;
    ``"tangent"``, the consistent tangent of :meth:`internal_force` (:meth:`tangent`: numpy
    reference :mod:`arlequin.models.plasticity.j2_tangent`, compiled
    :mod:`arlequin.models.plasticity.j2_tangent_kernel` on the numba backend), so the implicit
    integrators run it with full Newton.
    ``uses_time_step`` is True when the state update needs the step (rate-dependent hardening,
    bulk viscosity): the integrators then pass ``dt=`` to :meth:`internal_force`.
    """

    is_linear = False

    def __init__(
        self, mesh: Mesh, material: J2Material, kind: str | None = None, fbar: bool = True, *,
        backend: str = "auto", bulk_viscosity: BulkViscosity | bool | None = None,
        validate: bool = True, allow_seams: bool = False,
    ) -> None:  # fmt: skip
        if not isinstance(material, J2Material):
            raise ValueError(f"material must be a J2Material, got {type(material).__name__}")
        dim = mesh.dim()
        kind = ("axisymmetric" if dim == 2 else "3d") if kind is None else kind
        if backend not in BACKENDS:
            raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
        self.mesh = mesh
        self.material = material
        self.kind = kind
        self.fbar = bool(fbar)
        self.dim = dim
        self.intorder = 3
        checks = {"validate": validate, "allow_seams": allow_seams}
        # checks r >= 0 in axisymmetry; gives the mass, the small-strain stiffness and the bases
        self.elastic = LinearElastic(mesh, material.elastic, kind, intorder=self.intorder, **checks)
        self.basis = self.elastic.basis
        self.kin = Q1Kinematics(mesh, kind, self.elastic.scalar_basis(), self.elastic.nodal_dofs())
        # the compiled kernels: planar Q1 (j2_kernel) and 8-node hexahedra (j2_kernel_3d)
        compiled = material.law.kernel_code is not None
        if backend == "numba" and not compiled:
            raise ValueError("backend='numba' needs a built-in hardening law; use backend='numpy'")
        self.backend = "numba" if (backend == "auto" and compiled) else backend
        if self.backend == "auto":
            self.backend = "numpy"
        if bulk_viscosity is True:
            bulk_viscosity = BulkViscosity()
        self.bulk_viscosity = bulk_viscosity or None
        self.uses_time_step = bool(self.bulk_viscosity) or material.law.rate_dependent
        # reference cell size ℓ₀ (m): √(meridional area) in 2D, ∛(volume) in 3D
        area = self.kin.dv0.sum(axis=1) / self._measure_factor()
        self._h0 = np.sqrt(area) if dim == 2 else np.cbrt(area)
        self._critical_ratio: np.ndarray | None = None
        self._size_arrays: tuple | None = None  # the compiled critical step's mesh arrays
        self._wave_speed: float | None = None  # c_d (m/s), for the critical step
        self._kernel_static: tuple | None = None  # contiguous inputs and scratch of the kernel
        self._ones: np.ndarray | None = None
        self._alpha_of: tuple | None = None  # (read-only weight, its checked broadcast)
        self._assembler = None  # the tangent's sparse pattern, built at the first call
        self._tangent_static: tuple | None = None  # the tangent kernel's inputs and scratch
        self._cell_buffers: tuple | None = None  # the kernels' per-cell forces and flags
        self._assembly: tuple | None = None  # (kernel dofs, the nodal assembly's layout)
        self._state_pool = ArrayPool()  # state arrays, reused once unreferenced
        self._constants: tuple | None = None  # K, G, law code and parameters of the kernels
        self._kernel_weight: tuple | None = None  # (α, its read-only view for the kernels)

    def _measure_factor(self) -> np.ndarray:
        if self.kind == "axisymmetric":
            return 2.0 * np.pi * self.kin.radius.mean(axis=1)
        return np.ones(self.kin.shape[0])

    # ------------------------------------------------------------------ model protocol
    @property
    def n_dofs(self) -> int:
        """Number of displacement dofs."""
        return self.elastic.n_dofs

    @property
    def n_components(self) -> int:
        return self.dim

    @property
    def shape(self) -> tuple[int, int]:
        """(n_elems, n_qp) of the quadrature-point arrays."""
        return self.kin.shape

    def with_mesh(self, mesh: Mesh) -> FiniteStrainJ2:
        """Same material, kinematics, F-bar choice, backend and viscosity on another mesh."""
        return FiniteStrainJ2(mesh, self.material, self.kind, self.fbar, backend=self.backend,
                              bulk_viscosity=self.bulk_viscosity, validate=False)  # fmt: skip

    def nodal_dofs(self) -> np.ndarray:
        """Dof indices per node, shape (dim, n_nodes)."""
        return self.kin.dofs

    def dofs_where(self, where, components=None) -> np.ndarray:
        """Dofs of the nodes where ``where(x)`` holds (see :meth:`LinearElastic.dofs_where`)."""
        return self.elastic.dofs_where(where, components)

    def scalar_basis(self) -> Basis:
        """Scalar Q1 basis with the model's quadrature."""
        return self.elastic.scalar_basis()

    def quadrature_points(self) -> np.ndarray:
        """Reference quadrature points, shape (dim, n_elems, n_qp) (m)."""
        return self.elastic.quadrature_points()

    def mass(self, weight: WeightLike = None, lumped: bool = False):
        """Weighted reference mass ∫ α ρ₀ u·v dV₀ (kg); row sums when ``lumped``."""
        return self.elastic.mass(weight, lumped=lumped)

    def stiffness(self, weight: WeightLike = None) -> sp.csr_matrix:
        """Small-strain elastic stiffness (N/m): the initial tangent, for stable-step estimates."""
        return self.elastic.stiffness(weight)

    def body_force_vector(self, force, weight: WeightLike = None) -> np.ndarray:
        """Dead body load ∫ α ρ₀b·v dV₀ (N) for a force density (N/m³ of reference volume)."""
        return self.elastic.body_force_vector(force, weight)

    def traction_vector(self, facets: np.ndarray, traction, weight: WeightLike = None):
        """Dead traction load (N) for a nominal traction (Pa, per reference area) on ``facets``."""
        return self.elastic.traction_vector(facets, traction, weight)

    def initial_state(self, weight: WeightLike = None) -> PlasticState:
        """Virgin state: C_p⁻¹ = 1, ε̄p = 0, τ = 0, J = 1, no work."""
        ne, nq = self.shape
        eye = np.broadcast_to(np.eye(3)[:, :, None, None], (3, 3, ne, nq)).copy()
        zeros = np.zeros((ne, nq))
        return PlasticState(eye, zeros, np.zeros((3, 3, ne, nq)), np.ones((ne, nq)), zeros,
                            zeros.copy())  # fmt: skip

    def yield_stress(self, state: PlasticState | None = None) -> np.ndarray:
        """σ_y(ε̄p) (Pa), shape (n_elems, n_qp); σ_y0 for None (adaptive patches' member, with
        ``state_of_cells`` and ``with_cells`` of :class:`~arlequin.contract.CellStates`)."""
        eqps = np.zeros(self.shape) if state is None else np.asarray(state.eqps)
        return np.asarray(self.material.law.flow_stress(eqps), dtype=float) + 0.0 * eqps

    def equivalent_plastic_strain(self, state: PlasticState) -> np.ndarray:
        """ε̄p at the quadrature points, shape (n_elems, n_qp)."""
        return np.asarray(state.eqps)

    # ------------------------------------------------------------------ kinematics
    def deformation_gradient(self, u: np.ndarray) -> np.ndarray:
        """Deformation gradient at the quadrature points, shape (3, 3, n_elems, n_qp).

        In 2D, F_zz = 1 (plane strain) or F_θθ = 1 + u_r/R (axisymmetric).
        """
        return self.kin.deformation_gradient(u)

    def _kinematics(self, u: np.ndarray):
        return self.kin.kinematics(u, self.fbar)

    def _mean_dilatation(self, J: np.ndarray) -> np.ndarray:
        return self.kin.mean_dilatation(J)

    # ------------------------------------------------------------------ internal force
    def internal_force(
        self,
        u: np.ndarray,
        state: PlasticState | None = None,
        weight: WeightLike = None,
        dt: float | None = None,
    ) -> tuple[np.ndarray, PlasticState]:
        """Internal force (N) at displacement ``u`` from the committed ``state``.

        Parameters
        ----------
        u : ndarray, shape (n_dofs,)
            Displacement from the reference configuration (m).
        state : PlasticState, optional
            Committed state (default: virgin).
        weight : float, array (n_elems, n_qp) or callable, optional
            Partition weight α at the quadrature points.
        dt : float, optional
            The step that leads to u (s): rates of rate-dependent laws and of the bulk
            viscosity (ignored by rate-independent models without viscosity).

        Returns
        -------
        f : ndarray, shape (n_dofs,)
        trial_state : PlasticState
            The state after this evaluation, to be committed by the integrator.

        Raises
        ------
        InvertedElementError
            When det F ≤ 0 (or is not finite) at a quadrature point, naming the cell.
        """
        state = self.initial_state() if state is None else state
        alpha = self._weight(weight)
        if state.plastic_work is None:  # a state built by hand: no work accumulated yet
            zeros = np.zeros(self.shape)
            state = PlasticState(state.cp_inv, state.eqps, state.kirchhoff, state.jacobian,
                                 zeros, zeros.copy())  # fmt: skip
        if self.backend == "numba":
            return self._internal_force_numba(u, state, alpha, dt)
        return self._internal_force_numpy(u, state, alpha, dt)

    def _weight(self, weight: WeightLike) -> np.ndarray:
        """α at the quadrature points (n_elems, n_qp)."""
        if weight is None:  # the common case: one array of ones, made once
            if self._ones is None:
                self._ones = np.ones(self.shape)
            return self._ones
        if isinstance(weight, np.ndarray) and not weight.flags.writeable:
            # a read-only weight array cannot change between steps: checked and broadcast
            # once (an integrator passes the same one at every step)
            if self._alpha_of is None or self._alpha_of[0] is not weight:
                self._alpha_of = (weight, self.elastic.weight_at_quadrature(weight))
            return self._alpha_of[1]
        return self.elastic.weight_at_quadrature(weight)

    # ------------------------------------------------------------------ tangent
    def tangent(
        self,
        u: np.ndarray,
        state: PlasticState | None = None,
        weight: WeightLike = None,
        dt: float | None = None,
    ) -> sp.csr_matrix:
        """Consistent tangent ∂f/∂u (N/m) of :meth:`internal_force` at ``u`` from the committed
        ``state`` (capability ``"tangent"``), sparse (n_dofs, n_dofs), non-symmetric with F-bar.

        The algorithmic tangent of the exponential-map return (Hencky elasticity, the slope of
        the hardening law at the converged ε̄p) plus the geometric and F-bar terms
        (:mod:`arlequin.models.plasticity.j2_tangent`), weighted by α like the force. ``dt``: as
        in :meth:`internal_force` (a rate-dependent law's rate term; None: the force at a
        vanishing rate, as the integrators evaluate it without a step). The bulk viscosity is
        not differentiated (it vanishes without ``dt``).
        """
        from .j2_tangent import BlockAssembler, numpy_tangent

        state = self.initial_state() if state is None else state
        alpha = self._weight(weight)
        u = self._checked_displacement(u)
        if self._assembler is None:
            self._assembler = BlockAssembler(self.kin.cell_dofs, self.kin.n_dofs)
        if self.backend == "numba":
            return self._assembler.assemble(self._tangent_blocks_numba(u, state, alpha, dt))
        return numpy_tangent(self.kin, self.material, self.fbar, u, state, alpha, dt,
                             self._assembler)  # fmt: skip

    def _tangent_blocks_numba(self, u, state, alpha, dt) -> np.ndarray:
        """The per-cell tangent blocks from the compiled kernel (flagged cells raise)."""
        from .j2_tangent_kernel import j2_tangent_kernel, tangent_scratch

        kin, c = self.kin, np.ascontiguousarray
        ne, nq = self.shape
        nen = kin.grad.shape[0]
        if self._tangent_static is None:
            radius = kin.radius if kin.radius is not None else np.ones((ne, nq))
            self._tangent_static = (
                c(np.transpose(kin.cell_dofs, (2, 1, 0)), dtype=np.int64),
                c(np.moveaxis(kin.grad, (0, 1), (2, 3))), c(np.moveaxis(kin.val, 0, -1)),
                c(radius), c(kin.dv0), *tangent_scratch(nq, nen, self.dim),
            )  # fmt: skip
        dofs, grad, val, radius, dv0, *scratch = self._tangent_static
        law = self.material.law
        blocks = np.empty((ne, nen * self.dim, nen * self.dim))
        flags = np.empty(ne, dtype=np.int64)
        j2_tangent_kernel(
            u, dofs, grad, val, radius, dv0, c(np.broadcast_to(alpha, (ne, nq)), dtype=float),
            self.kind == "axisymmetric", self.fbar, self.material.bulk_modulus,
            self.material.shear_modulus, int(law.kernel_code), law.kernel_params,
            -1.0 if dt is None else float(dt), c(state.cp_inv), c(state.eqps), *scratch,
            blocks, flags,
        )  # fmt: skip
        if np.any(flags):
            cell = int(np.nonzero(flags)[0][0])
            if flags[cell] == 1:
                raise InvertedElementError(f"inverted or degenerate cell {cell}: det F <= 0")
            raise StateError(f"J2 return map not converged in cell {cell}")
        return blocks

    def _viscous_pressure(self, jbar: np.ndarray, jbar_old: np.ndarray, dt: float | None):
        """q (Pa) per cell, shape (n_elems, 1), of the bulk viscosity (0 where off/expanding)."""
        if not self.bulk_viscosity or dt is None or not dt > 0.0:
            return np.zeros_like(jbar)
        rate = (jbar - jbar_old) / (dt * jbar)
        ell = self._h0[:, None] * np.sqrt(jbar)
        rho = self.material.density / jbar
        bv, cd = self.bulk_viscosity, self.material.dilatational_wave_speed
        q = rho * (bv.quadratic * ell**2 * rate**2 - bv.linear * ell * cd * rate)
        return np.where(rate < 0.0, q, 0.0)

    def _internal_force_numpy(self, u, state, alpha, dt):
        trial = self.kin.trial_elastic_stretch(u, state.cp_inv, self.fbar)
        F, Finv, J = trial.F, trial.Finv, trial.J
        tau, be, eqps, dgamma, work = j2_return_map(
            trial.B, state.eqps, self.material, planar=self.dim == 2, dt=dt,
            minus_identity=True, log_volume=trial.log_volume,
        )  # fmt: skip
        Fbar_inv = Finv / trial.scale
        # C_p⁻¹ = F̄⁻¹ b_e F̄⁻ᵀ changes only where the point flowed (elsewhere: kept bit for bit)
        cp_inv = np.where(
            dgamma > 0.0,
            np.einsum("ikeq,kleq,jleq->ijeq", Fbar_inv, be, Fbar_inv),
            state.cp_inv,
        )
        w0 = alpha * self.kin.dv0
        jbar = self._mean_dilatation(J)
        q = self._viscous_pressure(jbar, self._mean_dilatation(state.jacobian), dt)
        tau_total = tau - (J * q)[None, None] * np.eye(3)[:, :, None, None]
        f = self.kin.internal_force(tau_total, F, Finv, J, w0, self.fbar)
        wv = state.viscous_work + q * (self._mean_dilatation(state.jacobian) - jbar)
        return f, PlasticState(cp_inv, eqps, tau, J, state.plastic_work + work, wv)

    def _internal_force_numba(self, u, state, alpha, dt):
        if self.dim == 3:
            return self._internal_force_numba_3d(u, state, alpha, dt)
        kin = self.kin
        ne, nq = self.shape
        nen = kin.grad.shape[0]
        if self._kernel_static is None:
            c = np.ascontiguousarray
            radius = kin.radius if kin.radius is not None else np.ones((ne, nq))
            visc = self._viscosity_params()
            self._kernel_static = (
                c(np.transpose(kin.cell_dofs, (2, 1, 0)), dtype=np.int64),
                c(np.moveaxis(kin.grad, (0, 1), (2, 3))), c(np.moveaxis(kin.val, 0, -1)),
                c(radius), c(kin.dv0),
                visc, c(self._h0), *j2_kernel.scratch(nq, nen),
            )  # fmt: skip
        dofs, grad, val, radius, dv0, visc, h0, s_h, s_g, s_u = self._kernel_static
        u = self._checked_displacement(u)
        out = self._kernel_outputs(2)
        c = np.ascontiguousarray
        weight, K, G, code, prm = self._kernel_constants(alpha)
        j2_kernel.run_kernel(
            j2_kernel.planar_j2_kernel, ne, u, dofs, grad, val, radius, dv0, weight,
            self.kind == "axisymmetric", self.fbar, K, G, code, prm,
            -1.0 if dt is None else float(dt), c(state.cp_inv), c(state.eqps),
            c(state.plastic_work), c(state.viscous_work), c(state.jacobian), visc, h0,
            s_h, s_g, s_u, *out,
        )  # fmt: skip
        return self._gathered(out, dofs)

    def _internal_force_numba_3d(self, u, state, alpha, dt):
        kin = self.kin
        ne, nq = self.shape
        nen = kin.grad.shape[0]
        c = np.ascontiguousarray
        if self._kernel_static is None:
            self._kernel_static = (
                c(np.transpose(kin.cell_dofs, (2, 1, 0)), dtype=np.int64),
                c(np.moveaxis(kin.grad, (0, 1), (2, 3))), c(kin.dv0), self._viscosity_params(),
                c(self._h0), *j2_kernel_3d.solid_scratch(nq, nen),
            )  # fmt: skip
        dofs, grad, dv0, visc, h0, s_h, s_g, s_m = self._kernel_static
        u = self._checked_displacement(u)
        out = self._kernel_outputs(3)
        weight, K, G, code, prm = self._kernel_constants(alpha)
        j2_kernel.run_kernel(
            j2_kernel_3d.solid_j2_kernel, ne, u, dofs, grad, dv0, weight, self.fbar, K, G, code,
            prm, -1.0 if dt is None else float(dt), c(state.cp_inv), c(state.eqps),
            c(state.plastic_work), c(state.viscous_work), c(state.jacobian), visc, h0,
            s_h, s_g, s_m, *out,
        )  # fmt: skip
        return self._gathered(out, dofs)

    def _kernel_constants(self, alpha: np.ndarray) -> tuple:
        """The kernels' weight (n_elems, n_qp) and material constants K, G (Pa), law code and
        parameters, made once: the material is frozen, and the weight is the same object at
        every step unless the caller passes a new writeable array (a property chain and a
        broadcast per call were a third of a small patch's evaluation)."""
        if self._constants is None:
            law = self.material.law
            self._constants = (self.material.bulk_modulus, self.material.shear_modulus,
                               int(law.kernel_code), law.kernel_params)  # fmt: skip
        if self._kernel_weight is None or self._kernel_weight[0] is not alpha:
            # a read-only broadcast view whatever its source: one type to numba, the one the
            # warm-ups compile
            ne, nq = self.shape
            weight = np.ascontiguousarray(np.broadcast_to(alpha, (ne, nq)), dtype=float)
            if alpha is not self._ones and alpha.flags.writeable:
                return (weight, *self._constants)  # the caller's array: it may change
            self._kernel_weight = (alpha, weight)
        return (self._kernel_weight[1], *self._constants)

    def _viscosity_params(self) -> np.ndarray:
        """(c_linear, c_quadratic, ρ₀, c_d) of the bulk viscosity for the kernels (0: off)."""
        visc = np.zeros(4)
        if self.bulk_viscosity:
            bv = self.bulk_viscosity
            visc[:] = (bv.linear, bv.quadratic, self.material.density,
                       self.material.dilatational_wave_speed)  # fmt: skip
        return visc

    def _checked_displacement(self, u) -> np.ndarray:
        u = np.ascontiguousarray(u, dtype=float)
        if u.shape != (self.kin.n_dofs,):
            raise ValueError(f"displacement must have shape ({self.kin.n_dofs},), got {u.shape}")
        return u

    def _kernel_outputs(self, dim: int) -> list[np.ndarray]:
        """The kernels' output buffers: forces, C_p⁻¹, ε̄p, τ, J, works, flags.

        The per-cell forces and flags are the model's own. The state's arrays come from a small
        pool: a set nothing outside it references any more is written over rather than
        allocated afresh (new arrays are new pages: about 1,000 page faults per evaluation at
        nr = 30, which cost as much as the kernel on the 2-core test machine).
        """
        ne, nq = self.shape
        nen = self.kin.grad.shape[0]
        if self._cell_buffers is None or self._cell_buffers[0].shape[0] != dim:
            self._cell_buffers = (np.empty((dim, nen, ne)), np.empty(ne, dtype=np.int64))
        fe, flags = self._cell_buffers
        arrays = self._state_pool.take([(3, 3, ne, nq), (ne, nq), (3, 3, ne, nq)]
                                       + [(ne, nq)] * 3)  # fmt: skip
        return [fe, *arrays, flags]

    def _gathered(self, out: list[np.ndarray], cell_dofs: np.ndarray):
        """The kernel's outputs (its dofs ``cell_dofs``) as (force, state); flagged cells raise."""
        fe, cp_inv, eqps, tau, J, wp, wv, flags = out
        if self._assembly is None or self._assembly[0] is not cell_dofs:
            self._assembly = (cell_dofs, j2_kernel.assembly_dofs(cell_dofs))
        f = np.empty(self.kin.n_dofs)
        if j2_kernel.assemble_cell_forces(self._assembly[1], fe, flags, f):
            bad = np.nonzero(flags)[0]
            cell = int(bad[0])
            if flags[cell] == 1:
                msg = f"inverted or degenerate cell {cell}: det F <= 0 ({bad.size} such cells)"
                raise InvertedElementError(msg)
            raise StateError(f"J2 return map not converged in cell {cell}")
        return f, PlasticState(cp_inv, eqps, tau, J, wp, wv)

    # ------------------------------------------------------------------ post-processing
    def stored_energy(self, u: np.ndarray, state: PlasticState, weight: WeightLike = None) -> float:
        """Elastic stored energy Σ w₀ ψ(ε_e) of a committed state at ``u`` (J)."""
        alpha = self.elastic.weight_at_quadrature(weight)
        trial = self.kin.trial_elastic_stretch(u, state.cp_inv, self.fbar)
        dev = hencky_strain(trial.B, self.dim == 2, minus_identity=True)[0]
        tr = trial.log_volume
        K, G = self.material.bulk_modulus, self.material.shear_modulus
        psi = 0.5 * K * tr**2 + G * np.sum(dev**2, axis=0)
        return float(np.sum(alpha * self.kin.dv0 * psi))

    def stored_energy_of_state(self, state: PlasticState, weight: WeightLike = None) -> float:
        """:meth:`elastic_energy_of_state` (J) as the energy contract's member paired with
        :meth:`plastic_dissipation`: a ``ValueError`` with bulk viscosity, whose work is
        dissipated too (the pair would not close a balance)."""
        if self.bulk_viscosity:
            raise ValueError("stored_energy_of_state: with bulk viscosity the dissipation is not "
                             "plastic_dissipation alone (the viscous work too); the elastic "
                             "energy alone is elastic_energy_of_state(state)")  # fmt: skip
        return self.elastic_energy_of_state(state, weight)

    def elastic_energy_of_state(self, state: PlasticState, weight: WeightLike = None) -> float:
        """Elastic energy Σ w₀ ψ (J) from a state's own Kirchhoff stress: for the Hencky law
        τ = K ln J 1 + 2G dev ε_e, so ψ = (tr τ)²/(18 K) + ‖dev τ‖²/(4 G).

        :meth:`stored_energy` at the state's own displacement (to round-off) without the
        kinematics; valid with bulk viscosity (the state's τ is the material stress)."""
        alpha = self.elastic.weight_at_quadrature(weight)
        tau = state.kirchhoff
        tr = tau[0, 0] + tau[1, 1] + tau[2, 2]
        dev2 = np.einsum("ij...,ij...->...", tau, tau) - tr**2 / 3.0
        K, G = self.material.bulk_modulus, self.material.shear_modulus
        psi = tr**2 / (18.0 * K) + dev2 / (4.0 * G)
        return float(np.sum(alpha * self.kin.dv0 * psi))

    def plastic_dissipation(self, state: PlasticState, weight: WeightLike = None) -> float:
        """Accumulated plastic work Σ w₀ w_p (J)."""
        alpha = self.elastic.weight_at_quadrature(weight)
        return float(np.sum(alpha * self.kin.dv0 * state.plastic_work))

    def viscous_dissipation(self, state: PlasticState, weight: WeightLike = None) -> float:
        """Accumulated work of the bulk viscosity Σ w₀ w_v (J)."""
        alpha = self.elastic.weight_at_quadrature(weight)
        return float(np.sum(alpha * self.kin.dv0 * state.viscous_work))

    def critical_time_step(self, u: np.ndarray, state: PlasticState | None = None) -> float:
        """Estimate (s) of the explicit critical step in the configuration X + u.

        min over the cells of κ_c h_c(u)/c_d, h_c the cell's measure over its longest edge, κ_c
        calibrated once per cell so that at u = 0 it is the element eigenvalue bound of
        :func:`~arlequin.models.elastic.element_critical_step` (a lower bound of the critical
        step): cheap enough to follow crushed cells. Capability ``"critical_time_step"``."""
        if self._wave_speed is None:  # the material is frozen: c_d once (8 µs a call)
            self._wave_speed = self.material.dilatational_wave_speed
        cd = self._wave_speed
        if self._critical_ratio is None:
            per_cell = element_critical_step(self.elastic, self.elastic.basis, per_cell=True)
            self._critical_ratio = per_cell * cd / self.kin.cell_sizes(self.mesh.p)
        if self.backend == "numba" and self.dim == 2:  # the same floats, compiled
            if self._size_arrays is None:  # one type for the compiled loop whatever the mesh's
                c, i8 = np.ascontiguousarray, np.int64
                self._size_arrays = (
                    c(self.mesh.p, float),
                    c(self.mesh.t, i8),
                    c(self.kin.dofs, i8),
                )
            args = (*self._size_arrays, self._checked_displacement(u), self._critical_ratio)
            return float(j2_kernel.min_scaled_cell_size(*args) / cd)
        h = self.kin.cell_sizes(self.current_coordinates(u))
        return float(np.min(self._critical_ratio * h) / cd)

    def current_coordinates(self, u: np.ndarray) -> np.ndarray:
        """Node positions x = X + u, shape (dim, n_nodes) (m)."""
        return self.mesh.p + np.asarray(u)[self.kin.dofs]
