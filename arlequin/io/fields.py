"""Field time series on one mesh, written as XDMF + HDF5 through meshio as the run goes.

ParaView opens the ``.xdmf`` file (the reference mesh and, per time, point and cell data; warp
by the ``displacement`` vector to see the deformed shape). The XML is rewritten after every
frame and the HDF5 file flushed, so an interrupted run keeps every frame already written.
Vectors are padded to 3 components (ParaView's convention); 1D meshes get y = z = 0.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import meshio
import numpy as np
from meshio._common import write_xml  # the XML writer meshio itself uses
from meshio.xdmf.time_series import TimeSeriesWriter
from skfem.io.meshio import to_meshio

__all__ = ["FieldSeries", "meshio_mesh", "pad_vectors", "read_series"]


def meshio_mesh(mesh: Any) -> meshio.Mesh:
    """The meshio mesh of a scikit-fem mesh (its node order; points padded to ≥ 2 columns); a
    meshio mesh as it is (one read back, :func:`read_series`)."""
    if isinstance(mesh, meshio.Mesh):
        return mesh
    out = to_meshio(mesh)
    if out.points.shape[1] == 1:
        out.points = np.hstack([out.points, np.zeros((out.points.shape[0], 2))])
    return out


def pad_vectors(values: np.ndarray, n_components: int) -> np.ndarray:
    """Node-interleaved vector dofs (n_components n,) -> array (n, 3) (zeros appended)."""
    values = np.asarray(values, dtype=float).reshape(-1, n_components)
    if n_components == 3:
        return values
    return np.hstack([values, np.zeros((values.shape[0], 3 - n_components))])


class _Writer(TimeSeriesWriter):
    """meshio's writer with the HDF5 file beside the XDMF file (meshio puts it in the current
    directory) and the XML flushed after every frame."""

    def __enter__(self):
        import h5py

        self.h5_filename = str(self.filename.with_suffix(".h5"))
        self.h5_file = h5py.File(self.h5_filename, "w")
        return self

    def flush(self) -> None:
        self.h5_file.flush()
        write_xml(self.filename, self.xdmf_file)


class FieldSeries:
    """A time series of fields on one mesh.

    Parameters
    ----------
    path : str or Path
        The ``.xdmf`` file to write (the ``.h5`` file goes beside it).
    mesh : skfem.Mesh or meshio.Mesh
        The (reference) mesh.

    Examples
    --------
    >>> series = FieldSeries(folder / "coarse.xdmf", mesh)          # doctest: +SKIP
    >>> series.write(0.0, {"displacement": u3}, {"alpha": alpha})   # doctest: +SKIP
    >>> series.close()                                              # doctest: +SKIP
    """

    def __init__(self, path: str | os.PathLike, mesh: Any) -> None:
        self.path = Path(path)
        self.mesh = meshio_mesh(mesh)
        self._writer = _Writer(self.path).__enter__()
        self._writer.write_points_cells(self.mesh.points, self.mesh.cells)
        self.times: list[float] = []
        self._writer.flush()

    def write(
        self,
        t: float,
        point_data: dict[str, np.ndarray] | None = None,
        cell_data: dict[str, np.ndarray] | None = None,
    ) -> None:
        """Append a frame at time t (s): point data (n_points, ...) and cell data (n_cells, ...)
        (one cell block)."""
        cells = {k: [np.asarray(v)] for k, v in (cell_data or {}).items()}
        self._writer.write_data(float(t), point_data=point_data or {}, cell_data=cells)
        self._writer.flush()
        self.times.append(float(t))

    def drop_after(self, t: float) -> int:
        """Remove the frames after time ``t`` (s) from the XDMF file and their data from the
        HDF5 file (an adaptive run's rejected interval); the number of frames removed."""
        writer = self._writer
        keep = sum(1 for s in self.times if s <= t)
        if writer is None or keep == len(self.times):
            return 0
        frames = [g for g in writer.collection.findall("Grid") if g.find("Time") is not None]
        for grid in frames[keep:]:
            for item in grid.iter("DataItem"):
                name = (item.text or "").rpartition(":/")[2]
                if name in writer.h5_file:
                    del writer.h5_file[name]
            writer.collection.remove(grid)
        dropped = len(self.times) - keep
        del self.times[keep:]
        writer.flush()
        return dropped

    def close(self) -> None:
        """Close the HDF5 file (the XML is already complete)."""
        if self._writer is not None:
            self._writer.flush()
            self._writer.h5_file.close()
            self._writer = None


def read_series(path: str | os.PathLike) -> tuple[meshio.Mesh, list[tuple[float, dict, dict]]]:
    """Read a series back with meshio: the mesh and [(t, point_data, cell_data), ...]."""
    path = Path(path)
    cwd = os.getcwd()
    os.chdir(path.parent)  # meshio resolves the HDF5 file relative to the current directory
    try:
        with meshio.xdmf.TimeSeriesReader(path.name) as reader:
            points, cells = reader.read_points_cells()
            frames = []
            for k in range(reader.num_steps):
                t, point_data, cell_data = reader.read_data(k)
                frames.append((float(t), point_data, cell_data))
    finally:
        os.chdir(cwd)
    return meshio.Mesh(points, cells), frames
