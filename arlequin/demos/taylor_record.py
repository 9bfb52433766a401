"""What a Taylor bar run records as it goes: the history, the energy balance, field frames.

:class:`TaylorRecorder` listens to the integrator (``on_record``) and, at every record, appends
a row of the history (length, footprint radius, energies, the wall's force and work, the step)
to memory and to ``history.csv``, checks the energy balance and writes the field frames
(fields/bar.xdmf) at the frame times; :func:`write_results` writes the scalar results and the
pictures at the end. SI units.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..io import ResultsFolder

__all__ = ["HISTORY_UNITS", "TaylorRecorder", "write_results"]

#: History columns and their units.
HISTORY_UNITS = {
    "t": "s",
    "length": "m",
    "radius": "m",
    "kinetic": "J",
    "elastic": "J",
    "plastic_dissipation": "J",
    "viscous_dissipation": "J",
    "contact_work": "J",
    "contact_force": "N",
    "dt": "s",
}


class TaylorRecorder:
    """Listener of the run: the history (and its CSV), the balance, field frames, progress."""

    def __init__(self, model, con_name, weights, axis_top, face, ke0, folder, frame_times,
                 progress) -> None:  # fmt: skip
        self.model, self.con_name, self.weights = model, con_name, weights
        self.axis_top, self.face = axis_top, face
        self.ke0 = ke0
        self.history: dict[str, list[float]] = {k: [] for k in HISTORY_UNITS}
        self.balance: list[float] = []
        self.csv = folder.history([*HISTORY_UNITS, "balance_error"],
                                  {**HISTORY_UNITS, "balance_error": "1"}) if folder else None
        self.series = folder.series("bar", model.mesh) if folder else None
        self.frame_times = np.asarray(frame_times) if folder else np.zeros(0)
        self._next_frame = 0
        self.progress = progress
        self.loop_start: float | None = None  # perf_counter at the initial record
        self._last: tuple[float, float] | None = None  # (t, accumulated wall impulse N·s)
        dofs = model.nodal_dofs()
        self._r, self._z = dofs[0], dofs[1]

    def __call__(self, integ) -> None:
        if self.loop_start is None:
            self.loop_start = time.perf_counter()
        model, u = self.model, integ.u
        state = integ.states["bar"][0]
        x = model.current_coordinates(u)
        kinetic = float(sum(integ.energies()["kinetic"].values()))
        elastic = model.stored_energy(u, state)
        dp = model.plastic_dissipation(state)
        dv = model.viscous_dissipation(state)
        cstate = integ.constraint_states[self.con_name]
        wc = -float(cstate.work)
        # λ is the nominal pressure (Pa) at the collocation points (≤ 0 in compression): the
        # mean force since the last record from the accumulated impulse (exact, and smooth
        # where the single-step multipliers of an explicit wall chatter)
        impulse = float(-(cstate.impulse * self.weights).sum())
        if self._last is None:
            lam = integ.multipliers.get(self.con_name)
            force = 0.0 if lam is None or not lam.size else float(-(lam * self.weights).sum())
        else:
            force = (impulse - self._last[1]) / (integ.t - self._last[0])
        self._last = (float(integ.t), impulse)
        row = {
            "t": float(integ.t),
            "length": float(x[1, self.axis_top]),
            "radius": float(x[0, self.face].max()),
            "kinetic": kinetic,
            "elastic": elastic,
            "plastic_dissipation": dp,
            "viscous_dissipation": dv,
            "contact_work": wc,
            "contact_force": force,
            "dt": float(integ.step_size or 0.0),
        }
        err = abs(kinetic + elastic + dp + dv + wc - self.ke0) / self.ke0
        self.balance.append(err)
        for k, v in row.items():
            self.history[k].append(v)
        if self.csv is not None:
            self.csv.append({**row, "balance_error": err})
        while self._next_frame < self.frame_times.size and (
            integ.t >= self.frame_times[self._next_frame] - 1e-12
        ):
            self._next_frame += 1
            self.write_frame(integ.t, u, integ.v, state)
        if self.progress is not None:
            self.progress(float(integ.t))

    def write_frame(self, t, u, v, state) -> None:
        n = self.model.mesh.nvertices
        pad = np.zeros(n)
        point = {
            "displacement": np.column_stack([u[self._r], u[self._z], pad]),
            "velocity": np.column_stack([v[self._r], v[self._z], pad]),
        }
        cell = {
            "plastic_strain": state.eqps.mean(axis=1),
            "von_mises": state.von_mises.mean(axis=1),
        }
        self.series.write(float(t), point, cell)


def write_results(folder: ResultsFolder, result: Any, units: dict[str, str]) -> None:
    """The scalar results (with ``units``), the pictures and the final results.json."""
    from .plots import plot_taylor_bar
    from .render import render_taylor_bar

    values = {k: v for k, v in result.to_json().items()
              if k not in ("history", "config", "reference")}  # fmt: skip
    hist = result.history
    values["final_energies"] = {k: hist[k][-1] for k in ("kinetic", "elastic",
                                "plastic_dissipation", "viscous_dissipation", "contact_work")}
    folder.add_results(values, units)
    plot_taylor_bar(result, str(folder.picture("taylor_bar_history")))
    title = (f"t = {result.history['t'][-1] * 1e6:.1f} us: length {result.final_length * 1e3:.2f} "
             f"mm, footprint radius {result.mushroom_radius * 1e3:.2f} mm "
             f"(grey: initial shape)")  # fmt: skip
    render_taylor_bar(result.model, result.u, result.state, str(folder.picture("taylor_bar")),
                      title)  # fmt: skip
    folder.finish()
