"""What a Taylor bar run records as it goes: the history, the energy balance, field frames.

:class:`TaylorRecorder` listens to the integrator (``on_record``) and, at every record, appends
a row of the history (length, footprint radius, energies, the wall's force and work, the step)
to memory and to ``history.csv``, checks the energy balance and writes the field frames
(fields/bar.xdmf) at the frame times (:func:`~arlequin.demos.taylor_bar.report.write_results`
writes the scalar results and the pictures at the end). SI units.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

__all__ = ["HISTORY_UNITS", "MultiplierHistory", "TaylorRecorder"]

#: History columns and their units.
HISTORY_UNITS = {
    "t": "s",
    "length": "m",
    "radius": "m",
    "kinetic": "J",
    "elastic": "J",
    "plastic_dissipation": "J",
    "viscous_dissipation": "J",
    "coupling_work": "J",
    "contact_work": "J",
    "contact_force": "N",
    "dt": "s",
}


class TaylorRecorder:
    """Listener of the run: the history (and its CSV), the balance, field frames, progress.

    Parameters
    ----------
    bar : MonoBar or ArlequinBar
        The view of the models (:mod:`arlequin.demos.taylor_bar.models`): ``measures(u)``,
        ``energies(integ, integ.energies())``, ``series_meshes()``, ``frame(integ)``.
    con_name : str
        The wall constraint's name.
    weights : ndarray
        Collocation weights of the wall's surface (m²).
    ke0 : float
        KE_0 (J).
    folder : ResultsFolder or None
    frame_times : ndarray
        Times of the field frames (s).
    progress : callable or None
        ``progress(t)`` at every record.
    """

    def __init__(self, bar, con_name, weights, ke0, folder, frame_times, progress) -> None:
        self.bar, self.con_name, self.weights = bar, con_name, weights
        self.ke0 = ke0
        # with friction the history gains the friction work (the frictionless one is unchanged)
        self.friction = bool(getattr(bar.contact, "friction", 0.0))
        self.units = dict(HISTORY_UNITS)
        if self.friction:
            self.units["friction_work"] = "J"
        self.history: dict[str, list[float]] = {k: [] for k in self.units}
        self.balance: list[float] = []
        self.iterations: dict[int, int] = {}  # contact fixed-point iterations -> steps
        self.csv = (
            folder.history([*self.units, "balance_error"], {**self.units, "balance_error": "1"})
            if folder
            else None
        )
        self.series = (
            {name: folder.series(name, mesh) for name, mesh in bar.series_meshes().items()}
            if folder
            else {}
        )
        self.frame_times = np.asarray(frame_times) if folder else np.zeros(0)
        self._next_frame = 0
        self.progress = progress
        self.loop_start: float | None = None  # perf_counter at the initial record
        self._last: tuple[float, float] | None = None  # (t, accumulated wall impulse N·s)

    def __call__(self, integ) -> None:
        if self.loop_start is None:
            self.loop_start = time.perf_counter()
        length, radius = self.bar.measures(integ.u)
        energies = integ.energies()
        kinetic = float(sum(energies["kinetic"].values()))
        parts = self.bar.energies(integ, energies)
        cstate = integ.constraint_states[self.con_name]
        wc = -float(cstate.work)
        # λ is the nominal pressure (Pa) at the collocation points (≤ 0 in compression): the
        # mean force since the last record from the accumulated impulse (exact, and smooth
        # where the single-step multipliers of an explicit wall chatter)
        impulse = float(-(cstate.impulse * self.weights).sum())
        if self._last is None:
            lam = integ.multipliers.get(self.con_name)
            # the normal multipliers come first (a frictional wall adds its tangential ones)
            lam = None if lam is None else lam[: self.weights.size]
            force = 0.0 if lam is None or not lam.size else float(-(lam * self.weights).sum())
        else:
            force = (impulse - self._last[1]) / (integ.t - self._last[0])
        self._last = (float(integ.t), impulse)
        row = {
            "t": float(integ.t),
            "length": length,
            "radius": radius,
            "kinetic": kinetic,
            **parts,
            "contact_work": wc,
            "contact_force": force,
            "dt": float(integ.step_size or 0.0),
        }
        # KE + W_el + D_p + D_visc + W_c (+ D_f) = KE_0 + W_coupling (the net work of the
        # coupling forces: zero for a mediator enforced exactly, kept to show it)
        wf = 0.0
        if self.friction:
            wf = -float(cstate.friction_work)
            row["friction_work"] = -wf
        err = abs(kinetic + parts["elastic"] + parts["plastic_dissipation"]
                  + parts["viscous_dissipation"] + wc + wf - parts["coupling_work"]
                  - self.ke0) / self.ke0  # fmt: skip
        self.balance.append(err)
        for k in self.units:
            self.history[k].append(row[k])
        if self.csv is not None:
            self.csv.append({**row, "balance_error": err})
        while self._next_frame < self.frame_times.size and (
            integ.t >= self.frame_times[self._next_frame] - 1e-12
        ):
            self._next_frame += 1
            for name, (point, cell) in self.bar.frame(integ).items():
                self.series[name].write(float(integ.t), point, cell)
        if self.progress is not None:
            self.progress(float(integ.t))

    def count_step(self, integ) -> None:
        """An ``on_step`` listener: the distribution of the contact fixed-point iterations."""
        k = int(integ.status_iterations)
        self.iterations[k] = self.iterations.get(k, 0) + 1

    def iteration_summary(self) -> dict[str, Any]:
        """``{"mean", "max", "counts"}`` of the fixed-point iterations per step."""
        steps = sum(self.iterations.values())
        if not steps:
            return {"mean": 0.0, "max": 0, "counts": {}}
        mean = sum(k * n for k, n in self.iterations.items()) / steps
        return {
            "mean": mean,
            "max": max(self.iterations),
            "counts": {k: self.iterations[k] for k in sorted(self.iterations)},
        }

    def state(self) -> dict[str, Any]:
        """What the run has recorded so far (a checkpoint; see :meth:`restore`)."""
        return {"history": {k: list(v) for k, v in self.history.items()},
                "balance": list(self.balance), "next_frame": self._next_frame,
                "last": self._last, "iterations": dict(self.iterations)}  # fmt: skip

    def restore(self, state: dict[str, Any], frames: dict[str, list]) -> None:
        """Continue from a :meth:`state`: the history rows and the field frames written until
        then (``frames``: series name -> [(t, point_data, cell_data)] read back from the
        interrupted run's files) are written again, then the run appends to them."""
        self.history = {k: list(v) for k, v in state["history"].items()}
        self.balance = list(state["balance"])
        self._next_frame = int(state["next_frame"])
        self._last = state["last"]
        self.iterations = dict(state.get("iterations", {}))
        if self.csv is not None:
            for i, err in enumerate(self.balance):
                self.csv.append({**{k: v[i] for k, v in self.history.items()},
                                 "balance_error": err})  # fmt: skip
        for name, series in self.series.items():
            for t, point, cell in frames.get(name, [])[: self._next_frame]:
                series.write(t, point, {k: v[0] for k, v in cell.items()})


class MultiplierHistory:
    """Per-step multipliers of one mediator (an ``on_step`` listener), for the chatter check.

    ``chatter()`` is max over the steps n and rows k of
    |λ_n,k − (λ_{n−1},k + λ_{n+1},k)/2| / max_{n,k} |λ_n,k|: the step-to-step oscillation of the
    multiplier history against its largest value (the Arlequin Taylor bar's criterion ≤ 0.05).

    The rows are kept in float32 (N), in the mediator's own basis. When the integrator solves
    for the multipliers in another basis
    (:class:`~arlequin.solvers.dynamics.row_basis.Multipliers`), a step keeps the scheme's
    stacked multipliers and :attr:`chunk` steps are converted in one solve: the same numbers as
    a conversion at every step, which cost 41 µs of each Arlequin Taylor bar step in a warm loop
    (most of the 8 to 11 s that the 20-cells run spent outside its steps).
    """

    #: Steps converted together (their scheme multipliers in float64 until then).
    chunk = 512

    def __init__(self, name: str) -> None:
        self.name = name
        self._blocks: list[np.ndarray] = []  # (k, n_rows) float32, in order
        self._pending: list[np.ndarray] = []  # stacked scheme multipliers of the last steps
        self._convert = None  # their conversion: Multipliers.to_original

    def __call__(self, integ) -> None:
        lam = integ.multipliers
        if getattr(lam, "converted", None) is not None and lam.converted(self.name):
            self._pending.append(lam.stacked_in_scheme_basis())
            self._convert = lam.to_original
            if len(self._pending) >= self.chunk:
                self._flush()
            return
        lam = lam.get(self.name)
        if lam is not None:
            self._flush()
            self._blocks.append(np.asarray(lam, dtype=np.float32).reshape(1, -1).copy())

    def _flush(self) -> None:
        """Convert the pending steps (one solve) into a float32 block."""
        if self._pending:
            stacked = np.vstack(self._pending)
            self._pending = []
            self._blocks.append(np.asarray(self._convert(self.name, stacked), dtype=np.float32))

    def state(self) -> list[np.ndarray]:
        """The rows recorded so far (a checkpoint)."""
        return list(self.array())

    def restore(self, rows: list[np.ndarray]) -> None:
        """Continue from a :meth:`state`."""
        self._pending = []
        self._blocks = [np.vstack(rows).astype(np.float32)] if len(rows) else []

    def array(self) -> np.ndarray:
        """(n_steps, n_rows) multipliers (N, float32), one row per step (read-only)."""
        self._flush()
        if not self._blocks:
            return np.zeros((0, 0), dtype=np.float32)
        if len(self._blocks) > 1:  # one block from now on
            self._blocks = [np.vstack(self._blocks)]
        self._blocks[0].flags.writeable = False  # handed out as it is
        return self._blocks[0]

    def chatter(self) -> dict[str, float]:
        """``{"global": ..., "per_row": ...}``: the oscillation against the largest multiplier
        of all rows, and the largest over the rows of the oscillation of a row against that
        row's own largest value (rows above 1% of the global largest only)."""
        lam = self.array().astype(float)
        if lam.shape[0] < 3:
            return {"global": 0.0, "per_row": 0.0}
        osc = np.abs(lam[1:-1] - 0.5 * (lam[:-2] + lam[2:])).max(axis=0)
        peak = np.abs(lam).max(axis=0)
        top = float(peak.max())
        if top == 0.0:
            return {"global": 0.0, "per_row": 0.0}
        big = peak > 0.01 * top
        return {"global": float(osc.max() / top), "per_row": float((osc[big] / peak[big]).max())}
