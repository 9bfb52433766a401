"""The pressure-vessel demo (arlequin.demos.pressure_vessel) against Hill's exact solutions.

Reference values (issue 29; small strain, perfectly plastic, E = 210 GPa, ν = 0.3,
σy = 240 MPa, a = 100 mm, b = 200 mm): sphere P0 = 140.0 MPa; at 200 MPa c = 115.99 mm,
u_b = 31.212 µm; at 300 MPa c = 157.56 mm, u_b = 78.233 µm; limit 332.71 MPa. Cylinder (plane
strain): P0 = 103.75 MPa, limit 192.09 MPa.
"""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest

from arlequin.demos.pressure_vessel import PressureVesselConfig, hill, run_pressure_vessel
from arlequin.demos.pressure_vessel.result import HISTORY_KEYS, JSON_KEYS

A, B, E, NU, SY = 0.1, 0.2, 210e9, 0.3, 240e6


def test_hill_reference_values():
    """Hill's formulas give the issue's reference values (its digits)."""
    assert hill.sphere_first_yield(A, B, SY) == pytest.approx(140.0e6, rel=1e-12)
    assert hill.sphere_plastic_radius(200e6, A, B, SY) == pytest.approx(115.99e-3, abs=5e-6)
    assert hill.sphere_outer_displacement(200e6, A, B, E, NU, SY) == pytest.approx(
        31.212e-6, abs=5e-10
    )
    assert hill.sphere_plastic_radius(300e6, A, B, SY) == pytest.approx(157.56e-3, abs=5e-6)
    assert hill.sphere_outer_displacement(300e6, A, B, E, NU, SY) == pytest.approx(
        78.233e-6, abs=5e-10
    )
    assert hill.sphere_limit_load(A, B, SY) == pytest.approx(332.71e6, abs=5e3)
    assert hill.cylinder_first_yield(A, B, NU, SY) == pytest.approx(103.75e6, abs=5e3)
    assert hill.cylinder_limit_load(A, B, SY) == pytest.approx(192.09e6, abs=5e3)
    # the elastic and the plastic outer displacements meet at first yield
    p0 = hill.sphere_first_yield(A, B, SY)
    below = hill.sphere_outer_displacement(p0 * (1 - 1e-12), A, B, E, NU, SY)
    above = hill.sphere_outer_displacement(p0 * (1 + 1e-12), A, B, E, NU, SY)
    assert below == pytest.approx(above, rel=1e-9)


#: A coarse set-up for the default test run: 16 fine cells across the wall (4 coarse).
COARSE = {"coarse_size": 0.025, "fine_size": 0.025 / 4}


@pytest.mark.parametrize("model", ["arlequin", "mono"])
def test_sphere_coarse_run_against_hill(model):
    """16 fine cells across the wall, 300 MPa in 10 steps. Measured (this resolution): first
    yield +0.5 to +0.7%, c at 300 MPa −0.4%, u_b −1.6%; the bounds below are twice those
    (the issue's 0.5% / 1% bounds hold at the default resolution: the slow test)."""
    r = run_pressure_vessel(model=model, **COARSE)
    h = r.history
    assert r.first_yield_pressure == pytest.approx(140.0e6, rel=0.015)
    assert h["pressure"][-1] == pytest.approx(300e6, rel=1e-12)
    assert h["plastic_radius"][-1] == pytest.approx(157.56e-3, rel=0.01)
    assert h["outer_displacement"][-1] == pytest.approx(78.233e-6, rel=0.035)
    assert not r.limit_load_reached
    assert max(h["newton_iterations"]) <= 8
    assert set(JSON_KEYS) <= set(r.to_json()) and set(HISTORY_KEYS) == set(h)
    # the elastic zone outside the patch (from 175 mm) stays below yield: (c/r)³ ≈ 0.73 at
    # most in Hill's solution, 0.62 measured (the coarse cells' own stress)
    assert r.max_coarse_yield_ratio < 0.8


def test_sphere_ten_steps_to_300_mpa_newton():
    """The issue's Newton criterion on the sphere's 300 MPa run in 10 equal steps (defaults):
    median iterations a step ≤ 5 (measured 3.5: 1, 0, 0, 0, 3, 4, 3, 4, 5, 4; the elastic
    steps' last increment extrapolated is exact), and below 1e-3 each residual ≤ 10 × the
    previous one squared (measured ratio at most 0.45)."""
    r = run_pressure_vessel(model="arlequin")
    its = r.history["newton_iterations"][1:]
    assert len(its) == 10 and float(np.median(its)) <= 5
    for res in r.history["residuals"][1:]:
        for r0, r1 in itertools.pairwise(res):
            if r0 < 1e-3 and r1 > 1e-10:
                assert r1 <= 10.0 * r0**2, res


def test_an_outgrown_patch_is_reported():
    """The cylinder pressed past its limit load with the patch to 187.5 mm: the elastic ring
    outside carries the load the plastic wall cannot (no limit load): the run warns and says by
    how much the coarse model exceeds the yield stress (measured 2.5 times)."""
    from arlequin import CoarseYieldWarning

    with pytest.warns(CoarseYieldWarning, match="outgrown the patch"):
        r = run_pressure_vessel(shape="cylinder", pressure=2.4e8, steps=8, **COARSE)
    assert r.max_coarse_yield_ratio > 1.0


@pytest.mark.slow
@pytest.mark.parametrize("material", ["small-strain", "finite-strain"])
def test_sphere_default_resolution_meets_the_issue_bounds(material):
    """The default resolution (64 fine cells across the wall, the patch to 185 mm), 15 steps
    of 20 MPa (200 and 300 MPa both reached): first yield within 0.5% of P0; c within 1% and
    one fine cell, u_b within 1% of Hill at 200 and 300 MPa; Arlequin and mono within 0.5%;
    Newton quadratic below 1e-3 (each residual ≤ 10 × the previous one squared, until 1e-10).
    Measured (docs/quasi_static.md): P0 +0.13% / +0.10%; at 300 MPa arlequin c +0.16% (small
    strain) / −0.08% (finite), u_b −0.14% / −0.75%; arlequin − mono: c −0.08%, u_b −0.11% /
    −0.14%; the largest r_{k+1}/r_k² 0.45; the coarse model outside the patch at most 0.55 σy.
    """
    runs = {}
    for model in ("arlequin", "mono"):
        r = run_pressure_vessel(model=model, material=material, steps=15)
        runs[model] = r
        h = r.history
        assert r.first_yield_pressure == pytest.approx(140.0e6, rel=0.005)
        for p in (200e6, 300e6):
            i = int(np.argmin(np.abs(np.array(h["pressure"]) - p)))
            assert h["pressure"][i] == pytest.approx(p, rel=1e-12)
            c = hill.sphere_plastic_radius(p, A, B, SY)
            ub = hill.sphere_outer_displacement(p, A, B, E, NU, SY)
            assert abs(h["plastic_radius"][i] - c) <= min(0.01 * c, (B - A) / 64)
            assert h["outer_displacement"][i] == pytest.approx(ub, rel=0.01)
        for res in h["residuals"][1:]:
            for r0, r1 in itertools.pairwise(res):
                if r0 < 1e-3 and r1 > 1e-10:
                    assert r1 <= 10.0 * r0**2, res
    a, m = runs["arlequin"].history, runs["mono"].history
    for key in ("plastic_radius", "outer_displacement"):
        assert a[key][-1] == pytest.approx(m[key][-1], rel=0.005)
    assert runs["arlequin"].max_coarse_yield_ratio < 1.0


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"pressure": -1.0}, "pressure"),
        ({"pressure": 0.0}, "pressure"),
        ({"inner": 0.2, "outer": 0.1}, "inner radius"),
        ({"patch_outer": 0.25}, "patch_outer"),
        ({"patch_outer": 0.05}, "patch_outer"),
        ({"yield_stress": 0.0}, "yield_stress"),
        ({"hardening": -1e9}, "hardening"),
        ({"steps": 0}, "steps"),
        ({"shape": "torus"}, "shape"),
        ({"pressure": 1e8, "inner_displacement": 1e-4}, "one of"),
        ({"coarse_size": 0.02, "fine_size": 0.003}, "power of 2"),
    ],
)
def test_bad_input_named_before_any_work(options, match):
    with pytest.raises(ValueError, match=match):
        PressureVesselConfig(**options)


def test_cli_writes_the_interface_json_and_a_results_folder(tmp_path, capsys):
    """The command's JSON has the Interface's keys; the folder its results.json (inputs as
    plain JSON), the Newton history, one XDMF frame per step and the pictures."""
    from arlequin.cli.main import main
    from arlequin.io import read_history, read_series

    out, js = tmp_path / "run", tmp_path / "pv.json"
    argv = ["pressure-vessel", "--shape", "cylinder", "--pressure", "1.5e8", "--steps", "3",
            "--coarse-size", "0.025", "--fine-size", "0.0125", "--out", str(out), "--json",
            str(js), "--quiet"]  # fmt: skip
    assert main(argv) == 0
    data = json.loads(js.read_text())
    assert list(data)[: len(JSON_KEYS)] == list(JSON_KEYS)
    assert set(data["history"]) == set(HISTORY_KEYS)
    assert len(data["history"]["pressure"]) == 4
    meta = json.loads((out / "results.json").read_text())
    assert meta["status"] == "complete"
    assert meta["inputs"]["yield_stress"] == {"value": 240e6, "unit": "Pa"}
    rows = read_history(out / "history.csv")
    assert len(rows["load_factor"]) == 3
    _mesh, frames = read_series(out / "fields" / "patch0.xdmf")
    assert len(frames) == 3 and "eqps" in frames[-1][2]
    assert (out / "pressure_displacement.png").exists() and (out / "plastic_zone.png").exists()
    assert "first yield" in capsys.readouterr().out
    assert math.isfinite(data["first_yield_pressure"])


def test_an_interrupted_run_resumes_bit_for_bit(tmp_path, monkeypatch):
    """A run interrupted after its 6th converged step continues with ``--resume --out DIR``
    from its checkpoint: the same history (pressures, displacements, fronts, Newton's
    iterations and residuals) as the uninterrupted run, bit for bit, and every frame kept."""
    import arlequin.solvers.statics.quasi_static as qs
    from arlequin.cli.main import main
    from arlequin.demos.pressure_vessel import run as run_module
    from arlequin.io import read_series

    args = ["pressure-vessel", "--coarse-size", "0.025", "--fine-size", "0.00625", "--steps",
            "10", "--quiet"]  # fmt: skip
    full, cut = tmp_path / "full", tmp_path / "cut"
    assert main([*args, "--out", str(full), "--json", str(tmp_path / "full.json")]) == 0

    class Interrupted(Exception):
        pass

    original, calls = qs.QuasiStaticSolver.step, []

    def step(self):
        calls.append(1)
        if len(calls) == 7:
            raise Interrupted
        return original(self)

    monkeypatch.setattr(qs.QuasiStaticSolver, "step", step)
    with pytest.raises(Interrupted):
        run_module.run(PressureVesselConfig(coarse_size=0.025, fine_size=0.00625, steps=10),
                       out=str(cut))  # fmt: skip
    monkeypatch.setattr(qs.QuasiStaticSolver, "step", original)
    # other options than the run's are refused with --resume
    assert main(["pressure-vessel", "--resume", "--out", str(cut), "--steps", "3"]) == 2
    assert main(["pressure-vessel", "--resume", "--out", str(cut), "--quiet", "--json",
                 str(tmp_path / "cut.json")]) == 0  # fmt: skip
    a = json.loads((tmp_path / "full.json").read_text())["history"]
    b = json.loads((tmp_path / "cut.json").read_text())["history"]
    assert a == b
    assert len(read_series(cut / "fields" / "patch0.xdmf")[1]) == 10
    assert main(["pressure-vessel", "--resume", "--out", str(tmp_path / "none")]) == 2


@pytest.mark.slow
def test_cylinder_first_yield_limit_load_and_plateau():
    """The plane-strain cylinder at the default resolution (issue 29 item 4). Measured: first
    yield 103.80 MPa mono, 103.84 arlequin (+0.05%, +0.09% of 103.75); pressure-driven to
    240 MPa, mono stops at a reported limit load of 192.09 MPa (−0.0003%); driven by the
    bore's displacement to 1 mm, the pressure's plateau 192.06 MPa (−0.02%); at 150 and
    180 MPa arlequin − mono: c equal, u_b −0.02% and −0.22%."""
    p0 = hill.cylinder_first_yield(A, B, NU, SY)
    limit = hill.cylinder_limit_load(A, B, SY)
    mono = run_pressure_vessel(shape="cylinder", model="mono", pressure=1.8e8, steps=6)
    arl = run_pressure_vessel(shape="cylinder", model="arlequin", pressure=1.8e8, steps=6)
    for r in (mono, arl):
        assert r.first_yield_pressure == pytest.approx(p0, rel=0.005)
    for i in (5, 6):  # 150 and 180 MPa
        for key in ("plastic_radius", "outer_displacement"):
            assert arl.history[key][i] == pytest.approx(mono.history[key][i], rel=0.005)
    pressed = run_pressure_vessel(shape="cylinder", model="mono", pressure=2.4e8, steps=12)
    assert pressed.limit_load_reached
    assert pressed.limit_load == pytest.approx(limit, rel=0.02)
    driven = run_pressure_vessel(shape="cylinder", model="mono", inner_displacement=1e-3)
    assert driven.history["pressure"][-1] == pytest.approx(limit, rel=0.01)
    assert driven.history["pressure"][-2] == pytest.approx(limit, rel=0.01)  # a plateau
    # item 5 wherever the tangent is regular (docs/quasi_static.md): every step of the runs to
    # 180 MPa and of the displacement-driven run (largest r_k+1 / r_k² below 1e-3 measured
    # 0.17 on mono); the pressure-driven steps beyond 180 MPa exceed the factor 10, as the
    # tangent turns singular at the limit point (C about 0.008 / its smallest eigenvalue
    # relative to the elastic one: 180 at 4.9e-5, 192.09 MPa): not asserted
    pressed_regular = [
        res
        for p, res in zip(pressed.history["pressure"], pressed.history["residuals"])
        if p <= 1.8e8 * (1.0 + 1e-9)
    ]
    for residuals in (mono.history["residuals"], arl.history["residuals"],
                      driven.history["residuals"], pressed_regular):  # fmt: skip
        for res in residuals:
            for r0, r1 in itertools.pairwise(res):
                if r0 < 1e-3 and r1 > 1e-10:
                    assert r1 <= 10.0 * r0**2, res


@pytest.mark.slow
def test_sphere_eighth_in_hexahedra_against_hill():
    """The 3D eighth of the sphere on hexahedra (issue 29 item 3, the benchmark's case), one
    J2 mesh of 16 cells across the wall (41,667 dofs): u_b within 1% of Hill's at 300 MPa
    (measured −0.48%; the plastic front −0.95%)."""
    r = run_pressure_vessel(dim=3, model="mono", coarse_size=0.025, fine_size=0.00625)
    ub = hill.sphere_outer_displacement(300e6, A, B, E, NU, SY)
    assert r.history["outer_displacement"][-1] == pytest.approx(ub, rel=0.01)


def test_3d_pictures_draw_the_symmetry_plane():
    """A 3D mesh is drawn by its boundary faces on z = 0: for the octant with n = 2 and two
    shells, the plane's arc from x to y is cut in 2n = 4 segments, so 4 × 2 = 8 quadrilaterals;
    their areas (shoelace, vertices in order around each face) sum to the quarter annulus
    π (b² − a²)/4 less the chords' segments: exactly Σ ½ (r₂² − r₁²) sin Δθ over the
    straight-sided cells, from the arc's node angles."""
    import skfem

    from arlequin.demos.pressure_vessel.meshes_3d import octant_sphere_mesh
    from arlequin.demos.pressure_vessel.report import plane_polygons

    a, b = 0.1, 0.2
    mesh = octant_sphere_mesh(a, b, 2, 2)
    polys, cells = plane_polygons(mesh)
    assert polys.shape == (8, 4, 2) and cells.shape == (8,)
    x, y = polys[..., 0], polys[..., 1]
    area = 0.5 * (x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y).sum(axis=1)
    assert np.all(np.abs(area) > 0.0)
    on_arc = np.abs(np.hypot(mesh.p[0], mesh.p[1]) - a) < 1e-12 * b
    theta = np.sort(np.arctan2(mesh.p[1], mesh.p[0])[on_arc & (np.abs(mesh.p[2]) < 1e-15)])
    exact = 0.5 * (b**2 - a**2) * np.sin(np.diff(theta)).sum()
    assert np.abs(area).sum() == pytest.approx(exact, rel=1e-12)
    # the cell of each face touches z = 0 with four nodes
    assert np.all((np.abs(mesh.p[2, mesh.t[:, cells]]) < 1e-15).sum(axis=0) == 4)
    # a plane mesh: its own cells
    polys2, cells2 = plane_polygons(skfem.MeshQuad())
    assert polys2.shape == (1, 4, 2) and list(cells2) == [0]


def test_any_failure_leaves_the_folder_failed_with_its_message(tmp_path, monkeypatch):
    """An exception the demo does not expect (here a picture that cannot be drawn) ends the
    folder's results.json with status "failed" and the error, not "running"."""
    from arlequin.cli.main import main
    from arlequin.demos.pressure_vessel import report

    def broken(*args, **kwargs):
        raise RuntimeError("no picture")

    monkeypatch.setattr(report, "plot_pressure_curve", broken)
    out = tmp_path / "run"
    argv = ["pressure-vessel", "--shape", "cylinder", "--pressure", "1.5e8", "--steps", "1",
            "--coarse-size", "0.025", "--fine-size", "0.0125", "--out", str(out),
            "--quiet"]  # fmt: skip
    assert main(argv) == 1
    meta = json.loads((out / "results.json").read_text())
    assert meta["status"] == "failed"
    assert meta["message"] == "RuntimeError: no picture"


@pytest.mark.slow
def test_3d_adaptive_run_draws_its_growths(tmp_path):
    """The new user's command (about 13 s): the 3D adaptive run draws patch_1.png at its first
    growth (it died there on a 3D PolyCollection), then stops at the patch's cap, the folder
    saying why."""
    from arlequin.cli.main import main

    out = tmp_path / "run"
    argv = ["pressure-vessel", "--dim", "3", "--adaptive", "--coarse-size", "0.025",
            "--fine-size", "0.0125", "--steps", "3", "--out", str(out), "--quiet"]  # fmt: skip
    assert main(argv) == 1
    assert (out / "patch_1.png").exists()
    meta = json.loads((out / "results.json").read_text())
    assert meta["status"] == "failed" and "max_fraction" in meta["message"]


@pytest.mark.parametrize("ratio", [2, 3, 5])
def test_adaptive_first_yield_from_the_run_itself(ratio):
    """Issue 42, part 2: the adaptive sphere's first yield read from its own last elastic
    state (on the patch grown by then), not from a probe patch: within 0.5% of Hill at
    b/a = 2, 3 and 5 (measured +0.29%, +0.33%, +0.26%; the probe on two rings gave +0.40%,
    +0.89%, +1.88%, the seed +1.7%, +3.1%, +5.0%). To 1.25 P0 in 5 steps: the first yield
    falls between the third and fourth."""
    b = A * ratio
    p0 = hill.sphere_first_yield(A, b, SY)
    r = run_pressure_vessel(model="arlequin", outer=b, adaptive=True, pressure=1.25 * p0,
                            steps=5)  # fmt: skip
    assert r.first_yield_pressure == pytest.approx(p0, rel=0.005)
    assert r.adaptations  # the patch grew before the first yield
    assert r.band_plastic_fraction == 0.0
