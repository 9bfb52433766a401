"""Must-show checks of the two-bar impact demo (issue 4) against the exact solution.

Exact solution (same material, bars touching at t = 0, c = √(E/ρ)): interface velocity v₀/2,
contact pressure ρ c v₀/2, contact duration 2L/c, final mean velocities (0, v₀); bar on a rigid
wall: pressure ρ c v₀, duration 2L/c, rebound −v₀. Errors are measured over the records in contact
except the first two and the last two (``impact_metrics``). Bounds are the issue's, unchanged;
the pressure and rebound criteria are those restated by the robustness issue (the pressure over
the exact contact interval, the rebound at 200 elements per bar), which the scheme meets.
"""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from arlequin.cli.main import main
from arlequin.demos.block_impact import run_block_impact
from arlequin.demos.two_bars import (
    JSON_KEYS,
    exact_two_bars,
    run_two_bars,
    run_wall,
)


@pytest.fixture(scope="module")
def theta_run():
    return run_two_bars()  # level-set, θ = 1/2, 100 elements per bar, CFL 1


@pytest.fixture(scope="module")
def explicit_run():
    return run_two_bars(integrator="explicit", cfl=0.9)


@pytest.fixture(scope="module")
def wall_theta():
    return run_wall()


@pytest.fixture(scope="module")
def wall_explicit():
    return run_wall(integrator="explicit", cfl=0.9)


def test_exact_solution_values():
    ex = exact_two_bars()
    c = np.sqrt(210e9 / 7850.0)
    assert ex["interface_velocity"] == 0.5  # v0 / 2
    assert ex["pressure"] == pytest.approx(7850.0 * c * 0.5)  # ρ c v0 / 2
    assert ex["duration"] == pytest.approx(2.0 / c)  # 2 L / c
    assert ex["final_velocities"] == [0.0, 1.0]


# ------------------------------------------------------------------ items 1-4: θ = 1/2
def test_item1_interface_velocity(theta_run):
    assert theta_run.metrics()["velocity_rms_error"] <= 0.01  # ≤ 1% of v0/2


def test_item2_contact_pressure(theta_run):
    # Criterion restated by the robustness issue: the rms error of the pressure over the exact
    # contact interval t in (2.5 dt, 2L/c - 2.5 dt), t = 0 the exact first contact, within 2%
    # of ρ c v0/2. Measured 1.23% (4.34% when the records of the smeared release wave, after
    # 2L/c, are counted: the consistent-mass dispersion, see docs/contact.md).
    assert theta_run.metrics()["pressure_rms_error_exact_interval"] <= 0.02


def test_item3_duration_and_final_velocities(theta_run):
    m = theta_run.metrics()
    assert abs(m["duration_error_steps"]) <= 3.0  # within 3 Δt of 2L/c
    v1, v2 = theta_run.final_velocities
    assert abs(v1 - 0.0) <= 0.01 and abs(v2 - 1.0) <= 0.01  # (0, v0) within 0.01 v0


def test_item4_energy_loss_and_contact_work(theta_run):
    m = theta_run.metrics()
    assert 0.0 <= m["energy_loss"] <= 0.01  # ≤ 1%
    # θ = 1/2: the energy change is exactly the contact work computed from the multipliers
    assert m["balance_error"] <= 1e-10
    assert theta_run.fixed_point_iterations.max() <= 10


@pytest.mark.parametrize("elements", [25, 50, 100])
def test_item4_energy_loss_vanishes_fast(elements):
    # DESIGN §3: energy loss ≈ 0.29 / N_el per impact (1.15% at 25, 0.29% at 100)
    loss = run_two_bars(elements=elements).metrics()["energy_loss"]
    assert loss <= 0.3 / elements


@pytest.mark.slow
def test_item4_energy_loss_table():
    losses = [run_two_bars(elements=n).metrics()["energy_loss"] for n in (25, 50, 100, 200, 400)]
    assert all(b < a for a, b in itertools.pairwise(losses))
    assert losses[-1] <= 1e-3


# ------------------------------------------------------------------ item 5: Newmark baselines
@pytest.mark.parametrize("variant", ["trapezoidal", "hht"])
def test_item5_newmark_baselines(theta_run, variant):
    nm = run_two_bars(method="newmark", newmark=variant).metrics()
    ls = theta_run.metrics()
    # the baseline oscillates at the interface: much larger velocity and pressure errors
    assert nm["velocity_rms_error"] > 10 * max(ls["velocity_rms_error"], 1e-3)
    assert nm["pressure_rms_error"] > 2 * ls["pressure_rms_error"]
    if variant == "trapezoidal":
        # DESIGN §3: the energy grows several-fold
        assert nm["max_energy_gain"] > 1.0


# ------------------------------------------------------------------ item 6: rigid wall, θ = 1/2
def test_item6_wall_rebound():
    # Criterion restated: the rebound within 1% of −v0 at 200 elements per bar (measured
    # −0.9916 v0; −0.9864 v0 at 100 elements, where 2.1% of the energy stays in vibration).
    wall = run_wall(elements=200)
    assert abs(wall.final_velocities[0] + 1.0) <= 0.01


def test_item6_wall_duration(wall_theta):
    assert abs(wall_theta.metrics()["duration_error_steps"]) <= 3.0  # 2L/c within 3 Δt


def test_item6_wall_pressure(wall_theta):
    # as item 2, over the exact contact interval: measured 1.23% of ρ c v0
    assert wall_theta.metrics()["pressure_rms_error_exact_interval"] <= 0.02


# ----------------------------------------- items 2 and 6 at the dispersion-free Courant number
@pytest.mark.parametrize("run", [run_two_bars, run_wall])
def test_items2_6_at_dispersion_free_cfl(run):
    # Consistent-mass P1 elements with the trapezoidal rule have the phase velocity
    # c (1 + (kh)²(1 − 2C²)/24) to second order in kh, so the leading error cancels at C = 1/√2.
    # The θ = ½ level-set scheme then meets items 2 and 6 on the same 100-element mesh, which
    # shows that the misses at CFL 1 of the first criteria are the bulk dispersion, not the contact
    # algorithm. Measured (benchmarks/two_bars_cfl.py): pressure 0.85% rms, rebound −0.9941 v0.
    result = run(cfl=1.0 / np.sqrt(2.0))
    m = result.metrics()
    assert m["pressure_rms_error"] <= 0.02  # items 2 and 6: ≤ 2% rms
    assert abs(m["duration_error_steps"]) <= 3.0
    target = [-1.0] if run is run_wall else [0.0, 1.0]
    assert np.allclose(result.final_velocities, target, atol=0.01)  # within 1% of v0


# ------------------------------------------------------------------ item 7: explicit, CFL 0.9
def test_item7_explicit_bars(explicit_run):
    m = explicit_run.metrics()
    assert m["velocity_rms_error"] <= 0.01
    assert m["pressure_rms_error"] <= 0.02
    assert abs(m["duration_error_steps"]) <= 3.0
    v1, v2 = explicit_run.final_velocities
    assert abs(v1) <= 0.01 and abs(v2 - 1.0) <= 0.01


def test_item7_explicit_wall(wall_explicit):
    m = wall_explicit.metrics()
    assert abs(wall_explicit.final_velocities[0] + 1.0) <= 0.01
    assert abs(m["duration_error_steps"]) <= 3.0
    assert m["pressure_rms_error"] <= 0.02


# ------------------------------------------------------------------ item 8: 2D / 3D
def _check_block(r, theta=0.5):
    # the gap of an active point does not drift (≤ 1e-8 h)
    assert r.max_gap_drift <= 1e-8 * r.h
    # penetration at activation ≤ (1 − θ) Δt [[v_n]] + 1e-8 h
    assert r.max_penetration_excess <= 1e-8 * r.h
    assert r.max_penetration >= 0.0  # gap_steps = 2.3: activation inside a step, 0.2 v0 Δt
    assert np.mean(r.iterations_contact) <= 10.0
    assert r.n_status_failures == 0


@pytest.fixture(scope="module")
def block2d():
    return {
        ("plane", 40): run_block_impact(2, "plane", 40),
        ("plane", 80): run_block_impact(2, "plane", 80),
        ("block", 20): run_block_impact(2, "block", 20),
        ("block", 40): run_block_impact(2, "block", 40),
    }


@pytest.mark.parametrize("key", [("plane", 40), ("block", 20)])
def test_item8_2d(block2d, key):
    r = block2d[key]
    _check_block(r)
    assert r.energy_loss <= 0.02  # ≤ 2% between first contact and separation


@pytest.mark.parametrize("target,coarse,fine", [("plane", 40, 80), ("block", 20, 40)])
def test_item8_2d_refinement(block2d, target, coarse, fine):
    assert block2d[(target, fine)].energy_loss < block2d[(target, coarse)].energy_loss


def test_item8_3d_block_fast():
    r = run_block_impact(3, "block", 20)
    _check_block(r)
    assert r.energy_loss <= 0.02


def test_item8_3d_plane_fast():
    r = run_block_impact(3, "plane", 20)
    _check_block(r)  # energy at 20 elements: 2.83% (≤ 2% from 40 elements, slow test)


@pytest.mark.slow
@pytest.mark.parametrize("target", ["plane", "block"])
def test_item8_3d_refinement(target):
    r40 = run_block_impact(3, target, 40)
    r20 = run_block_impact(3, target, 20)
    _check_block(r40)
    assert r40.energy_loss <= 0.02
    assert r40.energy_loss < r20.energy_loss


# ------------------------------------------------------------------ interface
def test_json_keys_and_cli(tmp_path, capsys):
    path = tmp_path / "tb.json"
    png = tmp_path / "tb.png"
    rc = main(
        [
            "two-bars",
            "--method",
            "both",
            "--elements",
            "20",
            "--json",
            str(path),
            "--plot",
            str(png),
        ]
    )
    assert rc == 0
    data = json.loads(path.read_text())
    assert list(data) == [*JSON_KEYS, "newmark"]
    assert list(data["newmark"]) == list(JSON_KEYS)
    assert data["t"][0] == 0.0 and len(data["t"]) == len(data["contact_pressure"])
    assert png.stat().st_size > 0
    assert "levelset" in capsys.readouterr().out


def test_invalid_arguments():
    with pytest.raises(ValueError, match="method"):
        run_two_bars(method="penalty")
    with pytest.raises(ValueError, match="approach"):
        run_two_bars(velocity=0.0)
