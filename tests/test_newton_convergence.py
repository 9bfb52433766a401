"""Newton's quadratic convergence in the quasi-static demos, read from their newton.csv, and the
quasi-static results folders' history.csv and newton.csv (issue 42, parts 3 and 5).

The criterion (docs/quasi_static.md, "Newton's convergence"): once the relative residual r_k
is below 1e-3, r_k+1 <= 10 r_k² on every iteration whose plastic set did not change (no
quadrature point crossed the yield surface in it nor in the next one), below the limit point.
Residuals at the round-off floor of the relative residual (measured about 1e-14; 1e-12 here)
are not rates. Measured on the main branch's defaults (coarse mediator): the largest
r_k+1 / r_k² is 0.84 on the sphere, 0.73 on the cylinder to 180 MPa (0.14 mono), 9.3 on the
plate.
"""

from __future__ import annotations

import json
from collections import defaultdict

import numpy as np
import pytest

from arlequin.demos.plate_with_hole import run_plate_with_hole
from arlequin.demos.pressure_vessel import run_pressure_vessel
from arlequin.io import read_history

#: The small configurations of tests/test_pressure_vessel.py and tests/test_plate_adaptive.py.
COARSE = {"coarse_size": 0.025, "fine_size": 0.00625}
SMALL_PLATE = {"levels": 1, "steps": 3}
#: Below it, a relative residual is round-off (the runs converge to about 1e-14).
FLOOR = 1e-12

CASES = {
    "sphere": (run_pressure_vessel, dict(COARSE)),
    "cylinder": (run_pressure_vessel, dict(shape="cylinder", pressure=1.8e8, steps=6, **COARSE)),
    "cylinder-mono": (
        run_pressure_vessel,
        dict(shape="cylinder", model="mono", pressure=1.8e8, steps=6, **COARSE),
    ),
    "plate": (run_plate_with_hole, dict(SMALL_PLATE)),
}

HISTORY_COLUMNS = ["step", "load_factor", "load_step", "newton_iterations", "cuts",
                   "first_residual", "last_residual", "crossings"]  # fmt: skip
NEWTON_COLUMNS = ["step", "load_factor", "iteration", "start_residual", "residual",
                  "equilibrium_residual", "constraint_residual", "line_search", "crossings",
                  "plastic_points"]  # fmt: skip


def _iterations(newton: dict[str, list]) -> dict[int, list[tuple[float, float, int]]]:
    """newton.csv's rows by step: (r_k, r_k+1, crossings) of each iteration, in order."""
    steps: dict[int, list[tuple[float, float, int]]] = defaultdict(list)
    for step, r0, r1, crossings in zip(newton["step"], newton["start_residual"],
                                       newton["residual"], newton["crossings"]):  # fmt: skip
        steps[int(step)].append((r0, r1, int(crossings)))
    return steps


def quadratic_violations(newton: dict[str, list], factor: float = 10.0) -> list[tuple]:
    """The iterations that break r_k+1 <= factor r_k² once r_k < 1e-3 with no crossing in
    them nor in the next iteration (above the round-off floor): (step, iteration, r_k,
    r_k+1)."""
    bad = []
    for step, its in _iterations(newton).items():
        for k, (r0, r1, crossings) in enumerate(its):
            following = its[k + 1][2] if k + 1 < len(its) else 0
            regular = crossings == 0 and following == 0
            if regular and r0 < 1e-3 and r1 > FLOOR and r1 > factor * r0**2:
                bad.append((step, k + 1, r0, r1))
    return bad


@pytest.mark.parametrize("case", list(CASES))
def test_newton_converges_quadratically_where_the_plastic_set_holds(case, tmp_path):
    """The sphere (300 MPa, below its limit load 332.7 MPa), the plane-strain cylinder to
    180 MPa (its limit load 192.1 MPa) and the plate: every regular iteration quadratic."""
    run, options = CASES[case]
    result = run(out=str(tmp_path), **options)
    newton = read_history(tmp_path / "newton.csv")
    assert newton["step"], "no Newton iteration written"
    bad = quadratic_violations(newton)
    assert not bad, (
        f"{case}: iterations slower than r_k+1 <= 10 r_k² with an unchanged plastic set "
        f"(step, iteration, r_k, r_k+1): {bad}. The relative residual is scaled by the "
        "largest of |f_ext|, the reactions and |Bᵀμ|: multipliers drifting along dependent "
        "constraint rows inflate that scale (docs/quasi_static.md)"
    )
    # one row an iteration, as many as the history's Newton iterations
    history = read_history(tmp_path / "history.csv")
    assert len(newton["step"]) == sum(int(n) for n in history["newton_iterations"])
    assert result.history["newton_iterations"][-1] == history["newton_iterations"][-1]


def test_the_criterion_flags_a_linear_rate():
    """The check itself: a linear rate below 1e-3 is flagged, a crossing exempts the
    iteration and the one before it, round-off is not a rate."""
    rows = {"step": [1, 1, 1, 2, 2, 2], "start_residual": [1e-2, 1e-4, 1e-6, 1e-4, 1e-5, 1e-6],
            "residual": [1e-4, 1e-6, 1e-13, 1e-5, 1e-6, 1e-7],
            "crossings": [0, 0, 0, 0, 4, 0]}  # fmt: skip
    # step 1: 1e-4 -> 1e-6 breaks 10 r², 1e-6 -> 1e-13 is round-off; step 2: the first two
    # iterations are exempt (a crossing in the second), the third is flagged
    assert quadratic_violations(rows) == [(1, 2, 1e-4, 1e-6), (2, 3, 1e-6, 1e-7)]


def _crossings(text) -> list[int]:
    """history.csv's per-iteration counts (read_history gives a lone count as a number)."""
    if isinstance(text, float):
        return [] if text != text else [int(text)]
    return [int(c) for c in text.split()]


def test_pressure_vessel_folder_has_history_and_newton_rows(tmp_path):
    """history.csv: one row a converged step (the result's history but the unloaded state),
    its measures equal to the result's; newton.csv: one row a Newton iteration; both listed
    in results.json with their units in the headers."""
    r = run_pressure_vessel(out=str(tmp_path), **COARSE)
    h = read_history(tmp_path / "history.csv")
    header = (tmp_path / "history.csv").read_text().splitlines()[0]
    assert "pressure [Pa]" in header and "outer_displacement [m]" in header
    assert set(HISTORY_COLUMNS) <= set(h)
    n_steps = len(r.history["pressure"]) - 1
    assert h["step"] == [float(k) for k in range(1, n_steps + 1)]
    for key in ("pressure", "plastic_radius", "outer_displacement", "inner_displacement"):
        assert h[key] == r.history[key][1:]
    assert h["newton_iterations"] == r.history["newton_iterations"][1:]
    assert [_crossings(c) for c in h["crossings"]] == [
        [c for s, c in zip(*_newton(tmp_path, "crossings")) if s == k] for k in h["step"]
    ]
    n = read_history(tmp_path / "newton.csv")
    assert list(n) == NEWTON_COLUMNS
    assert len(n["step"]) == sum(r.history["newton_iterations"])
    assert max(n["crossings"]) > 0 and max(n["plastic_points"]) > 0  # it yields at 300 MPa
    files = json.loads((tmp_path / "results.json").read_text())["files"]["history"]
    assert files == {"history": "history.csv", "newton": "newton.csv"}
    _coarse_von_mises_is_written(tmp_path, n_steps)


def _coarse_von_mises_is_written(folder, frames: int) -> None:
    """The coarse elastic model's series carries its von Mises stress, one frame a step."""
    from arlequin.io import read_series

    _mesh, series = read_series(folder / "fields" / "coarse.xdmf")
    assert len(series) == frames
    vm = series[-1][2]["von_mises"]
    assert float(np.max(vm[0] if isinstance(vm, list) else vm)) > 0.0


def _newton(folder, column):
    n = read_history(folder / "newton.csv")
    return n["step"], [int(c) for c in n[column]]


def test_plate_folder_has_history_and_newton_rows(tmp_path):
    """The plate: one history row a converged state after the unloaded one (first yield and
    the load steps), the load factor and the nominal stress S, its measures the result's."""
    r = run_plate_with_hole(out=str(tmp_path), **SMALL_PLATE)
    h = read_history(tmp_path / "history.csv")
    header = (tmp_path / "history.csv").read_text().splitlines()[0]
    assert "load [Pa]" in header and "load_factor [1]" in header and "plastic_area [m^2]" in header
    assert len(h["step"]) == len(r.history["load"]) - 1 == SMALL_PLATE["steps"] + 1
    for key in ("load", "displacement", "plastic_area", "plastic_extent", "patch_fraction"):
        assert h[key] == r.history[key][1:]
    load = r.config["load"]
    assert [lam * load for lam in h["load_factor"]] == pytest.approx(h["load"], rel=1e-12)
    n = read_history(tmp_path / "newton.csv")
    assert len(n["step"]) == sum(r.history["newton_iterations"][2:]) + int(
        h["newton_iterations"][0]
    )
    assert set(n["step"]) <= set(h["step"])
    _coarse_von_mises_is_written(tmp_path, SMALL_PLATE["steps"])  # first yield: no frame


class _Interrupted(Exception):
    pass


def _interrupted_run(run, config, out, monkeypatch, calls: int) -> None:
    """``run(config, out=out)`` stopped at its ``calls``-th solver step (after ``calls - 1``
    converged steps: their checkpoint on disk), as a hard stop would."""
    import arlequin.solvers.statics.quasi_static as qs

    original, seen = qs.QuasiStaticSolver.step, []

    def step(self):
        seen.append(1)
        if len(seen) == calls:
            raise _Interrupted
        return original(self)

    with monkeypatch.context() as patched:
        patched.setattr(qs.QuasiStaticSolver, "step", step)
        with pytest.raises(_Interrupted):
            run(config, out=str(out))


def test_a_resumed_run_writes_the_same_files(tmp_path, monkeypatch):
    """A pressure vessel interrupted after its 6th converged step and resumed: history.csv and
    newton.csv byte for byte those of the uninterrupted run (the pattern of
    tests/test_pressure_vessel.py's resume test)."""
    from arlequin.demos.pressure_vessel import PressureVesselConfig
    from arlequin.demos.pressure_vessel import run as run_module

    config = PressureVesselConfig(steps=10, **COARSE)
    full, cut = tmp_path / "full", tmp_path / "cut"
    run_module.run(config, out=str(full))
    _interrupted_run(run_module.run, config, cut, monkeypatch, calls=7)
    run_module.resume(str(cut))
    for name in ("history.csv", "newton.csv"):
        assert (cut / name).read_bytes() == (full / name).read_bytes(), name


def test_a_resumed_run_keeps_its_band_watch(tmp_path, monkeypatch):
    """The gluing band's watch is in the checkpoint: a sphere whose patch ends at 0.15 m (its
    band 0.125-0.15 m) yields in the band from the 8th step (240 MPa; Hill's front reaches
    0.125 m at 228 MPa); interrupted after the 9th and resumed, it reports the whole run's
    band share and does not warn again (without the watch in the checkpoint it warned again
    at λ = 0.9)."""
    import json
    import warnings

    import arlequin
    from arlequin.demos.pressure_vessel import PressureVesselConfig
    from arlequin.demos.pressure_vessel import run as run_module

    config = PressureVesselConfig(steps=10, patch_outer=0.15, **COARSE)
    full, cut = tmp_path / "full", tmp_path / "cut"
    with pytest.warns(arlequin.BandYieldWarning, match="at λ = 0.8 patch0"):
        run_module.run(config, out=str(full))
    with pytest.warns(arlequin.BandYieldWarning):
        _interrupted_run(run_module.run, config, cut, monkeypatch, calls=10)
    with warnings.catch_warnings():
        warnings.simplefilter("error", arlequin.BandYieldWarning)
        run_module.resume(str(cut))
    shares = [json.loads((d / "results.json").read_text())["results"]["band_plastic_fraction"]
              for d in (full, cut)]  # fmt: skip
    assert shares[0]["value"] > 0.0 and shares[1] == shares[0]
