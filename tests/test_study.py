"""Parameter studies on Dask (arlequin.demos.study): checks before any case, equality with serial
runs, resume, fault tolerance (loopback only)."""

from __future__ import annotations

import json
import textwrap

import pytest

from arlequin.cli.main import main
from arlequin.demos.study import StudyError, comparable, load_spec, run_case, study

TWO_BARS = {
    "demo": "two-bars",
    "parameters": {"velocity": [1.0, 2.0, 3.0, 4.0], "elements": [20, 40], "cfl": 1.0},
}


def test_the_minimal_spec_has_the_cartesian_product(tmp_path):
    spec = tmp_path / "s.toml"
    spec.write_text(
        textwrap.dedent("""
        demo = "two-bars"            # a CLI demo name
        [parameters]
        velocity = [1.0, 2.0, 3.0]   # a list is a grid axis
        elements = [50, 100]
        cfl = 1.0                    # a scalar is fixed for every case
    """)
    )
    parsed = load_spec(spec)
    assert len(parsed.cases) == 6
    assert parsed.cases[1].params == {"cfl": 1.0, "velocity": 1.0, "elements": 100}
    assert len({c.case_id for c in parsed.cases}) == 6


@pytest.mark.parametrize("data, match", [
    ({"demo": "three-bars"}, "demo 'three-bars' is not one of"),
    ({"demo": "two-bars", "parameters": {"speed": 1.0}}, "parameter 'speed' is not an option"),
    ({"demo": "two-bars", "parameters": {"velocty": 1.0}}, "did you mean 'velocity'"),
    ({"demo": "two-bars", "parameters": {"velocity": "fast"}}, "'velocity'.*not a valid float"),
    ({"demo": "two-bars", "parameters": {"elements": 2.5}}, "'elements'.*not a valid int"),
    ({"demo": "two-bars", "parameters": {"method": "magic"}}, "'method'.*not one of"),
    ({"demo": "two-bars", "parameters": {"cfl": [1.0, -1.0]}}, "cfl"),
    ({"demo": "sliding-block", "parameters": {"incline": 10.0}}, "needs the gravity"),
    ({"demo": "taylor-bar", "parameters": {"elements_radial": [10, 1]}}, "coarse cells"),
    ({"demo": "taylor-bar", "parameters": {"model": "mono", "mediator": "coarse"}},
     "apply to model='arlequin' only"),
    ({"demo": "wave", "parameters": {"ratio": 0}}, "ratio must be a positive integer"),
    ({"demo": "two-bars", "parameters": {"velocity": -1.0}}, "bar 1 must approach bar 2"),
    ({"demo": "two-bars", "parameters": {"lengths": 1.0}}, "'lengths'.*takes 2 values"),
    ({"demo": "two-bars", "parameters": {"velocity": []}}, "'velocity' has an empty list"),
    ({"demo": "two-bars", "parameters": {"out": "x"}}, "'out' is set by the study"),
    ({"demo": "two-bars", "extra": 1}, r"unknown keys \['extra'\]"),
])  # fmt: skip
def test_a_bad_spec_is_refused_before_any_case_runs(tmp_path, data, match):
    with pytest.raises(StudyError, match=match):
        study(data, out=tmp_path / "study")
    assert not (tmp_path / "study").exists()  # nothing written, nothing run


def test_a_local_cluster_gives_the_serial_numbers_bit_for_bit(tmp_path):
    # 8 cases on 2 worker processes against the same cases one by one in this process (one
    # thread each: Dask's workers set the BLAS threads to 1, the runner numba's)
    run = study(TWO_BARS, out=tmp_path / "dask", workers=2)
    assert len(run.ran) == 8 and not run.failed
    index = json.loads((tmp_path / "dask" / "index.json").read_text())["cases"]
    parsed = load_spec(TWO_BARS)
    for case in parsed.cases:
        serial = run_case("two-bars", case.params, tmp_path / "serial" / case.case_id)
        parallel = index[case.case_id]["results"]
        assert comparable(parallel) == comparable(serial)
        # the demo's metrics of its results folder are in the table too
        assert {"pressure_rms_error", "contact_duration"} <= set(parallel)
        # and every computed value of the case's JSON (histories included), bit for bit
        docs = [json.loads((root / case.case_id / "case.json").read_text())
                for root in (tmp_path / "dask" / "cases", tmp_path / "serial")]  # fmt: skip
        assert docs[0] == docs[1] and len(docs[0]["interface_velocity"]) > 50
        assert (tmp_path / "dask" / "cases" / case.case_id / "run" / "results.json").exists()
    rows = (tmp_path / "dask" / "results.csv").read_text().splitlines()
    assert len(rows) == 9 and rows[0].startswith("case,param.")


def test_a_rerun_skips_the_completed_cases(tmp_path):
    data = {"demo": "two-bars", "parameters": {"velocity": [1.0, 2.0, 3.0], "elements": 20}}
    first = study(data, out=tmp_path / "s", workers=2)
    assert len(first.ran) == 3
    again = study(data, out=tmp_path / "s", workers=2)
    assert again.ran == [] and len(again.skipped) == 3
    # an interrupted study: one case left running
    path = tmp_path / "s" / "index.json"
    index = json.loads(path.read_text())
    victim = sorted(index["cases"])[1]
    index["cases"][victim]["status"] = "running"
    path.write_text(json.dumps(index))
    resumed = study(data, out=tmp_path / "s", workers=2)
    assert resumed.ran == [victim] and len(resumed.skipped) == 2
    assert len((tmp_path / "s" / "results.csv").read_text().splitlines()) == 4
    # a grown grid runs its new cases only; another study in the same folder is refused
    grown = {"demo": "two-bars", "parameters": {"velocity": [1.0, 2.0, 3.0, 4.0], "elements": 20}}
    assert len(study(grown, out=tmp_path / "s", workers=2).ran) == 1
    other = {"demo": "two-bars", "parameters": {"velocity": [1.0, 2.0], "elements": 30}}
    with pytest.raises(StudyError, match="holds another study"):
        study(other, out=tmp_path / "s")


CASES = '''
import os
from pathlib import Path


def square(out, x):
    return {"x2": x * x}


def kill_once(out, x):
    """Kills its worker the first time it runs (a marker in its folder), then succeeds."""
    marker = Path(out) / "killed-once"
    if x == 2 and not marker.exists():
        marker.write_text("")
        os._exit(1)
    return {"x2": x * x}


def kill_always(out, x):
    if x == 3:
        os._exit(1)
    return {"x2": x * x}
'''


@pytest.fixture
def case_module(tmp_path, monkeypatch):
    (tmp_path / "study_cases.py").write_text(CASES)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setenv("PYTHONPATH", str(tmp_path))  # the workers' processes
    return tmp_path


def test_a_killed_worker_is_replaced_and_every_case_done_once(case_module, tmp_path):
    data = {"demo": "study_cases:kill_once", "parameters": {"x": [1, 2, 3, 4]}}
    run = study(data, out=tmp_path / "s", workers=2)
    assert not run.failed and sorted(run.ran) == sorted(c.case_id for c in load_spec(data).cases)
    index = json.loads((tmp_path / "s" / "index.json").read_text())["cases"]
    assert sorted(e["results"]["x2"] for e in index.values()) == [1, 4, 9, 16]
    # the worker of case x = 2 was killed once (its marker) and the case ran again elsewhere
    killed = [c for c, e in index.items() if e["params"]["x"] == 2]
    assert (tmp_path / "s" / "cases" / killed[0] / "killed-once").exists()


def test_a_case_that_always_kills_its_worker_is_recorded_as_failed(case_module, tmp_path):
    import dask

    data = {"demo": "study_cases:kill_always", "parameters": {"x": [1, 2, 3, 4]}}
    with dask.config.set({"distributed.scheduler.allowed-failures": 1}):
        run = study(data, out=tmp_path / "s", workers=2)
    assert len(run.failed) == 1 and len(run.ran) == 3
    (reason,) = run.failed.values()
    assert "KilledWorker" in reason
    index = json.loads((tmp_path / "s" / "index.json").read_text())["cases"]
    assert sorted(e["status"] for e in index.values()) == ["complete"] * 3 + ["failed"]


def test_cli_study(tmp_path):
    spec = tmp_path / "s.toml"
    spec.write_text('demo = "two-bars"\n[parameters]\nvelocity = [1.0, 2.0]\nelements = 20\n')
    assert main(["study", str(spec), "--out", str(tmp_path / "s"), "--workers", "2",
                 "--quiet"]) == 0  # fmt: skip
    assert len((tmp_path / "s" / "results.csv").read_text().splitlines()) == 3
    bad = tmp_path / "bad.toml"
    bad.write_text('demo = "two-bars"\n[parameters]\nspeed = 1.0\n')
    assert main(["study", str(bad), "--out", str(tmp_path / "b")]) == 2


def test_the_shipped_sensitivity_study_parses():
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent
    spec = root / "examples" / "studies" / "taylor_sensitivity.toml"
    parsed = load_spec(spec)
    assert parsed.demo == "taylor-bar" and len(parsed.cases) == 11
    assert parsed.cases[0].params == {"elements_radial": 10}  # the defaults
