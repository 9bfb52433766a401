"""The one round-trip helper of the readers and writers: write, read back and compare.

Every writer's output is read with the readers a user has (meshio for the XDMF series, the csv
module for the histories, json for results.json) and compared with the in-memory result to
round-off (the files store float64: equality is exact). User meshes go the other way: written
by meshio in a format, read by :func:`arlequin.io.read_mesh`, compared cell by cell.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from arlequin.io import RESULTS_JSON, read_history, read_series
from arlequin.io.fields import pad_vectors


def load_results(folder: Path) -> dict:
    """results.json, checked for the documented keys (inputs with units, versions, command)."""
    meta = json.loads((Path(folder) / RESULTS_JSON).read_text(encoding="utf-8"))
    for key in ("command", "command_line", "versions", "inputs", "results", "status", "files"):
        assert key in meta, key
    assert meta["status"] == "complete"
    for name, q in meta["inputs"].items():
        assert set(q) == {"value", "unit"}, name
    assert "numpy" in meta["versions"] and "python" in meta["versions"]
    for rel in [
        *meta["files"].get("history", {}).values(),
        *meta["files"].get("fields", {}).values(),
    ]:
        assert (Path(folder) / rel).is_file(), rel
    return meta


def assert_series_equal(
    folder: Path, series: str, times: np.ndarray, fields: dict[str, np.ndarray], n_components: int
) -> int:
    """The XDMF series ``series`` holds, at each of its frame times, the rows of ``fields``
    (name -> (n_rec, n_block_dofs), node-interleaved) recorded at that time. Returns the number
    of frames compared."""
    meta = json.loads((Path(folder) / RESULTS_JSON).read_text(encoding="utf-8"))
    _, frames = read_series(Path(folder) / meta["files"]["fields"][series])
    assert frames, series
    for t, point_data, _ in frames:
        k = int(np.nonzero(times == t)[0][0])  # frames are written at record times, exactly
        for name, values in fields.items():
            np.testing.assert_array_equal(point_data[name], pad_vectors(values[k], n_components))
    return len(frames)


def assert_history_equal(folder: Path, columns: dict[str, np.ndarray], name: str = "history"):
    """The CSV history ``name`` has the given columns (name -> values), to round-off."""
    meta = json.loads((Path(folder) / RESULTS_JSON).read_text(encoding="utf-8"))
    hist = read_history(Path(folder) / meta["files"]["history"][name])
    for col, values in columns.items():
        np.testing.assert_array_equal(np.asarray(hist[col]), np.asarray(values, dtype=float))


def _cells_as_points(mesh) -> np.ndarray:
    """Each cell as the sorted coordinates of its nodes: independent of the node numbering."""
    cells = np.round(mesh.p[:, mesh.t].transpose(2, 1, 0), 12)  # (n_cells, n_nodes, dim)
    keyed = np.array([sorted(map(tuple, c)) for c in cells])
    return keyed[np.lexsort(keyed.reshape(len(keyed), -1).T[::-1])]


def assert_mesh_round_trip(mesh, path: Path, **write_options):
    """Write a scikit-fem mesh with meshio to ``path`` (its format from the extension, or
    ``file_format=`` in the options), read it back with :func:`arlequin.io.read_mesh` and check
    the same mesh comes back (type, node and cell counts, every cell's nodes). Returns it."""
    import skfem

    from arlequin.io import read_mesh

    skfem.io.meshio.to_file(mesh, str(path), **write_options)
    back = read_mesh(path)
    assert type(back) is type(mesh)
    assert back.p.shape == mesh.p.shape and back.t.shape == mesh.t.shape
    assert np.array_equal(_cells_as_points(back), _cells_as_points(mesh))
    return back
