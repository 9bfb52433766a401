"""Adaptive patches in explicit runs (issue 31, the explicit half): ``solve(..., adapt=)``.

Measured on these set-ups (the figures in the comments of each test come from them):

* the patch test at rest under a uniform traction, the patch grown twice: the largest nodal
  error relative to the largest displacement 8.7e-15 at the records, 6.7e-15 after the
  growths, energy jumps −2.9e-15 and 4.8e-15 (2D; the issue's bound 1e-10); 3D alike;
* a 2D bar (16 × 4 coarse cells) whose first mode is struck (v_x = V sin(πx/2L), fixed at
  x = 0), the seed patch grown at steps 100 and 200: energy jumps −1.5e-4 and −1.4e-4 of the
  total energy (the issue's bound 1e-3), the largest drift between adaptations 9.8e-15 of the
  total energy against 9.4e-15 in the run with the final patch fixed (both round-off).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import skfem

import arlequin
from arlequin import AdaptivePatch, ArlequinProblem, Patch, PatchLimitError
from arlequin.adapt import IndicatorError, NonNestedPatchError
from arlequin.models import IsotropicElastic, J2Material, LinearElastic, SmallStrainJ2

E, NU, RHO, P = 200e9, 0.3, 7800.0, 1e8
L = 4.0


def _bar(box, nx: int = 8, sigma_y: float = 1e15, traction: bool = True):
    """A plane-strain bar [0, 4] × [0, 1] of nx × nx/4 coarse quadrilaterals, rollers on x = 0
    and y = 0, a J2 patch (elastic with the default σy) one level finer on the coarse cells
    whose centres lie in ``box``, glued over one coarse cell by a fine mediator; a uniform
    traction P on x = 4."""
    mesh = skfem.MeshQuad.init_tensor(np.linspace(0, L, nx + 1), np.linspace(0, 1, nx // 4 + 1))
    coarse = LinearElastic(mesh, IsotropicElastic(E, NU, RHO), "plane_strain")
    material = J2Material(E, NU, RHO, sigma_y, 0.0)
    patch = Patch.from_region(mesh, lambda m: SmallStrainJ2(m, material, "plane_strain"), 1,
                              box=box, gluing_width=L / nx, mediator="fine")  # fmt: skip
    problem = ArlequinProblem(coarse, [patch])
    problem.add_dirichlet("coarse", lambda x: np.isclose(x[0], 0.0), [0])
    problem.add_dirichlet("coarse", lambda x: np.isclose(x[1], 0.0), [1])
    if traction:
        problem.add_traction([P, 0.0], where=lambda x: np.isclose(x[0], L))
    return problem, mesh


def _nodal(problem, field) -> np.ndarray:
    """A vector of the problem's dofs from ``field(points (2, n)) -> (2, n)`` at every block's
    nodes."""
    system = problem.system()
    out = np.zeros(system.dofmap.n_dofs)
    for b in system.blocks:
        out[system.dofmap[b.name].slice] = field(b.model.mesh.p).T.ravel()
    return out


def _uniform(x: np.ndarray) -> np.ndarray:
    """The plane-strain displacement of σ_xx = P, the other stresses zero."""
    return np.vstack([(1 - NU**2) / E * P * x[0], -NU * (1 + NU) / E * P * x[1]])


def _grow_at(mesh, steps: dict[int, float]):
    """An indicator flagging the cells within ``steps[k]`` of x = 2 at step k."""
    cx = mesh.p[0, mesh.t].mean(axis=0)

    def indicator(view):
        reach = steps.get(view.step)
        return np.zeros(mesh.nelements, bool) if reach is None else np.abs(cx - 2.0) < reach

    return indicator


SEED = ((1.5, -1.0), (2.5, 2.0))


class _Errors:
    """The largest nodal error against the uniform solution, relative, at every record and
    after every growth."""

    def __init__(self):
        self.records, self.growths = [], []

    def error(self, integ) -> float:
        worst = 0.0
        for b in integ.system.blocks:
            u = integ.system.split(integ.u)[b.name].reshape(-1, 2).T
            exact = _uniform(b.model.mesh.p)
            worst = max(worst, float(np.abs(u - exact).max() / np.abs(exact).max()))
        return worst

    def __call__(self, integ) -> None:
        self.records.append(self.error(integ))

    def on_adapt(self, integ, adapt) -> None:
        self.growths.append(self.error(integ))


def test_explicit_patch_test_stays_exact_through_two_growths():
    """At rest in the uniform-stress state, the traction held: the coupled system is in
    equilibrium (the impulses cancel the unbalanced forces exactly), and the growths move
    the exact field exactly (nested patch: the coarse field is in the fine space)."""
    problem, mesh = _bar(SEED)
    adapt = AdaptivePatch(indicator=_grow_at(mesh, {10: 1.0, 20: 1.6}), buffer=0, every=10)
    errors = _Errors()
    res = arlequin.solve(problem, "explicit", n_steps=30, u0=_nodal(problem, _uniform),
                         adapt=adapt, on_record=[errors])  # fmt: skip
    assert res.status == 0 and res.n_steps == 30
    assert [a.step for a in res.adaptations] == [10, 20]
    assert res.adaptations[1].n_fine_elements > res.adaptations[0].n_fine_elements > 16
    assert len(errors.growths) == 2 and len(errors.records) == 31
    assert max(errors.growths + errors.records) <= 1e-10  # the bound; round-off
    assert all(abs(a.energy_jump) <= 1e-10 for a in res.adaptations)
    assert res.max_coarse_yield_ratio < 1e-6  # σy = 1e15 Pa
    assert res.problem is adapt.problem and len(res.times) == 31


def test_explicit_patch_test_stays_exact_through_two_growths_3d():
    """The same in 3D: a bar [0, 4] × [0, 1] × [0, 1] of 8 × 2 × 2 hexahedra, rollers on the
    planes x_i = 0, uniaxial stress P; the patch (one level finer, fine mediator) grown twice."""
    mesh = skfem.MeshHex.init_tensor(np.linspace(0, L, 9), np.linspace(0, 1, 3),
                                     np.linspace(0, 1, 3))  # fmt: skip
    coarse = LinearElastic(mesh, IsotropicElastic(E, NU, RHO), "3d")
    material = J2Material(E, NU, RHO, 1e15, 0.0)
    patch = Patch.from_region(mesh, lambda m: SmallStrainJ2(m, material, "3d"), 1,
                              box=((1.5, -1, -1), (2.5, 2, 2)), gluing_width=0.5,
                              mediator="fine")  # fmt: skip
    problem = ArlequinProblem(coarse, [patch])
    for i in range(3):
        problem.add_dirichlet("coarse", lambda x, i=i: np.isclose(x[i], 0.0), [i])
    problem.add_traction([P, 0.0, 0.0], where=lambda x: np.isclose(x[0], L))

    def exact(x):  # uniaxial: σ_xx = P, the others zero
        return np.vstack([P / E * x[0], -NU * P / E * x[1], -NU * P / E * x[2]])

    system = problem.system()
    u0 = np.zeros(system.dofmap.n_dofs)
    for b in system.blocks:
        u0[system.dofmap[b.name].slice] = exact(b.model.mesh.p).T.ravel()
    worst = []

    def error(integ, *_):
        for b in integ.system.blocks:
            u = integ.system.split(integ.u)[b.name].reshape(-1, 3).T
            ref = exact(b.model.mesh.p)
            worst.append(float(np.abs(u - ref).max() / np.abs(ref).max()))

    error.on_adapt = error
    adapt = AdaptivePatch(indicator=_grow_at(mesh, {5: 1.0, 10: 1.6}), buffer=0, every=5)
    res = arlequin.solve(problem, "explicit", n_steps=15, u0=u0, adapt=adapt, on_record=[error])
    assert [a.step for a in res.adaptations] == [5, 10]
    assert max(worst) <= 1e-10, max(worst)  # the bound; round-off
    assert all(abs(a.energy_jump) <= 1e-10 for a in res.adaptations)


def _struck(nx: int = 16):
    problem, mesh = _bar(SEED, nx, traction=False)

    def mode(x):  # the first mode of the bar fixed at x = 0, 1 m/s at the free end
        return np.vstack([np.sin(np.pi * x[0] / (2 * L)), np.zeros_like(x[0])])

    return problem, mesh, mode


def _total(res) -> np.ndarray:
    return sum(res.kinetic[n] + res.strain[n] for n in res.kinetic)


def test_explicit_energy_jump_and_drift_of_a_growing_patch():
    """Must-show 2. The jump: the lumped masses of the new fine nodes carry the coarse
    velocity's kinetic energy to O(h²), and the old band's fields, where fine and coarse
    differed, weigh 1 (measured −1.5e-4 and −1.4e-4 of the total energy); the drift between
    adaptations is round-off, as with the final patch fixed (the scheme's energy form closes
    to round-off on linear systems)."""
    problem, mesh, mode = _struck()
    adapt = AdaptivePatch(indicator=_grow_at(mesh, {100: 0.8, 200: 1.1}), buffer=0, every=50)
    res = arlequin.solve(problem, "explicit", n_steps=400, v0=_nodal(problem, mode), adapt=adapt)
    assert [a.step for a in res.adaptations] == [100, 200]
    jumps = [a.energy_jump for a in res.adaptations]
    assert all(abs(j) <= 1e-3 for j in jumps), jumps  # the bound
    total = _total(res)
    # the records at steps 100 and 200 are before the growths: the drift within each interval
    drift = max(float(np.ptp(total[a:b])) / total[a] for a, b in ((0, 101), (101, 201),
                                                                   (201, 401)))  # fmt: skip
    final = ((0.9, -1.0), (3.1, 2.0))  # the grown patch: cells within 1.1 of x = 2
    fixed_problem, _ = _bar(final, 16, traction=False)
    assert fixed_problem.patches[0].model.mesh.nelements == res.adaptations[-1].n_fine_elements
    fixed = arlequin.solve(fixed_problem, "explicit", n_steps=400,
                           v0=_nodal(fixed_problem, mode))  # fmt: skip
    fixed_drift = float(np.ptp(_total(fixed))) / _total(fixed)[0]
    # both at round-off (measured 9.8e-15 and 9.4e-15)
    assert drift <= 1e-12 and fixed_drift <= 1e-12, (drift, fixed_drift)
    # the histories continue across the growths: one record a step, times increasing
    assert len(res.times) == 401 and np.all(np.diff(res.times) > 0)
    assert res.multipliers["coupling:patch0"].shape[0] == 401


def test_explicit_interval_above_yield_is_computed_again():
    """σy = 40 MPa: the struck bar's coarse stress reaches β σy outside the seed by step 200
    (a growth), then exceeds σy in the interval that follows: that interval is rejected (three
    times, measured), the patch grows from the committed state (step 200) and the interval is
    computed again; the coarse model stays below yield at every accepted check (measured
    largest σ_vm/σy 0.89)."""
    problem, _ = _bar(SEED, 16, sigma_y=4e7, traction=False)
    _, _, mode = _struck()
    adapt = AdaptivePatch(threshold=0.8, buffer=1, every=50, max_fraction=1.0)
    res = arlequin.solve(problem, "explicit", n_steps=300, v0=_nodal(problem, mode), adapt=adapt)
    assert res.status == 0 and res.n_steps == 300
    assert any(a.rejected for a in res.adaptations)
    assert 0.0 < res.max_coarse_yield_ratio <= 1.0
    assert len(res.times) == 301 and np.all(np.diff(res.times) > 0)
    for a in res.adaptations:
        assert a.step % 50 == 0


class _Steps:
    """A listener keeping every step's time and displacement norm, rewound with the run."""

    def __init__(self):
        self.times, self.norms, self.rewinds = [], [], 0

    def __call__(self, integ) -> None:
        self.times.append(integ.t)
        self.norms.append(float(np.linalg.norm(integ.u)))

    def on_rewind(self, integ) -> None:
        self.rewinds += 1
        keep = int(np.searchsorted(self.times, integ.t, side="right"))
        del self.times[keep:], self.norms[keep:]


def test_explicit_rejected_interval_rewinds_the_listeners(tmp_path):
    """The set-up of the previous test (three rejected intervals, measured): the listeners are
    told of each (``on_rewind``) before the growth, so that after the run a per-step listener's
    records and a results folder's history and frames are the committed trajectory's, the same
    as the solver's result (no time twice, times increasing)."""
    from arlequin.io import DynamicRunWriter, ResultsFolder, read_history, read_series

    problem, _ = _bar(SEED, 16, sigma_y=4e7, traction=False)
    _, _, mode = _struck()
    adapt = AdaptivePatch(threshold=0.8, buffer=1, every=50, max_fraction=1.0)
    steps = _Steps()
    folder = ResultsFolder(tmp_path, "test", {})
    frames = np.linspace(0.0, 300 * 2.2e-5, 31)[1:]  # every ~10 steps (dt ≈ 1.9e-5 s measured)
    writer = DynamicRunWriter(folder, problem.system(), layout=problem.field_layout(),
                              frame_times=frames)  # fmt: skip
    res = arlequin.solve(problem, "explicit", n_steps=300, v0=_nodal(problem, mode), adapt=adapt,
                         on_step=[steps], on_record=[writer])  # fmt: skip
    folder.finish()
    n_rejected = sum(a.rejected for a in res.adaptations)
    assert n_rejected >= 1 and steps.rewinds == n_rejected
    # the per-step listener: steps 1 to 300 of the committed run, the result's records
    assert len(steps.times) == 300 and np.all(np.diff(steps.times) > 0)
    np.testing.assert_array_equal(steps.times, res.times[1:])
    # the history file: one row per record of the result
    history = read_history(tmp_path / "history.csv")
    np.testing.assert_array_equal(history["t"], res.times)
    np.testing.assert_array_equal(history["step"], np.arange(301))
    # the frames of every series of the patch and the coarse model: each frame time once, in
    # order, and the frames of the coarse series at the first record at or after each time
    written = []
    for path in sorted((tmp_path / "fields").glob("patch0*.xdmf")):
        written += [t for t, _, _ in read_series(path)[1]]
    assert np.all(np.diff(written) > 0)
    coarse = [t for t, _, _ in read_series(tmp_path / "fields" / "coarse.xdmf")[1]]
    times = np.asarray(res.times)
    expected = [times[np.searchsorted(times, f * (1 - 1e-12))] for f in frames if f <= times[-1]]
    np.testing.assert_array_equal(coarse, np.unique(expected))
    assert writer.frames_written == coarse
    # no series left without frames by a rejected interval (measured before the fix: three
    # of the five patch series were empty and listed in results.json); results.json lists the
    # files on disk, and no HDF5 file is left without its XDMF file
    listed = json.loads((tmp_path / "results.json").read_text())["files"]["fields"]
    on_disk = sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.glob("fields/*.xdmf"))
    assert sorted(listed.values()) == on_disk
    assert all(read_series(tmp_path / rel)[1] for rel in on_disk)
    assert sorted(p.stem for p in tmp_path.glob("fields/*.h5")) == sorted(
        p.stem for p in tmp_path.glob("fields/*.xdmf")
    )


def test_explicit_checks_every_interval_of_simulated_time():
    """``interval`` (s) instead of ``every``: with a fixed step, checks every 50 steps' time,
    the growth at the same step as with ``every=50``."""
    problem, mesh, mode = _struck()
    dt = 1.5e-5  # s, below the critical step (2.1e-5 s)
    adapt = AdaptivePatch(indicator=_grow_at(mesh, {100: 0.8}), buffer=0, interval=50 * dt)
    seen = []
    adapt_assess = adapt.assess

    def assess(solver, step, due=None):
        seen.append(step)
        return adapt_assess(solver, step, due)

    adapt.assess = assess
    res = arlequin.solve(problem, "explicit", dt=dt, n_steps=160, v0=_nodal(problem, mode),
                         adapt=adapt)  # fmt: skip
    assert seen == [0, 50, 100, 150, 160]  # the initial state, every 50 steps and the last
    assert [a.step for a in res.adaptations] == [100]
    assert res.adaptations[0].time == pytest.approx(100 * dt, rel=1e-12)


def test_explicit_growths_in_a_results_folder(tmp_path):
    """A results folder follows the growths: the grown patch's frames in a new series (only
    for growths followed by a frame), the history's balance moved by each growth's energy
    change (round-off again: the struck bar's balance closes on linear systems)."""
    from arlequin.io import DynamicRunWriter, ResultsFolder, read_history, read_series

    problem, mesh, mode = _struck()
    adapt = AdaptivePatch(indicator=_grow_at(mesh, {100: 0.8, 120: 1.1}), buffer=0, every=20)
    folder = ResultsFolder(tmp_path, "test", {})
    writer = DynamicRunWriter(folder, problem.system(), layout=problem.field_layout(),
                              frame_times=[5e-4, 3e-3])  # fmt: skip
    res = arlequin.solve(problem, "explicit", n_steps=200, v0=_nodal(problem, mode),
                         adapt=adapt, on_record=[writer])  # fmt: skip
    folder.finish()
    assert [a.step for a in res.adaptations] == [100, 120]
    names = sorted(p.stem for p in (tmp_path / "fields").glob("patch0*.xdmf"))
    assert names == ["patch0", "patch0_2"]  # no frame between the two growths
    _, frames = read_series(tmp_path / "fields" / "patch0_2.xdmf")
    assert len(frames) == 1
    history = read_history(tmp_path / "history.csv")
    scale = max(np.abs(history["energy"]))
    assert np.abs(history["balance"]).max() <= 1e-12 * scale


@pytest.mark.filterwarnings("ignore::arlequin.ExactnessWarning")
def test_explicit_non_nested_patch_is_refused_before_any_step():
    mesh = skfem.MeshTri.init_tensor(np.linspace(0, 4, 9), np.linspace(0, 2, 5))
    grid = skfem.MeshTri.init_tensor(np.linspace(1.3, 2.7, 6), np.linspace(0.3, 1.7, 6))
    coarse = LinearElastic(mesh, IsotropicElastic(E, NU, RHO), "plane_strain")
    material = J2Material(E, NU, RHO, 1e15, 0.0)
    problem = ArlequinProblem(coarse, [Patch(SmallStrainJ2(grid, material), gluing_width=0.3)])
    problem.add_dirichlet("coarse", lambda x: np.isclose(x[0], 0.0))
    with pytest.raises(NonNestedPatchError, match="nested"):
        arlequin.solve(problem, "explicit", n_steps=5, adapt=AdaptivePatch())


def test_explicit_indicator_of_the_wrong_shape_is_refused_at_the_initial_state():
    problem, mesh = _bar(SEED)
    adapt = AdaptivePatch(indicator=lambda view: np.zeros(mesh.nelements + 1, dtype=bool))
    with pytest.raises(IndicatorError, match=f"shape \\({mesh.nelements},\\)") as info:
        arlequin.solve(problem, "explicit", n_steps=5, adapt=adapt)
    assert info.value.result.n_steps == 0 and len(info.value.result.times) == 1


def test_explicit_cap_stops_the_run_with_every_step_kept():
    problem, mesh = _bar(SEED)
    adapt = AdaptivePatch(indicator=_grow_at(mesh, {10: 1.0, 20: 1.6}), buffer=0, every=10,
                          max_fraction=0.5)  # fmt: skip
    with pytest.raises(PatchLimitError, match="max_fraction") as info:
        arlequin.solve(problem, "explicit", n_steps=30, u0=_nodal(problem, _uniform),
                       adapt=adapt)  # fmt: skip
    res = info.value.result
    assert info.value.step == 20 and res.status == -1
    # the first growth (to 0.5 of the mesh) made, the second (0.75) refused; 20 steps kept
    assert [a.patch_fraction for a in res.adaptations] == pytest.approx([0.5])
    assert res.n_steps == 20 and len(res.times) == 21


def test_explicit_adaptation_refuses_extra_constraints_and_checkpoints():
    problem, _ = _bar(SEED)
    with pytest.raises(ValueError, match="constraints"):
        arlequin.solve(problem, "explicit", n_steps=5, adapt=AdaptivePatch(),
                       constraints=[object()])  # fmt: skip
    with pytest.raises(ValueError, match="restore"):
        arlequin.solve(problem, "explicit", n_steps=5, adapt=AdaptivePatch(),
                       restore=(None, None))  # fmt: skip
    with pytest.raises(ValueError, match="interval"):
        AdaptivePatch(interval=-1.0)


def test_explicit_adaptation_of_one_body_of_a_multi_body_problem():
    """Two struck bars side by side in one system, the second's patch adapting
    (BodyAdaptation): the first body's fields go through the growths untouched (its blocks
    are the same dofs, before the grown body's), the second's jump as in the one-body run."""
    from arlequin.adapt import BodyAdaptation
    from arlequin.problem.bodies import MultiBodyProblem

    first, _, mode = _struck()
    second, mesh, _ = _struck()
    bodies = MultiBodyProblem({"a": first, "b": second})
    v0 = np.concatenate([_nodal(first, mode), _nodal(second, mode)])
    adapt = BodyAdaptation(AdaptivePatch(indicator=_grow_at(mesh, {100: 0.8}), buffer=0,
                                         every=50), "b")  # fmt: skip
    dt = 1.5e-5  # s, below both systems' critical steps (2.1e-5 s): the same steps
    res = arlequin.solve(bodies, "explicit", dt=dt, n_steps=150, v0=v0, adapt=adapt)
    alone = arlequin.solve(first, "explicit", dt=dt, n_steps=150, v0=_nodal(first, mode))
    assert [a.step for a in res.adaptations] == [100]
    assert abs(res.adaptations[0].energy_jump) <= 1e-3  # one body of two: half the 1.5e-4
    assert res.problem is adapt.problem and res.problem.bodies["b"] is adapt.body_problem
    n = alone.u.size  # body "a" first: the same steps as alone, to round-off
    for got, ref in ((res.u[:n], alone.u), (res.v[:n], alone.v)):
        assert np.abs(got - ref).max() <= 1e-10 * np.abs(ref).max()
    # the growth kept body "a"'s system: its operators and its own critical step computed
    # once (the same objects in the grown problem's system), those of "b" computed again
    before, after = bodies.system(), res.problem.system()
    assert res.problem.body_systems()["a"] is bodies.body_systems()["a"]
    for name in ("a.coarse", "a.patch0"):
        assert after.block_stiffness(after.block(name)) is before.block_stiffness(
            before.block(name))  # fmt: skip
        assert after.block_mass(after.block(name)) is before.block_mass(before.block(name))
    assert after.block_mass(after.block("b.coarse")) is not before.block_mass(
        before.block("b.coarse"))  # fmt: skip
    fresh = MultiBodyProblem(dict(res.problem.bodies)).system()
    for b in after.blocks:  # what is shared is what would be computed
        diff = after.block_stiffness(b) - fresh.block_stiffness(fresh.block(b.name))
        assert abs(diff).max() == 0.0


# -- the ball impact, adaptive (arlequin ball-impact --regime plastic --adaptive) --------------
BALL = {"regime": "plastic", "block_radius": 0.02, "block_height": 0.02,
        "coarse_size": 0.25 * np.pi * 0.01 / 20}  # fmt: skip


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"adaptive": True}, "regime"),  # the elastic regime's block patch has no J2 states
        ({"adaptive": True, "regime": "plastic", "model": "mono"}, "model"),
        ({"adaptive": True, "regime": "plastic", "block_patch_size": 0.008}, "block_patch_size"),
        ({"adapt_threshold": 0.0}, "adapt_threshold"),
        ({"adapt_threshold": 1.5}, "adapt_threshold"),
        ({"adapt_buffer": -1}, "adapt_buffer"),
        ({"adapt_every": 0}, "adapt_every"),
        ({"max_patch_fraction": 0.0}, "max_patch_fraction"),
    ],
)
def test_ball_impact_adaptive_bad_input_named(options, match):
    from arlequin.demos.ball_impact import BallImpactConfig

    with pytest.raises(ValueError, match=match):
        BallImpactConfig(**options).check()


@pytest.mark.slow
def test_ball_impact_adaptive_cap_stops_the_run_with_the_steps_on_disk(tmp_path):
    """The plastic set-up of test_ball_impact's plastic runs, adaptive, capped at 4% of the
    block: the patch grows from its seed, and the growth past 0.04 (the uncapped run's growth
    at step 500, from 0.038 to 0.041 of the block) stops the run with PatchLimitError; the
    folder is marked failed and keeps the history rows up to the check that stopped it
    (18 s)."""
    import json

    from arlequin.demos.ball_impact import run_ball_impact
    from arlequin.io import read_history

    with pytest.raises(PatchLimitError, match="max_fraction") as info:
        run_ball_impact(adaptive=True, max_patch_fraction=0.04, out=tmp_path, **BALL)
    err = info.value
    assert err.result is not None and err.result.n_steps == err.step
    assert err.result.adaptations and err.result.adaptations[-1].patch_fraction <= 0.04
    meta = json.loads((tmp_path / "results.json").read_text())
    assert meta["status"] == "failed" and "max_fraction" in meta["message"]
    # impact.csv: a row every t_end/1000 (1e-7 s here) up to the check that stopped the run
    t = read_history(tmp_path / "impact.csv")["t"]
    assert err.time * 0.98 <= t[-1] <= err.time


@pytest.mark.slow
def test_ball_impact_adaptive_against_the_uniform_mesh(tmp_path):
    """Must-show 5's accuracy (its cost is measured, not asserted: the figures in
    docs/adaptive.md): the plastic set-up of test_ball_impact's plastic runs, the block's patch
    grown from a seed of radius 0.4 R; dent, peak force and restitution within the issue's 2%
    of mono. Measured: peak 16108 N, restitution 0.4349, dent 0.1723 mm against mono's
    16028.5 N, 0.4353, 0.1716 mm (+0.50%, −0.08%, +0.46%; the fixed patch 16121 N, 0.4351,
    0.1724 mm); 13 growths, the largest energy jump 5.3e-5, the coarse block at most 0.47 σy
    outside the patch, no plastic flow in the gluing band."""
    import json

    from arlequin.cli.main import main
    from arlequin.demos.ball_impact import run_ball_impact

    js = tmp_path / "ball.json"
    argv = ["ball-impact", "--regime", "plastic", "--adaptive", "--block-radius", "0.02",
            "--block-height", "0.02", "--coarse-size", str(BALL["coarse_size"]), "--json",
            str(js), "--quiet"]  # fmt: skip
    assert main(argv) == 0
    adaptive = json.loads(js.read_text())
    mono = run_ball_impact(model="mono", **BALL)
    for key in ("peak_force", "restitution", "dent_depth"):
        assert adaptive[key] == pytest.approx(getattr(mono, key), rel=0.02)
    assert adaptive["adaptations"] and adaptive["max_coarse_yield_ratio"] < 1.0
    for growth in adaptive["adaptations"]:
        assert set(growth) >= {"step", "time", "n_fine_elements", "patch_fraction",
                               "energy_jump"}  # fmt: skip
        assert abs(growth["energy_jump"]) <= 1e-3
    assert adaptive["band_max_plastic_strain"] == 0.0


def test_ball_impact_adaptive_pictures_and_patch_history_on_disk(tmp_path):
    """The adaptive run's results folder (a tiny set-up: coarse π R/32, the seed 0.45 R,
    7 m/s, checked every 10 steps, capped at 9% of the block so that the cap stops it at
    11 µs, 5 s of CPU): ``patch_K.png`` after each growth, ``patch_size.png`` (kept when the
    cap stops the run), the patch's share per row of ``impact.csv`` following the growths,
    the grown patch's field series (opened by meshio) and each growth's timers."""
    from arlequin.demos.ball_impact import run_ball_impact
    from arlequin.io import read_history, read_series

    tiny = {**BALL, "coarse_size": 0.25 * np.pi * 0.01 / 8, "velocity": 7.0,
            "patch_size": 0.0045}  # fmt: skip
    with pytest.raises(PatchLimitError, match="max_fraction") as info:
        run_ball_impact(adaptive=True, adapt_every=10, max_patch_fraction=0.09, out=tmp_path,
                        **tiny)  # fmt: skip
    growths = info.value.result.adaptations
    # recorded (this set-up, 2026-12-04): growths at steps 50, 80, 100 to 0.0554, 0.0651,
    # 0.0747 of the block; the next (to 0.094, step 210) refused by the cap
    assert [g.step for g in growths] == [50, 80, 100]
    assert info.value.step == 210
    for k in range(1, len(growths) + 1):
        assert (tmp_path / f"patch_{k}.png").stat().st_size > 0
    assert not (tmp_path / f"patch_{len(growths) + 1}.png").exists()
    assert (tmp_path / "patch_size.png").stat().st_size > 0
    rows = read_history(tmp_path / "impact.csv")
    t, share = np.asarray(rows["t"]), np.asarray(rows["patch_fraction"])
    assert np.all(np.diff(share) >= 0.0)
    for g in growths:  # the rows before a growth show the patch before it, those after it
        assert np.all(share[t > g.time + 1e-12] >= g.patch_fraction - 1e-15)
        assert np.all(share[t <= g.time - 1e-12] < g.patch_fraction)
    assert share[-1] == growths[-1].patch_fraction
    # the one frame (t_end / 10 = 9.8 µs) after the third growth: its own series
    mesh, frames = read_series(tmp_path / "fields" / "block.patch_3.xdmf")
    assert len(frames) == 1 and frames[0][0] > growths[-1].time
    assert mesh.cells[0].data.shape[0] == growths[-1].n_fine_elements
    for g in growths:  # the explicit growths' timers, as the quasi-static ones
        assert g.wall_time_s > 0.0 and g.system_time_s > 0.0 and g.resolve_time_s > 0.0
        assert g.discarded_time_s == 0.0 and not g.rejected


def test_ball_impact_adaptive_rejected_interval_leaves_no_discarded_rows(tmp_path):
    """The coarser set-up of ``benchmarks/adaptive.py --case ball --size quick`` (coarse π R/32,
    seed 0.45 R, 3 m/s), checked every 400 steps at β = 1: the interval from step 400 to 800
    is rejected (measured) and computed again on the grown patch. ``impact.csv`` and the
    result's history then hold the committed rows only: every row after a growth carries the
    patch's share after it (without the rewind, 199 rows of the discarded interval kept the
    share before it, and the peak force was the discarded interval's, 4759.6 N against the
    committed 4744.9 N, measured)."""
    from arlequin.demos.ball_impact import run_ball_impact
    from arlequin.io import read_history

    quick = {"regime": "plastic", "block_radius": 0.02, "block_height": 0.02,
             "coarse_size": 0.25 * np.pi * 0.01 / 8, "velocity": 3.0,
             "patch_size": 0.0045}  # fmt: skip
    res = run_ball_impact(adaptive=True, adapt_every=400, adapt_threshold=1.0, out=tmp_path,
                          **quick)  # fmt: skip
    assert any(a["rejected"] for a in res.adaptations)
    rows = read_history(tmp_path / "impact.csv")
    t, share = np.asarray(rows["t"]), np.asarray(rows["patch_fraction"])
    assert np.all(np.diff(t) > 0)
    np.testing.assert_array_equal(t, res.history["t"])
    np.testing.assert_array_equal(rows["contact_force"], res.history["contact_force"])
    for a in res.adaptations:
        assert np.all(share[t > a["time"]] >= a["patch_fraction"])
    assert res.peak_force >= max(rows["contact_force"])


def test_ball_impact_adaptive_series_all_have_frames(tmp_path):
    """Issue 42: the quick ball checked every 50 steps grows its block's patch first at
    t = 7.95 µs (measured), before the run's first frame (t_end / 10 = 9.83 µs): the seed's
    fields/block.patch.xdmf, opened at the start, was left without any frame; every series
    listed now has frames, the block patch's with ε̄p."""
    import json

    import meshio

    from arlequin.demos.ball_impact import run_ball_impact

    quick = {"regime": "plastic", "block_radius": 0.02, "block_height": 0.02,
             "coarse_size": 0.25 * np.pi * 0.01 / 8, "velocity": 3.0,
             "patch_size": 0.0045}  # fmt: skip
    res = run_ball_impact(adaptive=True, adapt_every=50, out=tmp_path, **quick)
    assert res.adaptations[0]["time"] < res.t_end / 10
    listed = json.loads((tmp_path / "results.json").read_text())["files"]["fields"]
    assert sorted(listed.values()) == sorted(
        f"fields/{p.name}" for p in (tmp_path / "fields").glob("*.xdmf")
    )
    for name, rel in listed.items():
        with meshio.xdmf.TimeSeriesReader(tmp_path / rel) as reader:
            reader.read_points_cells()
            assert reader.num_steps > 0, rel
            _, _, cells = reader.read_data(reader.num_steps - 1)
        if name.startswith("block.patch"):
            assert "plastic_strain" in cells
