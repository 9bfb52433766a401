"""Plasticity: hardening laws, the J2 material point, finite-strain Q1 kinematics (F-bar), the
compiled J2 kernels and the finite-strain J2 model :class:`FiniteStrainJ2`."""
