"""What the pressure-vessel demo measures in a J2 state: the von Mises stress, radial profiles
of quadrature-point fields, the plastic front and a field's value at the bore."""

from __future__ import annotations

from typing import Any

import numpy as np

from ...problem.arlequin_problem import von_mises_of

__all__ = ["bore_value", "plastic_radius", "radial_profile", "von_mises"]


def von_mises(state: Any) -> np.ndarray:
    """The von Mises stress (Pa) at the quadrature points of a J2 state, (n_elems, n_qp)."""
    if hasattr(state, "cauchy"):  # finite strain: the Cauchy stress of the last evaluation
        return von_mises_of(state.cauchy)
    return np.asarray(state.von_mises)


def radial_profile(radius: np.ndarray, values: np.ndarray, h: float):
    """Quadrature-point values of a radially symmetric field averaged over bins of radius
    (h/20 wide): (bin radii, bin means), by increasing radius."""
    r, v = radius.ravel(), values.ravel()
    _, inv = np.unique(np.round(r / (h / 20.0)).astype(np.int64), return_inverse=True)
    count = np.bincount(inv)
    return np.bincount(inv, weights=r) / count, np.bincount(inv, weights=v) / count


def plastic_radius(radius: np.ndarray, eqps: np.ndarray, inner: float, h: float) -> float:
    """The plastic front (m) of a radially symmetric plastic zone: ε̄p averaged over radial
    bins (:func:`radial_profile`); the front is where the outermost two plastic bins' ε̄p,
    extrapolated linearly, reaches 0 (at most one bin beyond the last plastic one). ``inner``
    when nothing has yielded."""
    if not np.any(eqps > 0.0):
        return inner
    rb, eb = radial_profile(radius, eqps, h)
    plastic = np.nonzero(eb > 1e-6 * eb.max())[0]
    last = plastic[-1]
    if last == 0 or last - 1 not in plastic:
        return float(rb[last])
    r1, r0, e1, e0 = rb[last], rb[last - 1], eb[last], eb[last - 1]
    front = r1 + e1 * (r1 - r0) / (e0 - e1) if e0 > e1 else r1
    upper = rb[last + 1] if last + 1 < rb.size else r1
    return float(np.clip(front, r1, upper))


def bore_value(radius: np.ndarray, values: np.ndarray, inner: float, h: float) -> float:
    """A radially symmetric field at the bore r = ``inner``: the cell means of its two
    innermost layers of cells extrapolated linearly. (The bilinear cells' Gauss points read
    the von Mises stress alternately 0.9% low and high across a cell, and it falls as 1/r³ in
    the sphere's wall: the innermost points alone read it 1.5% low at 64 cells across; the
    cell means extrapolated, 0.1%.)"""
    rb, vb = radial_profile(radius.mean(axis=1), values.mean(axis=1), 5.0 * h)
    if rb.size < 2:
        return float(vb[0])
    return float(vb[0] + (inner - rb[0]) * (vb[1] - vb[0]) / (rb[1] - rb[0]))
