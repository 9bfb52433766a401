"""Sparse direct solvers for sequences of matrices with one sparsity pattern (Newton systems).

A Newton iteration of the quasi-static solver factorises a new tangent whose sparsity pattern
is that of the previous one: a solver that keeps its symbolic analysis (fill-reducing ordering,
elimination tree) across the factorisations does only the numerical factorisation again.
:class:`SparseDirectSolver` factorises such a sequence with one of two backends:

``"superlu"``
    scipy's SuperLU (:func:`scipy.sparse.linalg.splu`), always available; every factorisation
    starts from scratch (ordering included). The ordering is chosen as the quasi-static solver
    always did: the symmetric minimum degree of A + Aᵀ with threshold pivoting when few diagonal
    entries are zero (few multiplier rows), COLAMD with partial pivoting otherwise; one step of
    iterative refinement.
``"pardiso"``
    Intel MKL PARDISO through :mod:`pypardiso` (an optional dependency: ``pip install
    arlequin[pardiso]``), imported only when asked for: the analysis (phase 11: METIS nested
    dissection, weighted matching and scaling) is done for the first matrix of a sparsity
    pattern, or after :meth:`SparseDirectSolver.renew_analysis`, each factorisation is phase 22,
    each solve phase 33 (with PARDISO's iterative refinement). The matching and scaling depend
    on the values of the analysed matrix: the quasi-static solver renews the analysis at the
    start of each load step, so that its pivoting follows the tangent as the material yields,
    and so that a run resumed at a step factorises exactly as the uninterrupted run did. The
    matrix type is real nonsymmetric (``mtype=11``, pypardiso's default): the saddle points are
    symmetric indefinite, for which the symmetric types would need the upper triangle only and
    Bunch-Kaufman pivoting; the nonsymmetric type with matching is the robust choice.
``"auto"``
    ``"pardiso"`` where pypardiso is installed, else ``"superlu"``: on the 3D eighth of the
    pressure sphere at 32,778 dofs (``benchmarks/quasi_static.py --case sphere-3d``), where the
    factorisations are most of a Newton iteration, a PARDISO factorisation is 4.2x faster than
    SuperLU's and the run 2.8x (``docs/quasi_static.md``, the cost).

A singular matrix raises :class:`numpy.linalg.LinAlgError` with both backends: SuperLU's exact
zero pivot, or for PARDISO (which perturbs tiny pivots instead of failing) a solution whose
relative residual exceeds :data:`SINGULAR_RESIDUAL`. Each solver adds the seconds spent in its
factorisations and in its solves to :attr:`SparseDirectSolver.timings`.
"""

from __future__ import annotations

import importlib.util
import logging
import time
import weakref
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = [
    "LINEAR_SOLVERS",
    "SINGULAR_RESIDUAL",
    "SparseDirectSolver",
    "pardiso_available",
    "resolve_linear_solver",
]

logger = logging.getLogger(__name__)

#: The ``linear_solver`` option's values.
LINEAR_SOLVERS = ("auto", "superlu", "pardiso")

#: A PARDISO solution whose residual ‖A x − b‖ / ‖b‖ exceeds this is taken for the sign of a
#: singular matrix (PARDISO perturbs zero pivots rather than failing; a regular Newton system
#: solves to ~1e-14).
SINGULAR_RESIDUAL = 1e-6


def pardiso_available() -> bool:
    """Whether :mod:`pypardiso` can be imported (without importing it: MKL is large)."""
    return importlib.util.find_spec("pypardiso") is not None


def resolve_linear_solver(name: str) -> str:
    """The backend that ``name`` selects: ``"auto"`` is ``"pardiso"`` where pypardiso is
    installed, else ``"superlu"``.

    Raises
    ------
    ValueError
        ``name`` is not one of :data:`LINEAR_SOLVERS`, or is ``"pardiso"`` without pypardiso.
    """
    if name not in LINEAR_SOLVERS:
        raise ValueError(f"linear_solver must be one of {LINEAR_SOLVERS}, got {name!r}")
    if name == "auto":
        return "pardiso" if pardiso_available() else "superlu"
    if name == "pardiso" and not pardiso_available():
        raise ValueError(
            "linear_solver='pardiso' needs the optional package pypardiso "
            "(pip install pypardiso, or arlequin[pardiso]); use linear_solver='superlu'"
        )
    return name


class SparseDirectSolver:
    """Factorisations of a sequence of square sparse matrices (see the module docstring).

    Parameters
    ----------
    backend : {"auto", "superlu", "pardiso"}

    Attributes
    ----------
    name : str
        The backend used (``"auto"`` resolved).
    timings : dict
        ``"factorisation_s"`` and ``"solve_s"``: seconds spent so far (wall time).
    factorisations, analyses : int
        Numerical factorisations done, and symbolic analyses (PARDISO: one per sparsity
        pattern or :meth:`renew_analysis`; SuperLU: one per factorisation).

    Notes
    -----
    A factor is valid until the next :meth:`factor` call of the same solver (PARDISO keeps one
    factorisation per handle): use one solver per matrix that must stay factorised.
    """

    def __init__(self, backend: str = "auto") -> None:
        self.name = resolve_linear_solver(backend)
        self.timings = {"factorisation_s": 0.0, "solve_s": 0.0}
        self.factorisations = self.analyses = 0
        self._generation = 0
        self._pardiso: Any = None
        self._pattern: tuple[np.ndarray, np.ndarray] | None = None

    def renew_analysis(self) -> None:
        """Make the next :meth:`factor` start with a symbolic analysis of its matrix (PARDISO;
        SuperLU analyses every matrix)."""
        self._pattern = None

    def factor(self, mat: sp.spmatrix) -> _Factor:
        """Factorise ``mat`` (n, n); returns an object whose ``solve(rhs)`` takes rhs of shape
        (n,) or (n, k).

        Raises
        ------
        numpy.linalg.LinAlgError
            ``mat`` is singular (SuperLU: an exact zero pivot).
        """
        t0 = time.perf_counter()
        try:
            self._generation += 1
            if self.name == "superlu":
                handle: Any = _superlu(sp.csc_matrix(mat))
                self.analyses += 1
            else:
                handle = self._pardiso_factor(mat)
            self.factorisations += 1
        finally:
            self.timings["factorisation_s"] += time.perf_counter() - t0
        return _Factor(self, handle, self._generation)

    # -- PARDISO -----------------------------------------------------------------------------
    def _pardiso_factor(self, mat: sp.spmatrix) -> sp.csr_matrix:
        csr = sp.csr_matrix(mat, dtype=np.float64, copy=True)
        csr.sum_duplicates()
        csr.sort_indices()
        if self._pardiso is None:
            import pypardiso  # lazily: MKL takes a second to load

            self._pardiso = pypardiso.PyPardisoSolver(mtype=11)
            # PARDISO's memory is not Python's: released with the solver
            weakref.finalize(self, _release, self._pardiso)
        same = self._pattern is not None and (
            np.array_equal(self._pattern[0], csr.indptr)
            and np.array_equal(self._pattern[1], csr.indices)
        )
        if not same:
            self._pardiso_call(11, csr, np.zeros(csr.shape[0]))
            self._pattern = (csr.indptr.copy(), csr.indices.copy())
            self.analyses += 1
        self._pardiso_call(22, csr, np.zeros(csr.shape[0]))
        return csr

    def _pardiso_call(self, phase: int, csr: sp.csr_matrix, b: np.ndarray) -> np.ndarray:
        import pypardiso

        # the CSR arrays as given: pypardiso's public solve() re-hashes the matrix to decide
        # whether it is factorised; the phases are driven here instead
        self._pardiso.set_iparm(12, 0)  # A x = b (not Aᵀ): the matrix is passed as CSR
        self._pardiso.set_phase(phase)
        try:
            return self._pardiso._call_pardiso(csr, np.asfortranarray(b))
        except pypardiso.PyPardisoError as exc:
            raise np.linalg.LinAlgError(f"PARDISO phase {phase}: {exc}") from exc

    def _solve(self, handle: Any, generation: int, rhs: np.ndarray) -> np.ndarray:
        if generation != self._generation:
            raise RuntimeError("this factor was replaced by a later factor() of its solver")
        t0 = time.perf_counter()
        try:
            if self.name == "superlu":
                mat, lu = handle
                x = lu.solve(rhs)
                x = x + lu.solve(rhs - mat @ x)  # one step of iterative refinement
            else:
                x = self._pardiso_call(33, handle, np.asarray(rhs, dtype=np.float64))
                x = x.reshape(np.shape(rhs))
                scale = np.linalg.norm(rhs)
                if scale > 0.0 and np.linalg.norm(handle @ x - rhs) > SINGULAR_RESIDUAL * scale:
                    raise np.linalg.LinAlgError(
                        f"PARDISO: the matrix is singular (relative residual "
                        f"{np.linalg.norm(handle @ x - rhs) / scale:.2e} after "
                        f"{self._pardiso.get_iparm(14)} perturbed pivots)"
                    )
        finally:
            self.timings["solve_s"] += time.perf_counter() - t0
        return x


class _Factor:
    """A factorised matrix (valid until its solver's next :meth:`SparseDirectSolver.factor`)."""

    def __init__(self, solver: SparseDirectSolver, handle: Any, generation: int) -> None:
        self._solver, self._handle, self._generation = solver, handle, generation

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """x with A x = rhs; rhs of shape (n,) or (n, k)."""
        return self._solver._solve(self._handle, self._generation, rhs)


def _superlu(mat: sp.csc_matrix) -> tuple[sp.csc_matrix, Any]:
    zero_diag = np.count_nonzero(mat.diagonal() == 0.0)
    # few multiplier rows: threshold pivoting keeps the diagonal, so the symmetric ordering of
    # A + Aᵀ fits (the plate: 0.61 -> 0.32 s a factorisation); many: partial pivoting, COLAMD
    if zero_diag < 0.1 * mat.shape[0]:
        permc, threshold, options = "MMD_AT_PLUS_A", 0.01, {"SymmetricMode": True}
    else:
        permc, threshold, options = "COLAMD", 1.0, {}
    try:
        lu = spla.splu(mat, permc_spec=permc, diag_pivot_thresh=threshold, options=options)
    except RuntimeError as exc:  # "Factor is exactly singular"
        raise np.linalg.LinAlgError(str(exc)) from exc
    return mat, lu


def _release(solver: Any) -> None:
    """Free PARDISO's internal memory (phase −1)."""
    try:
        solver.free_memory(everything=True)
    except Exception:  # at interpreter exit MKL may be gone already
        logger.debug("PARDISO memory not released", exc_info=True)
