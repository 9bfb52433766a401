"""What every solver reads off the coupled system: its operators (masses, internal forces,
tangents: :mod:`~arlequin.solvers.system.operators`), its constraint rows
(:mod:`~arlequin.solvers.system.rows`), the minimal unilateral constraint
(:mod:`~arlequin.solvers.system.constraints`), load curves (:mod:`~arlequin.solvers.system.loads`)
and the watch on the J2 patches' gluing bands after a step
(:mod:`~arlequin.solvers.system.yield_watch`).
"""
