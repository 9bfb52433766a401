"""Every CLI command writes its results folder; the files read back equal the in-memory result.

The CLI runs and the Python runs below are the same deterministic computation, so the CLI's
folder is compared with the Python result's fields (u and v at every record) to the bit.
"""

from __future__ import annotations

import numpy as np
import pytest
from _roundtrip import assert_history_equal, assert_series_equal, load_results

from arlequin.cli.main import main
from arlequin.demos.patch_test import run_patch_test
from arlequin.demos.two_bars import run_two_bars
from arlequin.demos.wave import run_wave
from arlequin.io import FieldSeries, ResultsFolder, read_series


def test_wave_folder_matches_the_run(tmp_path):
    out = tmp_path / "cli"
    assert main(["wave", "--ratio", "2", "--out", str(out)]) == 0
    meta = load_results(out)
    assert meta["inputs"]["ratio"] == {"value": 2, "unit": "1"}
    assert meta["results"]["reflected_energy_fraction"]["unit"] == "1"
    assert (out / "wave.png").stat().st_size > 0
    r = run_wave(ratio=2, out=tmp_path / "py")
    dyn = r.dynamic
    n_coarse = r.fields["x_coarse"].size  # 1D: one dof per node, the coarse block first
    blocks = {"coarse": slice(0, n_coarse), "patch0": slice(n_coarse, None)}
    for name, sl in blocks.items():
        fields = {"displacement": dyn.fields["u"][:, sl], "velocity": dyn.fields["v"][:, sl]}
        n = assert_series_equal(out, name, dyn.times, fields, 1)
        assert n == 51  # frames at 51 times from 0 to the snapshot
    # the multiplier field lives on the coarse (mediator) nodes; alpha sums to one in the overlap
    _, frames = read_series(out / "fields" / "coarse.xdmf")
    assert "multiplier:patch0" in frames[-1][1] and "alpha" in frames[-1][2]
    assert_history_equal(out, {"t": dyn.times, "energy": dyn.total_energy})


def test_two_bars_folder_matches_the_run(tmp_path):
    out = tmp_path / "cli"
    args = ["two-bars", "--method", "both", "--elements", "10", "--out", str(out)]
    assert main(args) == 0
    meta = load_results(out)
    assert meta["inputs"]["young"]["unit"] == "Pa"
    assert "newmark-trapezoidal:pressure_rms_error" in meta["results"]
    r = run_two_bars(method="both", elements=10)
    for run, prefix in ((r, ""), (r.newmark, "newmark-trapezoidal_")):
        dyn = run.dynamic
        n1 = dyn.fields["u"].shape[1] // 2
        for name, sl in (("bar1", slice(0, n1)), ("bar2", slice(n1, 2 * n1))):
            fields = {"displacement": dyn.fields["u"][:, sl], "velocity": dyn.fields["v"][:, sl]}
            n_frames = assert_series_equal(out, prefix + name, dyn.times, fields, 1)
            assert n_frames == min(61, dyn.times.size)  # 61 frame times, at most one a record
        assert_history_equal(
            out, {"t": dyn.times, "energy": dyn.total_energy}, name=f"{prefix}history"
        )


def test_patch_test_folder_matches_the_solution(tmp_path):
    out = tmp_path / "cli"
    assert main(["patch-test", "--dim", "axi", "--out", str(out)]) == 0
    meta = load_results(out)
    assert meta["results"]["max_error"]["value"] <= 1e-10  # exact configuration
    r = run_patch_test(dim="axi")
    s = r.static
    dm = s.system.dofmap
    for name in dm:
        fields = {"displacement": s.u[dm[name].slice][None, :]}
        assert assert_series_equal(out, name, np.array([0.0]), fields, 2) == 1
    _, frames = read_series(out / "fields" / "patch0.xdmf")
    alpha = frames[0][2]["alpha"][0]
    assert alpha.min() > 0.0 and alpha.max() <= 1.0


def test_folder_errors_before_any_work(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert main(["wave", "--out", str(blocker / "sub")]) == 2
    assert "cannot write the results folder" in capsys.readouterr().err
    with pytest.raises(ValueError, match="results folder"):
        ResultsFolder(blocker, "x", {})


def test_output_files_checked_before_the_run(capsys):
    assert main(["wave", "--ratio", "2", "--json", "/nonexistent/dir/a.json"]) == 2
    assert "--json '/nonexistent/dir/a.json'" in capsys.readouterr().err
    assert main(["two-bars", "--plot", "/nonexistent/dir/a.png"]) == 2


def test_series_written_as_it_goes(tmp_path):
    """An interrupted run keeps its frames: the XDMF file is complete after every frame."""
    import skfem

    mesh = skfem.MeshTri().refined(2)
    series = FieldSeries(tmp_path / "s.xdmf", mesh)
    for k in range(3):
        series.write(0.1 * k, {"displacement": np.full((mesh.nvertices, 3), float(k))})
        _, frames = read_series(tmp_path / "s.xdmf")  # read while still open
        assert [f[0] for f in frames] == pytest.approx([0.1 * j for j in range(k + 1)])
    series.close()
