"""A trimmed non-nested overlap (only the pieces where the weights vary are cut; the coarse
cells inside the patch carry the floor ε themselves) gives the operators of the full overlap.

Expected values: the two constructions integrate the same polynomials exactly on different
cells, so they agree to round-off (1e-12 of the largest entry); the full overlap is the
reference (it is what every non-nested patch used before trimming, and what the patch tests
check against the exact solution).
"""

from __future__ import annotations

import numpy as np
import pytest
from skfem import MeshTet, MeshTri

import arlequin.coupling.gluing as gluing
from arlequin import ArlequinProblem, Patch
from arlequin.models import IsotropicElastic, LinearElastic

STEEL = IsotropicElastic(young=200e9, poisson=0.3, density=7800.0)


def _meshes(dim: int):
    """A coarse unit square/cube and a non-nested structured patch of an off-grid box."""
    n, lo, hi, nf = (8, 0.13, 0.87, 9) if dim == 2 else (4, 0.06, 0.94, 8)
    x = np.linspace(0.0, 1.0, n + 1)
    xf = np.linspace(lo, hi, nf + 1)
    if dim == 2:
        return MeshTri.init_tensor(x, x), MeshTri.init_tensor(xf, xf + 0.01)
    return MeshTet.init_tensor(x, x, x), MeshTet.init_tensor(xf, xf + 0.01, xf - 0.02)


def _system(dim: int, weights: str, trim: bool, monkeypatch):
    coarse_mesh, fine_mesh = _meshes(dim)
    if not trim:
        full = gluing.build_overlap
        monkeypatch.setattr(gluing, "build_overlap", lambda *a, pair_filter=None: full(*a))
    coarse = LinearElastic(coarse_mesh, STEEL)
    fine = LinearElastic(fine_mesh, STEEL)
    width = 0.1 if dim == 2 else 0.11  # m
    patch = Patch(fine, gluing_width=width, weights=weights, coupling="H1", mediator="coarse")
    problem = ArlequinProblem(coarse, [patch])
    problem.add_body_force(np.arange(1.0, dim + 1.0) * 1e4)
    problem.add_traction(np.full(dim, 1e6), where=lambda x: x[0] < 1e-9)
    pc = problem.couplings[0]  # built here, on first use
    system = problem.system()
    monkeypatch.undo()
    return pc, system


@pytest.mark.filterwarnings("ignore::arlequin.ExactnessWarning")
@pytest.mark.parametrize("dim,weights", [(2, "ramp"), (3, "ramp"), (3, "constant")])
def test_trimmed_overlap_gives_the_full_overlaps_operators(dim, weights, monkeypatch):
    pc_t, sys_t = _system(dim, weights, True, monkeypatch)
    pc_f, sys_f = _system(dim, weights, False, monkeypatch)
    assert pc_t.overlap.trimmed and not pc_f.overlap.trimmed
    assert pc_t.coarse_floor == pytest.approx(1e-3, rel=1e-12) and pc_f.coarse_floor == 0.0
    # the trimming really drops pieces: coarse cells deep in the patch are not cut
    n_t = pc_t.overlap.integration_mesh.nelements
    n_f = pc_f.overlap.integration_mesh.nelements
    assert pc_t._surely_covered.any()
    assert n_t < (0.8 if dim == 2 else 0.95) * n_f, (n_t, n_f)

    def close(a, b):
        a, b = np.asarray(a.todense() if hasattr(a, "todense") else a), np.asarray(
            b.todense() if hasattr(b, "todense") else b)  # fmt: skip
        assert np.max(np.abs(a - b)) <= 1e-12 * np.max(np.abs(b)), np.max(np.abs(a - b))

    close(sys_t.stiffness(), sys_f.stiffness())
    close(sys_t.mass(), sys_f.mass())
    close(pc_t.coupling.coarse, pc_f.coupling.coarse)
    close(pc_t.coupling.fine, pc_f.coupling.fine)
    close(sys_t.external_force(0.0), sys_f.external_force(0.0))
