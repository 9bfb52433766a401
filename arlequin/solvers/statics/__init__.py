"""Static and quasi-static solves: the static saddle point
(:mod:`~arlequin.solvers.statics.static`), load stepping with Newton
(:mod:`~arlequin.solvers.statics.quasi_static`) and its result
(:mod:`~arlequin.solvers.statics.quasi_static_result`), its Newton systems condensed
(:mod:`~arlequin.solvers.statics.condensation`) and an adaptive patch's load stepping
(:mod:`~arlequin.solvers.statics.adaptive`).
"""
