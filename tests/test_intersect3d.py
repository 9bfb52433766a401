"""Exact tetrahedron–tetrahedron intersections (arlequin.geometry.intersect3d) against an
independent construction: scipy's half-space intersection (Qhull) of the eight face planes."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, HalfspaceIntersection
from skfem import MeshTet

from arlequin.geometry.intersect3d import candidate_pairs, classify_pairs, tetrahedra_intersections


def _halfspaces(v: np.ndarray) -> np.ndarray:
    """The 4 half-spaces a·x + b ≤ 0 of tetrahedron v (4, 3), as Qhull wants them."""
    out = []
    for k in range(4):
        face = np.delete(v, k, axis=0)
        n = np.cross(face[1] - face[0], face[2] - face[0])
        if n @ (v[k] - face[0]) > 0:  # outward: away from the opposite vertex
            n = -n
        out.append([*n, -n @ face[0]])
    return np.array(out)


def _reference_volume(a: np.ndarray, b: np.ndarray) -> float:
    """Volume of a ∩ b by Qhull (0 if the Chebyshev ball has no radius)."""
    hs = np.vstack([_halfspaces(a), _halfspaces(b)])
    norm = np.linalg.norm(hs[:, :3], axis=1)
    # the Chebyshev centre: max r s.t. a·x + r|a| ≤ −b
    res = linprog([0, 0, 0, -1], A_ub=np.c_[hs[:, :3], norm], b_ub=-hs[:, 3],
                  bounds=[(None, None)] * 3 + [(0, None)])  # fmt: skip
    if res.status != 0 or res.x[3] <= 1e-9:  # infeasible: disjoint; no radius: flat
        return 0.0
    pts = HalfspaceIntersection(hs, res.x[:3]).intersections
    return float(ConvexHull(pts).volume)


def _volumes(tets: np.ndarray) -> np.ndarray:
    e = tets[:, 1:] - tets[:, :1]
    return np.einsum("kj,kj->k", np.cross(e[:, 0], e[:, 1]), e[:, 2]) / 6.0


def test_random_pairs_match_qhull():
    # random pairs of overlapping tetrahedra of comparable size: every kind of cut; the
    # reference is an independent convex-hull construction, exact to round-off
    rng = np.random.default_rng(7)
    n = 300
    a = rng.random((n, 4, 3))
    # b around a point of a, from much smaller than a (inside it) to much larger (around it)
    centre = a.mean(axis=1, keepdims=True) + rng.uniform(-0.2, 0.2, (n, 1, 3))
    b = centre + (rng.random((n, 4, 3)) - 0.5) * rng.uniform(0.1, 4.0, (n, 1, 1))
    tets, fi, _ = tetrahedra_intersections(a, b, pairs=(np.arange(n), np.arange(n)))
    vol = _volumes(tets)
    assert np.all(vol > 0.0)  # positively oriented
    ours = np.bincount(fi, weights=vol, minlength=n)
    ref = np.array([_reference_volume(a[i], b[i]) for i in range(n)])
    assert np.count_nonzero(ref) > n // 2  # the sample really intersects
    np.testing.assert_allclose(ours, ref, rtol=0, atol=1e-12)


def test_contained_and_separated_pairs_are_recognised():
    a = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    small = 0.1 + 0.2 * a  # inside a
    far = a + np.array([2.0, 0.0, 0.0])  # disjoint
    touching = a * [-1, 1, 1]  # shares the face x = 0 only
    kinds = classify_pairs(np.array([small, a, a, a]), np.array([a, small, far, touching]))
    np.testing.assert_array_equal(kinds, [1, 2, 0, 0])
    tets, _, _ = tetrahedra_intersections(np.array([small]), np.array([a]),
                                           pairs=(np.zeros(1, int), np.zeros(1, int)))  # fmt: skip
    assert tets.shape[0] == 1  # the small cell itself, not a cone of its faces
    assert _volumes(tets)[0] == pytest.approx(0.008 / 6.0, rel=1e-14)


def test_non_nested_meshes_tile_the_fine_cells():
    # two structured meshes of boxes off each other's planes: the pieces of each fine cell
    # inside the coarse box add up to the fine cell (fine box inside the coarse one)
    x = np.linspace(0.0, 1.0, 5)
    coarse = MeshTet.init_tensor(x, x, x)
    fine = MeshTet.init_tensor(*[np.linspace(lo, hi, 7) for lo, hi in
                                 ((0.11, 0.83), (0.07, 0.9), (0.2, 0.77))])  # fmt: skip
    fc = np.transpose(fine.p[:, fine.t], (2, 1, 0))
    cc = np.transpose(coarse.p[:, coarse.t], (2, 1, 0))
    tets, fi, ci = tetrahedra_intersections(fc, cc)
    vol = _volumes(tets)
    fine_vol = np.abs(_volumes(fc))
    np.testing.assert_allclose(np.bincount(fi, weights=vol, minlength=len(fc)), fine_vol,
                               rtol=1e-12)  # fmt: skip
    # every candidate pair's piece agrees with Qhull (a sample)
    f, c = candidate_pairs(fc, cc)
    sel = np.random.default_rng(3).choice(f.size, 150, replace=False)
    keys, where = np.unique(fi * len(cc) + ci, return_inverse=True)
    lookup = dict(zip(keys.tolist(), np.bincount(where, weights=vol).tolist(), strict=True))
    for s in sel:
        ref = _reference_volume(fc[f[s]], cc[c[s]])
        assert lookup.get(int(f[s] * len(cc) + c[s]), 0.0) == pytest.approx(ref, abs=1e-14)


@pytest.mark.parametrize("box", [((0.11, 0.83), (0.0, 1.0), (0.2, 0.77)),
                                 ((0.06, 0.94), (0.07, 0.95), (0.04, 0.92))])  # fmt: skip
def test_compiled_kernel_is_the_numpy_path(box):
    # the same pieces (volumes per pair to round-off) from the compiled clipping kernel and the
    # numpy path, on non-nested structured meshes with faces in common planes (the second box:
    # cut pairs sharing a diagonal plane, where a cap would repeat a face)
    x = np.linspace(0.0, 1.0, 5)
    coarse = MeshTet.init_tensor(x, x, x)
    fine = MeshTet.init_tensor(*[np.linspace(lo, hi, 9) for lo, hi in box])
    fc = np.transpose(fine.p[:, fine.t], (2, 1, 0))
    cc = np.transpose(coarse.p[:, coarse.t], (2, 1, 0))
    pieces = []
    for backend in ("numba", "numpy"):
        tets, fi, ci = tetrahedra_intersections(fc, cc, backend=backend)
        vol = _volumes(tets)
        assert np.all(vol > 0.0)
        keys, where = np.unique(fi * len(cc) + ci, return_inverse=True)
        pieces.append(dict(zip(keys.tolist(), np.bincount(where, weights=vol).tolist(),
                               strict=True)))  # fmt: skip
    scale = np.abs(_volumes(fc)).max()
    for key in set(pieces[0]) | set(pieces[1]):
        assert abs(pieces[0].get(key, 0.0) - pieces[1].get(key, 0.0)) <= 1e-13 * scale
