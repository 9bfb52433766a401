"""The sliding block: an elastic block on a rigid plane with Coulomb friction.

``arlequin sliding-block`` runs it; :func:`run_sliding_block` from Python. The package:
:mod:`.config` (:class:`SlidingBlockConfig`, the parameters), :mod:`.setup` (mesh, model,
loading, contact, exact solution), :mod:`.run` (the run as named steps), :mod:`.result`
(:class:`SlidingBlockResult`), :mod:`.report` (the results folder and the picture),
:mod:`.api` (:func:`run_sliding_block`).

A block of height H (the last axis is vertical, the plane is z = 0 in 3D, y = 0 in 2D plane
strain) lies on a rigid plane; the level-set contact with Coulomb friction μ
(:class:`arlequin.models.CoulombContact`) acts at the nodes of its bottom face. Two loadings:

``pressure`` (default)
    a uniform normal pressure p on the top face. The block starts from the exact static state
    under p (the uniform stress σ_zz = −p, laterally free: the discrete solution of the
    bilinear elements too) and is launched at t = 0 with V (``velocity``, default 1 m/s) along
    x. Exact, for the mean velocity (momentum / mass): v̄(t) = V − a t with a = μ p / (ρ H),
    stop at t = V/a; then the block sticks (it may keep vibrating elastically).
``gravity``
    a body force ρ g (sin θ, −cos θ) on an incline θ (``incline``, degrees; x downslope),
    ramped from the block at rest on the plane over ``ramp_time`` (smooth step; default
    :data:`RAMP_TRANSITS` H/c_d), times counted from the end of the ramp. Exact after the
    ramp, at rest (``velocity`` 0, the command line's default under gravity): the block sticks
    for tan θ < μ and slides with the acceleration g (sin θ − μ cos θ) for tan θ > μ.

    Launched (``velocity`` V > 0): at the end of the ramp (t = 0) V is added to the x velocity
    of every node, the way the pressure loading launches its block: the ramp is run, then the
    run continues from its final state with the velocity V added (the contact starting afresh,
    its works and those of the loads carried over, the kinetic energy the launch gave counted
    with the work of the loads). Exact: v̄(t) = V + g (sin θ − μ cos θ) t while it slides; for
    tan θ < μ it decelerates, stops at t = V / (g (μ cos θ − sin θ)) and sticks; for
    tan θ > μ it keeps accelerating (tan θ = μ: it keeps V). The acceleration is fitted
    between 0.9 and 0.1 V when it stops, over the whole run after the ramp otherwise; the
    stop time, the slip after it and the default ``t_end`` (1.3 × the stop time) as with the
    pressure loading.

The sudden onset of friction at the launch sends shear waves of traction amplitude μp through
the block; their velocity amplitude relative to V is r = μp/(ρ c_s V), which sets how far the
mean velocity wanders from the straight line, so the default pressure keeps r ≈ 1.2e-3.

Those waves, and the stop's, make an undamped block vibrate in shear for ever, its base traction
reaching the Coulomb limit at the contact's edges: the corners slip by turns (up to 9.7e-4 V,
38% of the steps after the stop, not decaying; no creep). Material damping settles them and the
block sticks for good: stiffness-proportional damping (``RayleighDamping``), ratio ``damping``
(default :data:`DAMPING`, 0: undamped) at the first shear mode ω₁ = π c_s/(2H). It leaves the
rigid motion untouched; its work is in the balance.

The step is 0.6 of the critical one (:data:`SAFETY`): friction feeds the normal force into the
tangential one and lowers the stable step.

Outputs (``out``): results.json (inputs and results with units), history.csv (energies per
record), sliding.csv (per step: mean velocity, slip velocity, works, fixed-point iterations),
fields/block.xdmf, sliding_block.png. SI units.
"""

from ..config import register_runner
from . import run as _run
from .api import run_sliding_block
from .config import DAMPING, DEFAULT_PRESSURE, RAMP_TRANSITS, SlidingBlockConfig
from .report import plot_sliding_block
from .result import JSON_KEYS, RESULT_UNITS, SlidingBlockResult
from .run import SAFETY, STOP_FRACTION

__all__ = [
    "DAMPING",
    "DEFAULT_PRESSURE",
    "JSON_KEYS",
    "RAMP_TRANSITS",
    "RESULT_UNITS",
    "SAFETY",
    "STOP_FRACTION",
    "SlidingBlockConfig",
    "SlidingBlockResult",
    "plot_sliding_block",
    "run_sliding_block",
]

# the configuration runs through its package's runner (it does not import its run module)
register_runner(SlidingBlockConfig, _run.run)
