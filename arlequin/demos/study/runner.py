"""The study runner: a study's pending cases as tasks on a Dask cluster (local by default),
each case's outcome recorded in the study folder as it finishes (:func:`study`)."""

from __future__ import annotations

import contextlib
import logging
import os
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .cases import _task
from .folder import StudyIndex, open_study_folder, write_table
from .spec import Case, StudySpec, load_spec

__all__ = ["StudyRun", "study"]

logger = logging.getLogger(__name__)

#: ``progress(done, running, failed, total, eta_s)`` after each finished case
Progress = Callable[[int, int, int, int, "float | None"], None]


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
          numba_threads: int = 1, progress: Progress | None = None,
          on_cluster: Callable[[str | None], None] | None = None,
          ) -> StudyRun:  # fmt: skip
    """Run a study (see :mod:`arlequin.demos.study`) and return its table.

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
    index = open_study_folder(root, parsed)
    todo = [c for c in parsed.cases if not (resume and _complete(index, c))]
    run = StudyRun(None, root, [], {}, [c.case_id for c in parsed.cases if c not in todo])
    if todo:
        with _client(scheduler, workers) as client:
            run.dashboard = client.dashboard_link
            logger.info("Dask dashboard: %s", run.dashboard)
            if on_cluster is not None:
                on_cluster(run.dashboard)
            _run_cases(client, parsed, todo, root, index, numba_threads, run, progress)
    run.table = write_table(root, index, parsed)
    return run


def _complete(index: StudyIndex, case: Case) -> bool:
    return index.cases[case.case_id].get("status") == "complete"


@contextlib.contextmanager
def _client(scheduler: str | None, workers: int | None) -> Iterator[Any]:
    """A Dask client: on the scheduler at ``scheduler``, or on a local cluster of ``workers``
    processes of one thread each (closed on leaving)."""
    from distributed import Client, LocalCluster

    # Dask logs every connection at INFO: its warnings only, unless asked for more
    dlog = logging.getLogger("distributed")
    if dlog.getEffectiveLevel() < logging.WARNING and not logger.isEnabledFor(logging.DEBUG):
        dlog.setLevel(logging.WARNING)
    cluster = None
    if scheduler is None:
        import dask

        n = int(workers or os.cpu_count() or 1)
        # one task per worker thread at a time: a case that kills its worker takes no queued
        # innocent case with it (their retries would count against them too)
        with dask.config.set({"distributed.scheduler.worker-saturation": 1.0}):
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                   dashboard_address=":0")  # fmt: skip
        client = Client(cluster)
    else:
        client = Client(scheduler)
    try:
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


@dataclass
class _Tally:
    """Cases finished so far, for the progress callback's estimate of the time left."""

    total: int
    start: float = field(default_factory=time.perf_counter)
    done: int = 0

    def eta(self) -> float | None:
        elapsed = time.perf_counter() - self.start
        return elapsed / self.done * (self.total - self.done) if self.done else None


def _run_cases(client: Any, spec: StudySpec, todo: list[Case], root: Path, index: StudyIndex,
               numba_threads: int, run: StudyRun, progress: Progress | None) -> None:  # fmt: skip
    """Submit every pending case, then record each as it finishes (a failed case is recorded
    with its reason and does not stop the others)."""
    from distributed import as_completed

    futures = {}
    for c in todo:
        index.set(c.case_id, status="running", error=None)
        fut = client.submit(_task, spec.demo, c.params,
                            str((root / "cases" / c.case_id).resolve()), numba_threads,
                            key=f"{c.case_id}-{time.time_ns()}", pure=False)  # fmt: skip
        futures[fut] = c
    tally = _Tally(len(todo))
    for fut in as_completed(futures):
        c = futures[fut]
        try:
            results = fut.result()
            index.set(c.case_id, status="complete", results=results, error=None)
            run.ran.append(c.case_id)
        except Exception as exc:  # the case failed: recorded, the others go on
            reason = f"{type(exc).__name__}: {exc}"
            index.set(c.case_id, status="failed", error=reason)
            run.failed[c.case_id] = reason
        tally.done += 1
        if progress is not None:
            progress(tally.done, tally.total - tally.done, len(run.failed), tally.total,
                     tally.eta())  # fmt: skip
