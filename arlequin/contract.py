"""The contract between the coupling core and the physics models: protocols and shared errors.

This is the only part of :mod:`arlequin` that the models (:mod:`arlequin.models`) import, besides
the pure geometry helpers listed in ``docs/architecture.md`` (reference elements, facet
geometry, mesh checks). Everything the core calls on a model or a constraint is written down here,
so that a new model or constraint is written against this page and nothing else.

Models
------
A model is single-mesh physics that knows nothing about Arlequin. The integrators need
:class:`DynamicModel`; an :class:`~arlequin.problem.arlequin_problem.ArlequinProblem` needs the full
:class:`Model` (mesh, bases and loads as well). Every assembled quantity takes an optional
quadrature-point ``weight`` (the partition weight α of the coupling, default 1), evaluated at the
quadrature points of the model's basis: an array of shape ``(n_elems, n_qp)``, a scalar, or a
callable of the quadrature points ``x`` of shape ``(dim, n_elems, n_qp)``.

Optional capabilities are declared by implementing their protocol (checked with
:func:`capabilities`), never guessed from other members:

``"tangent"`` (:class:`SupportsTangent`)
    the consistent tangent ``∂f_int/∂u``; implicit integrators need it for nonlinear models
    (without it they raise :class:`CapabilityError`, or use the documented alternative
    ``newton="initial"``, a modified Newton iteration on the model's ``stiffness``).
``"critical_time_step"`` (:class:`SupportsCriticalTimeStep`)
    an element estimate of the explicit stable step in the current configuration, used by the
    :class:`~arlequin.solvers.CriticalFraction` controller to follow a changing
    configuration.

State at quadrature points is immutable: a *trial* state from ``internal_force``, committed by
the integrator once the step is accepted (a step can be redone from the committed state).

Constraints
-----------
Equality rows ``B u = g(t)`` are :class:`arlequin.problem.system.LinearConstraint` records. Rows
whose active set is decided inside each time step (contact) follow :class:`UnilateralConstraint`:
the constraint object holds only its configuration; its state lives in immutable records
(:class:`ConstraintState` between steps, :class:`ConstraintTrial` during a step's status
iterations) that the integrator passes in and commits. See the protocol for the calling sequence.

Sign convention: a constraint's force on the system is ``−Bᵀλ`` (N), ``λ`` the integrators'
multiplier, as in the static saddle point ``K u + Bᵀλ = f``.

Dof layout
----------
Within a model, dofs are interleaved by node, ``n_components * node + component``
(:func:`node_dofs`); a coupled system stacks them in blocks (:class:`arlequin.dofs.DofMap`).
Units are SI throughout (m, kg, s, Pa, N, J).
"""

from __future__ import annotations

import copy
from typing import Any, Protocol, runtime_checkable

import numpy as np
import scipy.sparse as sp

__all__ = [
    "CAPABILITIES", "BandYieldWarning", "CapabilityError", "CellStates", "CoarseYieldWarning",
    "ConstraintError", "ConstraintState", "ConstraintTrial", "ContractError", "DynamicModel",
    "LinearSolverError", "Model", "SimulationError", "StateError", "SupportsCellStates",
    "SupportsCriticalTimeStep", "SupportsTangent", "UnilateralConstraint", "capabilities",
    "check_protocol", "csr_pattern", "csr_with_data", "is_linear", "is_unilateral", "node_dofs",
    "put_cells", "require", "same_pattern", "take_cells",
]  # fmt: skip


# ---------------------------------------------------------------------------------------------
# errors shared by the core and the models
# ---------------------------------------------------------------------------------------------
class StateError(ValueError):
    """A model's state became invalid during a run (an inverted cell, a failed return mapping).

    Models raise subclasses of it from ``internal_force``; the integrators turn it into a
    :class:`SimulationError` naming the step and the time, keeping what was recorded."""


class SimulationError(ValueError):
    """A run failed (non-finite values, an invalid model state, a Newton failure...).

    Attributes
    ----------
    step : int
        Index of the failed step (1 for the first step).
    time : float
        Time (s) the failed step was to reach.
    result : DynamicResult or None
        What was recorded until then (set by :func:`arlequin.solvers.solve`).
    """

    def __init__(self, message: str, step: int, time: float) -> None:
        super().__init__(message)
        self.step = int(step)
        self.time = float(time)
        self.result: Any = None


class CoarseYieldWarning(UserWarning):
    """A coarse elastic model carries von Mises stresses above its patches' yield stress
    outside them: the plastic zone has outgrown the patches."""


class BandYieldWarning(UserWarning):
    """A patch yields in its gluing band, where its fields are the coupling's: its plastic zone
    reached the band (widen the patch) or the mediator concentrates strain there."""


class ConstraintError(ValueError):
    """The constraint rows cannot be enforced (linearly dependent rows, zero masses...)."""


class LinearSolverError(ValueError):
    """An iterative linear solve did not reach its tolerance: its true residual (relative to the
    right-hand side) is above it after the allowed iterations. No unconverged solution is ever
    returned; the message names the residual reached and the iterations spent."""


class CapabilityError(ValueError):
    """A model lacks an optional capability that the requested computation needs."""


class ContractError(ValueError):
    """An object is used as a model or a constraint but lacks members of its protocol."""


# ---------------------------------------------------------------------------------------------
# models
# ---------------------------------------------------------------------------------------------
@runtime_checkable
class DynamicModel(Protocol):
    """What the integrators call on a model (one block term of a coupled system).

    Attributes
    ----------
    n_dofs : int
        Number of degrees of freedom (dofs interleaved by node: ``n_components * node + c``).
    is_linear : bool
        True if ``internal_force(u) = stiffness() @ u`` for every ``u`` (the integrators then use
        the assembled stiffness and never call ``internal_force``).

    Notes
    -----
    Optional members: ``n_components`` (default 1), ``initial_state(weight)`` (default None:
    the first ``internal_force`` call gets ``state=None``) and ``uses_time_step`` (default
    False): when True, the integrators call ``internal_force(u, state, weight, dt=h)`` with h
    (s) the step that leads to u (None at the initial time), for rate-dependent state updates,
    and ``tangent(u, state, weight, dt=h)`` likewise (the derivative of that force).

    Energy members (optional, looked up with ``getattr``; both or neither):
    ``stored_energy_of_state(state, weight) -> float``, the stored (recoverable) energy of a
    committed state (J), and ``plastic_dissipation(state, weight) -> float``, the plastic
    dissipation accumulated up to it (J), both weighted by α like the forces. With them the
    integrators report a nonlinear block's ``stored`` energy and ``dissipation``
    (``Integrator.energies``, ``DynamicResult.material_balance``); without them its stored
    energy is the accumulated work of its internal forces. A model whose state does not
    determine them may raise ``ValueError`` (the block then falls back likewise).
    """

    n_dofs: int
    is_linear: bool

    def mass(self, weight: Any = None, lumped: bool = False) -> Any:
        """Weighted mass ∫ α ρ u·v (kg): sparse (n_dofs, n_dofs), or its row sums when lumped."""

    def stiffness(self, weight: Any = None) -> Any:
        """Weighted stiffness (N/m), sparse (n_dofs, n_dofs); the small-strain (initial) tangent
        of a nonlinear model, used for stable-step estimates."""

    def internal_force(
        self, u: np.ndarray, state: Any = None, weight: Any = None
    ) -> tuple[np.ndarray, Any]:
        """Internal force (N), shape (n_dofs,), and the trial state at displacement u (m)."""


@runtime_checkable
class Model(DynamicModel, Protocol):
    """What an :class:`~arlequin.problem.arlequin_problem.ArlequinProblem` calls on a model.

    Attributes
    ----------
    mesh : skfem.Mesh
        The reference mesh (m), first order (P1 or Q1 cells).
    kind : str
        Kinematics: ``"1d"``, ``"plane_strain"``, ``"plane_stress"``, ``"axisymmetric"`` or
        ``"3d"``; the coarse model and its patches must share it.
    n_components : int
        Displacement components per node.
    """

    mesh: Any
    kind: str
    n_components: int

    def scalar_basis(self) -> Any:
        """Scalar first-order ``skfem.Basis`` with the model's quadrature: weights are evaluated
        at its quadrature points, shape (n_elems, n_qp)."""

    def with_mesh(self, mesh: Any) -> Model:
        """The same material and kinematics on another mesh (overlap integration meshes)."""

    def initial_state(self, weight: Any = None) -> Any:
        """State at the quadrature points before the first step (None for stateless models)."""

    def body_force_vector(self, force: Any, weight: Any = None) -> np.ndarray:
        """Load vector ∫ α f·v (N), shape (n_dofs,), of a body force density f (N/m³)."""

    def traction_vector(self, facets: np.ndarray, traction: Any, weight: Any = None) -> np.ndarray:
        """Load vector ∫ α t·v (N), shape (n_dofs,), of a traction t (Pa) on boundary facets."""


@runtime_checkable
class SupportsTangent(Protocol):
    """Capability ``"tangent"``: the consistent tangent of ``internal_force``."""

    def tangent(self, u: np.ndarray, state: Any = None, weight: Any = None) -> Any:
        """∂f_int/∂u (N/m) at u from the committed state, sparse (n_dofs, n_dofs)."""


@runtime_checkable
class SupportsCriticalTimeStep(Protocol):
    """Capability ``"critical_time_step"``: explicit stable-step estimate in a configuration."""

    def critical_time_step(self, u: np.ndarray, state: Any = None) -> float:
        """An estimate (s) of the critical step of central differences with the lumped mass at
        displacement u (m), never larger than the true value of the model alone (weight 1)."""


@runtime_checkable
class SupportsCellStates(Protocol):
    """Optional members of a nonlinear model that adaptive patches call
    (:mod:`arlequin.problem.adapt`): its state cut into cells and put back, and its yield stress.
    Not a capability of the integrators (not in :data:`CAPABILITIES`); a model without them
    cannot be the model of an adaptive patch. :class:`CellStates` gives the first two to any
    model whose state is a dataclass of arrays of shape (…, n_elems, n_qp).
    """

    def state_of_cells(self, state: Any, cells: np.ndarray) -> Any:
        """The state restricted to ``cells`` (the arrays' n_elems axis taken at them)."""

    def with_cells(self, state: Any, cells: np.ndarray, part: Any) -> Any:
        """A new state: ``state`` with its ``cells`` replaced by those of ``part`` (a state of
        ``len(cells)`` cells, as :meth:`state_of_cells` returns)."""

    def yield_stress(self, state: Any = None) -> np.ndarray:
        """The current yield stress σ_y(ε̄p) (Pa), shape (n_elems, n_qp); σ_y0 for ``None``."""


def take_cells(state: Any, cells: np.ndarray) -> Any:
    """A state (a dataclass of arrays (…, n_elems, n_qp)) restricted to ``cells``."""
    import dataclasses

    cells = np.asarray(cells, dtype=np.int64)
    values = {f.name: np.take(np.asarray(getattr(state, f.name)), cells, axis=-2)
              for f in dataclasses.fields(state)}  # fmt: skip
    return type(state)(**values)


def put_cells(state: Any, cells: np.ndarray, part: Any) -> Any:
    """A new state: ``state`` with its ``cells`` replaced by ``part``'s (both dataclasses of
    arrays (…, n_elems, n_qp), ``part`` of ``len(cells)`` cells); ``state`` is not changed."""
    import dataclasses

    cells = np.asarray(cells, dtype=np.int64)
    values = {}
    for f in dataclasses.fields(state):
        a = np.array(getattr(state, f.name), dtype=float)
        a[..., cells, :] = np.asarray(getattr(part, f.name))
        values[f.name] = a
    return type(state)(**values)


class CellStates:
    """:meth:`state_of_cells` and :meth:`with_cells` of :class:`SupportsCellStates` for a
    model whose state is a dataclass of arrays of shape (…, n_elems, n_qp)."""

    def state_of_cells(self, state: Any, cells: np.ndarray) -> Any:
        """The state at ``cells`` (:func:`take_cells`)."""
        return take_cells(state, cells)

    def with_cells(self, state: Any, cells: np.ndarray, part: Any) -> Any:
        """``state`` with its ``cells`` replaced by ``part`` (:func:`put_cells`)."""
        return put_cells(state, cells, part)


#: The optional capabilities and their protocols.
CAPABILITIES: dict[str, type] = {
    "tangent": SupportsTangent,
    "critical_time_step": SupportsCriticalTimeStep,
}


def capabilities(model: Any) -> frozenset[str]:
    """The optional capabilities a model declares (the protocols of :data:`CAPABILITIES` it
    implements)."""
    return frozenset(name for name, proto in CAPABILITIES.items() if isinstance(model, proto))


def require(model: Any, capability: str, what: str) -> None:
    """Raise :class:`CapabilityError` naming the model if it lacks ``capability``.

    Parameters
    ----------
    model : object
    capability : str
        A key of :data:`CAPABILITIES`.
    what : str
        The computation that needs it (for the message).
    """
    if capability not in CAPABILITIES:
        raise ValueError(f"unknown capability {capability!r}; known: {sorted(CAPABILITIES)}")
    if capability not in capabilities(model):
        raise CapabilityError(
            f"{what} needs the {capability!r} capability, which model "
            f"{type(model).__name__} does not provide"
        )


def check_protocol(obj: Any, protocol: type, what: str) -> None:
    """Raise :class:`ContractError` naming the members of ``protocol`` that ``obj`` lacks.

    Parameters
    ----------
    obj : object
    protocol : type
        A protocol of this module (:class:`Model`, :class:`DynamicModel`,
        :class:`UnilateralConstraint`...).
    what : str
        What ``obj`` is used as (for the message), e.g. ``"the coarse model"``.
    """
    if isinstance(obj, protocol):
        return
    members = [
        m
        for klass in protocol.__mro__
        if klass not in (object, Protocol) and klass.__name__ != "Generic"
        for m in getattr(klass, "__annotations__", {}).keys() | vars(klass).keys()
        if not m.startswith("_")
    ]
    missing = sorted({m for m in members if not hasattr(obj, m)})
    raise ContractError(
        f"{what} is a {type(obj).__name__}, which lacks {', '.join(missing)} of the "
        f"{protocol.__name__} protocol (arlequin.contract)"
    )


def is_linear(model: Any) -> bool:
    """The model's declared ``is_linear`` flag.

    Raises
    ------
    CapabilityError
        If the model does not declare it (the integrators never guess linearity).
    """
    flag = getattr(model, "is_linear", None)
    if flag is None:
        raise CapabilityError(
            f"model {type(model).__name__} does not declare is_linear (True if its internal "
            "force is stiffness() @ u, False otherwise): see arlequin.contract.DynamicModel"
        )
    return bool(flag)


# ---------------------------------------------------------------------------------------------
# unilateral constraints (contact)
# ---------------------------------------------------------------------------------------------
@runtime_checkable
class ConstraintState(Protocol):
    """Committed state of a unilateral constraint between steps (immutable).

    Attributes
    ----------
    active : ndarray of bool, shape (m,)
        Statuses of the candidate rows after the last accepted step.
    work : float
        Accumulated work of the constraint forces (J).
    record : object or None
        The per-step record of the last accepted step (None before the first), for histories.
    """

    active: np.ndarray
    work: float
    record: Any


@runtime_checkable
class ConstraintTrial(Protocol):
    """A unilateral constraint inside one step's status iterations (immutable).

    Attributes
    ----------
    active : ndarray of bool, shape (m,)
        Current statuses: active rows are enforced as equalities at the constraint's level.
    matrix : scipy.sparse.csr_matrix, shape (m, n)
        Candidate rows in the configuration of the step.
    rhs : ndarray, shape (m,)
        Right-hand side of the rows (m for displacement rows, m/s for velocity rows) at the
        end of the step.
    changed : bool
        Whether the last :meth:`UnilateralConstraint.update_status` changed a status.
    iterations : int
        Status updates made in this step.

    A trial may also carry ``applied`` (ndarray (m,) or None): prescribed multipliers of
    inactive rows, a force −Bᵀλ_applied during the step (slip friction); the explicit
    integrator adds it to the free velocity, reports it with the multipliers and passes its
    impulse to ``commit``. Constraints that use it declare ``explicit_only = True``.
    """

    active: np.ndarray
    matrix: Any
    rhs: np.ndarray
    changed: bool
    iterations: int


@runtime_checkable
class UnilateralConstraint(Protocol):
    """Rows whose active set is decided inside each time step (the level-set contact model).

    Calling sequence of one step (the integrator drives it; the constraint keeps no state)::

        trial = c.begin_step(state, t, dt, u, v)       # geometry, statuses guess
        loop:   solve with trial.active rows enforced (trial.matrix, trial.rhs)
                trial = c.update_status(trial, u_pred, v_pred, multipliers)
                until not trial.changed (or the cap of iterations)
        state = c.commit(state, trial, t=..., u=..., v_before=..., v_after=...,
                         multipliers=..., impulse=...)

    A step that fails is simply not committed: the constraint's previous state is unchanged, so
    the step can be redone (with another step size) and an integrator restarted from a saved
    state.

    Attributes
    ----------
    name : str
        Name in the multiplier histories.
    level : {"velocity", "displacement"}
        An active row enforces ``G v = rhs`` on the end-of-step velocity, or ``G u = rhs``.
    kind : str
        Reporting group of its work (``"contact"``).
    max_iterations : int
        Cap on the status iterations of one step.
    n_rows : int
        Number of candidate rows m.
    """

    name: str
    level: str
    kind: str
    max_iterations: int

    @property
    def n_rows(self) -> int:
        """Number of candidate rows m."""

    def initial_state(self, u: np.ndarray, v: np.ndarray) -> ConstraintState:
        """The state before the first step at displacement u (m) and velocity v (m/s)."""

    def begin_step(
        self, state: ConstraintState, t: float, dt: float, u: np.ndarray, v: np.ndarray
    ) -> ConstraintTrial:
        """Start a step from time t (s) of size dt (s) at u (m) and the step's free velocity v
        (m/s): rows in the current configuration and a first guess of the statuses."""

    def update_status(
        self, trial: ConstraintTrial, u: np.ndarray, v: np.ndarray, multipliers: np.ndarray
    ) -> ConstraintTrial:
        """New statuses from the predicted end-of-step u (m), v (m/s) and the multipliers of all
        candidate rows, shape (m,) (zero on inactive rows)."""

    def commit(
        self,
        state: ConstraintState,
        trial: ConstraintTrial,
        *,
        t: float,
        u: np.ndarray,
        v_before: np.ndarray,
        v_after: np.ndarray,
        multipliers: np.ndarray,
        impulse: np.ndarray,
    ) -> ConstraintState:
        """The state after the accepted step ending at t (s).

        ``multipliers`` (m,) are the step's reported multipliers; ``impulse`` (m,) is the time
        integral of the multipliers over the step, ∫ λ dt (the explicit impulse, Δt λ for the
        θ-scheme, Δt (λⁿ + λⁿ⁺¹)/2 for Newmark), so that the work of the constraint forces −Bᵀλ
        taking the velocities from v_before to v_after (m/s) is −impulse·B (v_before + v_after)/2
        (J), whatever the scheme."""


def is_unilateral(constraint: Any) -> bool:
    """Whether a constraint object follows the :class:`UnilateralConstraint` protocol."""
    return isinstance(constraint, UnilateralConstraint)


def node_dofs(nodes: np.ndarray, n_components: int, components=None, offset: int = 0) -> np.ndarray:
    """Dofs of nodes in the interleaved layout, shape (n_components', len(nodes)).

    Parameters
    ----------
    nodes : array_like of int
        Node indices of one model.
    n_components : int
        Displacement components per node.
    components : sequence of int, optional
        Components to return (default all), each in ``[0, n_components)``.
    offset : int
        Added to every dof (the model's block offset in a global vector).
    """
    nodes = np.asarray(nodes, dtype=np.int64).ravel()
    comps = np.arange(n_components) if components is None else np.asarray(components, np.int64)
    if comps.size and (comps.min() < 0 or comps.max() >= n_components):
        raise ValueError(f"components must lie in [0, {n_components}), got {comps.tolist()}")
    return offset + n_components * nodes[None, :] + comps[:, None]


def csr_pattern(indices: np.ndarray, indptr: np.ndarray, shape: tuple[int, int]) -> sp.csr_matrix:
    """A CSR template of rows on a fixed pattern, for :func:`csr_with_data`.

    Its index arrays are read-only and shared by every matrix made from it: a consumer that
    sorts or prunes a matrix's arrays in place raises instead of changing the others, and
    consumers key their caches on the arrays' identity (:func:`same_pattern`).

    Parameters
    ----------
    indices : ndarray of int, shape (nnz,)
        Column of each entry, sorted within each row, no duplicates.
    indptr : ndarray of int, shape (m + 1,)
        Row pointers.
    shape : tuple of int
        (m, n).

    Returns
    -------
    csr_matrix, shape (m, n)
        The template (zero entries).
    """
    template = sp.csr_matrix((np.zeros(indices.size), indices, indptr), shape=shape)
    template.indices.flags.writeable = False
    template.indptr.flags.writeable = False
    # sorted without duplicates by construction: flags set, so no consumer sorts or sums
    template.has_sorted_indices = True
    template.has_canonical_format = True
    return template


def csr_with_data(template: sp.csr_matrix, data: np.ndarray) -> sp.csr_matrix:
    """A new CSR matrix on the pattern of ``template`` (:func:`csr_pattern`) with the entries
    ``data`` (nnz,), not copied (the caller gives a new array: earlier matrices, which states
    may keep, stay as they were): a shallow copy of the template, 3.5 µs against 17 µs for
    scipy's constructor and its index checks (several matrices a step on a deforming contact).
    """
    cls = type(template)
    if cls not in _PLAIN_COPY:
        _PLAIN_COPY[cls] = _copies_dict_only(cls)
    # copy.copy's own steps for such a class (a new instance, the attribute dict copied):
    # 0.4 µs against 1.9 µs through __reduce_ex__
    out = object.__new__(cls) if _PLAIN_COPY[cls] else copy.copy(template)
    if _PLAIN_COPY[cls]:
        out.__dict__.update(template.__dict__)
    out.data = data
    return out


_PLAIN_COPY: dict[type, bool] = {}  # classes whose copy.copy is the attribute dict's copy


def _copies_dict_only(cls: type) -> bool:
    """Whether ``copy.copy`` of a ``cls`` instance copies its ``__dict__`` into a new one alone
    (no copy hook, reduction, state method or slot but object's, and object's ``__new__``)."""
    hooks = ("__copy__", "__reduce_ex__", "__reduce__", "__getstate__", "__setstate__")
    for klass in cls.__mro__[:-1]:
        if any(h in vars(klass) for h in hooks) or vars(klass).get("__slots__", ()):
            return False
    return cls.__new__ is object.__new__


def same_pattern(a: sp.csr_matrix, b: sp.csr_matrix) -> bool:
    """Whether CSR matrices ``a`` and ``b`` share their read-only index arrays (both made by
    :func:`csr_with_data` from one :func:`csr_pattern` template): the same pattern, known
    without comparing the arrays; False for writable index arrays (they could have changed)."""
    return (a.indices is b.indices and a.indptr is b.indptr and a.shape == b.shape
            and not b.indices.flags.writeable and not b.indptr.flags.writeable)  # fmt: skip
