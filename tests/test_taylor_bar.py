"""The Taylor bar demo (arlequin/demos/taylor_bar/): the product, and the physics against the
published values.

Reference values come from:
* DESIGN §4: the published converged values at 80 µs (3D, 1.5M elements) final length 21.43 mm
  and footprint radius 7.23 mm; the initial kinetic energy 239.8 J; an independent axisymmetric
  F-bar check giving 21.47–21.49 mm and 7.23–7.35 mm on 5 to 30 elements across the radius;
* exact facts of the discrete model: the impulse that stops the impact face at t = 0 removes
  ½ m_face v₀² (lumped mass, one row per node); Johnson–Cook with n = 1 and B = H is the linear
  law; an ordering of flow stresses at every strain orders the footprint radii;
* the JSON keys of the Interface of issue 10.
"""

from __future__ import annotations

import json

import meshio  # noqa: F401  (the XDMF reader below needs it)
import numpy as np
import pytest

from arlequin.cli.main import main
from arlequin.demos.taylor_bar import (
    JSON_KEYS,
    TAYLOR_REFERENCE,
    run_taylor_bar,
    taylor_bar_mesh,
)
from arlequin.io import read_history, read_series

HISTORY_KEYS = ["t", "length", "radius", "kinetic", "elastic", "plastic_dissipation",
                "viscous_dissipation", "contact_work", "contact_force", "dt"]  # fmt: skip


def test_mesh_has_nearly_square_cells():
    mesh = taylor_bar_mesh(32.4e-3, 3.2e-3, 5)
    assert mesh.t.shape[1] == 5 * 51  # round(32.4 / 0.64) = 51 axial cells
    p = mesh.p
    assert p[0].max() == pytest.approx(3.2e-3) and p[1].max() == pytest.approx(32.4e-3)
    assert np.ptp(np.diff(np.unique(p[1]))) < 1e-15  # uniform axial spacing


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"velocity": -227.0}, "velocity must be positive"),
        ({"elements_radial": 4, "mesh_size": 1e-3}, "not both"),
        ({"mesh_size": 5e-3}, "must not exceed the radius"),
        ({"elements_radial": 2.5}, "elements_radial must be a positive integer"),
        ({"model": "hybrid"}, "model must be one of"),
        ({"hardening_law": "swift"}, "hardening law must be one of"),
        ({"hardening_law": "voce", "jc_n": 0.3}, r"\['jc_n'\] do not belong to the voce law"),
        ({"poisson": 0.5}, "Poisson"),
        ({"safety": 1.5}, "safety factor must lie in"),
        ({"t_end": float("nan")}, "t_end must be positive and finite"),
        ({"yield_stress": 0.0}, "yield_stress must be positive"),
        ({"backend": "cuda"}, "backend must be one of"),
        ({"bulk_viscosity": "yes"}, "bulk_viscosity must be a bool"),
    ],
)
def test_bad_input_is_refused_before_any_work(kwargs, match, tmp_path):
    out = tmp_path / "run"
    with pytest.raises(ValueError, match=match):
        run_taylor_bar(out=out, **{"model": "mono", **kwargs})
    assert not out.exists()  # nothing written: refused before the results folder


@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("taylor") / "run"
    seen = []
    result = run_taylor_bar(model="mono", elements_radial=4, t_end=6e-6, out=out,
                            frame_interval=2e-6, progress=seen.append)  # fmt: skip
    return result, out, seen


def test_short_run_is_a_product(short_run):
    result, out, seen = short_run
    data = result.to_json()
    assert list(data)[: len(JSON_KEYS)] == list(JSON_KEYS)
    assert list(data["history"]) == HISTORY_KEYS
    t = np.asarray(data["history"]["t"])
    assert t[0] == 0.0 and t[-1] == pytest.approx(6e-6) and np.diff(t).max() <= 1e-6 + 1e-15
    assert seen == pytest.approx(list(t))  # the progress callback at every record
    # the results folder: inputs with units, results, histories, fields, pictures
    meta = json.loads((out / "results.json").read_text())
    assert meta["status"] == "complete"
    assert meta["inputs"]["velocity"] == {"value": 227.0, "unit": "m/s"}
    assert meta["results"]["final_length"]["unit"] == "m"
    hist = read_history(out / "history.csv")
    assert np.allclose(hist["length"], data["history"]["length"], rtol=1e-12)
    _, frames = read_series(out / "fields" / "bar.xdmf")
    assert [f[0] for f in frames] == pytest.approx([0.0, 2e-6, 4e-6, 6e-6])
    point, cell = frames[-1][1], frames[-1][2]
    assert {"displacement", "velocity"} <= set(point)
    assert {"plastic_strain", "von_mises"} <= set(cell)
    assert float(np.max(cell["plastic_strain"][0])) > 0.5  # the impact face has flowed
    for name in ("taylor_bar.png", "taylor_bar_history.png"):
        assert (out / name).stat().st_size > 10_000


def test_energy_balance_and_the_loss_at_impact(short_run):
    result, _, _ = short_run
    # KE_0 = ½ m v₀² of the whole bar (DESIGN §4: 239.8 J)
    mass = 8930.0 * np.pi * 3.2e-3**2 * 32.4e-3
    assert result.initial_kinetic_energy == pytest.approx(0.5 * mass * 227.0**2, rel=1e-12)
    assert result.initial_kinetic_energy == pytest.approx(239.8, abs=0.05)
    # the impulse at t = 0 stops the impact-face nodes: ½ m_face v₀² (lumped masses)
    model = result.model
    m = model.mass(lumped=True)
    face = np.nonzero(model.mesh.p[1] < 1e-12)[0]
    m_face = m[model.nodal_dofs()[1, face]].sum()
    assert result.impact_loss == pytest.approx(0.5 * m_face * 227.0**2, rel=1e-10)
    assert result.energy_balance_error <= 0.01
    h = {k: np.asarray(v) for k, v in result.history.items()}
    assert np.all(np.diff(h["plastic_dissipation"]) >= 0.0) and np.all(h["contact_work"] >= 0)
    # the wall only pushes; on this coarse mesh the face lifts off for about 1 µs after the
    # impact (the ringing of the stopped face nodes), hence the zeros
    assert np.all(h["contact_force"] >= 0.0) and np.mean(h["contact_force"][1:] > 0.0) > 0.5


def test_johnson_cook_with_unit_exponent_is_the_linear_law():
    # (A + B ε̄p^1)(1 + 0) with B = H is σ_y0 + H ε̄p: the same run, to round-off
    lin = run_taylor_bar(model="mono", elements_radial=3, t_end=3e-6)
    jc = run_taylor_bar(model="mono", elements_radial=3, t_end=3e-6, hardening_law="johnson-cook",
                        jc_b=0.1e9,
                        jc_n=1.0)  # fmt: skip
    assert jc.n_steps == lin.n_steps
    assert np.allclose(jc.u, lin.u, rtol=0, atol=1e-12 * np.abs(lin.u).max())


def test_numpy_and_numba_backends_give_the_same_run():
    a = run_taylor_bar(model="mono", elements_radial=3, t_end=2e-6, backend="numba")
    b = run_taylor_bar(model="mono", elements_radial=3, t_end=2e-6, backend="numpy")
    assert a.n_steps == b.n_steps
    assert np.allclose(a.u, b.u, rtol=0, atol=1e-10 * np.abs(a.u).max())


def test_inverted_cell_is_reported_and_the_folder_keeps_what_was_computed(tmp_path):
    from arlequin.contract import SimulationError

    out = tmp_path / "run"
    with pytest.raises(SimulationError, match=r"cell \d+: det F <= 0 .* at step \d+, t = "):
        run_taylor_bar(model="mono", elements_radial=3, velocity=3000.0, t_end=20e-6, out=out)
    meta = json.loads((out / "results.json").read_text())
    assert meta["status"] == "failed" and "det F" in meta["message"]
    assert len(read_history(out / "history.csv")["t"]) >= 1


def test_cli_json_has_the_interface_keys(tmp_path, capsys):
    path = tmp_path / "taylor.json"
    rc = main(["taylor-bar", "--model", "mono", "--elements-radial", "3", "--t-end", "2e-6",
               "--json", str(path), "--quiet"])  # fmt: skip
    assert rc == 0
    data = json.loads(path.read_text())
    assert list(data)[: len(JSON_KEYS)] == list(JSON_KEYS)
    assert list(data["history"]) == HISTORY_KEYS
    assert "final length" in capsys.readouterr().out
    assert main(["taylor-bar", "--mesh-size", "-1", "--quiet"]) == 2


# ------------------------------------------------------------------ physics (long runs)
@pytest.mark.slow
@pytest.mark.parametrize("cells", [5, 20])
def test_taylor_bar_matches_the_published_values(cells):
    # 5 cells across the radius (~6 s) already within 1% and 2% (DESIGN §4: coarse meshes give
    # 21.4–21.7 mm and 6.9–7.3 mm; measured 21.48 mm, 7.22 mm); 20 cells, the acceptance mesh
    # of issue 10 (~2 min): measured 21.47 mm, 7.34 mm
    r = run_taylor_bar(model="mono", elements_radial=cells)
    assert r.final_length == pytest.approx(TAYLOR_REFERENCE["final_length"], rel=0.01)
    assert r.mushroom_radius == pytest.approx(TAYLOR_REFERENCE["mushroom_radius"], rel=0.02)
    assert r.max_plastic_strain >= 2.5
    assert r.energy_balance_error <= 0.01


@pytest.mark.slow
def test_plain_cells_lock():
    # the same mesh without F-bar: isochoric flow locks the bilinear cells, which shows as a
    # spurious pressure (measured 8.5 GPa against 0.33 GPa with F-bar at 10 cells) and a
    # footprint smaller by more than 1% (measured −11.4% at 10 cells, −4.2% at 20). The final
    # length is NOT longer by 1% as issue 10 expected: −1.07% at 10 cells, +0.08% at 20 (the
    # locked bar spreads over a longer region instead; volume conserved to 3.5e-4, see
    # docs/plasticity.md), so it is not asserted.
    fbar = run_taylor_bar(model="mono", elements_radial=10)
    plain = run_taylor_bar(model="mono", elements_radial=10, fbar=False)
    assert plain.mushroom_radius < 0.99 * fbar.mushroom_radius

    def max_pressure(r):
        s = r.state
        return float(np.max(-np.einsum("iieq->eq", s.kirchhoff) / 3.0 / s.jacobian))

    assert max_pressure(plain) > 5.0 * max_pressure(fbar)


@pytest.mark.slow
def test_footprint_radius_follows_the_flow_stress():
    # σ_y ordered at every strain: perfect plasticity < linear (H = 0.1 GPa) < Voce (the linear
    # law plus a positive saturating term); the radii are ordered the other way
    soft = run_taylor_bar(model="mono", elements_radial=5, hardening=0.0)
    linear = run_taylor_bar(model="mono", elements_radial=5)
    hard = run_taylor_bar(model="mono", elements_radial=5, hardening_law="voce",
                          voce_saturation=0.1e9,
                          voce_rate=10.0)  # fmt: skip
    assert soft.mushroom_radius > linear.mushroom_radius > hard.mushroom_radius
    assert soft.final_length < linear.final_length < hard.final_length
