"""The recorder: samples an integrator at chosen times into a :class:`DynamicResult`.

It records the initial state, then the states it is asked to (every N steps, or the requested
output times that the driver makes the steps land on): energies and works per block, the
multipliers of every constraint, the step size, the status iterations, the unilateral
constraints' per-step records and, optionally, the fields u and v. Listeners (``on_record``)
receive each record as it is taken, so that a results folder is written as the run goes.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from typing import Any

import numpy as np

from .result import DynamicResult

__all__ = ["Recorder"]


def _stacked(values: list[np.ndarray]) -> np.ndarray:
    """The recorded arrays as one array (n_rec, ...); arrays of several sizes (an adaptive
    patch's multipliers and fields change size as it grows) as an object array of them."""
    if len({np.shape(v) for v in values}) <= 1:
        return np.array(values)
    out = np.empty(len(values), dtype=object)
    out[:] = values
    return out


class Recorder:
    """Samples an integrator.

    Parameters
    ----------
    integrator : Integrator
    save_fields : bool
        Also record u and v (memory: n_rec × n each).
    on_record : sequence of callables, optional
        ``listener(integrator)`` after each record (writers of results folders).
    """

    def __init__(
        self,
        integrator: Any,
        save_fields: bool = False,
        on_record: tuple[Callable[[Any], None], ...] = (),
    ) -> None:
        self.integ = integrator
        self.times: list[float] = []
        self.rows: list[dict[str, dict[str, float]]] = []
        self.mult: dict[str, list[np.ndarray]] = {}
        self.iters: list[int] = []
        self.sizes: list[float] = []
        self.records: dict[str, list[Any]] = {c.name: [] for c in integrator.unilateral}
        self.save_fields = bool(save_fields)
        self.us: list[np.ndarray] = []
        self.vs: list[np.ndarray] = []
        self.listeners = tuple(on_record)

    #: The attributes that :meth:`state` saves (everything recorded so far).
    _STATE = ("times", "rows", "mult", "iters", "sizes", "records", "us", "vs")

    def state(self) -> dict[str, Any]:
        """What has been recorded so far (a checkpoint of a run; restore it with
        :meth:`load_state`)."""
        return {name: copy.deepcopy(getattr(self, name)) for name in self._STATE}

    def load_state(self, state: dict[str, Any]) -> None:
        """Continue from a :meth:`state` (a resumed run)."""
        for name in self._STATE:
            setattr(self, name, copy.deepcopy(state[name]))

    def record(self) -> None:
        """Record the integrator's current state."""
        it = self.integ
        first = not self.times
        self.times.append(it.t)
        self.rows.append(it.energies())
        for name, lam in it.multipliers.items():
            self.mult.setdefault(name, []).append(np.array(lam, dtype=float))
        self.iters.append(int(it.status_iterations))
        self.sizes.append(0.0 if first or it.step_size is None else float(it.step_size))
        if not first:
            for name, recs in self.records.items():
                recs.append(it.constraint_states[name].record)
        if self.save_fields:
            self.us.append(it.u.copy())
            self.vs.append(it.v.copy())
        for listener in self.listeners:
            listener(it)

    def result(self, status: int, message: str) -> DynamicResult:
        """The :class:`DynamicResult` of what was recorded (status 0, 1 or −1)."""
        it = self.integ
        names = it.ops.names

        def hist(key: str, default: str | None = None) -> dict[str, np.ndarray]:
            # rows of a run resumed from an older checkpoint may lack the newer keys
            def value(r: dict, n: str) -> float:
                if key in r:
                    return r[key][n]
                return r[default][n] if default else 0.0

            return {n: np.array([value(r, n) for r in self.rows]) for n in names}

        fields = None
        if self.save_fields:
            fields = {"u": _stacked(self.us), "v": _stacked(self.vs)}
        sizes = np.array(self.sizes)
        last = it.step_size if it.step_size is not None else it.dt
        return DynamicResult(
            times=np.array(self.times),
            kinetic=hist("kinetic"),
            kinetic_full_step=hist("kinetic_full_step"),
            strain=hist("strain"),
            stored=hist("stored", "strain"),
            dissipation=hist("dissipation"),
            external_work=hist("external_work"),
            coupling_work=hist("coupling_work"),
            constraint_work=hist("constraint_work"),
            damping_work=hist("damping_work"),
            multipliers={k: _stacked(v) for k, v in self.mult.items()},
            status_iterations=np.array(self.iters, dtype=np.int64),
            u=it.u.copy(),
            v=it.v.copy(),
            n_steps=it.step_count,
            dt=float(last),
            status=status,
            message=message,
            critical_dt=it.critical_dt,
            n_status_failures=it.n_status_failures,
            integrator=it.name,
            fields=fields,
            states=it.states,
            step_sizes=sizes,
            constraint_states=dict(it.constraint_states),
            constraint_records={k: list(v) for k, v in self.records.items()},
        )
