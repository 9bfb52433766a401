"""Compiled vector updates of the explicit step, each one pass where numpy made two or three.

The central-difference step forms a handful of full-length vectors: the free velocity
``v* = v⁻ + Δt̄ a``, the new displacement ``u + Δt v``, the velocity at the step's time
``v⁻ + s (v⁺ − v⁻)`` and the products of the internal work ``Δu · ½(f_old + f_new)``. numpy
makes each operation a pass over all n dofs with a new array or a buffer (on the ball impact's
26,814 dofs, some ten passes a step, each 10–20 µs in the run's cold caches). Here each update
is one compiled loop over the same values with the same operations in the same order (numba's
default: no fused multiply-add), so the results are those of the numpy lines bit for bit
(tested against them).

The kick, the predictor, the velocity at t and the finite-state check are timed as linear
algebra by the step timers (:func:`~arlequin.linalg.timing.vector_updates_done`: they run
outside the step's other timed regions); the internal work's products are timed with the energy
bookkeeping by their caller.

numba compiles on first call (cached on disk, ``cache=True``).
"""

from __future__ import annotations

import numba as nb
import numpy as np

from .timing import timer_start, vector_updates_done

__all__ = ["interpolated", "scaled_plus", "subtract_scaled_at", "sum_of_squares", "work_products"]


@nb.njit(cache=True)
def _scaled_plus(alpha, x, y, out):
    for i in range(out.size):
        out[i] = alpha * x[i] + y[i]


@nb.njit(cache=True)
def _interpolated(x0, x1, share, out):
    for i in range(out.size):
        out[i] = (x1[i] - x0[i]) * share + x0[i]


@nb.njit(cache=True)
def _work_products(u_new, u_old, f_old, f_new, out):
    for i in range(out.size):
        out[i] = (u_new[i] - u_old[i]) * ((f_old[i] + f_new[i]) * 0.5)


# reassociation (the sum in SIMD lanes): the order does not matter to a finiteness test; no
# "nnan"/"ninf" flags, which would let the compiler assume away what it tests
@nb.njit(cache=True, fastmath={"reassoc", "contract"})
def _sum_of_squares(x):
    total = 0.0
    for i in range(x.size):
        total += x[i] * x[i]
    return total


@nb.njit(cache=True, fastmath={"reassoc", "contract"})
def _sum_of_squares_2(x, y):
    return _sum_of_squares(x) + _sum_of_squares(y)


@nb.njit(cache=True)
def subtract_scaled_at(v, cols, scale, x):
    """``v[cols] -= scale * x`` in place (v float64 (n,), distinct indices ``cols`` (k,),
    ``scale`` and ``x`` float64 (k,)): the bits of the numpy line (each entry's product, then
    its subtraction) in one pass, without its gather, temporary and scatter. The indices are
    not checked: :meth:`EqualityRows.subtract_at_cols
    <arlequin.solvers.system.rows.EqualityRows.subtract_at_cols>` calls it with its own, valid by
    construction."""
    for j in range(cols.size):
        c = cols[j]
        v[c] = v[c] - scale[j] * x[j]


def _compiled(*arrays: np.ndarray) -> bool:
    """Whether the compiled loops take these arrays: 1D contiguous float64 of one size."""
    n = arrays[0].shape
    # a loop, not all() of a generator: its frame cost more than the tests (several calls a step)
    for a in arrays:
        if not (a.dtype == np.float64 and a.ndim == 1 and a.shape == n and a.flags.c_contiguous):
            return False
    return True


def scaled_plus(alpha: float, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``alpha x + y``, a new array (n,): the bits of ``z = alpha * x; z += y``."""
    tic = timer_start()
    if not _compiled(x, y):
        z = alpha * x
        z += y
    else:
        z = np.empty(x.shape)
        _scaled_plus(float(alpha), x, y, z)
    vector_updates_done(tic)
    return z


def interpolated(x0: np.ndarray, x1: np.ndarray, share: float) -> np.ndarray:
    """``x0 + share (x1 − x0)``, a new array (n,): the bits of ``z = x1 − x0; z *= share;
    z += x0``."""
    tic = timer_start()
    if not _compiled(x0, x1):
        z = x1 - x0
        z *= share
        z += x0
    else:
        z = np.empty(x0.shape)
        _interpolated(x0, x1, float(share), z)
    vector_updates_done(tic)
    return z


def work_products(u_new: np.ndarray, u_old: np.ndarray, f_old: np.ndarray, f_new: np.ndarray,
                  out: np.ndarray) -> np.ndarray:  # fmt: skip
    """``(u_new − u_old) ⊙ ½(f_old + f_new)`` into ``out`` (n,) (J per dof): the bits of
    ``du = u_new − u_old; f = f_old + f_new; f *= 0.5; du * f``."""
    if not _compiled(u_new, u_old, f_old, f_new, out):
        f = f_old + f_new
        f *= 0.5
        np.multiply(u_new - u_old, f, out=out)
        return out
    _work_products(u_new, u_old, f_old, f_new, out)
    return out


def sum_of_squares(*arrays: np.ndarray) -> float:
    """Σ x_i² over the arrays (1D float arrays), a non-finite float if one holds a NaN or ±inf
    or the sum overflows: the test of the integrators' finite-state check. Compiled without
    numpy's floating-point error state (whose context cost as much as the two products it
    guarded), one call for one or two arrays; its sums run in another order than BLAS's dot,
    so the value differs by round-off."""
    tic = timer_start()
    if len(arrays) == 2 and _compiled(arrays[0]) and _compiled(arrays[1]):
        total = float(_sum_of_squares_2(*arrays))
    else:
        total = 0.0
        for x in arrays:
            if _compiled(x):
                total += float(_sum_of_squares(x))
            else:
                with np.errstate(over="ignore", invalid="ignore"):
                    total += float(np.dot(x, x))
    vector_updates_done(tic)
    return total
