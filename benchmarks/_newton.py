"""Newton diagnostics of the quasi-static solver for the benchmarks (instrumentation only).

Issue 29, item 5 asks that once the relative residual r_k is below 1e-3, each Newton iteration
gives r_k+1 ≤ 10 r_k² (until 1e-10). Newton on J2 plasticity is semismooth: its residual is
smooth only while every quadrature point stays on one side of the yield surface (yielding,
Δε̄p > 0, or elastic). :func:`newton_record` records, for every converged Newton solve, the
relative residuals and, per iteration, how many quadrature points changed side between the
iterate and the next (their plastic status, of the trial states at the two iterates), and
optionally the smallest eigenvalue of the tangent at the converged state against the elastic
one (the distance to a limit point). :func:`contraction_summary` separates the contraction
constants C = r_k+1 / r_k² of the iterations with a fixed plastic set from those where it
changed.
"""

from __future__ import annotations

import itertools
from contextlib import contextmanager
from typing import Any

import numpy as np
import scipy.sparse.linalg as spla

from arlequin.solvers.statics import quasi_static

#: Item 5's window and factor: r_k below START, r_k+1 above STOP, r_k+1 ≤ FACTOR r_k².
START, STOP, FACTOR = 1e-3, 1e-10, 10.0


def plastic_set(trial: dict[str, list[Any]], committed: dict[str, list[Any]]) -> np.ndarray:
    """Whether each quadrature point of every model with an ``eqps`` state yields in the step
    (Δε̄p > 0 from ``committed`` to ``trial``), concatenated: bool, shape (n_points,)."""
    out = [np.zeros(0, dtype=bool)]
    for name, states in trial.items():
        for new, old in zip(states, committed[name]):
            if hasattr(new, "eqps") and old is not None:
                out.append(np.ravel(np.asarray(new.eqps) > np.asarray(old.eqps)))
    return np.concatenate(out)


def smallest_eigenvalue(solver: Any, u: np.ndarray, states: dict[str, list[Any]]) -> float:
    """The smallest eigenvalue (N/m) of the tangent on the free dofs at ``u`` from ``states``
    (single-model problems: no multiplier rows; symmetric J2 tangents)."""
    kt = solver.ops.internal_force(u, states, tangent=True)[2]
    free = solver.saddle.free
    k = kt[free][:, free].tocsc()
    return float(spla.eigsh(k, k=1, sigma=0.0, which="LM", return_eigenvectors=False)[0])


@contextmanager
def newton_record(eigenvalues: bool = False):
    """Record every converged Newton solve of :class:`QuasiStaticSolver` (the class's
    ``_newton`` and ``_update`` wrapped, restored after; one more internal-force evaluation per
    iteration). Yields a list that fills with dicts: ``load_factor``, ``residuals`` (relative,
    per iterate), ``set_changes`` (points changing side per iteration) and, with
    ``eigenvalues``, ``min_eigenvalue_ratio`` (λ_min of the converged tangent over that of
    the initial, elastic one)."""
    cls = quasi_static.QuasiStaticSolver
    newton, update = cls._newton, cls._update
    records: list[dict[str, Any]] = []
    changes: list[int] = []
    elastic: dict[int, float] = {}

    def wrapped_update(self, u, mu, du, dmu, rel, lam):
        before = plastic_set(self.ops.internal_force(u, self.states)[1], self.states)
        out = update(self, u, mu, du, dmu, rel, lam)
        changes.append(int(np.count_nonzero(plastic_set(out[3], self.states) != before)))
        return out

    def wrapped_newton(self, lam):
        changes.clear()
        u, mu, trial, history = newton(self, lam)
        rec = {"load_factor": float(lam), "residuals": [float(r) for r in history],
               "set_changes": list(changes)}  # fmt: skip
        if eigenvalues:
            if id(self) not in elastic:
                zero = np.zeros_like(u)
                elastic[id(self)] = smallest_eigenvalue(self, zero, self.ops.initial_states())
            rec["min_eigenvalue_ratio"] = (
                smallest_eigenvalue(self, u, self.states) / elastic[id(self)]
            )
        records.append(rec)
        return u, mu, trial, history

    cls._newton, cls._update = wrapped_newton, wrapped_update
    try:
        yield records
    finally:
        cls._newton, cls._update = newton, update


def contractions(record: dict[str, Any]) -> list[tuple[float, int]]:
    """(C = r_k+1 / r_k², points changing side) of the iterations in item 5's window."""
    res, chg = record["residuals"], record["set_changes"]
    return [
        (r1 / r0**2, chg[k])
        for k, (r0, r1) in enumerate(itertools.pairwise(res))
        if r0 < START and r1 > STOP
    ]


def contraction_summary(records: list[dict[str, Any]]) -> dict[str, Any]:
    """Item 5's contraction constants split by whether the plastic set changed: the largest C
    and the iterations over the factor 10, of each kind; the steps' C and set changes."""
    pairs = [c for rec in records for c in contractions(rec)]
    fixed = [c for c, n in pairs if n == 0]
    moved = [c for c, n in pairs if n > 0]
    return {
        "max_C_fixed_set": max(fixed, default=0.0),
        "max_C_set_changed": max(moved, default=0.0),
        "iterations_fixed_set": len(fixed),
        "iterations_set_changed": len(moved),
        "over_10_fixed_set": sum(c > FACTOR for c in fixed),
        "over_10_set_changed": sum(c > FACTOR for c in moved),
        "steps": [_step_summary(rec) for rec in records if rec["set_changes"]],
    }


def _step_summary(record: dict[str, Any]) -> dict[str, Any]:
    """One step's load factor, its C and set changes in item 5's window (and λ_min ratio)."""
    pairs = contractions(record)
    out = {
        "load_factor": record["load_factor"],
        "C": [round(c, 3) for c, _ in pairs],
        "set_changes": [n for _, n in pairs],
    }
    if "min_eigenvalue_ratio" in record:
        out["min_eigenvalue_ratio"] = record["min_eigenvalue_ratio"]
    return out
