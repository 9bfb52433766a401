"""Problem: bodies (a coarse model and its patches each) assembled into one coupled system.

:mod:`~arlequin.problem.system` is the system the solvers see (blocks of weighted model terms
and linear constraint rows); :mod:`~arlequin.problem.arlequin_problem` builds one for a coarse
model and its patches, :mod:`~arlequin.problem.bodies` for several bodies.
"""
