"""Bad input gets a clear ValueError naming the quantity (issue 2, item 5)."""

from __future__ import annotations

import numpy as np
import pytest
import skfem

from arlequin.coupling.mediators import MediatorError, coupling_matrices
from arlequin.coupling.overlap import OverlapError
from arlequin.coupling.patches import refine_region
from arlequin.coupling.weights import CallableWeights, WeightSumError
from arlequin.models import IsotropicElastic, LinearElastic
from arlequin.problem.arlequin_problem import ArlequinProblem, Patch

STEEL = IsotropicElastic(young=210e9, poisson=0.3, density=7850.0)


def _coarse2d(n=8):
    return skfem.MeshTri.init_tensor(np.linspace(0, 2, 2 * n + 1), np.linspace(0, 1, n + 1))


def _models(coarse_mesh, fine_mesh, kind=None):
    return LinearElastic(coarse_mesh, STEEL, kind), LinearElastic(fine_mesh, STEEL, kind)


def test_weights_that_do_not_sum_to_one():
    cm = _coarse2d()
    fm = refine_region(cm, levels=1, box=((1.0, 0.0), (2.0, 1.0)))
    c, f = _models(cm, fm)
    bad = CallableWeights(coarse=lambda x: 0.5 + 0 * x[0], fine=lambda x: 0.6 + 0 * x[0])
    problem = ArlequinProblem(c, [Patch(f, gluing_width=0.25, weights=bad)])
    with pytest.raises(WeightSumError, match=r"do not sum to one.*1\.000e-01"):
        problem.couplings  # noqa: B018


def test_weights_out_of_range():
    cm = _coarse2d()
    fm = refine_region(cm, levels=1, box=((1.0, 0.0), (2.0, 1.0)))
    c, f = _models(cm, fm)
    bad = CallableWeights(coarse=lambda x: 1.5 + 0 * x[0], fine=lambda x: -0.5 + 0 * x[0])
    with pytest.raises(WeightSumError, match="alpha_coarse must lie in"):
        ArlequinProblem(c, [Patch(f, gluing_width=0.25, weights=bad)]).couplings  # noqa: B018


def test_patch_outside_the_coarse_mesh():
    cm = _coarse2d()
    fm = skfem.MeshTri.init_tensor(np.linspace(1.5, 2.5, 9), np.linspace(0, 1, 9))
    c, f = _models(cm, fm)
    with pytest.raises(OverlapError, match="outside the coarse mesh"):
        ArlequinProblem(c, [Patch(f, gluing_width=0.25)]).couplings  # noqa: B018


def test_patch_slightly_outside_a_faceted_boundary_is_accepted():
    # 1% of a coarse cell outside: within the default 5% boundary tolerance
    cm = _coarse2d()
    h = 0.125
    fm = skfem.MeshTri.init_tensor(np.linspace(1.0, 2.0 + 0.01 * h, 9), np.linspace(0, 1, 9))
    c, f = _models(cm, fm)
    assert ArlequinProblem(c, [Patch(f, gluing_width=0.25)]).couplings[0].gluing_cells.size > 0


def test_two_overlapping_patches():
    cm = _coarse2d()
    f1 = refine_region(cm, levels=1, box=((0.5, 0.0), (1.25, 1.0)))
    f2 = refine_region(cm, levels=1, box=((1.0, 0.0), (1.75, 1.0)))
    c = LinearElastic(cm, STEEL)
    patches = [Patch(LinearElastic(f1, STEEL), 0.25), Patch(LinearElastic(f2, STEEL), 0.25)]
    with pytest.raises(OverlapError, match="overlap"):
        ArlequinProblem(c, patches)


def test_two_disjoint_patches_are_fine():
    cm = _coarse2d()
    f1 = refine_region(cm, levels=1, box=((0.0, 0.0), (0.75, 1.0)))
    f2 = refine_region(cm, levels=1, box=((1.25, 0.0), (2.0, 1.0)))
    c = LinearElastic(cm, STEEL)
    problem = ArlequinProblem(
        c, [Patch(LinearElastic(f1, STEEL), 0.25), Patch(LinearElastic(f2, STEEL), 0.25)]
    )
    assert len(problem.couplings) == 2


def test_empty_gluing_zone_too_narrow():
    cm = _coarse2d()
    fm = refine_region(cm, levels=1, box=((1.0, 0.0), (2.0, 1.0)))
    c, f = _models(cm, fm)
    # fine cells are 1/16 wide: a band of 1e-3 contains no cell centroid
    with pytest.raises(MediatorError, match="empty gluing zone"):
        ArlequinProblem(c, [Patch(f, gluing_width=1e-3)]).couplings  # noqa: B018


def test_empty_gluing_zone_patch_covering_everything():
    cm = _coarse2d()
    fm = cm.refined(1)
    c, f = _models(cm, fm)
    with pytest.raises(MediatorError, match="no part inside the coarse domain"):
        ArlequinProblem(c, [Patch(f, gluing_width=0.25)]).couplings  # noqa: B018


def test_mediator_with_no_support():
    cm = _coarse2d()
    fm = refine_region(cm, levels=1, box=((1.0, 0.0), (2.0, 1.0)))
    c, f = _models(cm, fm)
    problem = ArlequinProblem(c, [Patch(f, gluing_width=0.25)])
    ov = problem.couplings[0].overlap
    with pytest.raises(MediatorError, match="gluing zone is empty"):
        coupling_matrices(ov, np.array([], dtype=int), 2, "L2")
    region = Patch(f, gluing_region=lambda x: np.zeros(x.shape[1], dtype=bool))
    with pytest.raises(MediatorError, match="empty gluing zone"):
        ArlequinProblem(c, [region]).couplings  # noqa: B018


def test_mismatched_dimensions():
    cm = _coarse2d()
    fm = skfem.MeshLine(np.linspace(0.5, 1.5, 5))
    c = LinearElastic(cm, STEEL)
    f = LinearElastic(fm, STEEL)
    with pytest.raises(
        ValueError, match="mismatched dimensions: coarse mesh is 2D, patch mesh is 1D"
    ):
        ArlequinProblem(c, [Patch(f, gluing_width=0.25)]).couplings  # noqa: B018


def test_mismatched_kinematics():
    cm = _coarse2d()
    fm = refine_region(cm, levels=1, box=((1.0, 0.0), (2.0, 1.0)))
    c = LinearElastic(cm, STEEL, "plane_strain")
    f = LinearElastic(fm, STEEL, "plane_stress")
    with pytest.raises(ValueError, match="mismatched kinematics"):
        ArlequinProblem(c, [Patch(f, gluing_width=0.25)]).couplings  # noqa: B018


@pytest.mark.parametrize(
    "kwargs,match",
    [
        ({"gluing_width": -1.0}, "gluing_width must be positive"),
        ({"gluing_width": 0.1, "coupling": "L3"}, "coupling must be"),
        ({"gluing_width": 0.1, "mediator": "both"}, "mediator must be"),
        ({"gluing_width": 0.1, "epsilon": 0.0}, "epsilon"),
        ({"gluing_width": 0.1, "weights": "cubic"}, "weights must be"),
        ({}, "gluing_width"),
    ],
)
def test_patch_parameters(kwargs, match):
    f = LinearElastic(_coarse2d(), STEEL)
    with pytest.raises(ValueError, match=match):
        Patch(f, **kwargs)


@pytest.mark.parametrize(
    "kwargs,match",
    [
        ({"young": -1.0}, "Young's modulus"),
        ({"young": 1.0, "poisson": 0.5}, "Poisson's ratio"),
        ({"young": 1.0, "density": -1.0}, "density"),
    ],
)
def test_material_parameters(kwargs, match):
    with pytest.raises(ValueError, match=match):
        IsotropicElastic(**kwargs)


def test_refine_region_selects_nothing():
    with pytest.raises(ValueError, match="selects no cell"):
        refine_region(_coarse2d(), levels=1, box=((5.0, 5.0), (6.0, 6.0)))
