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

from .cases import VOLATILE, comparable, run_case
from .runner import StudyRun, study
from .spec import DEMOS, Case, StudyError, StudySpec, load_spec

__all__ = ["DEMOS", "VOLATILE", "Case", "StudyError", "StudyRun", "StudySpec", "comparable",
           "load_spec", "run_case", "study"]  # fmt: skip
