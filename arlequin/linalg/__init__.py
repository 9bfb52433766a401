"""Linear algebra below :mod:`arlequin.solvers`: what the integrators multiply, factorise, solve.

Sparse products on fixed patterns (:mod:`~arlequin.linalg.csr`: ``CsrProduct``, scipy's floats
bit for bit), the compiled one-pass vector updates and per-block reductions of the explicit step
(:mod:`~arlequin.linalg.vector_updates`, :mod:`~arlequin.linalg.block_sums`), the
factorisations of constraint and saddle-point matrices (:mod:`~arlequin.linalg.factor`:
``ScaledLU``, ``factor_checked``, ``factor_rows``), the sparse direct solvers of the Newton
systems (:mod:`~arlequin.linalg.direct`: SuperLU, or PARDISO where pypardiso is installed), the
explicit scheme's impulse solve (:mod:`~arlequin.linalg.impulses`) with its compiled Schur
complement of the active contact rows (:mod:`~arlequin.linalg.active_schur`), the BLAS pool's
threads during a run (:mod:`~arlequin.linalg.threads`) and the optional step timers these
report their seconds to (:mod:`~arlequin.linalg.timing`).

It imports nothing of :mod:`arlequin` but the contract: the seam where a distributed backend
(PETSc through petsc4py) would come in without touching the integrators (``docs/architecture.md``).
"""
