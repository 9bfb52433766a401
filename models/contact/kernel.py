"""The compiled kernels of the contact constraints: the projection of point-to-segment contact
(2D deformable pairs), the rows' products and the level-set statuses of a step.

For each slave point, the closest point on every master segment (the parameter t of the
projection clipped to [0, 1]), the segment at the smallest distance (the first one on a tie),
its oriented unit normal and the projected point: the numpy path of
:meth:`~arlequin.models.contact.geometry.DeformableContactPair._project` with the same formulas
in the same order, so the same results bit for bit (tested). The numpy path builds m × n_f
arrays for each of about fifteen operations; a 30-point contact took 55 µs a step there.

The rows' products (:func:`rows_times`, :func:`rows_sum_dot`) sum each row's entries from
0.0 in their storage order, as scipy's CSR product does, and the status kernels
(:func:`level_set_begin`, :func:`level_set_status`) evaluate the numpy expressions of
:class:`~arlequin.models.contact.level_set.LevelSetContact` element by element with the same
roundings (no fused multiply-add: numba's default), so the same numbers bit for bit (tested):
a step's statuses took some twenty numpy calls and three scipy products (about 30 µs of a
Taylor bar step's contact, twice that in the run's cold caches) where one call does.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = [
    "equal_gathered",
    "level_set_begin",
    "level_set_status",
    "plane_gaps",
    "project_segments",
    "rows_sum_dot",
    "rows_times",
    "scaled_entries",
    "segment_geometry",
]


@njit(cache=True)
def project_segments(xs: np.ndarray, a: np.ndarray, b: np.ndarray, orient: np.ndarray):
    """Closest segment k (m,), its parameter t (m,), its unit normal (2, m) times ``orient[k]``
    and the projected point (2, m) of points ``xs`` (2, m) on the segments from ``a`` to ``b``
    (2, n_f) (m); the normal of a segment is its direction turned clockwise (as
    :func:`arlequin.geometry.facets.facet_normals`)."""
    m = xs.shape[1]
    nf = a.shape[1]
    k = np.zeros(m, dtype=np.int64)
    tk = np.zeros(m)
    nrm = np.zeros((2, m))
    xm = np.zeros((2, m))
    for i in range(m):
        best = np.inf
        for f in range(nf):
            d0 = b[0, f] - a[0, f]
            d1 = b[1, f] - a[1, f]
            t = ((xs[0, i] - a[0, f]) * d0 + (xs[1, i] - a[1, f]) * d1) / (d0 * d0 + d1 * d1)
            t = min(max(t, 0.0), 1.0)
            e0 = xs[0, i] - (a[0, f] + t * d0)
            e1 = xs[1, i] - (a[1, f] + t * d1)
            dist = e0 * e0 + e1 * e1
            if dist < best:
                best = dist
                k[i] = f
                tk[i] = t
        f = k[i]
        t0 = b[0, f] - a[0, f]
        t1 = b[1, f] - a[1, f]
        ln = np.sqrt(t1 * t1 + t0 * t0)
        nrm[0, i] = t1 / ln * orient[f]
        nrm[1, i] = -t0 / ln * orient[f]
        s0, s1 = 1.0 - tk[i], tk[i]
        xm[0, i] = a[0, f] * s0 + b[0, f] * s1
        xm[1, i] = a[1, f] * s0 + b[1, f] * s1
    return k, tk, nrm, xm


@njit(cache=True)
def plane_gaps(x_ref: np.ndarray, dofs: np.ndarray, u: np.ndarray, normal: np.ndarray,
               point: np.ndarray) -> np.ndarray:  # fmt: skip
    """Gaps ``−n·(X + u[dofs] − p)`` (m,) (m) of points at reference positions ``x_ref``
    (dim, m) with dofs ``dofs`` (dim, m) in u (n,), against the plane through ``point`` (dim,)
    of unit normal ``normal`` (dim,): :meth:`PlaneObstacle.phi
    <arlequin.models.contact.obstacles.PlaneObstacle.phi>` of the positions, negated, in one
    pass (three numpy calls and a BLAS product, ~20 µs of a Taylor bar step in the run, before).
    The sum over the dim components runs in order; BLAS's may not: equal to round-off."""
    d, m = x_ref.shape
    gap = np.empty(m)
    for i in range(m):
        s = 0.0
        for k in range(d):
            s += normal[k] * ((x_ref[k, i] + u[dofs[k, i]]) - point[k])
        gap[i] = -s
    return gap


@njit(cache=True)
def segment_geometry(x_ref: np.ndarray, s_dofs: np.ndarray, seg_ref: np.ndarray,
                     seg_dofs: np.ndarray, u: np.ndarray, orient: np.ndarray,
                     vals: np.ndarray):  # fmt: skip
    """The geometry of 2D point-to-segment contact at displacement u, in one call.

    The numbers of :meth:`DeformableContactPair.geometry
    <arlequin.models.contact.geometry.DeformableContactPair.geometry>`'s numpy lines bit for
    bit (the same operations on the same values): slave positions ``xs = x_ref + u[s_dofs]``,
    segment ends ``seg_ref + u[seg_dofs]``, the projection (:func:`project_segments`), the gaps
    ``−n·(xs − x_m)`` and the rows' values by point. About fifteen numpy calls a step before
    (24 µs warm of a ball impact step, three times that in the run).

    Parameters
    ----------
    x_ref, s_dofs : ndarray, shape (2, m)
        Slave points' reference positions (m) and dofs in u.
    seg_ref : ndarray, shape (2, n_f, 2)
        Segment ends' reference positions (m): component, segment, end.
    seg_dofs : ndarray, shape (2, n_f · 2)
        Their dofs in u (segment-major, then end).
    u : ndarray, shape (n,)
    orient : ndarray, shape (n_f,)
        ±1 per segment (outward normals).
    vals : ndarray, shape (m, 6)
        Output: the rows' values by point, ``−n`` then ``N_j n`` for the two ends j.

    Returns
    -------
    k : ndarray of int64, shape (m,)
        Closest segment.
    shape : ndarray, shape (m, 2)
        Its shape values (1 − t, t) at the projection.
    normal : ndarray, shape (2, m)
    gap : ndarray, shape (m,)
        d_n (m).
    """
    m = x_ref.shape[1]
    nf = seg_ref.shape[1]
    xs = np.empty((2, m))
    for c in range(2):
        for i in range(m):
            xs[c, i] = x_ref[c, i] + u[s_dofs[c, i]]
    a = np.empty((2, nf))
    b = np.empty((2, nf))
    for c in range(2):
        for f in range(nf):
            a[c, f] = seg_ref[c, f, 0] + u[seg_dofs[c, 2 * f]]
            b[c, f] = seg_ref[c, f, 1] + u[seg_dofs[c, 2 * f + 1]]
    k, tk, nrm, xm = project_segments(xs, a, b, orient)
    shape = np.empty((m, 2))
    gap = np.empty(m)
    for i in range(m):
        shape[i, 0] = 1.0 - tk[i]
        shape[i, 1] = tk[i]
        gap[i] = -(nrm[0, i] * (xs[0, i] - xm[0, i]) + nrm[1, i] * (xs[1, i] - xm[1, i]))
        vals[i, 0] = -nrm[0, i]
        vals[i, 1] = -nrm[1, i]
        for j in range(2):
            for c in range(2):
                vals[i, 2 + 2 * j + c] = shape[i, j] * nrm[c, i]
    return k, shape, nrm, gap


@njit(cache=True)
def rows_times(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, x: np.ndarray):
    """``G x`` (m,) of CSR rows G (arrays ``indptr`` (m + 1,), ``indices``, ``data`` (nnz,))
    and a vector x (n,): each row's entries summed from 0.0 in their order, as scipy's CSR
    product."""
    m = indptr.size - 1
    y = np.empty(m)
    for i in range(m):
        s = 0.0
        for jj in range(indptr[i], indptr[i + 1]):
            s += data[jj] * x[indices[jj]]
        y[i] = s
    return y


@njit(cache=True)
def rows_sum_dot(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, x: np.ndarray,
                 z: np.ndarray, w: np.ndarray) -> float:  # fmt: skip
    """``w · G (x + z)`` for rows G (m, n) (CSR arrays), vectors x and z (n,) and weights w
    (m,): each row's product as :func:`rows_times` with the sum x + z taken on the columns of G
    only (the same numbers as the full-size sum's at those columns), then the rows' products
    summed in order (BLAS's dot may pair them: equal to round-off). A contact step's work from
    its impulses, one call where a product and a dot took two."""
    total = 0.0
    for i in range(indptr.size - 1):
        s = 0.0
        for jj in range(indptr[i], indptr[i + 1]):
            j = indices[jj]
            s += data[jj] * (x[j] + z[j])
        total += w[i] * s
    return total


@njit(cache=True)
def level_set_begin(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, v: np.ndarray,
                    gap: np.ndarray, dt: float, was: np.ndarray):  # fmt: skip
    """The first statuses of a level-set step: ``vn0 = G v`` (m/s), ``gap_pred = gap + dt vn0``
    (m), ``s_d = (gap_pred >= 0) | was`` and ``active = s_d & (was | (vn0 > 0))`` (bool), each
    (m,), for rows G (CSR arrays), the step's free velocity v (n,), the gaps (m,), the step
    dt (s) and the last step's statuses ``was`` (m,)."""
    vn0 = rows_times(indptr, indices, data, v)
    m = vn0.size
    gap_pred = np.empty(m)
    s_d = np.empty(m, dtype=np.bool_)
    active = np.empty(m, dtype=np.bool_)
    for i in range(m):
        gap_pred[i] = gap[i] + dt * vn0[i]
        s_d[i] = (gap_pred[i] >= 0.0) or was[i]
        active[i] = s_d[i] and (was[i] or vn0[i] > 0.0)
    return vn0, gap_pred, s_d, active


@njit(cache=True)
def level_set_status(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray, v: np.ndarray,
                     lam: np.ndarray, kappa: float, s_d: np.ndarray, used: np.ndarray):  # fmt: skip
    """The statuses after a solve: ``vn = G v`` (m/s), ``s_v = lam − kappa vn <= 0`` and
    ``active = s_d & s_v`` (bool), each (m,), and whether ``active`` differs from ``used``, for
    rows G (CSR arrays), the solution's velocity v (n,), the multipliers lam (m,) (Pa) and κ
    (Pa·s/m)."""
    vn = rows_times(indptr, indices, data, v)
    m = vn.size
    s_v = np.empty(m, dtype=np.bool_)
    active = np.empty(m, dtype=np.bool_)
    changed = False
    for i in range(m):
        s_v[i] = lam[i] - kappa * vn[i] <= 0.0
        active[i] = s_d[i] and s_v[i]
        if active[i] != used[i]:
            changed = True
    return vn, s_v, active, changed


@njit(cache=True)
def equal_gathered(values: np.ndarray, b: np.ndarray, idx: np.ndarray) -> bool:
    """``bool((values == b[idx]).all())`` for gathered values (k,), a vector b and indices idx
    (k,), without the gather: False at the first difference."""
    for k in range(idx.size):
        if values[k] != b[idx[k]]:
            return False
    return True


@njit(cache=True)
def scaled_entries(data: np.ndarray, w: np.ndarray, keep_before: np.ndarray):
    """The entries ``data * w`` (nnz,) of rows scaled entry by entry, without their zeros (in
    their order), the mask of the non-zero ones (nnz,), whether it equals ``keep_before`` and
    whether every entry is kept: ``_make_b``'s numpy lines (``data * w``, ``!= 0``, ``all``,
    ``array_equal``, the compaction) in one call, for a deforming contact's rows (new at every
    step)."""
    n = data.size
    scaled = np.empty(n)
    keep = np.empty(n, dtype=np.bool_)
    same = keep_before.size == n
    count = 0
    for i in range(n):
        x = data[i] * w[i]
        scaled[i] = x
        k = x != 0.0
        keep[i] = k
        if k:
            count += 1
        if same and keep_before[i] != k:
            same = False
    if count == n:
        return scaled, keep, same, True
    out = np.empty(count)
    j = 0
    for i in range(n):
        if keep[i]:
            out[j] = scaled[i]
            j += 1
    return out, keep, same, False
