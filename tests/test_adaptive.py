"""Adaptive patches (issue 31, quasi-static half): exactness of a growing nested patch under a
uniform stress, and bad input refused by name.

Measured (this file's set-ups): the 2D patch test's largest nodal error after each of its two
growths and at every step, relative to the largest displacement, 5e-16 to 2.6e-13 (the 3D
one 1.7e-15 to 3.7e-13); the bound is the issue's 1e-10. The stored energy jumps across the
growths 5e-16 and 6e-14 (3D: 3e-15, 1.5e-14), relative, each re-solve converged at once
the fields moved exactly.
"""

from __future__ import annotations

import numpy as np
import pytest
import skfem

from arlequin import AdaptivePatch, ArlequinProblem, Patch, PatchLimitError, solve_quasi_static
from arlequin.adapt import IndicatorError, NonNestedPatchError
from arlequin.models import IsotropicElastic, J2Material, LinearElastic, SmallStrainJ2

E, NU, RHO, P = 200e9, 0.3, 7800.0, 1e8


def _problem(dim: int, seed_box, mediator: str = "fine"):
    """A bar [0, 4] × [0, 2] (× [0, 2]) pulled by a uniform traction P on x = 4, rollers on the
    planes x_i = 0; an elastic J2 patch (σy huge) on the coarse cells whose centres lie in
    ``seed_box``, one level finer."""
    axes = [np.linspace(0, 4, 9)] + [np.linspace(0, 2, 5)] * (dim - 1)
    mesh = (skfem.MeshQuad if dim == 2 else skfem.MeshHex).init_tensor(*axes)
    kind = "plane_strain" if dim == 2 else "3d"
    coarse = LinearElastic(mesh, IsotropicElastic(E, NU, RHO), kind)
    material = J2Material(E, NU, RHO, 1e15, 0.0)
    patch = Patch.from_region(mesh, lambda m: SmallStrainJ2(m, material, kind), 1, box=seed_box,
                              gluing_width=0.25, mediator=mediator)  # fmt: skip
    problem = ArlequinProblem(coarse, [patch])
    for i in range(dim):
        problem.add_dirichlet("coarse", lambda x, i=i: np.isclose(x[i], 0.0), [i])
    problem.add_traction([P] + [0.0] * (dim - 1), where=lambda x: np.isclose(x[0], 4.0))
    return problem, mesh


def _exact(dim: int, x: np.ndarray, lam: float) -> np.ndarray:
    """The uniform-stress solution σ_xx = λP: plane strain in 2D, uniaxial in 3D."""
    if dim == 2:
        ex, et = (1 - NU**2) / E * P, -NU * (1 + NU) / E * P
    else:
        ex, et = P / E, -NU * P / E
    return lam * np.vstack([ex * x[0]] + [et * x[i] for i in range(1, dim)])


class _Errors:
    """The largest nodal error of every block relative to the largest displacement, after
    every accepted step and after every growth."""

    def __init__(self, dim: int):
        self.dim, self.steps, self.growths = dim, [], []

    def error(self, solver) -> float:
        worst = 0.0
        for b in solver.system.blocks:
            mesh = b.model.mesh
            u = solver.system.split(solver.u)[b.name].reshape(-1, self.dim).T
            exact = _exact(self.dim, mesh.p, solver.t)
            worst = max(worst, float(np.abs(u - exact).max() / np.abs(exact).max()))
        return worst

    def __call__(self, solver) -> None:
        self.steps.append(self.error(solver))

    def on_adapt(self, solver, adapt) -> None:
        self.growths.append(self.error(solver))


def _grow_twice(mesh, dim: int):
    """An indicator flagging a wider block of cells at steps 1 and 2 (none after)."""
    c = mesh.p[:, mesh.t].mean(axis=1)
    near = np.all(np.abs(c[1:] - 1.0) < 0.8, axis=0)

    def indicator(view):
        flags = np.zeros(mesh.nelements, dtype=bool)
        if view.step == 1:
            flags = (np.abs(c[0] - 2.0) < 0.8) & np.all(np.abs(c[1:] - 1.0) < 0.3, axis=0)
        elif view.step == 2:
            flags = (np.abs(c[0] - 2.0) < 0.8) & near
        return flags

    return indicator


@pytest.mark.parametrize("dim", [2, 3])
def test_patch_test_stays_exact_through_two_growths(dim):
    seed = ((1.6,) + (0.6,) * (dim - 1), (2.4,) + (1.4,) * (dim - 1))
    problem, mesh = _problem(dim, seed)
    errors = _Errors(dim)
    adapt = AdaptivePatch(indicator=_grow_twice(mesh, dim), buffer=0)
    result = solve_quasi_static(problem, load=1.0, steps=3, adapt=adapt, on_step=[errors])
    assert result.status == "completed"
    assert [a.step for a in result.adaptations] == [1, 2]
    n0 = 2**dim * 2 ** (dim - 1)  # the seed: 2 × 2 (× 2) coarse cells, one level finer
    assert result.adaptations[0].n_fine_elements > n0
    assert result.adaptations[1].n_fine_elements > result.adaptations[0].n_fine_elements
    assert len(errors.growths) == 2 and len(errors.steps) == 3
    # the bound; measured 5e-16 to 2.6e-13 (2D), 1.7e-15 to 3.7e-13 (3D)
    assert max(errors.growths + errors.steps) <= 1e-10, (errors.growths, errors.steps)
    for a in result.adaptations:  # the fields move exactly: no energy jump (measured <= 6e-14)
        assert abs(a.energy_jump) <= 1e-10
        assert a.newton_iterations <= 1  # measured 0: the least-squares multipliers balance
    assert result.max_coarse_yield_ratio < 1e-6  # σy = 1e15 Pa: the coarse model far below it


@pytest.mark.filterwarnings("ignore::arlequin.ExactnessWarning")
def test_a_non_nested_patch_is_refused():
    """Triangles, the patch's grid not aligned with the coarse one (an exact intersection)."""
    mesh = skfem.MeshTri.init_tensor(np.linspace(0, 4, 9), np.linspace(0, 2, 5))
    grid = skfem.MeshTri.init_tensor(np.linspace(1.3, 2.7, 6), np.linspace(0.3, 1.7, 6))
    coarse = LinearElastic(mesh, IsotropicElastic(E, NU, RHO), "plane_strain")
    material = J2Material(E, NU, RHO, 1e15, 0.0)
    problem = ArlequinProblem(coarse, [Patch(SmallStrainJ2(grid, material), gluing_width=0.3)])
    problem.add_dirichlet("coarse", lambda x: np.isclose(x[0], 0.0))
    with pytest.raises(NonNestedPatchError, match="nested"):
        solve_quasi_static(problem, steps=2, adapt=AdaptivePatch())


@pytest.mark.parametrize("beta", [0.0, -0.5, 1.5, float("nan")])
def test_a_threshold_outside_zero_one_is_refused(beta):
    with pytest.raises(ValueError, match="threshold"):
        AdaptivePatch(threshold=beta)


BAD = [("buffer", -1), ("every", 0), ("max_fraction", 0.0), ("max_fraction", 1.5),
       ("band_weight", -0.1), ("band_weight", 1.0)]  # fmt: skip


@pytest.mark.parametrize(("option", "value"), BAD)
def test_other_bad_options_are_refused(option, value):
    with pytest.raises(ValueError, match=option):
        AdaptivePatch(**{option: value})


def test_the_cap_stops_the_run_with_the_steps_kept():
    problem, mesh = _problem(2, ((1.6, 0.6), (2.4, 1.4)))
    adapt = AdaptivePatch(indicator=_grow_twice(mesh, 2), buffer=0, max_fraction=0.3)
    seen = []
    with pytest.raises(PatchLimitError, match="max_fraction") as info:
        solve_quasi_static(problem, steps=3, adapt=adapt, on_step=[lambda s: seen.append(s.t)])
    err = info.value
    assert err.step == 2
    # the first growth (to 0.25 of the mesh) made, the second (0.5) refused; both steps kept
    assert [a.patch_fraction for a in err.result.adaptations] == pytest.approx([0.25])
    assert len(err.result.steps) == 2 and seen == pytest.approx([1 / 3, 2 / 3])


def test_an_indicator_of_the_wrong_shape_is_refused():
    problem, mesh = _problem(2, ((1.6, 0.6), (2.4, 1.4)))
    adapt = AdaptivePatch(indicator=lambda view: np.zeros(mesh.nelements - 1, dtype=bool))
    with pytest.raises(IndicatorError, match=f"shape \\({mesh.nelements},\\)"):
        solve_quasi_static(problem, steps=2, adapt=adapt)


def test_an_indicator_of_non_boolean_flags_is_refused():
    """0.5 everywhere is not a flag: it would have grown every cell."""
    problem, mesh = _problem(2, ((1.6, 0.6), (2.4, 1.4)))
    adapt = AdaptivePatch(indicator=lambda view: np.full(mesh.nelements, 0.5))
    with pytest.raises(IndicatorError, match="boolean"):
        solve_quasi_static(problem, steps=2, adapt=adapt)


@pytest.mark.parametrize("value", [np.float32(0.8), np.float64(0.5), 1])
def test_a_threshold_given_as_any_real_number_is_taken(value):
    assert AdaptivePatch(threshold=value).threshold == pytest.approx(float(value))


@pytest.mark.parametrize(("option", "value"), [("max_fraction", "0.5"), ("max_fraction", None),
                                               ("threshold", "0.8")])  # fmt: skip
def test_options_of_the_wrong_type_are_named(option, value):
    with pytest.raises(ValueError, match=option):
        AdaptivePatch(**{option: value})


def test_adapt_that_is_not_an_adaptive_patch_is_named():
    problem, _ = _problem(2, ((1.6, 0.6), (2.4, 1.4)))
    with pytest.raises(ValueError, match="adapt must be an AdaptivePatch, got float"):
        solve_quasi_static(problem, steps=2, adapt=0.8)


def test_a_cap_below_the_seed_is_refused_before_any_step():
    """The seed (2 × 2 of the 8 × 4 coarse cells: 0.125 of the mesh) over a cap of 0.1."""
    problem, _ = _problem(2, ((1.6, 0.6), (2.4, 1.4)))
    seen = []
    with pytest.raises(ValueError, match=r"max_fraction=0\.1 is below .* \(0\.125\)"):
        solve_quasi_static(problem, steps=2, adapt=AdaptivePatch(max_fraction=0.1),
                           on_step=[lambda s: seen.append(s.t)])  # fmt: skip
    assert seen == []


def test_an_adaptive_patch_used_again_starts_afresh():
    """A second run with the same object reports its own growths, not the first run's too."""
    first, mesh = _problem(2, ((1.6, 0.6), (2.4, 1.4)))
    adapt = AdaptivePatch(indicator=_grow_twice(mesh, 2), buffer=0)
    one = solve_quasi_static(first, steps=3, adapt=adapt)
    n_first = len(one.adaptations)
    second, _ = _problem(2, ((1.6, 0.6), (2.4, 1.4)))
    never = AdaptivePatch(indicator=lambda view: np.zeros(mesh.nelements, dtype=bool))
    fresh = solve_quasi_static(second, steps=3, adapt=never)
    adapt.indicator = never.indicator
    again = solve_quasi_static(_problem(2, ((1.6, 0.6), (2.4, 1.4)))[0], steps=3, adapt=adapt)
    assert n_first == 2 and len(one.adaptations) == 2  # the first result keeps its own
    assert again.adaptations == [] == fresh.adaptations
    assert again.max_coarse_yield_ratio == pytest.approx(fresh.max_coarse_yield_ratio)


# -- the pressure sphere, adaptive (arlequin pressure-vessel --adaptive) -----------------------
SMALL = {"coarse_size": 0.025, "fine_size": 0.025 / 4, "pressure": 2e8, "steps": 5}


def test_adaptive_sphere_cli_json_series_and_history(tmp_path, capsys):
    """4 coarse rings, 200 MPa in 5 steps (c = 116 mm): the one-ring seed yields in its band
    at step 4, which is computed again on 3 rings (measured: energy jump 2.1e-2 at this
    resolution, coarse σ_vm/σy at most 0.35). The patch's frames go into a new series after
    the growth; the history has the patch's share at every step."""
    import json

    from arlequin.cli.main import main
    from arlequin.demos.adaptive_options import ADAPTATIONS_UNIT
    from arlequin.io import read_history, read_series

    out, js = tmp_path / "run", tmp_path / "pv.json"
    argv = ["pressure-vessel", "--adaptive", "--pressure", "2e8", "--steps", "5",
            "--coarse-size", "0.025", "--fine-size", "0.00625", "--out", str(out), "--json",
            str(js), "--quiet"]  # fmt: skip
    assert main(argv) == 0
    data = json.loads(js.read_text())
    (growth,) = data["adaptations"]
    assert set(growth) >= {"step", "time", "n_fine_elements", "patch_fraction", "energy_jump"}
    assert (
        growth["step"] == 4 and growth["n_fine_elements"] == 3 * 9 * 16
    )  # 3 rings of 9 cells, 16 fine each
    assert 0.0 < data["max_coarse_yield_ratio"] < 1.0
    fractions = data["history"]["patch_fraction"]
    assert len(fractions) == 6 and fractions[-1] == pytest.approx(data["patch_fraction"])
    assert fractions[3] < fractions[4]  # steps 1-3 on the seed, 4-5 on the grown patch
    # one measure for the history and the growth's record (the coarse cells covered: before,
    # the history's was the patch mesh's own area, 0.2% below the record's on a curved bore)
    assert fractions[4] == growth["patch_fraction"]
    _, before = read_series(out / "fields" / "patch0.xdmf")
    mesh, after = read_series(out / "fields" / "patch0_1.xdmf")
    assert len(before) == 3 and len(after) == 2 and "eqps" in after[-1][2]
    assert len(mesh.points) > 0
    assert len(read_history(out / "history.csv")["load_factor"]) == 5
    assert (out / "patch_1.png").exists() and (out / "patch_size.png").exists()
    meta = json.loads((out / "results.json").read_text())
    assert meta["results"]["adaptations"]["unit"] == ADAPTATIONS_UNIT
    summary = capsys.readouterr().out
    assert "the patch grew 1 times to" in summary and "coarse σ_vm/σy ≤ 0.3" in summary


def test_growth_titles_say_the_load_and_a_rejected_step():
    """patch_K.png's title: the growth, the load it grew at, a rejected step, the share."""
    from arlequin.demos.adaptive_options import growth_title

    title = growth_title(2, "P = 120 MPa (step 4)", True, "0.688 of the wall")
    assert (
        title == "growth 2 at P = 120 MPa (step 4), after a rejected step\npatch: 0.688 of the wall"
    )
    assert "rejected" not in growth_title(1, "t = 3 µs", False, "0.1 of the block")


def test_adaptive_sphere_cap_stops_the_run_with_the_steps_on_disk(tmp_path):
    """A cap below the growth the plastic zone asks for (0.5 of the wall): PatchLimitError,
    the results folder marked failed with the three converged steps."""
    import json

    from arlequin.demos.pressure_vessel import run_pressure_vessel
    from arlequin.io import read_history

    with pytest.raises(PatchLimitError, match="max_fraction") as info:
        run_pressure_vessel(adaptive=True, max_patch_fraction=0.5, out=str(tmp_path), **SMALL)
    assert len(info.value.result.steps) == 3
    meta = json.loads((tmp_path / "results.json").read_text())
    assert meta["status"] == "failed"
    assert len(read_history(tmp_path / "history.csv")["load_factor"]) == 3
    # results.json: the unloaded vessel and the three steps (written after every step)
    assert len(meta["results"]["history"]["value"]["pressure"]) == 4


def test_adaptive_sphere_interrupted_keeps_every_step_on_disk(tmp_path):
    """Ctrl-C after the second converged step (raised by the progress callback): the folder
    marked interrupted, results.json with the unloaded vessel and the two steps."""
    import json

    from arlequin.demos.pressure_vessel import run_pressure_vessel

    calls = []

    def progress(fraction: float) -> None:
        calls.append(fraction)
        if len(calls) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_pressure_vessel(adaptive=True, out=str(tmp_path), progress=progress, **SMALL)
    meta = json.loads((tmp_path / "results.json").read_text())
    assert meta["status"] == "interrupted"
    assert len(meta["results"]["history"]["value"]["pressure"]) == 3


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"adaptive": True, "adapt_threshold": 0.0}, "adapt_threshold"),
        ({"adaptive": True, "adapt_threshold": 1.2}, "adapt_threshold"),
        ({"adaptive": True, "adapt_buffer": -1}, "adapt_buffer"),
        ({"adaptive": True, "adapt_every": 0}, "adapt_every"),
        ({"adaptive": True, "max_patch_fraction": 0.0}, "max_patch_fraction"),
        ({"adaptive": True, "model": "mono"}, "adaptive"),
        ({"adaptive": True, "patch_outer": 0.15}, "patch_outer"),
    ],
)
def test_adaptive_sphere_bad_input_named(options, match):
    from arlequin.demos.pressure_vessel import PressureVesselConfig

    with pytest.raises(ValueError, match=match):
        PressureVesselConfig(**options)


@pytest.mark.slow
def test_adaptive_sphere_matches_the_fixed_patch_at_the_default_resolution():
    """The issue's item 3: 64 fine cells across the wall, 300 MPa in 10 steps, from a one-ring
    seed. Measured: c 157.8138 mm (fixed 157.8137), u_b 78.1246 µm (fixed 78.1261: −0.002%),
    the coarse σ_vm/σy outside the patch at most 0.604, three growths (the first a rejected
    step) to the fixed patch's 7 rings; wall times (3 runs each) 6.9–11.5 s adaptive, 8.4–11.1 s
    fixed: T_adaptive / T_fixed 0.79 (medians). The bounds: the issue's 0.5%, σy, and its 1.3
    on the faster of two runs each (the machine's cores are shared: single runs vary by 60%)."""
    import time

    from arlequin.demos.pressure_vessel import run_pressure_vessel

    runs, times = {}, {True: [], False: []}
    for _ in range(2):
        for adaptive in (True, False):
            start = time.perf_counter()
            runs[adaptive] = run_pressure_vessel(adaptive=adaptive)
            times[adaptive].append(time.perf_counter() - start)
    a, f = runs[True], runs[False]
    for key in ("plastic_radius", "outer_displacement"):
        assert a.history[key][-1] == pytest.approx(f.history[key][-1], rel=0.005)
    assert a.max_coarse_yield_ratio < 1.0
    assert [g["step"] for g in a.adaptations] == [5, 7, 9]
    assert all(abs(g["energy_jump"]) < 1e-2 for g in a.adaptations)  # measured <= 4.3e-3
    assert a.patch_fraction == pytest.approx(f.patch_fraction)
    assert min(times[True]) <= 1.3 * min(times[False]), times


@pytest.mark.parametrize(("band_weight", "counted"), [(0.0, True), (0.5, False)])
def test_band_weight_disregards_plastic_points_of_the_bands_outer_part(band_weight, counted):
    """Plastic strain put at the patch's quadrature points where α_f < 1/2 (the band's outer
    half, by construction of the state, not by a run): counted by default (the step rejected,
    the cells beyond flagged), disregarded with ``band_weight=0.5`` (no flag, no rejection);
    the same strain where α_f ≥ 1/2 in the band is counted by both."""
    from types import SimpleNamespace

    from arlequin.adapt import AdaptView

    problem, mesh = _problem(2, ((1.4, 0.0), (2.6, 1.2)))
    adapt = AdaptivePatch(band_weight=band_weight)
    adapt.bind(problem)
    pc = adapt.problem.couplings[0]
    alpha = np.asarray(pc.alpha_fine)
    band = np.zeros(pc.fine_model.mesh.nelements, dtype=bool)
    band[pc.fine_gluing_cells] = True
    outside = np.ones(mesh.nelements, dtype=bool)
    outside[adapt.cells] = False

    def flags(where):
        state = SimpleNamespace(eqps=np.where(where, 1e-4, 0.0))
        view = AdaptView(1, 1.0, adapt.problem, None, None, state, adapt.cells,
                         np.zeros(mesh.nelements), 1e15)  # fmt: skip
        return adapt._band_flags(view, outside)

    outer = band[:, None] & (alpha < 0.5)
    assert outer.any() and (band[:, None] & (alpha >= 0.5)).any()
    near, in_band = flags(outer)
    assert in_band == counted and near.any() == counted
    near, in_band = flags(band[:, None] & (alpha >= 0.5))
    assert in_band and near.any()


def test_no_growth_after_the_last_step():
    """An indicator flagging one more coarse cell after every step: the patch grows after
    each step but the last (a growth prepares the next step; none follows the last), and the
    final patch is the one the last state was computed on."""
    problem, mesh = _problem(2, ((1.4, 0.0), (2.6, 1.2)))
    centres = mesh.p[:, mesh.t].mean(axis=1)

    def one_more(view):
        flags = np.zeros(mesh.nelements, dtype=bool)
        out = np.setdiff1d(np.arange(mesh.nelements), view.patch_cells)
        flags[out[np.argmin(np.hypot(centres[0, out] - 2.0, centres[1, out] - 0.5))]] = True
        return flags

    adapt = AdaptivePatch(indicator=one_more, buffer=0)
    result = solve_quasi_static(problem, steps=3, adapt=adapt)
    assert [r.step for r in result.adaptations] == [1, 2]
    assert result.problem.patches[0].model.mesh.nelements == 4 * adapt.cells.size


@pytest.mark.parametrize("command", ["pressure-vessel", "plate-with-hole", "ball-impact"])
@pytest.mark.parametrize(
    ("flag", "value", "name"),
    [("--adapt-threshold", "0.5", "adapt_threshold"), ("--adapt-buffer", "2", "adapt_buffer"),
     ("--adapt-every", "7", "adapt_every"), ("--max-patch-fraction", "0.3", "max_patch_fraction")],
)  # fmt: skip
def test_adaptive_settings_without_adaptive_are_refused(command, flag, value, name, capsys):
    """A setting of the growing patch given without --adaptive was silently ignored: now
    refused (exit 2) naming the option and its value; its default given explicitly is not."""
    import dataclasses

    from arlequin.cli.main import main
    from arlequin.demos.ball_impact import BallImpactConfig
    from arlequin.demos.plate_with_hole import PlateWithHoleConfig
    from arlequin.demos.pressure_vessel import PressureVesselConfig

    assert main([command, flag, value, "--quiet"]) == 2
    err = capsys.readouterr().err
    assert name in err and value in err and "--adaptive" in err
    config = {"pressure-vessel": PressureVesselConfig, "plate-with-hole": PlateWithHoleConfig,
              "ball-impact": BallImpactConfig}[command]  # fmt: skip
    default = {f.name: f.default for f in dataclasses.fields(config)}[name]
    config(**{name: default}).check()  # the default, given explicitly: accepted
