"""Coupling consistency (issue 2, item 2).

Expected values: interpolants of one linear field (and rigid motions) are the same function on the
gluing zone, so C_c u_c − C_f u_f = c(λ, u − u) = 0 up to round-off (1e-12 relative, the issue's
bound). For the scalar L2 Gram block, both mediator bases and both displacement bases are
partitions of unity on S_g, so 1ᵀ C 1 = ∫_Sg 1 = |S_g|, the band area (axisymmetric: 2π ∫ r dr dz,
our measure carries the 2π), computed here from the band's geometry.
"""

from __future__ import annotations

import numpy as np
import pytest

from arlequin.coupling.mediators import coupling_matrices
from arlequin.demos.patch_test import build_patch_test_problem

CASES = [
    ("1", "nested"),
    ("2", "nested"),
    ("axi", "nested"),
    ("3", "nested"),
    ("1", "nonnested"),
    ("2", "nonnested"),
]


def _nodal(field, mesh):
    return np.asarray(field(mesh.p)).T.ravel()


@pytest.mark.parametrize("dim,mesh", CASES)
@pytest.mark.parametrize("coupling", ["L2", "H1"])
@pytest.mark.parametrize("mediator", ["coarse", "fine"])
def test_linear_fields_and_rigid_motions_are_coupled_consistently(dim, mesh, coupling, mediator):
    problem, _ = build_patch_test_problem(dim, coupling, "ramp", mediator, mesh, seed=3)
    pc = problem.couplings[0]
    cm, fm = problem.coarse.mesh, pc.fine_model.mesh
    d = cm.dim()
    rng = np.random.default_rng(0)
    a = rng.standard_normal((d, d))
    c = rng.standard_normal(d)
    fields = [lambda x: a @ x, lambda x: np.broadcast_to(c[:, None], x.shape)]
    if d == 2:
        fields.append(lambda x: np.array([-x[1], x[0]]))  # infinitesimal rotation
    if d == 3:
        fields.append(lambda x: np.array([-x[1], x[0], 0 * x[2]]))
    for f in fields:
        uc, uf = _nodal(f, cm), _nodal(f, fm)
        a = pc.coupling.coarse @ uc
        b = pc.coupling.fine @ uf
        assert np.abs(a - b).max() <= 1e-12 * np.abs(a).max()


@pytest.mark.parametrize("dim,mesh", CASES)
@pytest.mark.parametrize("mediator", ["coarse", "fine"])
def test_scalar_l2_gram_sums_to_gluing_measure(dim, mesh, mediator):
    problem, _ = build_patch_test_problem(dim, "L2", "ramp", mediator, mesh, seed=4)
    pc = problem.couplings[0]
    axi = dim == "axi"
    cm = coupling_matrices(
        pc.overlap, pc.gluing_cells, 1, "L2", mediator=mediator, axisymmetric=axi
    )
    fm = pc.fine_model.mesh
    lo, hi = fm.p.min(axis=1), fm.p.max(axis=1)
    w = pc.gluing_width
    along = 1 if axi else 0  # the coupled direction (bands normal to it)
    if dim == "1":
        measure = 2 * w
    elif axi:
        r = hi[0]
        measure = 2 * w * np.pi * r**2  # 2 bands x 2π ∫_0^R r dr x w
    else:
        cross = np.prod(np.delete(hi - lo, along))
        measure = 2 * w * cross
    ones_c = np.ones(cm.coarse.shape[1])
    ones_f = np.ones(cm.fine.shape[1])
    ones_m = np.ones(cm.n_multipliers)
    assert ones_m @ (cm.coarse @ ones_c) == pytest.approx(measure, rel=1e-12)
    assert ones_m @ (cm.fine @ ones_f) == pytest.approx(measure, rel=1e-12)


@pytest.mark.parametrize("dim,mesh", [("2", "nested"), ("2", "nonnested"), ("3", "nested"),
                                      ("3", "nonnested")])  # fmt: skip
@pytest.mark.parametrize("coupling", ["L2", "H1"])
def test_closed_form_gram_is_the_quadrature(dim, mesh, coupling):
    # the closed form of P1 simplices against scikit-fem's quadrature of the same form (order
    # 2: exact for products of two P1 functions), to round-off
    from arlequin.coupling.mediators import gram_matrix

    problem, _ = build_patch_test_problem(dim, coupling, "ramp", "coarse", mesh, seed=4)
    pc = problem.couplings[0]
    d = int(dim)
    args = (pc.overlap, pc.gluing_cells, d, coupling, 0.37 * pc.gluing_width)
    closed = gram_matrix(*args, intorder=2)
    quadrature = gram_matrix(*args, intorder=2, closed_form=False)
    scale = abs(quadrature).max()
    assert abs(closed - quadrature).max() <= 1e-13 * scale
