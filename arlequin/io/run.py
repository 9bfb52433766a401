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
from .history import read_rows
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
                current = self.series.get(bf.name)
                if current is not None and not current.times:
                    # the outgoing mesh's series has no frame (a growth before the run's first
                    # frame): removed, no field listed without data
                    self._folder.remove_series(current)
                    del self.series[bf.name]
                    self._grown.discard(bf.name)
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


#: The columns of a quasi-static run's ``history.csv`` (one row a converged step; the demo's
#: measures go between ``load_factor`` and ``load_step``) and their units.
STEP_COLUMNS = {"step": "1", "load_factor": "1"}
STEP_NEWTON_COLUMNS = {"load_step": "1", "newton_iterations": "1", "cuts": "1",
                       "first_residual": "1", "last_residual": "1", "crossings": "1"}  # fmt: skip
#: The columns of ``newton.csv`` (one row a Newton iteration of a converged step).
NEWTON_COLUMNS = {"step": "1", "load_factor": "1", "iteration": "1", "start_residual": "1",
                  "residual": "1", "equilibrium_residual": "1", "constraint_residual": "1",
                  "line_search": "1", "crossings": "1", "plastic_points": "1"}  # fmt: skip


class QuasiStaticRunWriter:
    """Writes a quasi-static run into a results folder as it goes: a listener of
    :func:`arlequin.solvers.solve_quasi_static` (``on_step``), called after every converged
    load step.

    Each step appends a row to ``history.csv``: ``step`` (the solver's converged steps so
    far), ``load_factor``, the demo's ``measures``, ``load_step`` (its Δλ), the Newton
    iterations, step cuts, first and last relative residuals, and ``crossings``: the
    quadrature points that crossed the yield surface in each Newton iteration, one count an
    iteration separated by spaces
    (:class:`~arlequin.solvers.statics.quasi_static_result.NewtonIteration`).
    Each of its Newton iterations appends a row to ``newton.csv``: ``step``, ``load_factor``,
    ``iteration`` (from 1), ``start_residual`` and ``residual`` (the relative residual before
    and after it, as the solver compares it with its tolerance), its ``equilibrium_residual``
    and ``constraint_residual`` parts, ``line_search`` (the update's length), ``crossings``
    and ``plastic_points``. Then a frame goes to every block's field series (displacement, the
    mediators' multipliers, the blocks' cell data such as ``alpha``, and the cell data
    ``cell_data(solver)`` returns, e.g. ε̄p and the von Mises stress), at the "time" λ. Rows
    and frames are flushed as they are written: an interrupted run keeps every converged step.

    Parameters
    ----------
    folder : ResultsFolder
    system : CoupledSystem
    layout : FieldLayout
    cell_data : callable, optional
        ``cell_data(solver) -> {block name: {field name: (n_cells,) array}}``.
    units : mapping, optional
        Units of those fields (recorded in results.json).
    replay : dict, optional
        What an interrupted run had written (:meth:`written`), written again first; with
        ``replay["growths"] = K`` (an adaptive run's growths at its checkpoint) the series
        its growths opened too, ``NAME_1`` to ``NAME_K`` on their own meshes, the next frames
        going to the last (``layout`` is then the grown problem's).
    measures : callable, optional
        ``measures(solver) -> {name: value}``: the demo's own columns of ``history.csv``.
    measure_units : mapping, optional
        Their names, in order, and units.
    """

    def __init__(self, folder: ResultsFolder, system: Any, layout: FieldLayout,
                 cell_data: Any = None, units: dict[str, str] | None = None,
                 replay: dict[str, Any] | None = None, measures: Any = None,
                 measure_units: dict[str, str] | None = None) -> None:  # fmt: skip
        self.system, self.layout, self.cell_data = system, layout, cell_data
        self.measures = measures
        self._folder = folder
        step_units = {**STEP_COLUMNS, **(measure_units or {}), **STEP_NEWTON_COLUMNS}
        self.history = folder.history(list(step_units), step_units)
        self.newton = folder.history(list(NEWTON_COLUMNS), NEWTON_COLUMNS, name="newton")
        self._growths = 0 if replay is None else int(replay.get("growths", 0))
        # a resumed adaptive run: the first series on the meshes they were written on
        first = replay["meshes"] if self._growths else {}
        self.series = {bf.name: folder.series(bf.name, first.get(bf.name, bf.mesh))
                       for bf in layout.blocks}  # fmt: skip
        self._meshes = {bf.name: bf.mesh for bf in layout.blocks}
        folder.meta.setdefault("field_units", {}).update({**layout.units, **(units or {})})
        if replay is not None:
            self._replay(replay)

    def _replay(self, replay: dict[str, Any]) -> None:
        """A resumed run: what the interrupted one had written, first (its rows as their
        text, so that the files equal those of an uninterrupted run; a file of another
        layout is not written again), and its frames: in the series of its growths up to
        the checkpoint's, opened again in their order (those of later growths, made again,
        are not)."""
        for writer, name in ((self.history, "history"), (self.newton, "newton")):
            header, rows = replay["rows"].get(name, (None, []))
            if header == writer.header:
                for row in rows:
                    writer.append_text(row)
        series = dict(self.series)  # by file name
        for k in range(1, self._growths + 1):
            for bf in self.layout.blocks:
                name = f"{bf.name}_{k}"
                if name in replay["meshes"]:
                    series[name] = self._folder.series(name, replay["meshes"][name])
                    self.series[bf.name] = series[name]
        for name, frames in replay["frames"].items():
            if name not in series:  # a later growth's (made again) or another run's
                continue
            for t, point, cell in frames:  # meshio gives cell data per cell block
                cell = {k: v[0] if isinstance(v, list) else v for k, v in cell.items()}
                series[name].write(t, point, cell)

    @staticmethod
    def written(out: str | os.PathLike, steps: int | None = None,
                load_factor: float | None = None) -> dict[str, Any]:  # fmt: skip
        """What a writer had written in the folder ``out``: its rows and every series'
        frames (read before a resumed run's writer opens the files again), those of the first
        ``steps`` converged steps only (the rows) and of the load factors up to
        ``load_factor`` (the frames): the ones of its checkpoint, whatever was written after
        it before the run stopped), and each series' mesh (``meshes``, meshio's)."""
        out = Path(out)
        rows: dict[str, tuple[list[str], list[list[str]]]] = {}
        for name in ("history", "newton"):
            path = out / f"{name}.csv"
            if path.is_file():
                header, lines = read_rows(path)
                if steps is not None and header and header[0] == "step [1]":
                    lines = [r for r in lines if r and int(float(r[0])) <= steps]
                rows[name] = (header, lines)
        read = {p.stem: read_series(p) for p in sorted((out / "fields").glob("*.xdmf"))}
        frames = {k: v[1] for k, v in read.items()}
        if load_factor is not None:
            limit = load_factor + 1e-12 * max(abs(load_factor), 1.0)
            frames = {k: [f for f in v if f[0] <= limit] for k, v in frames.items()}
        return {"rows": rows, "frames": frames, "meshes": {k: v[0] for k, v in read.items()}}

    def on_adapt(self, solver: Any, adapt: Any) -> None:
        """A patch grew (``solve_quasi_static(..., adapt=)``): the next frames go on the new
        system, the blocks whose mesh changed into a new series ``fields/NAME_K.xdmf`` (K the
        growths so far: a meshio XDMF time series holds one mesh)."""
        self.system, self.layout = solver.system, adapt.problem.field_layout()
        self._growths += 1
        for bf in self.layout.blocks:
            if bf.mesh is not self._meshes[bf.name]:
                self.series[bf.name] = self._folder.series(f"{bf.name}_{self._growths}", bf.mesh)
                self._meshes[bf.name] = bf.mesh

    def rows(self, solver: Any) -> None:
        """The rows of the step just converged (``history.csv``, ``newton.csv``), without a
        frame (a demo's step whose fields it does not keep)."""
        rec, step = solver.history[-1], len(solver.history)
        row = {"step": step, "load_factor": rec.load_factor}
        if self.measures is not None:
            row.update(self.measures(solver))
        newton = getattr(rec, "newton", ())
        row.update({"load_step": rec.step, "newton_iterations": rec.iterations,
                    "cuts": rec.cuts, "first_residual": rec.residuals[0],
                    "last_residual": rec.residuals[-1],
                    "crossings": " ".join(str(it.crossings) for it in newton)})  # fmt: skip
        self.history.append(row)
        for it, start in zip(newton, rec.residuals):
            self.newton.append({
                "step": step, "load_factor": rec.load_factor, "iteration": it.iteration,
                "start_residual": start, "residual": it.residual,
                "equilibrium_residual": it.equilibrium_residual,
                "constraint_residual": it.constraint_residual, "line_search": it.line_search,
                "crossings": it.crossings, "plastic_points": it.plastic_points,
            })  # fmt: skip

    def __call__(self, solver: Any) -> None:
        self.rows(solver)
        rec = solver.history[-1]
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
