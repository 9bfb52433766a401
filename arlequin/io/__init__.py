"""Results on disk: results folders, time histories, field series (XDMF + HDF5 via meshio).

``folder`` (:class:`ResultsFolder`: results.json, files), ``history`` (CSV written row by row),
``fields`` (XDMF series written frame by frame), ``layout`` (system vectors -> mesh fields),
``run`` (writers of dynamic and static runs), ``meshes`` (user meshes read through meshio:
:func:`read_mesh`). The core's integrators never import this package;
demos and the CLI do.
"""

from .checkpoint import CheckpointError, read_checkpoint, write_checkpoint
from .fields import FieldSeries, meshio_mesh, read_series
from .folder import (
    RESULTS_JSON,
    JsonResult,
    ResultsFolder,
    close_running,
    environment,
    jsonable,
)
from .history import HistoryCSV, read_history
from .layout import BlockFields, FieldLayout
from .meshes import UnsupportedMeshError, read_mesh
from .run import DynamicRunWriter, QuasiStaticRunWriter, write_static

__all__ = [
    "RESULTS_JSON",
    "BlockFields",
    "CheckpointError",
    "DynamicRunWriter",
    "FieldLayout",
    "FieldSeries",
    "HistoryCSV",
    "JsonResult",
    "QuasiStaticRunWriter",
    "ResultsFolder",
    "UnsupportedMeshError",
    "close_running",
    "environment",
    "jsonable",
    "meshio_mesh",
    "read_checkpoint",
    "read_history",
    "read_mesh",
    "read_series",
    "write_checkpoint",
    "write_static",
]
