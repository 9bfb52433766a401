"""Which Taylor bar a run builds: the model (``arlequin``, ``mono``, ``graded``) on the geometry
(``axisymmetric``, ``3d``), from the options of :func:`~arlequin.demos.taylor_bar.run_taylor_bar`
(checked there; the geometry's own checks here, before any mesh is built). SI units.
"""

from __future__ import annotations

from typing import Any

from ..models import J2Material
from .taylor_graded_3d import graded_bar_mesh_3d
from .taylor_meshes import ArlequinBarSizes, arlequin_bar_sizes, graded_bar_mesh
from .taylor_meshes_3d import (
    patch_levels,
    quarter_bar_mesh,
    quarter_section_counts,
    refined_bar_mesh,
)
from .taylor_models import ArlequinBar, MonoBar
from .taylor_models_3d import ArlequinBar3D, MonoBar3D
from .taylor_result import GEOMETRIES

__all__ = ["build_bar"]


def build_bar(
    model: str, geometry: str, length: float, radius: float, n_r: int, material: J2Material,
    config: dict[str, Any], *, nested: bool, coarse_size, patch_length, gluing_width,
    patch_surface, weights, mediator, coupling, fbar, backend, bulk_viscosity, friction,
) -> tuple[Any, int, ArlequinBarSizes | None]:  # fmt: skip
    """The bar of a run, its fine cells along the axis and its nested sizes (or None).

    ``config`` (the run's inputs) gains the sizes and the patch surface. ``nested``: the
    patch's sizes apply (``arlequin``, ``graded``, 3D ``mono`` with ``coarse_size``).

    Raises
    ------
    ValueError
        On a geometry, or a combination of model, geometry and options, that does not exist.
    """
    if geometry not in GEOMETRIES:
        raise ValueError(f"geometry must be one of {GEOMETRIES}, got geometry={geometry!r}")
    three_d = geometry == "3d"
    if patch_surface is not None and not (three_d and model == "arlequin"):
        raise ValueError(f"patch_surface applies to model='arlequin' with geometry='3d' only, "
                         f"got model={model!r}, geometry={geometry!r}")  # fmt: skip
    if patch_surface is not None and patch_length is not None:
        raise ValueError(
            f"give patch_length or patch_surface, not both (got "
            f"patch_length={patch_length}, patch_surface={patch_surface!r})"
        )
    if three_d and model == "mono" and patch_length is not None:
        raise ValueError(f"patch_length applies to model='arlequin' only, got model={model!r}")
    sizes = None
    if nested:
        sizes = arlequin_bar_sizes(length, radius, n_r, coarse_size, patch_length, gluing_width)
        config.update(sizes.as_dict())
    solid = dict(fbar=fbar, backend=backend, bulk_viscosity=bulk_viscosity, friction=friction)
    if model == "graded":
        if three_d:
            mesh = graded_bar_mesh_3d(length, radius, sizes)
            bar = MonoBar3D(length, radius, n_r, material, mesh=mesh, **solid)
            n_s, n_o = quarter_section_counts(sizes.coarse_radial)
            per_layer = n_s * n_s + 2 * n_s * n_o
            bar.graded_fine_elements = 8 * per_layer * sizes.patch_rows
        else:
            mesh = graded_bar_mesh(length, radius, sizes)
            bar = MonoBar(length, radius, n_r, material, mesh=mesh, **solid)
            bar.graded_fine_elements = 2 * sizes.coarse_radial * 2 * sizes.patch_rows
        return bar, 2 * sizes.patch_rows, sizes
    if model == "arlequin":
        options = dict(weights=weights, mediator=mediator, coupling=coupling, **solid)
        if three_d:
            config.update(patch_surface=None if patch_surface is None else str(patch_surface))
            bar: Any = ArlequinBar3D(length, radius, sizes, material, surface=patch_surface,
                                     **options)  # fmt: skip
            config["patch_length"] = bar.patch_top  # the surface's patch reaches this high
        else:
            bar = ArlequinBar(length, radius, sizes, material, **options)
        return bar, sizes.patch_rows * sizes.ratio, sizes
    if three_d:
        mesh = None
        if sizes is not None:  # the Arlequin patch's nodes over the whole bar
            coarse = quarter_bar_mesh(length, radius, sizes.coarse_radial, sizes.coarse_axial)
            mesh = refined_bar_mesh(coarse, radius, patch_levels(sizes.ratio))
        bar = MonoBar3D(length, radius, n_r, material, mesh=mesh, **solid)
        return bar, bar.elements_axial, sizes
    bar = MonoBar(length, radius, n_r, material, **solid)
    return bar, bar.mesh.t.shape[1] // n_r, sizes
