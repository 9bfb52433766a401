"""The records of a contact constraint: its state between steps, its trial within a step, and
the per-step records stacked into a history (all immutable, SI units; see
:mod:`arlequin.models.contact.level_set`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from .geometry import ContactGeometry

__all__ = ["ContactHistory", "ContactRecord", "ContactState", "ContactTrial", "build", "evolve"]


def build(cls: type, **fields: Any) -> Any:
    """``cls(**fields)`` for the frozen records of this module, every field given: their
    generated ``__init__`` sets each field through ``object.__setattr__`` (2.1 µs for a
    trial's 17 fields, against 1.2 µs here; several records a step).

    Raises
    ------
    TypeError
        If ``fields`` are not exactly the fields of ``cls``.
    """
    if fields.keys() != cls.__dataclass_fields__.keys():
        raise TypeError(f"{cls.__name__} needs the fields {list(cls.__dataclass_fields__)}, "
                        f"got {list(fields)}")  # fmt: skip
    new = object.__new__(cls)
    new.__dict__.update(fields)
    return new


def evolve(record: Any, **changes: Any) -> Any:
    """``dataclasses.replace(record, **changes)`` for frozen dataclass records (this module's,
    the friction trial: no ``__post_init__``, no ``InitVar``, every field in ``__init__``),
    without its per-call field introspection
    and keyword ``__init__``: 1 µs against 4 µs, at every status iteration of every step.

    Raises
    ------
    TypeError
        If a name in ``changes`` is not a field of the record.
    """
    fields = type(record).__dataclass_fields__
    for name in changes:
        if name not in fields:
            raise TypeError(f"{type(record).__name__} has no field {name!r}")
    new = object.__new__(type(record))
    new.__dict__.update(record.__dict__)
    new.__dict__.update(changes)
    return new


@dataclass
class ContactHistory:
    """Per-step records of a contact constraint (one entry per recorded step, aligned with the
    result's ``times[1:]``; every step when the run records every step).

    All arrays have a leading axis of length n_rec − 1; point arrays have shape (n_rec − 1, m).

    Attributes
    ----------
    t : ndarray
        Time of the step's end (s) (the explicit scheme: the time of the impulse that ends it).
    iterations : ndarray of int
        Status (fixed-point) iterations of the step.
    converged : ndarray of bool
    active : ndarray of bool
        Statuses S = S_d S_v used in the accepted solve.
    s_d, s_v : ndarray of bool
        Indicator fields at the collocation points.
    gap : ndarray
        d_n at the end of the step (m), from the geometry (not the linearised rows).
    gap_start : ndarray
        d_n at the start of the step (m).
    vn_start : ndarray
        [[v_n]] at the start of the step (m/s) (the explicit scheme: free mid-step velocity).
    vn : ndarray
        [[v_n]] of the accepted solution (m/s).
    lam : ndarray
        λ_v (Pa), ≤ 0 in contact.
    work : ndarray
        Accumulated contact work (J) up to the end of the step (≤ 0: dissipated).
    dt : ndarray
        Time step (s).
    """

    t: np.ndarray
    iterations: np.ndarray
    converged: np.ndarray
    active: np.ndarray
    s_d: np.ndarray
    s_v: np.ndarray
    gap: np.ndarray
    gap_start: np.ndarray
    vn_start: np.ndarray
    vn: np.ndarray
    lam: np.ndarray
    work: np.ndarray
    dt: np.ndarray

    @classmethod
    def from_records(cls, records: list[ContactRecord], m: int) -> ContactHistory:
        """Stack per-step records (m collocation points)."""
        keys = cls.__dataclass_fields__.keys()
        if not records:
            point_keys = ("active", "s_d", "s_v", "gap", "gap_start", "vn_start", "vn", "lam")
            empty = {k: np.zeros((0, m)) if k in point_keys else np.zeros(0) for k in keys}
            return cls(**empty)
        return cls(**{k: np.array([getattr(r, k) for r in records]) for k in keys})


@dataclass(frozen=True)
class ContactRecord:
    """The record of one accepted step of a contact constraint (see :class:`ContactHistory`)."""

    t: float
    iterations: int
    converged: bool
    active: np.ndarray
    s_d: np.ndarray
    s_v: np.ndarray
    gap: np.ndarray
    gap_start: np.ndarray
    vn_start: np.ndarray
    vn: np.ndarray
    lam: np.ndarray
    work: float
    dt: float


@dataclass(frozen=True)
class ContactState:
    """Committed state of a contact constraint between steps (immutable).

    Attributes
    ----------
    active : ndarray of bool, shape (m,)
        Statuses S used in the last accepted solve.
    work : float
        Accumulated contact work (J), from the multipliers (≤ 0: dissipated).
    record : ContactRecord or None
        The last accepted step's record.
    multipliers : ndarray, shape (m,)
        λ_v (Pa) of the last accepted step.
    geometry : ContactGeometry
        Gaps and rows at ``u_geometry`` (reused by the next step when it starts there).
    u_geometry : ndarray, shape (k,)
        u (m) on the pair's geometry dofs (``geometry_dofs``, k of them) where ``geometry``
        was made, or the whole u (n,) for a pair that does not name them.
    impulse : ndarray, shape (m,) or None
        Accumulated ∫λ_v dt at each collocation point (Pa·s): the force on the rows over any
        interval is −Σ w Δimpulse / Δt (N) with the collocation weights w.
    """

    active: np.ndarray
    work: float
    record: ContactRecord | None
    multipliers: np.ndarray
    geometry: ContactGeometry
    u_geometry: np.ndarray
    impulse: np.ndarray | None = None


@dataclass(frozen=True)
class ContactTrial:
    """A contact constraint inside one step's status iterations (immutable).

    ``active``, ``matrix``, ``rhs``, ``changed`` and ``iterations`` are those of
    :class:`arlequin.contract.ConstraintTrial`; the rest is the step's record in the making.
    """

    active: np.ndarray
    matrix: sp.csr_matrix
    rhs: np.ndarray
    changed: bool
    iterations: int
    t: float
    dt: float
    geometry: ContactGeometry
    gap_start: np.ndarray
    vn_start: np.ndarray
    gap_pred: np.ndarray
    s_d: np.ndarray
    s_v: np.ndarray
    used: np.ndarray
    lam: np.ndarray
    vn: np.ndarray
    u_start: np.ndarray
