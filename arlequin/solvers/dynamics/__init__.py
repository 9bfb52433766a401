"""Time integrators: the :class:`~arlequin.solvers.dynamics.base.Integrator` base class and its
registry, step controllers, the critical step, Rayleigh damping, the explicit scheme (with its
impulse basis) and its multi-time-step variant, the implicit schemes, and adaptive patches in an
explicit run. :func:`arlequin.solvers.solve` (:mod:`arlequin.solvers.run`) drives them.
"""
