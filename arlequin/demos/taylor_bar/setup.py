"""Which Taylor bar a run builds: the inputs resolved and checked (:func:`resolve`, the
configuration's ``check``), then the model (``arlequin``, ``mono``, ``graded``) on the geometry
(``axisymmetric``, ``3d``) built from them (:func:`build_bar`). SI units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, is_dataclass
from typing import Any

from ...coupling.weights import PartitionWeights
from ...models import BulkViscosity, J2Material
from ...solvers import CriticalFraction
from ..config import check_choice
from .graded_3d import check_graded_sizes, graded_bar_mesh_3d
from .meshes import (
    ArlequinBarSizes,
    arlequin_bar_sizes,
    elements_radial_of,
    fine_radial,
    graded_bar_mesh,
    positive,
)
from .meshes_3d import (
    patch_levels,
    quarter_bar_mesh,
    quarter_section_counts,
    refined_bar_mesh,
)
from .models import ArlequinBar, MonoBar, hardening_parameters
from .models_3d import ArlequinBar3D, MonoBar3D, check_arlequin_sizes_3d
from .result import GEOMETRIES, MODELS

__all__ = ["Resolved", "build_bar", "resolve"]


@dataclass(frozen=True)
class Resolved:
    """The inputs of a run as it uses them: the defaults computed, the material made.

    Attributes
    ----------
    n_r : int
        Fine cells across the radius.
    nested : bool
        The patch's sizes apply (``arlequin``, ``graded``, 3D ``mono`` with ``coarse_size``).
    sizes : ArlequinBarSizes or None
        The nested sizes (``nested`` only).
    weights, mediator, coupling, coarse_step_ratio, band_warning
        The Arlequin options with their defaults.
    material : J2Material
    controller : CriticalFraction
        The step controller (safety, estimate_every).
    visc : BulkViscosity or None
    fbar : bool
    """

    n_r: int
    nested: bool
    sizes: ArlequinBarSizes | None
    weights: Any
    mediator: str
    coupling: str
    coarse_step_ratio: Any
    band_warning: float
    material: J2Material
    controller: CriticalFraction
    visc: BulkViscosity | None
    fbar: bool


def resolve(c: Any) -> Resolved:
    """The inputs of the configuration ``c`` resolved and checked, nothing built.

    Raises
    ------
    ValueError
        Naming the quantity and its value, on the first bad input.
    """
    if c.model not in MODELS:
        raise ValueError(f"model must be one of {MODELS}, got {c.model!r}")
    for name in ("checkpoint_interval", "t_end", "velocity", "length", "radius",
                 "sample_interval", "frame_interval"):  # fmt: skip
        positive(name, getattr(c, name))
    nested, n_r = _cells_across(c)
    weights = "ramp" if c.weights is None else c.weights
    mediator = "fine" if c.mediator is None else c.mediator
    coupling = "H1" if c.coupling is None else c.coupling
    ratio = 1 if c.coarse_step_ratio is None else c.coarse_step_ratio
    band_warning = 0.02 if c.band_warning is None else c.band_warning
    _check_arlequin_options(c.model, weights, mediator, coupling, ratio, band_warning)
    if isinstance(c.friction, bool) or not (
        isinstance(c.friction, (int, float)) and math.isfinite(c.friction) and c.friction >= 0.0
    ):
        raise ValueError(f"friction must be a non-negative number (Coulomb μ), got {c.friction!r}")
    if not (isinstance(band_warning, (int, float)) and band_warning >= 0.0):
        raise ValueError(f"band_warning must be a non-negative number, got {band_warning!r}")
    law = hardening_parameters(c.hardening_law, c.yield_stress, c.hardening,
                               **c.law_parameters())  # fmt: skip
    material = J2Material.with_law(c.young, c.poisson, c.density, law)
    if int(c.estimate_every) != c.estimate_every or c.estimate_every < 1:
        raise ValueError(f"estimate_every must be a positive integer, got {c.estimate_every}")
    controller = CriticalFraction(c.safety, int(c.estimate_every))  # checks safety ∈ (0, 1]
    if not isinstance(c.bulk_viscosity, (bool, BulkViscosity)):
        raise ValueError(
            f"bulk_viscosity must be a bool or a BulkViscosity, got {c.bulk_viscosity!r}"
        )
    if not isinstance(c.no_fbar, bool):
        raise ValueError(f"no_fbar must be True or False, got no_fbar={c.no_fbar!r}")
    check_choice("backend", c.backend, ("auto", "numba", "numpy"))
    visc = BulkViscosity() if c.bulk_viscosity is True else (c.bulk_viscosity or None)
    sizes = _sizes(c, nested, n_r)
    return Resolved(n_r, nested, sizes, weights, mediator, coupling, ratio, band_warning,
                    material, controller, visc, not c.no_fbar)  # fmt: skip


def _cells_across(c: Any) -> tuple[bool, int]:
    """Whether the patch's sizes apply, and the fine cells across the radius."""
    names = ("gluing_width", "weights", "band_warning", "mediator", "coupling",
             "coarse_step_ratio")  # fmt: skip
    only_arlequin = {k: v for k in names if (v := getattr(c, k)) is not None}
    if c.model != "arlequin" and only_arlequin:
        raise ValueError(f"{sorted(only_arlequin)} apply to model='arlequin' only, got "
                         f"model={c.model!r}")  # fmt: skip
    # the patch's sizes apply (3D mono with coarse_size: the coarse O-grid refined)
    nested = c.model in ("arlequin", "graded") or (
        c.model == "mono" and c.geometry == "3d" and c.coarse_size is not None
    )
    if nested:
        return nested, fine_radial(c.elements_radial, c.mesh_size, c.fine_size, c.radius)
    extra = {k: v for k in ("patch_length", "coarse_size") if (v := getattr(c, k)) is not None}
    if extra:
        raise ValueError(f"{sorted(extra)} apply to model='arlequin' or 'graded' only, got "
                         f"model={c.model!r}")  # fmt: skip
    if c.fine_size is not None:
        raise ValueError(f"fine_size applies to model='arlequin' or 'graded' only (use "
                         f"mesh_size), got model={c.model!r}")  # fmt: skip
    return nested, elements_radial_of(c.elements_radial, c.mesh_size, c.radius)


def _check_arlequin_options(model, weights, mediator, coupling, ratio, band_warning) -> None:
    if isinstance(ratio, bool) or int(ratio) != ratio or ratio < 1:
        raise ValueError(f"coarse_step_ratio must be a positive integer, got {ratio!r}")
    if ratio != 1 and model != "arlequin":
        raise ValueError(f"coarse_step_ratio={ratio} needs a coarse model: it applies "
                         f"to model='arlequin' only, got model={model!r}")  # fmt: skip
    if not isinstance(weights, PartitionWeights) and weights not in ("ramp", "constant"):
        raise ValueError(f"weights must be 'ramp', 'constant' or a PartitionWeights, got "
                         f"weights={weights!r}")  # fmt: skip
    for name, value, choices in (("mediator", mediator, ("coarse", "fine")),
                                 ("coupling", coupling, ("L2", "H1"))):  # fmt: skip
        if value not in choices:
            raise ValueError(f"{name} must be one of {choices}, got {name}={value!r}")


def _sizes(c: Any, nested: bool, n_r: int) -> ArlequinBarSizes | None:
    """The geometry's checks (before any mesh is built) and the nested sizes (or None)."""
    if c.geometry not in GEOMETRIES:
        raise ValueError(f"geometry must be one of {GEOMETRIES}, got geometry={c.geometry!r}")
    three_d = c.geometry == "3d"
    if c.patch_surface is not None and not (three_d and c.model == "arlequin"):
        raise ValueError(f"patch_surface applies to model='arlequin' with geometry='3d' only, "
                         f"got model={c.model!r}, geometry={c.geometry!r}")  # fmt: skip
    if c.patch_surface is not None and c.patch_length is not None:
        raise ValueError(
            f"give patch_length or patch_surface, not both (got "
            f"patch_length={c.patch_length}, patch_surface={c.patch_surface!r})"
        )
    if three_d and c.model == "mono" and c.patch_length is not None:
        raise ValueError(f"patch_length applies to model='arlequin' only, got model={c.model!r}")
    if not nested:
        if three_d:
            quarter_section_counts(n_r)
        return None
    sizes = arlequin_bar_sizes(c.length, c.radius, n_r, c.coarse_size, c.patch_length,
                               c.gluing_width)  # fmt: skip
    if three_d and c.model == "arlequin":
        check_arlequin_sizes_3d(sizes)
    elif three_d and c.model == "graded":
        check_graded_sizes(sizes)
    elif three_d:  # mono: the coarse O-grid refined to the fine size
        quarter_section_counts(sizes.coarse_radial)
        patch_levels(sizes.ratio)
    return sizes


def _plain(value: Any) -> Any:
    """A Python-only input as plain JSON: a name, or an object's type and named fields."""
    if value is None or isinstance(value, (str, int, float)):
        return value
    if is_dataclass(value):
        return {"type": type(value).__name__,
                **{f.name: getattr(value, f.name) for f in fields(value)}}  # fmt: skip
    return type(value).__name__


def build_bar(c: Any, r: Resolved) -> tuple[Any, int, dict[str, Any]]:
    """The bar of the configuration ``c`` (resolved: ``r``), its fine cells along the axis and
    the inputs it records so far (the model, the geometry, the nested sizes, the patch surface
    and the Arlequin options).

    Raises
    ------
    ValueError
        On a combination of model, geometry and options that the models refuse (a patch surface
        that misses the impact face, ...).
    """
    record: dict[str, Any] = {"model": c.model, "geometry": c.geometry}
    sizes = r.sizes
    if sizes is not None:
        record.update(sizes.as_dict())
    solid = dict(fbar=r.fbar, backend=c.backend, bulk_viscosity=r.visc, friction=c.friction)
    if c.model == "graded":
        return _graded(c, r, solid), 2 * sizes.patch_rows, record
    if c.model == "arlequin":
        options = dict(weights=r.weights, mediator=r.mediator, coupling=r.coupling, **solid)
        if c.geometry == "3d":
            surface = c.patch_surface
            record.update(patch_surface=None if surface is None else _surface_name(surface))
            bar: Any = ArlequinBar3D(c.length, c.radius, sizes, r.material, surface=surface,
                                     **options)  # fmt: skip
            record["patch_length"] = bar.patch_top  # the surface's patch reaches this high
        else:
            bar = ArlequinBar(c.length, c.radius, sizes, r.material, **options)
        record.update(weights=_plain(r.weights), mediator=r.mediator, coupling=r.coupling,
                      coarse_step_ratio=int(r.coarse_step_ratio), band_warning=r.band_warning,
                      epsilon=bar.problem.patches[0].epsilon)  # fmt: skip
        return bar, sizes.patch_rows * sizes.ratio, record
    if c.geometry == "3d":
        mesh = None
        if sizes is not None:  # the Arlequin patch's nodes over the whole bar
            coarse = quarter_bar_mesh(c.length, c.radius, sizes.coarse_radial, sizes.coarse_axial)
            mesh = refined_bar_mesh(coarse, c.radius, patch_levels(sizes.ratio))
        bar = MonoBar3D(c.length, c.radius, r.n_r, r.material, mesh=mesh, **solid)
        return bar, bar.elements_axial, record
    bar = MonoBar(c.length, c.radius, r.n_r, r.material, **solid)
    return bar, bar.mesh.t.shape[1] // r.n_r, record


def _graded(c: Any, r: Resolved, solid: dict[str, Any]) -> Any:
    """The graded bar: one conforming mesh, fine over the patch region, coarse above."""
    sizes = r.sizes
    if c.geometry == "3d":
        mesh = graded_bar_mesh_3d(c.length, c.radius, sizes)
        bar = MonoBar3D(c.length, c.radius, r.n_r, r.material, mesh=mesh, **solid)
        n_s, n_o = quarter_section_counts(sizes.coarse_radial)
        per_layer = n_s * n_s + 2 * n_s * n_o
        bar.graded_fine_elements = 8 * per_layer * sizes.patch_rows
    else:
        mesh = graded_bar_mesh(c.length, c.radius, sizes)
        bar = MonoBar(c.length, c.radius, r.n_r, r.material, mesh=mesh, **solid)
        bar.graded_fine_elements = 2 * sizes.coarse_radial * 2 * sizes.patch_rows
    return bar


def _surface_name(surface: Any) -> str:
    """The patch surface as recorded: its path, or the type of the object given."""
    import os

    if isinstance(surface, (str, os.PathLike)):
        return str(surface)
    return type(surface).__name__
