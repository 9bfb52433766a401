"""Plastic flow in a patch's gluing band: what the coupling, not the material, may make.

In the gluing band the patch's fields are tied to the coarse model's by the mediator and its
weight α_fine ramps down to zero: stresses there are the coupling's, not the material's. A J2
patch that yields in its band shows either a plastic zone that has reached the band (widen the
patch) or strain concentrated by the coupling (a mediator that does not hold the band's
fine-scale modes: docs/theory.md, "The band's fine-scale modes"). Either way the band's plastic
strain is not a result: :func:`band_plasticity` measures it after a step, for the solvers'
watches (:class:`~arlequin.contract.BandYieldWarning`), and :func:`largest_plastic_strain` says
where a patch's largest plastic strain lies, in the band or not.

The models are duck-typed: a patch model with ``equivalent_plastic_strain(state)`` (shape
(n_elems, n_qp)), ``quadrature_points()`` ((dim, n_elems, n_qp), m) and ``scalar_basis()``
(its ``dx``: quadrature weights) is checked; other models are skipped.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from .gluing import PatchCoupling

__all__ = [
    "BandPlasticity",
    "PlasticPeak",
    "band_cells",
    "band_plasticity",
    "largest_plastic_strain",
    "plastic_peak",
]


@dataclass(frozen=True)
class PlasticPeak:
    """The largest equivalent plastic strain of a patch and where it lies.

    Attributes
    ----------
    value : float
        Largest equivalent plastic strain (1).
    position : ndarray, shape (dim,)
        Its quadrature point (m, reference configuration).
    in_band : bool
        Whether that point lies in a cell of the gluing band.
    """

    value: float
    position: np.ndarray
    in_band: bool


@dataclass(frozen=True)
class BandPlasticity:
    """Plastic flow in one patch's gluing band.

    Attributes
    ----------
    patch : str
        The patch's block name.
    fraction : float
        Share of the band's quadrature weight (its volume; area in 2D) at points with a
        positive equivalent plastic strain (1).
    peak : float
        Largest equivalent plastic strain in the band (1); 0 when the band is elastic.
    position : ndarray, shape (dim,)
        Where the band's largest plastic strain lies (m); NaN when the band is elastic.
    """

    patch: str
    fraction: float
    peak: float
    position: np.ndarray


def _measures(model: Any) -> tuple[Any, Any] | None:
    """The model's ``equivalent_plastic_strain`` and quadrature weights, or None."""
    eqps = getattr(model, "equivalent_plastic_strain", None)
    basis = getattr(model, "scalar_basis", None)
    if not callable(eqps) or not callable(basis):
        return None
    return eqps, basis


#: per patch coupling: its band's cell mask and quadrature weights (a dynamic run measures
#: the band at every recorded sample; the patch's mesh and band do not change)
_BANDS: weakref.WeakKeyDictionary[Any, tuple[np.ndarray, np.ndarray]] = weakref.WeakKeyDictionary()


def band_cells(pc: PatchCoupling) -> np.ndarray:
    """The patch cells of the gluing band, shape (n_fine_elems,) bool."""
    mask = np.zeros(pc.fine_model.mesh.nelements, dtype=bool)
    mask[pc.fine_gluing_cells] = True
    return mask


def _band(pc: PatchCoupling, basis_of: Any) -> tuple[np.ndarray, np.ndarray]:
    """The band's cell mask and quadrature weights (n_band, n_qp), computed once per patch."""
    if pc not in _BANDS:
        mask = band_cells(pc)
        _BANDS[pc] = (mask, np.asarray(basis_of().dx)[mask])
    return _BANDS[pc]


def band_plasticity(pc: PatchCoupling, state: Any) -> BandPlasticity | None:
    """Plastic flow in the gluing band of ``pc`` for the patch's ``state``.

    Parameters
    ----------
    pc : PatchCoupling
        The patch as glued.
    state : Any
        The patch model's committed state (its first term's).

    Returns
    -------
    BandPlasticity or None
        None when the patch model tells no plastic strain (an elastic patch).
    """
    measures = _measures(pc.fine_model)
    if measures is None or state is None:
        return None
    eqps_of, basis_of = measures
    eqps = np.asarray(eqps_of(state))  # (n_elems, n_qp)
    band, weight = _band(pc, basis_of)
    in_band = eqps[band]
    plastic = in_band > 0.0
    total = float(weight.sum())
    fraction = float(weight[plastic].sum() / total) if total > 0.0 else 0.0
    dim = pc.fine_model.mesh.dim()
    if not plastic.any():
        return BandPlasticity(pc.name, 0.0, 0.0, np.full(dim, np.nan))
    x = np.asarray(pc.fine_model.quadrature_points())[:, band]  # (dim, n_band, n_qp)
    cell, point = np.unravel_index(int(np.argmax(in_band)), in_band.shape)
    return BandPlasticity(pc.name, fraction, float(in_band[cell, point]), x[:, cell, point].copy())


def plastic_peak(model: Any, state: Any, band: np.ndarray | None = None) -> PlasticPeak | None:
    """The largest equivalent plastic strain of ``model`` in ``state`` and where it lies.

    Parameters
    ----------
    model : Any
        A model with ``equivalent_plastic_strain(state)`` and ``quadrature_points()``.
    state : Any
        Its state.
    band : ndarray of bool, shape (n_elems,), optional
        The model's cells in a gluing band (:func:`band_cells`); None: no band (a single mesh).

    Returns
    -------
    PlasticPeak or None
        None for a model without plastic strain.
    """
    if _measures(model) is None or state is None:
        return None
    eqps = np.asarray(model.equivalent_plastic_strain(state))
    cell, point = np.unravel_index(int(np.argmax(eqps)), eqps.shape)
    x = np.asarray(model.quadrature_points())[:, cell, point].copy()
    return PlasticPeak(float(eqps[cell, point]), x, bool(band is not None and band[cell]))


def largest_plastic_strain(pc: PatchCoupling, state: Any) -> PlasticPeak | None:
    """The largest equivalent plastic strain of the patch of ``pc`` and whether it lies in the
    gluing band (None for a patch model without plastic strain)."""
    return plastic_peak(pc.fine_model, state, band_cells(pc))
