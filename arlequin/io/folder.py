"""A results folder: ``results.json``, ``history.csv`` and field series, written as the run goes.

Layout (every CLI command with ``--out DIR``)::

    DIR/results.json        inputs with units, results (scalars with units), versions of the
                            stack, the command line, status, the list of files, the units of
                            the fields
    DIR/history.csv         time histories (header ``name [unit]``)
    DIR/fields/NAME.xdmf    field time series (XDMF + HDF5, open in ParaView)
    DIR/*.png               pictures

``results.json`` is written when the folder is opened (``"status": "running"``) and rewritten
atomically (write then rename) when results are added and when the run ends.
"""

from __future__ import annotations

import datetime
import importlib.metadata
import json
import math
import os
import platform
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .fields import FieldSeries
from .history import HistoryCSV

__all__ = [
    "RESULTS_JSON",
    "JsonResult",
    "ResultsFolder",
    "close_running",
    "environment",
    "jsonable",
]

RESULTS_JSON = "results.json"

_STACK = ("arlequin", "numpy", "scipy", "scikit-fem", "meshio", "h5py", "trimesh", "pyvista",
          "matplotlib", "tqdm")  # fmt: skip


def environment() -> dict[str, str]:
    """Versions of Python and of the installed stack (distribution metadata, no imports)."""
    out = {"python": platform.python_version(), "platform": platform.platform()}
    for name in _STACK:
        try:
            out[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out


def jsonable(value: Any) -> Any:
    """numpy scalars/arrays and tuples as JSON values; non-finite floats as strings."""
    if isinstance(value, Mapping):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer, int)):
        return int(value)
    if isinstance(value, (np.floating, float)):
        v = float(value)
        return v if math.isfinite(v) else repr(v)
    if isinstance(value, Path):
        return str(value)
    return value


class JsonResult:
    """Mixin of the demos' result dataclasses: one way to turn a result into JSON.

    ``to_json()`` gives the fields named in ``json_keys`` (default: every dataclass field but
    those in ``json_exclude``) as JSON values (:func:`jsonable`); ``dumps()`` the text.
    """

    json_keys: tuple[str, ...] | None = None
    json_exclude: tuple[str, ...] = ()

    def to_json(self) -> dict[str, Any]:
        """The result as JSON values: the fields of ``json_keys`` (default all but
        ``json_exclude``)."""
        keys = self.json_keys
        if keys is None:
            keys = tuple(k for k in self.__dataclass_fields__ if k not in self.json_exclude)
        return {k: jsonable(getattr(self, k)) for k in keys}

    def dumps(self) -> str:
        """The JSON document as indented text."""
        return json.dumps(self.to_json(), indent=2)


def _unit(value: Any, unit: str | None) -> str:
    """A given unit, "" for text and choices, "unspecified" for a number given without one."""
    if unit is not None:
        return unit
    return "" if value is None or isinstance(value, (str, bool)) else "unspecified"


def _quantities(values: Mapping[str, Any], units: Mapping[str, str]) -> dict[str, Any]:
    return {k: {"value": jsonable(v), "unit": _unit(v, units.get(k))} for k, v in values.items()}


class ResultsFolder:
    """A results folder (see the module docstring).

    Parameters
    ----------
    path : str or Path
        The folder (created with its parents).
    command : str
        What produced it (``"arlequin wave"``, a function name...).
    inputs : mapping
        Input name -> value.
    units : mapping, optional
        Input name -> SI unit (``"m"``, ``"Pa"``, ``"1"`` for dimensionless numbers and counts);
        text and choices get ``""``, a number given without a unit ``"unspecified"``.
    argv : sequence of str, optional
        The command line (default ``sys.argv``).

    Raises
    ------
    ValueError
        If the folder cannot be created or written (before any computation).
    """

    def __init__(
        self,
        path: str | os.PathLike,
        command: str,
        inputs: Mapping[str, Any],
        units: Mapping[str, str] | None = None,
        argv: Sequence[str] | None = None,
    ) -> None:
        self.path = Path(path)
        try:
            self.path.mkdir(parents=True, exist_ok=True)
            probe = self.path / ".write-test"
            probe.write_text("", encoding="utf-8")
            probe.unlink()
        except OSError as exc:
            raise ValueError(f"cannot write the results folder {str(self.path)!r}: {exc}") from exc
        self.meta: dict[str, Any] = {
            "command": command,
            "command_line": list(sys.argv if argv is None else argv),
            "started": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "status": "running",
            "versions": environment(),
            "inputs": _quantities(inputs, units or {}),
            "results": {},
            "files": {},
        }
        self._open: list[Any] = []
        self._write_json()

    # ------------------------------------------------------------------ files
    def _register(self, kind: str, name: str, rel: str) -> None:
        self.meta["files"].setdefault(kind, {})[name] = rel

    def history(
        self, columns: Sequence[str], units: Mapping[str, str] | None = None, name: str = "history"
    ) -> HistoryCSV:
        """A CSV history file ``NAME.csv`` in the folder."""
        rel = f"{name}.csv"
        writer = HistoryCSV(self.path / rel, columns, units)
        self._register("history", name, rel)
        self._open.append(writer)
        self._write_json()
        return writer

    def series(self, name: str, mesh: Any) -> FieldSeries:
        """A field series ``fields/NAME.xdmf`` on a mesh."""
        (self.path / "fields").mkdir(exist_ok=True)
        rel = f"fields/{name}.xdmf"
        series = FieldSeries(self.path / rel, mesh)
        self._register("fields", name, rel)
        self._open.append(series)
        self._write_json()
        return series

    def remove_series(self, series: FieldSeries) -> None:
        """Close a series of this folder and delete its files (``.xdmf``, ``.h5``) and its
        entry in results.json: a series left without any frame (by an adaptive run's
        rejected interval, :meth:`DynamicRunWriter.on_rewind
        <arlequin.io.DynamicRunWriter.on_rewind>`), which would list a field with no data."""
        series.close()
        for path in (series.path, series.path.with_suffix(".h5")):
            path.unlink(missing_ok=True)
        fields = self.meta["files"].get("fields", {})
        rel = series.path.relative_to(self.path).as_posix()
        for name in [k for k, v in fields.items() if v == rel]:
            del fields[name]
        self._open = [f for f in self._open if f is not series]
        self._write_json()

    def picture(self, name: str) -> Path:
        """Path of a picture ``NAME.png`` in the folder (registered in results.json)."""
        rel = f"{name}.png"
        self._register("pictures", name, rel)
        return self.path / rel

    # ------------------------------------------------------------------ results
    def add_results(
        self, values: Mapping[str, Any], units: Mapping[str, str] | None = None
    ) -> None:
        """Add scalar (or small array) results with their units, and rewrite results.json."""
        self.meta["results"].update(_quantities(values, units or {}))
        self._write_json()

    def finish(self, status: str = "complete", message: str = "") -> None:
        """Close the open files and write the final results.json."""
        for f in self._open:
            f.close()
        self._open = []
        self.meta["status"] = status
        if message:
            self.meta["message"] = message
        self.meta["finished"] = datetime.datetime.now(datetime.timezone.utc).isoformat(
            timespec="seconds"
        )
        self._write_json()

    def _write_json(self) -> None:
        tmp = self.path / (RESULTS_JSON + ".tmp")
        tmp.write_text(json.dumps(jsonable(self.meta), indent=2) + "\n", encoding="utf-8")
        os.replace(tmp, self.path / RESULTS_JSON)

    def __enter__(self) -> ResultsFolder:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if self.meta["status"] == "running":
            self.finish("failed" if exc is not None else "complete", str(exc or ""))


def close_running(path: str | os.PathLike | None, status: str, message: str) -> bool:
    """End the ``results.json`` of ``path`` left ``"running"`` by a run that raised.

    A demo marks its own folder when it catches the failure it expects (a Newton failure, the
    patch's cap); any other exception (a picture that cannot be drawn, a bug) would otherwise
    leave ``"status": "running"`` and no message. The CLI calls this after every failed run, so
    the folder of each demo says how the run ended; a folder already ended is left as it is.

    Parameters
    ----------
    path : str or Path or None
        The results folder (``None``, or a folder without ``results.json``: nothing done).
    status : str
        The final status (``"failed"``, ``"interrupted"``).
    message : str
        Why (the exception's text).

    Returns
    -------
    bool
        Whether ``results.json`` was rewritten.
    """
    if path is None:
        return False
    file = Path(path) / RESULTS_JSON
    try:
        meta = json.loads(file.read_text(encoding="utf-8"))
    except (OSError, ValueError):  # no folder yet (bad input), or not ours: nothing to end
        return False
    if meta.get("status") != "running":
        return False
    meta["status"] = status
    meta["message"] = message
    meta["finished"] = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    tmp = file.with_name(RESULTS_JSON + ".tmp")
    tmp.write_text(json.dumps(jsonable(meta), indent=2) + "\n", encoding="utf-8")
    os.replace(tmp, file)
    return True
