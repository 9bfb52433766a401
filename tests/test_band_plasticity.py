"""What a J2 patch shows is the material's, not the coupling's (issue 42, part 1).

A quarter plate with a hole (R = 10 mm, 50 mm × 50 mm × 5 mm, SmallStrainJ2, σy = 250 MPa)
pulled to 170 MPa in six steps: a coarse elastic model of the whole plate and a J2 patch over
the hole, every option at its default. The references are single J2 meshes at the patch's
resolution: the coarse mesh refined once (nested patches) or the gmsh mesh the non-nested
patch's cells are part of (tests/data/make_plate3d.py). Measured:

| case | patch max ε̄p | where (r/R) | single mesh |
|---|---|---|---|
| 3D nested to 4R, coarse mediator (main's default) | 0.353 | 4.12 (band) | 0.00379 at 1.03 |
| 3D nested to 4R, default ("auto": fine here) | 0.00375 | 1.03 | 0.00379 at 1.03 |
| 3D non-nested to 4R, default (coarse here) | 0.00420 | 1.04 | 0.00424 at 1.04 |

The cause (docs/theory.md, "The band's fine-scale modes"): a nested tetrahedral patch's
staircase edge leaves whole band cells with α_fine = 0 at every vertex (41 of 3448 here); the
coarse mediator holds only the coarse-scale part of the band's field, so they deform freely.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import meshio
import numpy as np
import pytest
import scipy.spatial as sps

import arlequin
from arlequin.coupling.band_plasticity import band_plasticity, largest_plastic_strain
from arlequin.coupling.exactness import unheld_band_cells
from arlequin.coupling.patches import resolve_mediator
from arlequin.io import read_mesh
from arlequin.models import J2Material, LinearElastic, SmallStrainJ2

DATA = Path(__file__).parent / "data"
R, W = 10e-3, 50e-3
STEEL = J2Material(200e9, 0.3, 7800.0, 250e6, hardening_modulus=2e9)
LOAD = 170e6


def _supports(problem, blocks, dim):
    """Symmetry planes x = 0, y = 0 (and z = 0 in 3D), the traction on x = W."""
    for block in blocks:
        for axis in range(dim):
            problem.add_dirichlet(block, lambda x, i=axis: np.isclose(x[i], 0.0, atol=1e-9),
                                  components=[axis])  # fmt: skip
    traction = np.zeros(dim)
    traction[0] = LOAD
    problem.add_traction(traction, where=lambda x: np.isclose(x[0], W, atol=1e-9))


def _kind(mesh):
    return "3d" if mesh.dim() == 3 else "plane_strain"


def _j2(mesh):
    return SmallStrainJ2(mesh, STEEL, _kind(mesh))


def _peak(model, state):
    """(largest ε̄p, its quadrature point's r/R)."""
    eqps = model.equivalent_plastic_strain(state)
    x = np.asarray(model.quadrature_points())
    cell, point = np.unravel_index(np.argmax(eqps), eqps.shape)
    return float(eqps[cell, point]), float(np.hypot(*x[:2, cell, point]) / R)


def _mono(mesh):
    model = _j2(mesh)
    problem = arlequin.ArlequinProblem(model, [])
    _supports(problem, ["coarse"], mesh.dim())
    result = arlequin.solve_quasi_static(problem, load=1.0, steps=6)
    return _peak(model, result.states["coarse"][0])


def _arlequin(coarse_mesh, patch):
    problem = arlequin.ArlequinProblem(LinearElastic(coarse_mesh, STEEL.elastic,
                                                     _kind(coarse_mesh)), [patch])  # fmt: skip
    _supports(problem, ["coarse", "patch0"], coarse_mesh.dim())
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = arlequin.solve_quasi_static(problem, load=1.0, steps=6)
    band_warnings = [w for w in caught if issubclass(w.category, arlequin.BandYieldWarning)]
    _arlequin.exactness = [  # the set-up's, for the tests that ask
        str(w.message) for w in caught if issubclass(w.category, arlequin.ExactnessWarning)
    ]
    pc = problem.couplings[0]
    state = result.states["patch0"][0]
    return _peak(patch.model, state), result, band_warnings, pc, state


def _nested(coarse_mesh, extent, **options):
    return arlequin.Patch.from_level_set(
        coarse_mesh, lambda x: np.hypot(x[0], x[1]) - extent * R, _j2, levels=1,
        gluing_width=6e-3, **options,
    )  # fmt: skip


@pytest.fixture(scope="module")
def coarse3d():
    return read_mesh(DATA / "plate3d_coarse.vtu")


@pytest.fixture(scope="module")
def mono3d(coarse3d):
    # the single fine mesh of the nested patches: every coarse cell refined once
    return _mono(coarse3d.refined(1))


def test_auto_mediator_resolution():
    """The coarse mediator unless it leaves band cells unheld; explicit choices kept; a bad
    name named."""
    assert resolve_mediator("auto", 0) == "coarse"
    assert resolve_mediator("auto", 3) == "fine"
    assert resolve_mediator("coarse", 3) == "coarse"
    assert resolve_mediator("fine", 0) == "fine"
    with pytest.raises(ValueError, match="mediator must be one of"):
        resolve_mediator("both", 0)
    mesh = read_mesh(DATA / "plate3d_coarse.vtu")
    with pytest.raises(ValueError, match="'both'"):
        arlequin.Patch(_j2(mesh), gluing_width=6e-3, mediator="both")


@pytest.mark.parametrize("coupling", ["H1", "L2"])
def test_nested_3d_patch_defaults_show_the_materials_plastic_strain(coarse3d, mono3d, coupling):
    """Nested patch to 4R, defaults (H1, the default coupling, and L2): the largest plastic
    strain within 10% of the single fine mesh's (measured −1.1% with both) at the same point,
    not in the band, the band elastic."""
    patch = _nested(coarse3d, 4.0, coupling=coupling)
    (peak, where), result, band_warnings, pc, state = _arlequin(coarse3d, patch)
    assert pc.mediator == "fine"  # 41 unheld band cells: "auto" takes the fine mediator
    assert unheld_band_cells(pc).size > 0
    assert peak == pytest.approx(mono3d[0], rel=0.10)
    assert where == pytest.approx(mono3d[1], abs=1e-9)  # the same quadrature point
    top = largest_plastic_strain(pc, state)
    assert top is not None and not top.in_band
    assert result.band_plastic_fraction == 0.0
    assert band_warnings == []
    # no multiplier drift: the fine mediator's rows on the symmetry planes are dropped
    # (mediator_dirichlet="auto"); kept, they are dependent and the multipliers reach 1e17.
    # Bound: 100 times σy over the band's width (an L2 multiplier is a force per volume)
    mu = np.concatenate([np.ravel(m) for m in result.multipliers.values()])
    assert np.abs(mu).max() < 100 * 250e6 / 6e-3


def test_nested_3d_coarse_mediator_is_named_and_watched(coarse3d, mono3d):
    """main's default (the coarse mediator) on the same patch: set-up names the unheld cells
    (ExactnessWarning) and the run reports the band's plastic flow (BandYieldWarning,
    band_plastic_fraction): measured 0.353 in the band, 93 times the single mesh's."""
    patch = _nested(coarse3d, 4.0, mediator="coarse")
    (peak, _), result, band_warnings, pc, state = _arlequin(coarse3d, patch)
    assert any("α_fine = 0 at every vertex" in m for m in _arlequin.exactness)
    assert peak > 10 * mono3d[0]
    assert largest_plastic_strain(pc, state).in_band
    assert result.band_plastic_fraction > 0.0
    assert len(band_warnings) == 1
    assert "yields in its gluing band" in str(band_warnings[0].message)


def test_band_check_fires_where_the_plastic_zone_reaches_the_band(coarse3d):
    """A patch to 2.5R only, defaults: at 170 MPa the real plastic zone reaches the band
    (its inner edge lies at 1.9R to 2.5R on the staircase); the run says so."""
    patch = _nested(coarse3d, 2.5)
    _, result, band_warnings, pc, state = _arlequin(coarse3d, patch)
    band = band_plasticity(pc, state)
    assert band.fraction > 0.0 and band.fraction == result.band_plastic_fraction
    assert np.hypot(*band.position[:2]) < 2.6 * R
    assert len(band_warnings) == 1
    assert "widen the patch" in str(band_warnings[0].message)


def test_non_nested_3d_patch_defaults(coarse3d):
    """A non-nested gmsh patch to 4R (its cells are part of the single fine mesh), defaults:
    within 10% of that mesh's largest plastic strain (measured −1.0%) at the same point."""
    reference = _mono(read_mesh(DATA / "plate3d_fine.vtu"))
    patch = arlequin.Patch(_j2(read_mesh(DATA / "plate3d_ring.vtu")), gluing_width=6e-3)
    (peak, where), result, band_warnings, pc, _ = _arlequin(coarse3d, patch)
    assert pc.mediator == "coarse"  # every band cell holds some weight
    assert peak == pytest.approx(reference[0], rel=0.10)
    assert where == pytest.approx(reference[1], abs=1e-9)
    assert result.band_plastic_fraction == 0.0 and band_warnings == []


def _triangles(h, outer, seed=0):
    """A quarter plate (or ring) with a hole of triangles: rings of nodes every h around the
    hole, jittered, the square's edges, Delaunay, the hole's cells removed (m)."""
    rng = np.random.default_rng(seed)
    points = []
    r = R
    while r < 1.5 * outer:
        n = max(3, int(np.ceil(0.5 * np.pi * r / h)))
        theta = np.linspace(0.0, 0.5 * np.pi, n + 1)
        if R < r < outer:
            theta[1:-1] += rng.uniform(-0.2, 0.2, n - 1) * (np.pi / 2 / n)
        points.append(np.c_[r * np.cos(theta), r * np.sin(theta)])
        r += h
    p = np.vstack(points)
    p = p[(p[:, 0] <= outer + 1e-12) & (p[:, 1] <= outer + 1e-12) | (np.hypot(*p.T) <= outer)]
    if outer >= W:
        s = np.linspace(0.0, W, int(np.ceil(W / h)) + 1)
        p = np.vstack([p, np.c_[np.full_like(s, W), s], np.c_[s, np.full_like(s, W)]])
        p = p[(p[:, 0] <= W + 1e-12) & (p[:, 1] <= W + 1e-12)]
    else:
        p = p[np.hypot(*p.T) <= outer * (1 + 1e-9)]
    p = np.unique(np.round(p, 12), axis=0)
    t = sps.Delaunay(p).simplices
    keep = np.hypot(*p[t].mean(axis=1).T) > R * 1.0001
    t = t[keep & ~np.isclose(np.hypot(*p.T), R)[t].all(axis=1)]
    used = np.unique(t)
    index = np.full(len(p), -1)
    index[used] = np.arange(used.size)
    return p[used], index[t]


def _read_triangles(tmp_path, name, p, t):
    path = tmp_path / f"{name}.vtu"
    meshio.write(path, meshio.Mesh(np.c_[p, np.zeros(len(p))], [("triangle", t)]))
    return read_mesh(path)


@pytest.mark.parametrize("nested", [True, False])
def test_2d_triangle_plate_defaults(tmp_path, nested):
    """The same plate in plane-strain triangles read through read_mesh, patch to 2.5R,
    defaults: the largest plastic strain within 10% of the single fine mesh's, near the hole,
    the band elastic (measured: nested −0.7%, at the same point; non-nested, its own cells at
    the hole, +1.2% of the refined coarse mesh's, the coarse mediator in both)."""
    coarse = _read_triangles(tmp_path, "coarse", *_triangles(3e-3, W))
    reference = _mono(coarse.refined(1))
    if nested:
        patch = arlequin.Patch.from_level_set(
            coarse, lambda x: np.hypot(x[0], x[1]) - 2.5 * R, _j2, levels=1, gluing_width=3e-3
        )
    else:
        fine = _read_triangles(tmp_path, "fine", *_triangles(1.5e-3, 2.5 * R, seed=1))
        patch = arlequin.Patch(_j2(fine), gluing_width=3e-3)
    (peak, where), result, band_warnings, pc, state = _arlequin(coarse, patch)
    assert peak == pytest.approx(reference[0], rel=0.10)
    assert where < 1.1
    assert not largest_plastic_strain(pc, state).in_band
    assert result.band_plastic_fraction == 0.0 and band_warnings == []


def test_plate_demo_reports_its_peak_and_band():
    """The plate demo (1 level; its own defaults), Arlequin against mono: the largest plastic
    strain within 10% (measured −0.4%) at the same quadrature point, outside the band, the
    band elastic; the keys in the result (and so in results.json)."""
    from arlequin.demos.plate_with_hole import run_plate_with_hole

    arl = run_plate_with_hole(model="arlequin", levels=1)
    mono = run_plate_with_hole(model="mono", levels=1)
    assert arl.max_plastic_strain == pytest.approx(mono.max_plastic_strain, rel=0.10)
    assert arl.max_plastic_strain_position == pytest.approx(mono.max_plastic_strain_position)
    assert arl.max_plastic_strain_in_band is False
    assert arl.band_plastic_fraction == 0.0
    assert mono.band_plastic_fraction is None and mono.max_plastic_strain_in_band is None
    assert {"band_plastic_fraction", "max_plastic_strain_in_band"} <= set(arl.to_json())


@pytest.mark.parametrize("pressure, band_yields", [(2.6e8, False), (3.0e8, True)])
def test_vessel_demo_reports_its_peak_and_band(pressure, band_yields):
    """The thick sphere at 16 fine cells across the wall (the patch to 0.175 m, its band the
    ring 0.15-0.175 m): at 260 MPa (Hill's plastic front at 0.138 m) the band is elastic and
    the largest plastic strain, at the bore like mono's, within 10% of it (measured −0.8%);
    at 300 MPa the front (0.158 m) is in the band and the run says so."""
    from arlequin.demos.pressure_vessel import run_pressure_vessel

    sizes = {"coarse_size": 0.025, "fine_size": 0.025 / 4, "pressure": pressure}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        arl = run_pressure_vessel(model="arlequin", **sizes)
    band = [w for w in caught if issubclass(w.category, arlequin.BandYieldWarning)]
    assert (arl.band_plastic_fraction > 0.0) is band_yields
    assert len(band) == int(band_yields)
    if not band_yields:
        mono = run_pressure_vessel(model="mono", **sizes)
        assert arl.max_plastic_strain == pytest.approx(mono.max_plastic_strain, rel=0.10)
        bore = np.linalg.norm(arl.max_plastic_strain_position)
        assert bore == pytest.approx(np.linalg.norm(mono.max_plastic_strain_position), rel=1e-3)
        assert arl.max_plastic_strain_in_band is False


def test_2d_notch_defaults():
    """A plate with a slot (plane strain quadrilaterals; the symmetry half, the slot 5 mm wide
    and 20 mm deep from the top edge) pulled to 60 MPa: a nested patch over the slot's root,
    defaults (the coarse mediator: every quadrilateral of the band keeps a vertex of positive
    weight). The largest plastic strain, at the root's corner, within 10% of the single fine
    mesh's at the same point (measured 0.0020174 against 0.0020239, −0.3%), the band elastic."""
    import skfem

    w, h = 0.1, 0.05

    def slotted(size):
        mesh = skfem.MeshQuad.init_tensor(np.linspace(0, w, round(w / size) + 1),
                                          np.linspace(0, h, round(h / size) + 1))  # fmt: skip
        c = mesh.p[:, mesh.t].mean(axis=1)
        return mesh.restrict(np.nonzero(~((c[0] < 0.005) & (c[1] > 0.03)))[0])

    def supports(problem, blocks):
        for block in blocks:
            problem.add_dirichlet(block, lambda x: np.isclose(x[0], 0.0), components=[0])
        problem.add_dirichlet(blocks[0], lambda x: np.isclose(x[1], 0.0) & np.isclose(x[0], w),
                              components=[1])  # fmt: skip
        problem.add_traction(np.array([60e6, 0.0]), where=lambda x: np.isclose(x[0], w))

    def peak(model, state):
        eqps = model.equivalent_plastic_strain(state)
        cell, point = np.unravel_index(np.argmax(eqps), eqps.shape)
        return eqps.max(), np.asarray(model.quadrature_points())[:, cell, point]

    coarse = slotted(2.5e-3)
    mono = _j2(coarse.refined(1))
    single = arlequin.ArlequinProblem(mono, [])
    supports(single, ["coarse"])
    reference = peak(
        mono, arlequin.solve_quasi_static(single, load=1.0, steps=6).states["coarse"][0]
    )
    patch = arlequin.Patch.from_box(coarse, ((0.0, 0.015), (0.025, 0.05)), _j2, levels=1,
                                    gluing_width=5e-3)  # fmt: skip
    problem = arlequin.ArlequinProblem(LinearElastic(coarse, STEEL.elastic, "plane_strain"),
                                       [patch])  # fmt: skip
    supports(problem, ["coarse", "patch0"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", arlequin.ExactnessWarning)  # the band's corners
        result = arlequin.solve_quasi_static(problem, load=1.0, steps=6)
    value, where = peak(patch.model, result.states["patch0"][0])
    assert problem.couplings[0].mediator == "coarse"
    assert value == pytest.approx(reference[0], rel=0.10)
    np.testing.assert_allclose(where, reference[1], atol=1e-12)
    assert result.band_plastic_fraction == 0.0
