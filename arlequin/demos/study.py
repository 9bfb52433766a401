"""Parameter studies on Dask: many runs of a demo, one task per case (``arlequin study SPEC``).

A study file (TOML) names a demo and its parameters::

    demo = "two-bars"            # a CLI demo name, or "package.module:function"
    [parameters]                 # option names as in the CLI, without dashes, '-' written '_'
    velocity = [1.0, 2.0, 3.0]   # a list is a grid axis
    elements = [50, 100]
    cfl = 1.0                    # a scalar is fixed for every case

    [[cases]]                    # optional: explicit cases instead of (or after) the grid
    velocity = 4.0

The cases are the Cartesian product of the lists (in the file's order, the last key varying
fastest), or the explicit ``[[cases]]`` tables, each completed by the scalars. Every case is
checked before any runs: the demo exists, each parameter is an option of its command, each value
parses as the command line would parse it (type and choices) and, for the demos that have one,
passes the demo's own checks (every demo but patch-test, whose options are all choices and
integers); a bad value is refused with its key.

Each case runs the demo's command in a task on a Dask cluster (a ``LocalCluster`` of processes
sized to the machine by default, or the scheduler at ``scheduler``), with one thread per worker
and numba set to one thread, so that a case gives the same numbers as when run alone with the
same settings. It writes its own results folder ``cases/<id>/`` (``results.json``, histories,
fields, pictures) and its JSON; the study keeps ``index.json`` (each case's parameters, status and
error) and ``results.csv`` (one row per completed case: its parameters and the demo's scalar
results). Rerunning a study skips the completed cases; a case that fails (an error, or a worker
killed more often than Dask's ``distributed.scheduler.allowed-failures``) is recorded with its
reason and does not stop the others.

A ``"package.module:function"`` demo is called as ``function(out=<case folder>, **parameters)``
and returns a mapping of results (its scalars go to results.csv); its parameters are not checked
beforehand.
"""

from __future__ import annotations

import csv
import json
import logging
import math
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .study_spec import (
    DEMOS,
    Case,
    StudyError,
    StudySpec,
    _argv,
    _resolve,
    load_spec,
)

__all__ = ["DEMOS", "Case", "StudyError", "StudyRun", "StudySpec", "comparable", "load_spec",
           "run_case", "study"]  # fmt: skip


logger = logging.getLogger(__name__)

#: Keys of the results that depend on the run, not on the computation (left out of comparisons).
VOLATILE = ("wall_time_s", "setup_time_s", "qp_updates_per_second", "wall_time")


def _scalars(data: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """The scalar results of a JSON document (nested mappings flattened with '.')."""
    out: dict[str, Any] = {}
    for k, v in data.items():
        if isinstance(v, Mapping):
            out.update(_scalars(v, f"{prefix}{k}."))
        elif isinstance(v, (int, float, str, bool)) or v is None:
            out[prefix + k] = v
    return out


def run_case(demo: str, params: Mapping[str, Any], out: str | os.PathLike,
             numba_threads: int = 1) -> dict[str, Any]:  # fmt: skip
    """Run one case into the folder ``out`` and return its scalar results (the task of a study).

    Raises
    ------
    RuntimeError
        If the demo's command fails (its message is the case's recorded error).
    """
    try:  # the same thread settings in a worker and in a serial run
        import numba

        numba.set_num_threads(max(1, min(int(numba_threads), numba.config.NUMBA_NUM_THREADS)))
    except ImportError:  # pragma: no cover
        pass
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    if ":" in demo:
        result = dict(_resolve(demo)(out=str(out), **params))
        (out / "case.json").write_text(json.dumps(result, indent=2, default=float))
        return _scalars(result)
    import contextlib
    import io

    from ..cli.demos import demo_parser

    parser, commands = demo_parser()
    argv = _argv(demo, params, commands[demo])
    argv += ["--json", str(out / "case.json"), "--out", str(out / "run")]
    if demo in ("taylor-bar", "sliding-block", "two-bars", "wave", "ball-impact"):
        argv.append("--quiet")
    args = parser.parse_args(argv)
    # the command's own run: an error of the demo is the case's error (its message recorded);
    # its warnings go into the case's results, not onto the worker's stderr
    import warnings

    with contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code = args.func(args)
    if code:
        raise RuntimeError(f"{demo} exited with {code}")
    if caught:
        data = json.loads((out / "case.json").read_text())
        data["warnings"] = "; ".join(sorted({f"{w.category.__name__}: {w.message}"
                                             for w in caught}))  # fmt: skip
        (out / "case.json").write_text(json.dumps(data, indent=2))
    return _case_results(out, params)


def _case_results(out: Path, params: Mapping[str, Any]) -> dict[str, Any]:
    """The case's scalar results: those of its JSON and of its results folder's
    ``results.json`` (the demo's metrics with their units), without its own parameters."""
    results = _scalars(json.loads((out / "case.json").read_text()))
    meta = out / "run" / "results.json"
    if meta.exists():
        for k, v in json.loads(meta.read_text()).get("results", {}).items():
            value = v.get("value") if isinstance(v, Mapping) else v
            if isinstance(value, (int, float, str, bool)) and k not in results:
                results[k] = value
    return {k: v for k, v in results.items() if k not in params}


def _task(demo: str, params: dict, out: str, numba_threads: int) -> dict[str, Any]:
    return run_case(demo, params, out, numba_threads)


class _Index:
    """``index.json`` of a study folder: each case's parameters, status, error (rewritten
    atomically after every case)."""

    def __init__(self, root: Path, spec: StudySpec) -> None:
        self.path = root / "index.json"
        old = json.loads(self.path.read_text()) if self.path.exists() else {}
        self.cases: dict[str, dict[str, Any]] = old.get("cases", {})
        self.demo = spec.demo
        for c in spec.cases:
            self.cases.setdefault(c.case_id, {"number": c.number, "params": c.params,
                                              "status": "pending"})  # fmt: skip
        self.write()

    def set(self, case_id: str, **entry: Any) -> None:
        self.cases[case_id].update(entry)
        self.write()

    def write(self) -> None:
        tmp = self.path.with_suffix(".tmp")
        tmp.write_text(json.dumps({"demo": self.demo, "cases": self.cases}, indent=2,
                                  default=float))  # fmt: skip
        os.replace(tmp, self.path)


def _write_table(root: Path, index: _Index, spec: StudySpec) -> list[dict[str, Any]]:
    rows = []
    for c in spec.cases:
        entry = index.cases[c.case_id]
        if entry.get("status") != "complete":
            continue
        rows.append({"case": c.case_id, **{f"param.{k}": json.dumps(v) if isinstance(v, list)
                                           else v for k, v in c.params.items()},
                     **entry.get("results", {})})  # fmt: skip
    columns: list[str] = []
    for r in rows:
        columns += [k for k in r if k not in columns]
    with open(root / "results.csv", "w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, columns)
        writer.writeheader()
        writer.writerows(rows)
    try:
        import pandas as pd

        table = pd.DataFrame(rows, columns=columns)
        try:
            table.to_parquet(root / "results.parquet")
        except Exception:  # no pyarrow: the CSV is the table
            pass
        return table
    except ImportError:
        return rows


@dataclass
class StudyRun:
    """What :func:`study` did: the table, the folder, how many cases ran now, failed, skipped."""

    table: Any
    out: Path
    ran: list[str]
    failed: dict[str, str]
    skipped: list[str]
    dashboard: str | None = None


def study(spec: str | os.PathLike | Mapping[str, Any], out: str | os.PathLike = "study",
          scheduler: str | None = None, workers: int | None = None, resume: bool = True,
          numba_threads: int = 1,
          progress: Callable[[int, int, int, int, float | None], None] | None = None,
          on_cluster: Callable[[str | None], None] | None = None,
          ) -> StudyRun:  # fmt: skip
    """Run a study (see the module docstring) and return its table.

    Parameters
    ----------
    spec : path or mapping
        The study file (TOML) or its content.
    out : path
        The study folder (created): ``index.json``, ``results.csv`` (and ``results.parquet``
        with pyarrow), ``cases/<id>/``.
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:8786``); default a ``LocalCluster``
        of ``workers`` processes, one thread each.
    workers : int, optional
        Workers of the local cluster (default: the machine's cores).
    resume : bool
        Skip the cases the folder has completed (default True); False reruns every case.
    numba_threads : int
        numba threads in each case (default 1, as Dask's workers set the BLAS threads).
    progress : callable, optional
        ``progress(done, running, failed, total, eta_s)`` after each finished case.
    on_cluster : callable, optional
        ``on_cluster(dashboard_link)`` once the cluster is up (the link None without one).

    Returns
    -------
    StudyRun
        ``table`` is a pandas DataFrame when pandas is installed, else a list of records.
    """
    parsed = load_spec(spec)
    root = Path(out)
    try:
        (root / "cases").mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise StudyError(f"cannot write the study folder {str(root)!r}: {exc}") from exc
    old_index = root / "index.json"
    if old_index.exists():
        old = json.loads(old_index.read_text())
        ours = {c.case_id for c in parsed.cases}
        others = sorted(set(old.get("cases", {})) - ours)
        if old.get("demo") != parsed.demo or others:
            raise StudyError(
                f"the study folder {str(root)!r} holds another study ({old.get('demo')!r}, "
                f"{len(others)} cases not in this one): give another out, or remove the folder"
            )
    index = _Index(root, parsed)
    todo, skipped = [], []
    for c in parsed.cases:
        if resume and index.cases[c.case_id].get("status") == "complete":
            skipped.append(c.case_id)
        else:
            todo.append(c)
    ran: list[str] = []
    failed: dict[str, str] = {}
    dashboard = None
    if todo:
        from distributed import Client, LocalCluster, as_completed

        # Dask logs every connection at INFO: its warnings only, unless asked for more
        dlog = logging.getLogger("distributed")
        if dlog.getEffectiveLevel() < logging.WARNING and not logger.isEnabledFor(logging.DEBUG):
            dlog.setLevel(logging.WARNING)
        cluster = None
        if scheduler is None:
            import dask

            n = int(workers or os.cpu_count() or 1)
            # one task per worker thread at a time: a case that kills its worker takes no
            # queued innocent case with it (their retries would count against them too)
            with dask.config.set({"distributed.scheduler.worker-saturation": 1.0}):
                cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                       dashboard_address=":0")  # fmt: skip
            client = Client(cluster)
        else:
            client = Client(scheduler)
        try:
            dashboard = client.dashboard_link
            logger.info("Dask dashboard: %s", dashboard)
            if on_cluster is not None:
                on_cluster(dashboard)
            futures = {}
            for c in todo:
                index.set(c.case_id, status="running", error=None)
                fut = client.submit(_task, parsed.demo, c.params,
                                    str((root / "cases" / c.case_id).resolve()), numba_threads,
                                    key=f"{c.case_id}-{time.time_ns()}", pure=False)  # fmt: skip
                futures[fut] = c
            start = time.perf_counter()
            done = 0
            for fut in as_completed(futures):
                c = futures[fut]
                try:
                    results = fut.result()
                    index.set(c.case_id, status="complete", results=results, error=None)
                    ran.append(c.case_id)
                except Exception as exc:  # the case failed: recorded, the others go on
                    reason = f"{type(exc).__name__}: {exc}"
                    index.set(c.case_id, status="failed", error=reason)
                    failed[c.case_id] = reason
                done += 1
                if progress is not None:
                    elapsed = time.perf_counter() - start
                    eta = elapsed / done * (len(todo) - done) if done else None
                    progress(done, len(todo) - done, len(failed), len(todo), eta)
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    table = _write_table(root, index, parsed)
    return StudyRun(table, root, ran, failed, skipped, dashboard)


def comparable(record: Mapping[str, Any]) -> dict[str, Any]:
    """A result record without its run-dependent values (wall times, rates): what two runs of
    the same case must have equal, bit for bit."""
    return {k: v for k, v in record.items()
            if not any(k == s or k.endswith("." + s) for s in VOLATILE)
            and not (isinstance(v, float) and math.isnan(v))}  # fmt: skip
