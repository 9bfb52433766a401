"""Adaptive runs resume bit for bit like fixed ones (issue 42, part 3).

An adaptive pressure sphere (coarse 12.5 mm, fine 3.125 mm, 250 MPa in 6 steps: the seed's
step 4 rejected and computed again on 3 rings, the patch grown again after step 5) is stopped
after a growth and continued with ``resume``: ``history.csv``, ``newton.csv``, the results of
``results.json`` (but the wall times), every field frame and the final displacement,
multipliers and states are those of the uninterrupted run, bit for bit. The stops: after step
4 (its patch grown by the rejection), after step 5 (the growth it decided not made yet: the
resumed run makes it first), and during step 6 (that growth made, its series opened, then the
step stopped).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from arlequin.demos.pressure_vessel import PressureVesselConfig
from arlequin.demos.pressure_vessel import run as run_module
from arlequin.io import CheckpointError, read_checkpoint, read_series

CONFIG = {"adaptive": True, "coarse_size": 0.0125, "fine_size": 0.0125 / 4, "pressure": 2.5e8,
          "steps": 6}  # fmt: skip
TIMES = ("rebuild_time_s", "system_time_s", "resolve_time_s", "discarded_time_s")


@pytest.fixture(scope="module")
def full(tmp_path_factory):
    """The uninterrupted run's folder."""
    out = tmp_path_factory.mktemp("full")
    run_module.run(PressureVesselConfig(**CONFIG), out=str(out))
    return out


def _results(folder):
    """results.json's results, files and status, without the wall times."""
    meta = json.loads((folder / "results.json").read_text())
    results = meta["results"]
    results.pop("wall_time_s")
    for growth in results["adaptations"]["value"]:
        for key in TIMES:
            growth.pop(key)
    return results, meta["files"], meta["status"]


def _stop_after_step(k):
    """A progress callback raising KeyboardInterrupt after the k-th converged step."""
    calls = []

    def progress(fraction: float) -> None:
        calls.append(fraction)
        if len(calls) == k:
            raise KeyboardInterrupt

    return progress


@pytest.mark.parametrize("stop", ["after step 4", "after step 5", "in step 6"])
def test_an_interrupted_adaptive_run_resumes_bit_for_bit(full, tmp_path, monkeypatch, stop):
    import arlequin.solvers.statics.quasi_static as qs

    cut, config = tmp_path / "cut", PressureVesselConfig(**CONFIG)
    if stop == "in step 6":  # step() calls: 1-3, 4 (rejected), 4 again, 5, then 6
        original, calls = qs.QuasiStaticSolver.step, []

        def step(self):
            calls.append(1)
            if len(calls) == 7:  # Ctrl-C inside the step
                raise KeyboardInterrupt
            return original(self)

        monkeypatch.setattr(qs.QuasiStaticSolver, "step", step)
        with pytest.raises(KeyboardInterrupt):
            run_module.run(config, out=str(cut))
        monkeypatch.setattr(qs.QuasiStaticSolver, "step", original)
        assert (cut / "fields" / "patch0_2.xdmf").is_file()  # the growth after step 5 made
    else:
        k = int(stop[-1])
        with pytest.raises(KeyboardInterrupt):
            run_module.run(config, out=str(cut), progress=_stop_after_step(k))
    snap = read_checkpoint(cut / run_module.CHECKPOINT)
    # the checkpoint of the last converged step: the rejection's growth made, that of step 5
    # decided (made after the checkpoint in step 6's run, and made again when resumed)
    assert len(snap["adapt"]["records"]) == 1
    assert (snap["adapt"]["pending"] is None) == (stop == "after step 4")
    assert json.loads((cut / "results.json").read_text())["status"] == "interrupted"

    result = run_module.resume(str(cut))
    assert [a["step"] for a in result.adaptations] == [4, 5]
    for name in ("history.csv", "newton.csv"):
        assert (cut / name).read_bytes() == (full / name).read_bytes(), name
    assert _results(cut) == _results(full)
    for name in ("coarse", "patch0", "patch0_1", "patch0_2"):
        mesh_a, frames_a = read_series(full / "fields" / f"{name}.xdmf")
        mesh_b, frames_b = read_series(cut / "fields" / f"{name}.xdmf")
        assert np.array_equal(mesh_a.points, mesh_b.points)
        assert len(frames_a) == len(frames_b) > 0
        for (ta, pa, ca), (tb, pb, cb) in zip(frames_a, frames_b):
            assert ta == tb and pa.keys() == pb.keys() and ca.keys() == cb.keys()
            assert all(np.array_equal(pa[k], pb[k]) for k in pa)
            assert all(np.array_equal(ca[k][0], cb[k][0]) for k in ca)
    # the final state: the last step's checkpoint of each run
    a, b = (read_checkpoint(f / run_module.CHECKPOINT)["solver"] for f in (full, cut))
    assert a["t"] == b["t"] == 1.0
    assert np.array_equal(a["u"], b["u"]) and np.array_equal(a["mu"], b["mu"])
    for name in a["states"]:
        for sa, sb in zip(a["states"][name], b["states"][name]):
            if sa is not None:
                for key, value in vars(sa).items():
                    assert np.array_equal(value, getattr(sb, key)), (name, key)


def test_a_checkpoint_of_another_run_is_refused(full, tmp_path):
    """A checkpoint of another configuration, of a fixed patch's run, not an adaptive patch's
    checkpoint or none at all: a ValueError naming it."""
    from arlequin.problem.adapt import AdaptivePatch

    snap = read_checkpoint(full / run_module.CHECKPOINT)
    other = PressureVesselConfig(**{**CONFIG, "steps": 5})
    with pytest.raises(ValueError, match=r"another configuration \(it differs in \['steps'\]\)"):
        run_module.run(other, restore=snap)
    fixed = PressureVesselConfig(**{k: v for k, v in CONFIG.items() if k != "adaptive"})
    with pytest.raises(ValueError, match="of a run with an adaptive patch"):
        run_module.run(fixed, restore={**snap, "config": fixed})
    setup = run_module.build(PressureVesselConfig(**CONFIG))
    coarser = run_module.build(PressureVesselConfig(**{**CONFIG, "coarse_size": 0.025}))
    with pytest.raises(ValueError, match="another problem"):
        coarser.adapt.resume(coarser.problem, snap["adapt"])
    with pytest.raises(ValueError, match=r"not an AdaptivePatch\.checkpoint"):
        AdaptivePatch().resume(setup.problem, snap["solver"])
    with pytest.raises(CheckpointError, match="no checkpoint"):
        run_module.resume(str(tmp_path / "none"))
    assert issubclass(CheckpointError, ValueError)
