"""The plate with a hole with an adaptive patch (``plate-with-hole --adaptive``, issue 31):
the mechanics at a coarse resolution, the results kept on disk when the run stops (the cap,
an interruption), bad input, and criterion 4 at the default resolution (slow).

The seed is the coarse ring on the hole (8 coarse cells, all of them gluing band); the patch
grows where the plastic zone nears its band (and where the coarse stress reaches 0.9 σy, the
demo's default β), each growth closed over one-cell slots and notches; plastic points of the
band's outer half (α_f < 1/2) are disregarded by the indicator.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from arlequin import PatchLimitError
from arlequin.demos.plate_with_hole import PlateWithHoleConfig, run_plate_with_hole

#: One level of refinement (16 fine cells along the quarter hole), 3 steps past first yield:
#: about 2 s.
SMALL = {"levels": 1, "steps": 3}


def test_fill_notches_fills_slots_and_notches_not_corners():
    """The closure of the plate's adaptive patch: a cell between two of the patch's across
    opposite edges (a slot) joins, and so does one with the patch across three edges (a notch,
    the plate's edge y = 0 the fourth); a cell in a re-entrant corner (two adjacent edges)
    does not, so an L of three cells stays an L (the fixed-point closure over two edges
    filled it to its 2 × 2 square, and any staircase to its bounding rectangle); a straight
    row stays as it is."""
    from arlequin.demos.plate_with_hole.meshes import plate_mesh
    from arlequin.demos.plate_with_hole.setup import fill_notches

    mesh, _ = plate_mesh(0.01, 4, 4, 0.1, 0.02)
    centre = mesh.p[:, mesh.t].mean(axis=1) / 0.0025  # in quarter hole radii (a/4)

    def cell(i, j):  # the grid cell of centre ((2i + 1) a/4, (2j + 1) a/4), beyond 2a
        return int(np.argmin(np.hypot(centre[0] - (2 * i + 1), centre[1] - (2 * j + 1))))

    def mask_of(*cells):
        mask = np.zeros(mesh.nelements, dtype=bool)
        mask[[cell(i, j) for i, j in cells]] = True
        return mask

    closure = fill_notches(mesh)
    ell = mask_of((10, 0), (11, 0), (10, 1))
    assert np.array_equal(closure(ell), ell)
    row = mask_of((10, 0), (11, 0), (12, 0))
    assert np.array_equal(closure(row), row)
    slot = closure(mask_of((10, 1), (12, 1)))
    assert np.array_equal(slot, mask_of((10, 1), (11, 1), (12, 1)))
    notch = closure(mask_of((10, 0), (12, 0), (10, 1), (11, 1), (12, 1)))
    assert np.array_equal(notch, mask_of((10, 0), (11, 0), (12, 0), (10, 1), (11, 1), (12, 1)))


def test_adaptive_plate_grows_and_reports(tmp_path):
    """One level, 3 steps to 195 MPa from the one-ring seed. Measured: three growths, after
    step 2 (the first step past yield: rejected, plastic flow in the seed's band, to 0.0122 of
    the plate; then to 0.0437) and at the last step (rejected: at one level the band's fine
    cells are coarse, and plastic flow reaches its inner half, α_f ≥ 1/2; to 0.1156, the
    fixed patch's 65 coarse cells); the coarse σ_vm/σy outside the patch at most 0.823; the
    loaded edge's final displacement 87.02673 µm against the fixed patch's 87.02678 µm (same
    steps: −5e-7, the same final patch). Bounds: the growth (to the fixed patch's area: 11.5a²
    of 99.2a²), σy, 1e-4 on the displacement."""
    from arlequin.cli.main import main
    from arlequin.io import read_history, read_series

    out, js = tmp_path / "run", tmp_path / "plate.json"
    argv = ["plate-with-hole", "--adaptive", "--levels", "1", "--steps", "3", "--out",
            str(out), "--json", str(js), "--quiet"]  # fmt: skip
    assert main(argv) == 0
    data = json.loads(js.read_text())
    assert data["adaptations"], "the seed never grew"
    for growth in data["adaptations"]:
        assert set(growth) >= {"step", "time", "n_fine_elements", "patch_fraction",
                               "energy_jump"}  # fmt: skip
    fractions = data["history"]["patch_fraction"]
    assert len(fractions) == 5  # the unloaded plate, first yield, three steps
    assert fractions[0] < fractions[-1] and np.all(np.diff(fractions) >= 0.0)
    # the growth's share is of the coarse cells (chords on the hole), the run's of the fine
    # mesh (its hole nodes on the circle): 3e-4 apart
    assert data["patch_fraction"] == pytest.approx(data["adaptations"][-1]["patch_fraction"],
                                                   rel=1e-3)  # fmt: skip
    assert 0.1 < data["patch_fraction"] < 0.13
    assert 0.0 < data["max_coarse_yield_ratio"] < 1.0
    assert all(abs(g["energy_jump"]) < 1e-2 for g in data["adaptations"])
    fixed = run_plate_with_hole(**SMALL)
    u, ref = data["history"]["displacement"][-1], fixed.history["displacement"][-1]
    assert u == pytest.approx(ref, rel=1e-4)
    # the folder: a series per patch mesh, one row and one frame per step, a picture a growth
    assert json.loads((out / "results.json").read_text())["status"] == "complete"
    # history.csv: first yield (no frame) and the three steps
    assert len(read_history(out / "history.csv")["load_factor"]) == 4
    frames = sum(len(read_series(p)[1]) for p in (out / "fields").glob("patch0*.xdmf"))
    assert frames == 3
    assert (out / "patch_1.png").exists() and (out / "patch_size.png").exists()


def test_adaptive_plate_cap_keeps_every_step_on_disk(tmp_path):
    """A cap (0.03 of the plate) below the growth the plastic zone asks for after the first
    step (to 0.0437): PatchLimitError, named; the results folder marked failed, with the
    converged step in history.csv, its frame, and the history in results.json."""
    from arlequin.io import read_history

    with pytest.raises(PatchLimitError, match="max_fraction") as info:
        run_plate_with_hole(adaptive=True, max_patch_fraction=0.03, out=str(tmp_path), **SMALL)
    assert len(info.value.result.steps) >= 1
    meta = json.loads((tmp_path / "results.json").read_text())
    assert meta["status"] == "failed" and "max_fraction" in meta["message"]
    history = meta["results"]["history"]["value"]
    # the unloaded plate, first yield, and the converged step(s)
    assert len(history["load"]) == 1 + len(read_history(tmp_path / "history.csv")["load_factor"])
    assert len(history["load"]) >= 3
    assert meta["results"]["adaptations"]["value"]  # the growths made before the cap


def test_adaptive_plate_interrupted_keeps_every_step_on_disk(tmp_path):
    """Ctrl-C after the second converged step (the progress callback raises it): the folder
    marked interrupted, its results.json with every converged state."""
    calls = []

    def progress(fraction: float) -> None:
        calls.append(fraction)
        if len(calls) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_plate_with_hole(adaptive=True, out=str(tmp_path), progress=progress, **SMALL)
    meta = json.loads((tmp_path / "results.json").read_text())
    assert meta["status"] == "interrupted"
    assert len(meta["results"]["history"]["value"]["load"]) == 4  # unloaded, yield, 2 steps


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"adaptive": True, "adapt_threshold": 0.0}, "adapt_threshold"),
        ({"adaptive": True, "adapt_threshold": 1.5}, "adapt_threshold"),
        ({"adaptive": True, "adapt_buffer": -1}, "adapt_buffer"),
        ({"adaptive": True, "adapt_every": 0}, "adapt_every"),
        ({"adaptive": True, "max_patch_fraction": 1.2}, "max_patch_fraction"),
        ({"adaptive": True, "model": "graded"}, "adaptive"),
        ({"adaptive": True, "patch_radius": 0.035}, "patch_radius"),
    ],
)
def test_adaptive_plate_bad_input_named(options, match):
    with pytest.raises(ValueError, match=match):
        PlateWithHoleConfig(**options)


def _displacement_deviation(run, mono) -> np.ndarray:
    """run / mono − 1 of the loaded edge's displacement at the run's states from first yield
    on, mono's curve interpolated at the run's loads (the adaptive run's first yield, probed
    on a small fixed patch, is 0.3% above mono's; the curve is smooth between mono's states,
    10.5 MPa apart)."""
    load = np.array(run.history["load"][1:])
    ref = np.interp(load, mono.history["load"], mono.history["displacement"])
    return np.array(run.history["displacement"][1:]) / ref - 1.0


@pytest.mark.slow
def test_adaptive_plate_follows_mono_at_the_default_resolution():
    """Criterion 4, accuracy: the default configuration (3 levels, 195 MPa in 10 steps) from
    the one-ring seed. Measured: the loaded edge's displacement within 0.07% of mono at every
    state (interpolated at the same loads), the final plastic area +1.0% (it holds the
    band's outer half's few plastic points), the coarse σ_vm/σy outside the patch at most
    0.892. The bounds: the issue's 0.5%, item 6's 3%,
    σy. (The time ratio T_mono / T_adaptive is measured by benchmarks/adaptive.py.)"""
    mono, run = run_plate_with_hole(model="mono"), run_plate_with_hole(adaptive=True)
    assert np.all(np.abs(_displacement_deviation(run, mono)) <= 0.005)
    area, ref = run.history["plastic_area"][-1], mono.history["plastic_area"][-1]
    assert area == pytest.approx(ref, rel=0.03)
    assert run.max_coarse_yield_ratio < 1.0


@pytest.mark.slow
def test_adaptive_plate_patch_area_at_the_default_resolution():
    """Criterion 4, size: the final patch at most 1.5 times the area of the plastic zone and
    its gluing band. The plastic zone's area: the quadrature weights with ε̄p > 0 (the
    history's ``plastic_area``); its gluing band: the final patch's (``band_fraction``, the
    fine cells within one coarse cell of the patch's interior boundary), the band the plastic
    zone needs around it to be held by a patch. Measured (the default configuration): the
    patch 0.0437 of the plate (the one the last step was computed on), the plastic zone
    0.0076, the band 0.0254: 1.32 times. (The coarse cells over a plastic fine cell plus one
    ring, ``plastic_cover_fraction``, 0.0529, hold the band's outer half too, whose plastic
    points the indicator disregards: 0.83 times; that measure counts one ring beyond them.)"""
    run = run_plate_with_hole(adaptive=True)
    config = PlateWithHoleConfig()
    # the quarter plate's area, W² − πa²/4 (the coarse mesh with its chords on the hole: +0.005%)
    plate = config.width**2 - np.pi * config.radius**2 / 4.0
    held = run.history["plastic_area"][-1] / plate + run.band_fraction
    assert run.patch_fraction <= 1.5 * held
