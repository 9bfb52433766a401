"""The plate-with-hole demo (arlequin.demos.plate_with_hole): Arlequin and the graded mesh
against the single fine mesh (issue 29, item 6), Newton, bad input, the command line.

A quarter of a plane-strain plate 20a × 20a with a hole of radius a, pulled past first yield
(S = 195 MPa: the plastic zone reaches 2.3a from the hole's centre), E = 210 GPa, ν = 0.3,
σy = 240 MPa, perfectly plastic. ``mono``, the whole coarse mesh refined ``levels`` times with
J2 everywhere, is the reference of the other two.
"""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from arlequin.demos.plate_with_hole import (
    HISTORY_KEYS,
    JSON_KEYS,
    PlateWithHoleConfig,
    run_plate_with_hole,
)


def _relative(run, ref, key: str, start: int) -> np.ndarray:
    """run / ref − 1 of a history key from state ``start`` on (0: unloaded, 1: first yield)."""
    return np.array(run.history[key][start:]) / np.array(ref.history[key][start:]) - 1.0


def test_coarse_mesh_is_quasi_uniform_and_conforming():
    """The coarse mesh: the hole's rings in [0, 2a]², cells of 2a / n_theta beyond, no hanging
    node (its only boundary facets are the plate's), every hole node on the circle."""
    from arlequin.demos.plate_with_hole.meshes import hole_nodes, plate_mesh

    a, w, n_theta, n_rings = 0.01, 0.1, 4, 4
    mesh, lines = plate_mesh(a, n_theta, n_rings, w, 2 * a)
    assert np.allclose(np.diff(lines), a / 2)
    grid = (len(lines) - 1) ** 2 - n_theta**2
    assert mesh.nelements == 2 * n_theta * n_rings + grid
    # the hole, the two symmetry lines (rings and grid) and the two outer edges
    n = len(lines) - 1  # grid cells along an outer edge; the symmetry lines: n - n_theta
    assert len(mesh.boundary_facets()) == 2 * n_theta + 2 * n + 2 * (n - n_theta + n_rings)
    assert np.allclose(np.linalg.norm(mesh.p[:, hole_nodes(mesh, a)], axis=0), a)


def test_graded_mesh_is_conforming_and_holds_the_patch():
    """The graded mesh has no hanging node (its only boundary facets are the plate's: the hole,
    the two symmetry lines and the two outer edges), and its first cells are the patch's."""
    from arlequin.demos.plate_with_hole.meshes import (
        graded_plate_mesh,
        plate_mesh,
        refine_projected,
        square_radius,
    )

    a, w, n_theta, n_rings, levels, r = 0.01, 0.1, 4, 4, 2, 0.035
    coarse, lines = plate_mesh(a, n_theta, n_rings, w, 2 * a)
    cells = np.nonzero(square_radius(coarse) <= r * (1 + 1e-12))[0]
    mesh, zone = graded_plate_mesh(coarse, lines, a, levels, cells)
    patch = refine_projected(coarse, levels, a, cells=cells)
    assert np.array_equal(zone, np.arange(patch.nelements))
    assert np.allclose(mesh.p[:, mesh.t[:, zone]], patch.p[:, patch.t])
    split = 2**levels
    fine_lines = 7 * split  # [0, 3.5a] in cells of a/2, each split
    coarse_lines = 13  # [3.5a, 10a]
    edge = fine_lines + coarse_lines  # cells along the outer edges
    axis = n_rings * split + 3 * split + coarse_lines  # along a symmetry line from the hole
    assert len(mesh.boundary_facets()) == 2 * n_theta * split + 2 * edge + 2 * axis
    assert mesh.nelements == patch.nelements + edge**2 - fine_lines**2


@pytest.fixture(scope="module")
def coarse_runs():
    """The default configuration at one level of refinement (0.7k-1.7k cells, under 2 s each)."""
    return {m: run_plate_with_hole(model=m, levels=1) for m in ("mono", "arlequin", "graded")}


def test_coarse_resolution_arlequin_and_graded_follow_mono(coarse_runs):
    """One level (16 fine cells along the quarter hole): measured against mono, the loaded
    edge's mean displacement within 0.093% (Arlequin; the coarse elastic plate's discretisation
    error outside the patch, largest at first yield and shrinking as the patch's plastic strain
    takes over) and 0.024% (graded) at every state; the final plastic area −1.29% (Arlequin)
    and 0.000% (graded), the plastic zone's extent equal (2.421a, the same quadrature point:
    nothing yields in the gluing band). Bounds: about twice those."""
    mono, arl, graded = coarse_runs["mono"], coarse_runs["arlequin"], coarse_runs["graded"]
    h = mono.history
    assert h["load"][-1] == pytest.approx(195e6, rel=1e-12)
    assert 2.0 < h["plastic_extent"][-1] / 0.01 < 3.0
    assert np.all(np.abs(_relative(arl, mono, "displacement", 1)) <= 0.002)
    assert np.all(np.abs(_relative(graded, mono, "displacement", 1)) <= 0.0005)
    assert arl.history["plastic_area"][-1] == pytest.approx(h["plastic_area"][-1], rel=0.05)
    assert graded.history["plastic_area"][-1] == pytest.approx(h["plastic_area"][-1], rel=0.015)
    for run in (arl, graded):
        assert run.history["plastic_extent"][-1] == pytest.approx(h["plastic_extent"][-1],
                                                                  rel=0.02)  # fmt: skip
        assert run.first_yield_load == pytest.approx(mono.first_yield_load, rel=0.005)
        assert set(JSON_KEYS) <= set(run.to_json()) and set(HISTORY_KEYS) == set(run.history)
        assert max(run.history["newton_iterations"]) <= 6
    # the J2 region's share of the plate: [0, 3.5a]² minus the hole, 11.5a² of 99.2a²
    assert 0.1 < arl.patch_fraction < 0.13 and mono.patch_fraction == 1.0


def test_assembled_tangent_is_the_derivative_of_the_assembled_force():
    """Issue 29, item 5's first suspect on the plate: the coupled tangent the quasi-static
    solver assembles (coarse plane-strain plate, J2 patch with B-bar weighted by α) equals the
    central difference of the assembled internal force at the converged plastic states, in
    the relative Frobenius norm on a random direction: measured 6e-11 to 1e-10 (h = 1e-6 ‖u‖)
    at the five plastic steps (2 to 147 yielding points), the roundoff of the difference; a
    tangent 1e-4 off gives 1e-4. Bound 1e-6: item 1's."""
    from arlequin.demos.plate_with_hole.setup import build
    from arlequin.solvers import QuasiStaticSolver

    setup = build(PlateWithHoleConfig(model="arlequin", levels=1))
    solver = QuasiStaticSolver(setup.problem.system(), load=1.0, steps=8)
    rng = np.random.default_rng(29)
    free, checked = solver.saddle.free, 0
    while solver.status == "running":
        committed = solver.states
        solver.step()
        yielding = solver.states[setup.plastic_block][setup.plastic_term].eqps > 0.0
        if not yielding.any():
            continue
        u = solver.u
        _, _, kt = solver.ops.internal_force(u, committed, tangent=True)
        d = np.zeros_like(u)
        d[free] = rng.standard_normal(free.size)
        d *= 1e-6 * np.linalg.norm(u) / np.linalg.norm(d)
        f_plus = solver.ops.internal_force(u + d, committed)[0]
        f_minus = solver.ops.internal_force(u - d, committed)[0]
        diff, exact = (f_plus - f_minus)[free] / 2.0, (kt @ d)[free]
        assert np.linalg.norm(diff - exact) <= 1e-6 * np.linalg.norm(exact), solver.t
        checked += 1
    assert checked == 5  # the steps past first yield (0.51 of 195 MPa): λ = 0.5 to 1


def _quadratic_failures(result) -> list[list[float]]:
    """The steps whose Newton residuals, once below 1e-3, do not each fall to at most 10 times
    the previous one squared (until 1e-10)."""
    bad = []
    for res in result.history["residuals"]:
        if any(r0 < 1e-3 and r1 > 1e-10 and r1 > 10.0 * r0**2
               for r0, r1 in itertools.pairwise(res)):  # fmt: skip
            bad.append(res)
    return bad


@pytest.mark.slow
def test_default_configuration_meets_item_6():
    """The default configuration (levels 3: 64 fine cells along the quarter hole; mono 26624
    cells): the load–displacement curve within 0.5% of mono at every state, the final plastic
    area within 3% (issue 29, item 6)."""
    runs = {m: run_plate_with_hole(model=m) for m in ("mono", "arlequin", "graded")}
    mono = runs["mono"]
    for model in ("arlequin", "graded"):
        run = runs[model]
        assert np.all(np.abs(_relative(run, mono, "displacement", 1)) <= 0.005), model
        area, ref = run.history["plastic_area"][-1], mono.history["plastic_area"][-1]
        assert area == pytest.approx(ref, rel=0.03), model


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="item 5 on the plate: J2 Newton is semismooth; below 1e-3, r_k+1 / r_k^2 reaches "
    "308 (mono) and 2319 (arlequin) in iterations where quadrature points of the plastic front "
    "(2e-5 to 7e-3 sigma_y from yield at the solution) cross the yield surface, against at "
    "most 4.9 and 10.9 where the plastic set stays fixed; the tangent is exact "
    "(test_assembled_tangent_is_the_derivative_of_the_assembled_force), the line search never "
    "cuts, hardening (E/1000 to E/10) leaves C over 10 (benchmarks/plate_with_hole.py: newton, "
    "newton_by_hardening; docs/plate_with_hole.md, Newton)",
)
def test_default_configuration_newton_quadratic():
    """Issue 29, item 5 on the plate's runs: once the relative residual is below 1e-3, each
    iteration at least squares it (up to a factor 10) until 1e-10. Expected to fail: the
    plastic set still changes below 1e-3 (the xfail's reason)."""
    for model in ("mono", "arlequin"):
        assert not _quadratic_failures(run_plate_with_hole(model=model)), model


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"load": 0.0}, "load"),
        ({"load": -1e8}, "load"),
        ({"steps": 0}, "steps"),
        ({"steps": 2.5}, "steps"),
        ({"levels": -1}, "levels"),
        ({"levels": 9}, "levels"),
        ({"yield_stress": 0.0}, "yield_stress"),
        ({"yield_stress": -1.0}, "yield_stress"),
        ({"hardening": -1e9}, "hardening"),
        ({"half_width": 0.05}, "half_width"),
        ({"patch_radius": 0.011}, "patch_radius"),
        ({"patch_radius": 0.2}, "patch_radius"),
        ({"edge_weight": 0.0}, "edge_weight"),
        ({"edge_weight": 1.5}, "edge_weight"),
        ({"model": "coarse"}, "model"),
        ({"poisson": 0.5}, "poisson"),
    ],
)
def test_bad_input_named_before_any_work(options, match):
    with pytest.raises(ValueError, match=match):
        PlateWithHoleConfig(**options)


def test_finite_strain_is_refused_without_its_tangent():
    from arlequin.models import FiniteStrainJ2

    if callable(getattr(FiniteStrainJ2, "tangent", None)):
        pytest.skip("FiniteStrainJ2 has its consistent tangent in this version")
    with pytest.raises(ValueError, match="finite-strain"):
        PlateWithHoleConfig(material="finite-strain")


def test_cli_writes_the_interface_json_and_a_results_folder(tmp_path, capsys):
    """The command's JSON has the Interface's keys (history: load, displacement,
    plastic_area); the folder its results.json (inputs with units), history.csv, one XDMF frame
    per step with ε̄p and σ_vm per cell, and the two pictures."""
    from arlequin.cli.main import main
    from arlequin.io import read_history, read_series

    out, js = tmp_path / "run", tmp_path / "plate.json"
    argv = ["plate-with-hole", "--model", "arlequin", "--material", "small-strain", "--load",
            "1.9e8", "--steps", "3", "--levels", "1", "--out", str(out), "--json", str(js),
            "--quiet"]  # fmt: skip
    assert main(argv) == 0
    data = json.loads(js.read_text())
    assert list(data)[: len(JSON_KEYS)] == list(JSON_KEYS)
    assert {"load", "displacement", "plastic_area"} <= set(data["history"])
    # the unloaded plate, first yield, three steps
    assert len(data["history"]["load"]) == 5
    assert data["history"]["load"][0] == 0.0 and data["history"]["load"][-1] == 1.9e8
    assert data["history"]["plastic_area"][1] == 0.0 < data["history"]["plastic_area"][-1]
    meta = json.loads((out / "results.json").read_text())
    assert meta["status"] == "complete"
    assert meta["inputs"]["load"] == {"value": 1.9e8, "unit": "Pa"}
    rows = read_history(out / "history.csv")
    assert len(rows["load_factor"]) == 4  # first yield (no frame), three steps
    _mesh, frames = read_series(out / "fields" / "patch0.xdmf")
    assert len(frames) == 3
    assert {"eqps", "von_mises", "alpha"} <= set(frames[-1][2])
    assert (out / "fields" / "coarse.xdmf").exists()
    assert (out / "load_displacement.png").exists() and (out / "plastic_zone.png").exists()
    assert "plate with a hole" in capsys.readouterr().out
