"""One case of a study: its run in a folder (the demo's command, or a user function) and its
scalar results; what two runs of the same case must have equal."""

from __future__ import annotations

import contextlib
import io
import json
import math
import os
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .spec import _argv, _resolve

__all__ = ["VOLATILE", "comparable", "run_case"]

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

    from ...cli.demos import demo_parser

    parser, commands = demo_parser()
    argv = _argv(demo, params, commands[demo])
    argv += ["--json", str(out / "case.json"), "--out", str(out / "run")]
    if any(a.dest == "quiet" for a in commands[demo]._actions):
        argv.append("--quiet")
    args = parser.parse_args(argv)
    # the command's own run: an error of the demo is the case's error (its message recorded);
    # its warnings go into the case's results, not onto the worker's stderr

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


def comparable(record: Mapping[str, Any]) -> dict[str, Any]:
    """A result record without its run-dependent values (wall times, rates): what two runs of
    the same case must have equal, bit for bit."""
    return {k: v for k, v in record.items()
            if not any(k == s or k.endswith("." + s) for s in VOLATILE)
            and not (isinstance(v, float) and math.isnan(v))}  # fmt: skip
