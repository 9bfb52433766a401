"""Acceptance test: plate with a hole, an Arlequin patch around the hole vs a single fine mesh.

2D plane-strain plate 10a × 10a with a hole of radius a under a uniaxial traction σ∞ (quarter
model with symmetry conditions, see ``examples/plate_with_hole.py``). A patch of the coarse rings
around the hole is refined ``levels`` times, the hole nodes projected onto the circle after every
level; the single-mesh reference is the whole coarse mesh refined the same way. σ_θθ at (a, 90°)
(= σ_xx at the node (0, a)) recovered by the same lumped L2 projection from the patch's fine
model and from the reference must agree within 1 %.

Ground truth is the reference run; Kirsch's 3σ∞ (infinite plate) is only a sanity bound. For this
finite *square* plate (free edges at y = ±5a, load at x = ±5a) the converged discrete value is
about 3.35σ∞ (reference runs: triangles 3.360 / 3.364 / 3.363 / 3.362 at 1 / 2 / 3 / 4 levels,
quadrilaterals 3.255 / 3.309 / 3.334 / 3.347), above Howland's 3.14σ∞ for a long strip with
d/W = 0.2. The same meshes loaded with the exact Kirsch tractions on x = 5a and y = 5a give
3.003σ∞ (triangles, 3 levels) and 2.978σ∞ (quadrilaterals, 3 levels), which checks the geometry,
the symmetry conditions and the recovery.

The Arlequin/reference difference does not shrink with the refinement levels: it is the coarse
model's discretization error outside the patch (the far field that loads the patch), so it is set
by the patch size and the coarse mesh. Measured |σ_arlequin − σ_ref| / |σ_ref| (coarse mesh 8 cells
per 45° of hole × 12 rings; ramp weights, coarse mediator, gluing band = 2 coarse rings; H1 with
the library's default length ℓ = mean coarse cell size on the band, 0.22a for triangles):

==========================  ======  =======  =======  ================================
patch (rings, x-axis edge)  levels  H1       L2       note
==========================  ======  =======  =======  ================================
tri, 7 rings (2.29a)        2       0.992 %  1.014 %  no margin for the 1 % bound
tri, 7 rings (2.29a)        3       1.031 %  1.060 %  fails the 1 % bound
tri, 8 rings (2.65a)        2       0.810 %  0.841 %  tested below
tri, 8 rings (2.65a)        3       0.833 %  0.875 %  tested below (H1)
tri, 8 rings (2.65a)        4       0.831 %  0.881 %  slow test
tri, 9 rings (3.08a)        3       0.681 %  0.717 %
quad, 7 rings (2.29a)       2       0.338 %  0.367 %  tested below
quad, 7 rings (2.29a)       4       0.348 %  0.390 %  slow test
==========================  ======  =======  =======  ================================

With ℓ = the gluing width (0.71a; the library default before the switch to the coarse cell size)
the 8-ring triangle patch gave 0.676 / 0.671 / 0.654 % at 2 / 3 / 4 levels.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

_EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "plate_with_hole.py"


def _load_example():
    spec = importlib.util.spec_from_file_location("plate_with_hole", _EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


plate = _load_example()

A = 0.01  # hole radius (m), the example's default
TOL = 0.01  # the acceptance bound: 1 % relative difference to the single-mesh reference

# (element, patch_radius in units of a): triangles need 8 coarse rings (patch edge 2.65a on the x
# axis) to pass the 1 % bound with margin, quadrilaterals pass with 7 (2.29a); see the table above
CONFIGS = {"tri": 3.0, "quad": 2.5}


def _check(result: dict) -> None:
    assert result["rel_diff"] <= TOL, result
    # both solves are direct (SuperLU): residuals at round-off (measured 4e-14 to 4e-13)
    assert result["residual_arlequin"] < 1e-9
    assert result["residual_reference"] < 1e-9
    # sanity bound only: Kirsch's 3σ∞ for an infinite plate; this square plate gives ≈ 3.35σ∞
    assert 3.0 < result["scf_arlequin"] < 3.5
    assert 3.0 < result["scf_reference"] < 3.5


def test_meshes_share_the_hole_node_and_lie_on_the_circle():
    """Hole nodes are on r = a in both fine meshes, which share their nodes inside the patch."""
    coarse, ring, radii = plate.quarter_plate_mesh(A, 8, 12, "tri")
    assert np.allclose(np.linalg.norm(coarse.p[:, plate.hole_nodes(coarse, A)], axis=0), A)
    # 7 rings have their outer edge within 2.5a on the x axis (radii from the grading)
    assert np.count_nonzero(radii[1:] <= 2.5 * A) == 7
    patch = plate.refine_projected(coarse, 2, A, cells=np.nonzero(ring < 7)[0])
    ref = plate.refine_projected(coarse, 2, A)
    for mesh in (patch, ref):
        nodes = plate.hole_nodes(mesh, A)
        assert nodes.size == 2 * 8 * 4 + 1  # 16 coarse hole facets, each split in 4
        assert np.allclose(np.linalg.norm(mesh.p[:, nodes], axis=0), A, rtol=1e-14)
    # every patch node is a reference node (same refinement and projection sequence)
    d = np.linalg.norm(patch.p[:, :, None] - ref.p[:, None, :], axis=0).min(axis=1)
    assert d.max() < 1e-12 * A
    assert plate._node_at(patch, np.array([0.0, A])) >= 0


# measured rel_diff at 2 levels (module docstring table): tri H1 0.810 %, tri L2 0.841 %,
# quad H1 0.338 %, quad L2 0.367 %
@pytest.mark.parametrize("element", ["tri", "quad"])
@pytest.mark.parametrize("coupling", ["H1", "L2"])
def test_hole_stress_matches_single_mesh(element, coupling):
    """2 levels: 4.3k (tri, 8 rings) / 3.8k (quad, 7 rings) fine dofs vs 6.4k reference dofs."""
    result = plate.run(
        a=A, levels=2, element=element, coupling=coupling, patch_radius=CONFIGS[element]
    )
    assert result["n_patch_rings"] == {"tri": 8, "quad": 7}[element]
    _check(result)


def test_hole_stress_matches_single_mesh_three_levels():
    """3 levels, triangles, H1: 16.8k fine dofs vs 25k reference dofs (about 3 s)."""
    result = plate.run(a=A, levels=3, element="tri", coupling="H1", patch_radius=CONFIGS["tri"])
    # measured: σ_θθ = 3.3352σ∞ (Arlequin) vs 3.3632σ∞ (reference), rel_diff 0.833 %
    _check(result)


# measured rel_diff at 4 levels (module docstring table): tri H1 0.831 %, tri L2 0.881 %,
# quad H1 0.348 %, quad L2 0.390 %; 19-33 s per case
@pytest.mark.slow
@pytest.mark.parametrize("element", ["tri", "quad"])
@pytest.mark.parametrize("coupling", ["H1", "L2"])
def test_hole_stress_matches_single_mesh_four_levels(element, coupling):
    """4 levels: 58k-66k fine dofs vs 99k reference dofs."""
    result = plate.run(
        a=A, levels=4, element=element, coupling=coupling, patch_radius=CONFIGS[element]
    )
    _check(result)
