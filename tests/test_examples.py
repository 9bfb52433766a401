"""Examples double as tests: each exposes run(**params) -> dict."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def load(name: str):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("coupling", ["L2", "H1"])
def test_refined_patch_example(coupling):
    # uniform tension: the exact tip displacement 2 t (1 − ν²) / E (plane strain) is reproduced
    # (the configuration satisfies the exactness conditions: nested, ramp weights, straight band)
    out = load("refined_patch").run(n=4, levels=1, coupling=coupling)
    assert out["relative_error"] <= 1e-10
    assert out["residual"] <= 1e-12


def test_arlequin_taylor_bar_tutorial_is_the_demo():
    # the tutorial builds with the public API what run_taylor_bar(model="arlequin") builds:
    # the same steps and the same answer (to round-off)
    import warnings

    from arlequin.demos import run_taylor_bar

    out = load("arlequin_taylor_bar").run(fine_radial=4, t_end=6e-6)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        demo = run_taylor_bar(elements_radial=4, t_end=6e-6)
    assert out["n_steps"] == demo.n_steps
    assert out["final_length"] == pytest.approx(demo.final_length, rel=1e-12)
    assert out["mushroom_radius"] == pytest.approx(demo.mushroom_radius, rel=1e-12)


def test_taylor_bar_3d_tutorial_is_the_demo(tmp_path):
    # the 3D tutorial (its patch from a closed surface) builds with the public API what
    # run_taylor_bar(geometry="3d", patch_surface=...) builds: the same steps and answer
    from arlequin.demos import run_taylor_bar

    example = load("taylor_bar_3d")
    stl = tmp_path / "patch.stl"
    example.patch_box(0.5 * 32.4e-3).export(stl)
    out = example.run(fine_radial=8, t_end=2e-6, surface=str(stl))
    demo = run_taylor_bar(geometry="3d", elements_radial=8, t_end=2e-6, patch_surface=str(stl))
    assert out["n_steps"] == demo.n_steps
    assert out["fine_elements"] == demo.arlequin["fine_elements"]
    assert out["final_length"] == pytest.approx(demo.final_length, rel=1e-12)
    assert out["mushroom_radius"] == pytest.approx(demo.mushroom_radius, rel=1e-12)


def test_two_bars_example_runs_small(tmp_path):
    # the figures of docs/contact.md at a small size; the picture goes where it is asked to
    out = load("two_bars").run(elements=20, refinement=(20, 40), blocks=False,
                               plot=str(tmp_path / "two_bars.png"))  # fmt: skip
    assert set(out) >= {"bars", "wall", "energy_loss_vs_elements"}
    # the level-set interface velocity is exact (docs/contact.md: rms 1e-13 at 100 elements)
    assert out["bars"]["levelset-theta"]["velocity_rms_error"] < 1e-10
    assert (tmp_path / "two_bars.png").stat().st_size > 0


def test_pressure_sphere_tutorial_is_the_demo():
    # the tutorial builds with the public API what `arlequin pressure-vessel` builds (at a
    # coarse size here: 4 coarse rings, 2 levels, the patch over 3 rings): the same numbers
    from arlequin.demos.pressure_vessel import run_pressure_vessel

    out = load("pressure_sphere").run(coarse_cells=4, levels=2, patch_rings=3)
    demo = run_pressure_vessel(coarse_size=0.025, fine_size=0.00625, patch_outer=0.175)
    assert out["status"] == "completed"
    assert out["newton_iterations"] == demo.history["newton_iterations"][1:]
    assert out["outer_displacement"] == pytest.approx(
        demo.history["outer_displacement"][-1], rel=1e-10
    )


def test_j2_patch_on_a_user_mesh():
    # a J2 patch on a mesh read through meshio, past first yield: the tip deflection within 1%
    # of one J2 mesh refined everywhere (measured 0.60% at one level: the coarse mesh's own
    # bending error outside the patch, 0.93% on the elastic beam)
    out = load("j2_patch_on_my_mesh").run(levels=1)
    assert out["max_plastic_strain"] > 0.0
    assert out["tip_deflection"] == pytest.approx(out["tip_deflection_reference"], rel=0.01)
    assert out["n_elements"] < 0.5 * out["n_elements_reference"]


# every example is run by the suite: the guard fails when a new one is not
COVERED = {
    "j2_patch_on_my_mesh",
    "pressure_sphere",
    "refined_patch",
    "arlequin_taylor_bar",
    "two_bars",
    "plate_with_hole",
    "ball_on_block",
    "taylor_bar_3d",
}


def test_every_example_is_covered():
    names = {p.stem for p in EXAMPLES.glob("*.py")}
    assert names == COVERED, f"examples not run by the test suite: {sorted(names - COVERED)}"


def test_ball_on_block_tutorial_is_the_demo():
    # the tutorial builds with the public API what run_ball_impact builds at the same sizes:
    # the same steps and the same answer (to round-off)
    import math

    from arlequin.demos.ball_impact import run_ball_impact

    out = load("ball_on_block").run(n=20, levels=1)
    h_c = 0.25 * math.pi * 0.01 / 20
    demo = run_ball_impact(coarse_size=h_c, fine_size=h_c / 2)
    assert out["n_steps"] == demo.n_steps
    assert out["peak_force"] == pytest.approx(demo.peak_force, rel=1e-12)
    assert out["contact_duration"] == demo.contact_duration
    assert out["hertz_peak_force"] == pytest.approx(demo.hertz["hertz_peak_force"], rel=1e-12)


def test_ball_on_block_tutorial_plastic_patch_is_the_demo():
    # the copper block's J2 patch built with the public API: the demo's plastic regime at the
    # same sizes (R_B = H_B = 2 R), without multi-time-step (the tutorial has one step)
    import math

    from arlequin.demos.ball_impact import run_ball_impact

    out = load("ball_on_block").run(n=20, levels=1, plastic=True)
    h_c = 0.25 * math.pi * 0.01 / 20
    demo = run_ball_impact(regime="plastic", block_radius=0.02, block_height=0.02,
                           coarse_size=h_c, fine_size=h_c / 2, coarse_step_ratio=1)  # fmt: skip
    assert out["n_steps"] == demo.n_steps
    for key in ("peak_force", "dent_depth", "restitution", "max_plastic_strain"):
        assert out[key] == pytest.approx(getattr(demo, key), rel=1e-10), key
    assert out["contact_duration"] == demo.contact_duration
