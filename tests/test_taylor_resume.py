"""Interrupted Taylor bar runs resume from their checkpoints to the uninterrupted run's values,
bit for bit (arlequin/demos/taylor_bar/checkpoint.py).

The reference is the same run, uninterrupted, in the same process: everything computed must be
equal (the exact values, not within a tolerance); wall times and timestamps are excluded.
"""

from __future__ import annotations

import json
import warnings

import meshio  # noqa: F401  (the XDMF reader below needs it)
import numpy as np
import pytest

from arlequin.cli.main import main
from arlequin.demos.taylor_bar import resume_taylor_bar, run_taylor_bar
from arlequin.io import read_series

#: Results that measure the machine, not the run.
WALL = {"wall_time_s", "setup_time_s", "qp_updates_per_second"}


def _interrupt_at(t_stop: float):
    def progress(t: float) -> None:
        if t >= t_stop:
            raise KeyboardInterrupt  # what Ctrl-C does

    return progress


@pytest.mark.parametrize(
    ("model", "geometry"), [("arlequin", "axisymmetric"), ("mono", "axisymmetric"), ("mono", "3d")]
)
def test_resumed_run_equals_the_uninterrupted_one(model, geometry, tmp_path):
    kw = {"model": model, "elements_radial": 4, "t_end": 8e-6, "checkpoint_interval": 2e-6,
          "geometry": geometry}  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the band warning of so coarse a patch
        whole = run_taylor_bar(out=tmp_path / "whole", **kw)
        with pytest.raises(KeyboardInterrupt):
            run_taylor_bar(out=tmp_path / "cut", progress=_interrupt_at(5e-6), **kw)
        assert (tmp_path / "cut" / "checkpoint.pkl").is_file()
        resumed = resume_taylor_bar(tmp_path / "cut")
    assert resumed.n_steps == whole.n_steps
    assert np.array_equal(resumed.u, whole.u)
    a = json.loads((tmp_path / "whole" / "results.json").read_text())
    b = json.loads((tmp_path / "cut" / "results.json").read_text())
    assert a["inputs"] == b["inputs"] and b["status"] == "complete"
    assert {k: v for k, v in a["results"].items() if k not in WALL} == \
        {k: v for k, v in b["results"].items() if k not in WALL}  # fmt: skip
    assert (tmp_path / "whole" / "history.csv").read_text() == \
        (tmp_path / "cut" / "history.csv").read_text()  # fmt: skip
    for name in a["files"]["fields"]:
        fa = read_series(tmp_path / "whole" / "fields" / f"{name}.xdmf")[1]
        fb = read_series(tmp_path / "cut" / "fields" / f"{name}.xdmf")[1]
        assert (
            [f[0] for f in fa]
            == [f[0] for f in fb]
            == pytest.approx([0, 2e-6, 4e-6, 6e-6, 8e-6], abs=1e-15)
        )
        for (_, pa, ca), (_, pb, cb) in zip(fa, fb):
            assert all(np.array_equal(pa[k], pb[k]) for k in pa)
            assert all(np.array_equal(ca[k][0], cb[k][0]) for k in ca)
    assert not (tmp_path / "cut" / "checkpoint.pkl").exists()  # removed once complete


def test_resume_refuses_what_it_cannot_continue(tmp_path):
    with pytest.raises(ValueError, match="no checkpoint"):
        resume_taylor_bar(tmp_path)
    with pytest.raises(ValueError, match="needs out=DIR"):
        run_taylor_bar(model="mono", elements_radial=3, t_end=1e-6, resume=True)
    with pytest.raises(KeyboardInterrupt):
        run_taylor_bar(model="mono", elements_radial=3, t_end=4e-6, out=tmp_path,
                       checkpoint_interval=1e-6, progress=_interrupt_at(2e-6))  # fmt: skip
    with pytest.raises(ValueError, match=r"other inputs \(\['t_end'\]\)"):
        run_taylor_bar(model="mono", elements_radial=3, t_end=5e-6, out=tmp_path,
                       checkpoint_interval=1e-6, resume=True)  # fmt: skip
    # the command: the inputs come from the checkpoint, other options are refused
    assert main(["taylor-bar", "--resume", "--out", str(tmp_path), "--t-end", "1e-6"]) == 2
    assert main(["taylor-bar", "--resume", "--out", str(tmp_path), "--quiet"]) == 0
