"""Writers of runs into a results folder: dynamic and quasi-static runs as they go, static
solutions at once.

:class:`DynamicRunWriter` is a listener for :func:`arlequin.solvers.solve` (``on_record``):
at every record it appends a history row (time, step, energies and works per block, the energy
balance) and, at the frame times, a frame of every block's field series.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .fields import read_series
from .folder import ResultsFolder
from .history import read_history
from .layout import FieldLayout

__all__ = ["DynamicRunWriter", "QuasiStaticRunWriter", "write_static"]

_ENERGIES = ("kinetic", "strain", "external_work", "coupling_work", "constraint_work",
             "kinetic_full_step", "damping_work")  # fmt: skip
_WORKS = ("external_work", "coupling_work", "constraint_work", "damping_work")


class DynamicRunWriter:
    """Writes a dynamic run into a results folder as it goes.

    Parameters
    ----------
    folder : ResultsFolder
    system : CoupledSystem
    layout : FieldLayout, optional
        Default: :meth:`FieldLayout.of_system`.
    frame_times : sequence of float, optional
        Times (s) of the field frames: a frame is written at the first record at or after each
        (default: every record). To have the frames exactly at these times, give them to
        :func:`~arlequin.solvers.solve` as ``t_eval`` too (the records are then only there).
    prefix : str
        Prefix of the file names (several runs in one folder).
    cell_data : callable, optional
        ``cell_data(integrator) -> {block name: {field name: (n_cells,) array}}``: more cell
        fields of a frame (the models' own, e.g. ε̄p and the von Mises stress of a J2 patch).
    units : mapping, optional
        Units of those fields (recorded in results.json).
    """

    def __init__(
        self,
        folder: ResultsFolder,
        system: Any,
        layout: FieldLayout | None = None,
        frame_times: Sequence[float] | None = None,
        prefix: str = "",
        cell_data: Any = None,
        units: dict[str, str] | None = None,
    ) -> None:
        self.system = system
        self.cell_data = cell_data
        self.layout = FieldLayout.of_system(system) if layout is None else layout
        names = [b.name for b in system.blocks]
        self.columns = ["t", "dt", "step", "energy", "balance"] + [
            f"{k}:{n}" for k in _ENERGIES for n in names
        ]
        columns_units = {c: "J" for c in self.columns}
        columns_units.update({"t": "s", "dt": "s", "step": "1"})
        self.history = folder.history(self.columns, columns_units, name=f"{prefix}history")
        self.series = {
            bf.name: folder.series(f"{prefix}{bf.name}", bf.mesh) for bf in self.layout.blocks
        }
        folder.meta.setdefault("field_units", {}).update({**self.layout.units, **(units or {})})
        self.frame_times = None if frame_times is None else np.sort(np.asarray(frame_times))
        self._folder, self._prefix = folder, prefix
        self._meshes = {bf.name: bf.mesh for bf in self.layout.blocks}
        self._pending_series: dict[str, tuple[str, Any]] = {}
        self._grown: set[str] = set()  # the blocks whose series a growth opened
        self._next = 0
        self._e0: float | None = None
        self.frames_written: list[float] = []
        # per history row: its time and how many frame times were consumed up to it (what an
        # adaptive run's rejected interval rewinds to)
        self._row_times: list[float] = []
        self._row_next: list[int] = []

    def __call__(self, integ: Any) -> None:
        e = integ.energies()
        row = {"t": integ.t, "dt": integ.step_size or 0.0, "step": integ.step_count}
        total = sum(e["kinetic"].values()) + sum(e["strain"].values())
        works = sum(sum(e[k].values()) for k in _WORKS)
        if self._e0 is None:
            self._e0 = total
        row["energy"] = total
        row["balance"] = total - self._e0 - works
        for k in _ENERGIES:
            for name, val in e[k].items():
                row[f"{k}:{name}"] = val
        self.history.append(row)
        if self._due(integ.t, integ.step_size):
            extra = self.cell_data(integ) if self.cell_data is not None else None
            self.write_frame(integ.t, integ.u, integ.v, integ.multipliers, extra)
        self._row_times.append(float(integ.t))
        self._row_next.append(self._next)

    def on_rewind(self, integ: Any) -> None:
        """An interval of an adaptive run was rejected (``solve(..., adapt=)``), the integrator
        is back at its committed state: the history rows and field frames after its time are
        removed from the files, the frame times they consumed are due again."""
        t = float(integ.t)
        keep = int(np.searchsorted(self._row_times, t, side="right"))
        self.history.truncate(keep)
        del self._row_times[keep:]
        del self._row_next[keep:]
        self._next = self._row_next[-1] if keep else 0
        if not keep:
            self._e0 = None
        for name, series in list(self.series.items()):
            series.drop_after(t)
            if not series.times and name in self._grown:
                # a growth's series with all its frames in the rejected interval: removed (no
                # field listed without data), opened again at the next frame unless the growth
                # that follows the rejection names a newer one first
                self._folder.remove_series(series)
                del self.series[name]
                self._grown.discard(name)
                self._pending_series.setdefault(name, (series.path.stem, self._meshes[name]))
        self.frames_written = [s for s in self.frames_written if s <= t]

    def on_adapt(self, integ: Any, adapt: Any) -> None:
        """A patch grew (``solve(..., adapt=)``): the next rows and frames on the new system,
        the blocks whose mesh changed into a new series ``fields/NAME_K.xdmf`` (K the growths
        so far), the balance moved by the growth's energy change."""
        self.system, self.layout = integ.system, adapt.problem.field_layout()
        self._growths = getattr(self, "_growths", 0) + 1
        for bf in self.layout.blocks:
            if bf.mesh is not self._meshes.get(bf.name):
                # opened at the next frame: growths between two frames leave no empty series
                self._pending_series[bf.name] = (f"{self._prefix}{bf.name}_{self._growths}",
                                                 bf.mesh)  # fmt: skip
                self._meshes[bf.name] = bf.mesh
        change = getattr(adapt.records[-1], "energy_change", None) if adapt.records else None
        if self._e0 is not None and change is not None:
            self._e0 += change

    def _due(self, t: float, dt: float | None) -> bool:
        if self.frame_times is None:
            return True
        tol = 1e-12 * (dt or 1.0)
        due = False
        while self._next < self.frame_times.size and t >= self.frame_times[self._next] - tol:
            self._next += 1
            due = True
        return due

    def write_frame(self, t, u, v=None, multipliers=None, cell_data=None) -> None:
        """One frame of every block at time t (s); ``cell_data``: {block name: {field name:
        (n_cells,) array}} added to the blocks' cell fields."""
        for name, (file, mesh) in self._pending_series.items():
            self.series[name] = self._folder.series(file, mesh)
            self._grown.add(name)
        self._pending_series = {}
        for name, (point, cell) in self.layout.frame(self.system.dofmap, u, v, multipliers).items():
            self.series[name].write(t, point, {**cell, **(cell_data or {}).get(name, {})})
        self.frames_written.append(float(t))


class QuasiStaticRunWriter:
    """Writes a quasi-static run into a results folder as it goes: a listener of
    :func:`arlequin.solvers.solve_quasi_static` (``on_step``), called after every converged
    load step.

    Each step appends a row to ``newton.csv`` (the load factor, its step, Newton iterations,
    the first and last relative residuals, step cuts) and a frame to every block's field series
    (displacement, the mediators' multipliers, the blocks' cell data such as ``alpha``, and the
    cell data ``cell_data(solver)`` returns, e.g. ε̄p and the von Mises stress), at the "time"
    λ. Frames and rows are flushed as they are written: an interrupted run keeps every
    converged step.

    Parameters
    ----------
    folder : ResultsFolder
    system : CoupledSystem
    layout : FieldLayout
    cell_data : callable, optional
        ``cell_data(solver) -> {block name: {field name: (n_cells,) array}}``.
    units : mapping, optional
        Units of those fields (recorded in results.json).
    """

    columns = ("load_factor", "step", "newton_iterations", "first_residual", "last_residual",
               "cuts")  # fmt: skip

    def __init__(self, folder: ResultsFolder, system: Any, layout: FieldLayout,
                 cell_data: Any = None, units: dict[str, str] | None = None,
                 replay: dict[str, Any] | None = None) -> None:  # fmt: skip
        self.system, self.layout, self.cell_data = system, layout, cell_data
        self._folder = folder
        self.history = folder.history(
            self.columns,
            {
                "load_factor": "1",
                "step": "1",
                "newton_iterations": "1",
                "first_residual": "1",
                "last_residual": "1",
                "cuts": "1",
            },
            name="newton",
        )
        self.series = {bf.name: folder.series(bf.name, bf.mesh) for bf in layout.blocks}
        self._meshes = {bf.name: bf.mesh for bf in layout.blocks}
        folder.meta.setdefault("field_units", {}).update({**layout.units, **(units or {})})
        if replay is not None:  # a resumed run: what the interrupted one had written, first
            for row in replay["rows"]:
                self.history.append(row)
            for name, frames in replay["frames"].items():
                for t, point, cell in frames:  # meshio gives cell data per cell block
                    cell = {k: v[0] if isinstance(v, list) else v for k, v in cell.items()}
                    self.series[name].write(t, point, cell)

    @staticmethod
    def written(out: str | os.PathLike) -> dict[str, Any]:
        """What a writer had written in the folder ``out``: its rows and every series'
        frames (read before a resumed run's writer opens the files again)."""
        out = Path(out)
        rows: list[dict[str, float]] = []
        path = out / "newton.csv"
        if path.is_file():
            cols = read_history(path)
            rows = [dict(zip(cols, vals)) for vals in zip(*cols.values())]
        frames = {
            p.stem: read_series(p)[1] for p in sorted((out / "fields").glob("*.xdmf"))
        }  # fmt: skip
        return {"rows": rows, "frames": frames}

    def on_adapt(self, solver: Any, adapt: Any) -> None:
        """A patch grew (``solve_quasi_static(..., adapt=)``): the next frames go on the new
        system, the blocks whose mesh changed into a new series ``fields/NAME_K.xdmf`` (K the
        growths so far: a meshio XDMF time series holds one mesh)."""
        self.system, self.layout = solver.system, adapt.problem.field_layout()
        self._growths = getattr(self, "_growths", 0) + 1
        for bf in self.layout.blocks:
            if bf.mesh is not self._meshes[bf.name]:
                self.series[bf.name] = self._folder.series(f"{bf.name}_{self._growths}", bf.mesh)
                self._meshes[bf.name] = bf.mesh

    def __call__(self, solver: Any) -> None:
        rec = solver.history[-1]
        self.history.append(
            {
                "load_factor": rec.load_factor,
                "step": rec.step,
                "newton_iterations": rec.iterations,
                "first_residual": rec.residuals[0],
                "last_residual": rec.residuals[-1],
                "cuts": rec.cuts,
            }
        )
        extra = self.cell_data(solver) if self.cell_data is not None else {}
        multipliers = solver.saddle.split_multipliers(solver.mu)
        frames = self.layout.frame(self.system.dofmap, solver.u, None, multipliers)
        for name, (point, cell) in frames.items():
            self.series[name].write(rec.load_factor, point, {**cell, **extra.get(name, {})})


def write_static(folder: ResultsFolder, system: Any, result: Any, layout: FieldLayout) -> None:
    """Write a static solution: a one-row history (strain energies, residual) and one frame."""
    names = [b.name for b in system.blocks]
    cols = ["t", "residual"] + [f"strain:{n}" for n in names]
    units = {c: "J" for c in cols}
    units.update({"t": "s", "residual": "1"})
    hist = folder.history(cols, units)
    row: dict[str, float] = {"t": 0.0, "residual": result.residual}
    row.update({f"strain:{n}": result.strain_energy[n] for n in names})
    hist.append(row)
    folder.meta.setdefault("field_units", {}).update(layout.units)
    for bf in layout.blocks:
        series = folder.series(bf.name, bf.mesh)
        point, cell = layout.frame(system.dofmap, result.u, None, result.multipliers)[bf.name]
        series.write(0.0, point, cell)
