"""The error catalogue: each bad input gives its error class and a message that names the
quantity and its value, before any expensive work; on the command line, exit code 2 and one
line (no traceback). Every case below was found by trying the library as a new user would."""

from __future__ import annotations

import numpy as np
import pytest
import skfem

from arlequin import ArlequinProblem, ContractError, Patch, solve, solve_static
from arlequin.cli.main import main
from arlequin.geometry.meshcheck import MeshError
from arlequin.models import IsotropicElastic, J2Material, LinearElastic
from arlequin.solvers import SingularSystemError

STEEL = IsotropicElastic(210e9, 0.3, 7850.0)


@pytest.mark.parametrize(
    "argv,needle",
    [
        (["two-bars", "--density", "0"], "density must be positive, got density=0.0"),
        (["wave", "--dt", "0"], "dt (s) must be positive and finite, got dt=0.0"),
        (["wave", "--dt", "nan"], "dt (s) must be positive and finite, got dt=nan"),
        (["two-bars", "--velocity", "nan"], "velocity must be finite, got velocity=nan"),
        (["two-bars", "--method", "newmark", "--cfl", "50"], "the contact lasts 2 record(s)"),
        (["patch-test", "--seed", "-1"], "seed must be a non-negative integer, got seed=-1"),
        (["two-bars", "--json", "/nonexistent/x.json"], "--json '/nonexistent/x.json'"),
        (["wave", "--plot", "/nonexistent/x.png"], "--plot '/nonexistent/x.png'"),
        (["patch-test", "--out", "/proc/none/x"], "cannot write the results folder"),
        (["patch-test", "--layout", "square", "--dim", "3"], "layout='square' is a 2D"),
        (["patch-test", "--layout", "strip", "--ratio", "0"], "ratio must be a positive"),
    ],
)
def test_cli_bad_input_is_one_line_and_exit_2(argv, needle, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert needle in err, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_implicit_wave_accepts_a_step_above_the_explicit_limit(capsys):
    # implicit schemes are unconditionally stable for linear problems
    assert main(["wave", "--ratio", "2", "--integrator", "implicit", "--dt", "1e-5"]) == 0


def test_api_bad_input_names_the_quantity():
    with pytest.raises(ValueError, match=r"young must be a number .* got '210e9'"):
        IsotropicElastic(young="210e9")
    with pytest.raises(ValueError, match="yield_stress must be a number"):
        J2Material(117e9, 0.35, 8930.0, "0.4e9")
    with pytest.raises(ValueError, match="material must be an IsotropicElastic"):
        LinearElastic(skfem.MeshLine(), skfem.MeshLine())
    mesh = skfem.MeshTri.init_tensor(np.linspace(0, 1, 5), np.linspace(0, 1, 5))
    with pytest.raises(ContractError, match="patch's model is a MeshTri1"):
        Patch(mesh, gluing_width=0.1)
    problem = ArlequinProblem(LinearElastic(mesh, STEEL))
    with pytest.raises(ValueError, match=r"traction \(Pa\) must be finite, got \[nan, 0.0\]"):
        problem.add_traction([np.nan, 0.0])
    with pytest.raises(ValueError, match=r"must have 2 components, got \[1.0\]"):
        problem.add_body_force([1.0])
    with pytest.raises(ValueError, match="selector `where` matches no boundary facet"):
        problem.add_traction([1.0, 0.0], where=lambda x: np.abs(x[0] - 0.5) < 1e-9)  # interior
    with pytest.raises(ValueError, match=r"v0 .* non-finite value"):
        solve(problem, "explicit", n_steps=1, v0={"coarse": np.full(50, np.nan)})


def test_static_problem_without_supports_is_refused():
    mesh = skfem.MeshTri.init_tensor(np.linspace(0, 1, 5), np.linspace(0, 1, 5))
    problem = ArlequinProblem(LinearElastic(mesh, STEEL))
    problem.add_traction([1e6, 0.0], where=lambda x: x[0] > 1 - 1e-9)
    with pytest.raises(SingularSystemError, match=r"leave 3 rigid-body mode\(s\) free"):
        solve_static(problem)
    problem.add_dirichlet("coarse", where=lambda x: x[0] < 1e-9, components=[0])
    with pytest.raises(SingularSystemError, match=r"1 rigid-body mode\(s\) free \(translation y"):
        solve_static(problem)
    problem.add_dirichlet("coarse", where=lambda x: (x[0] < 1e-9) & (x[1] < 1e-9))
    assert np.isfinite(solve_static(problem).u).all()


def _grid(n=4):
    return skfem.MeshTri.init_tensor(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1))


def test_bad_meshes_are_refused_naming_the_node_or_cell():
    m = _grid()
    # a duplicated node splitting the cells along a seam (measured 28.9 % error otherwise)
    seam = m.p[0] == 0.5
    p = np.hstack([m.p, m.p[:, seam]])
    copies = {int(i): m.p.shape[1] + k for k, i in enumerate(np.nonzero(seam)[0])}
    t = m.t.copy()
    right = m.p[0, m.t].mean(axis=0) > 0.5
    for i, j in copies.items():
        t[:, right] = np.where(t[:, right] == i, j, t[:, right])
    with pytest.raises(MeshError, match=r"nodes \d+ and \d+ coincide at x = \[0.5"):
        LinearElastic(skfem.MeshTri(p, t), STEEL)
    LinearElastic(skfem.MeshTri(p, t), STEEL, allow_seams=True)  # an intended crack
    # folded cells (measured 3.9 % error otherwise)
    p = m.p.copy()
    k = int(np.argmin(np.linalg.norm(m.p - 0.5, axis=0)))
    p[:, k] = [0.85, 0.62]
    with pytest.raises(MeshError, match="overlap across their common facet"):
        LinearElastic(skfem.MeshTri(p, m.t), STEEL)
    # a zero-area cell
    p = m.p.copy()
    a, b, c = m.t[:, 5]
    p[:, c] = 0.5 * (p[:, a] + p[:, b])  # cell 5 collapses onto its edge ab
    with pytest.raises(MeshError, match=r"cell \d+ .* has zero measure"):
        LinearElastic(skfem.MeshTri(p, m.t), STEEL)
    # an unused duplicate node (a raw "matmul: dimension mismatch" otherwise)
    p = np.hstack([m.p, m.p[:, [3]]])
    with pytest.raises(MeshError, match=r"node 25 at x = .* is used by no cell"):
        LinearElastic(skfem.MeshTri(p, m.t), STEEL)
    # non-finite coordinates
    p = m.p.copy()
    p[1, 2] = np.nan
    with pytest.raises(MeshError, match="node 2 has non-finite coordinates"):
        LinearElastic(skfem.MeshTri(p, m.t), STEEL)
