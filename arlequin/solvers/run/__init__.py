"""A dynamic run: :func:`~arlequin.solvers.run.driver.solve` builds the integrator, steps it to
the stop times and records it (:mod:`~arlequin.solvers.run.recorder`) into a
:class:`~arlequin.solvers.run.result.DynamicResult`.
"""
