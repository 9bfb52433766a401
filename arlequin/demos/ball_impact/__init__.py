"""The ball-impact demo: an elastic ball striking a thick block along the axis, axisymmetric.

``arlequin ball-impact`` runs it. The ball (radius R, centre (0, R)) moves at −v0 along z and
touches the block's top face z = 0 (radius R_B, height H_B, base on rollers) at t = 0; or, with
``rigid_wall``, the rigid plane z = 0. Models (:mod:`arlequin.demos.ball_impact.setup`):

``arlequin``
    each body a coarse linear-elastic model plus a refined nested patch of radius
    ``patch_size`` at the contact point, the contact between the two patches;
``mono``
    each body one mesh with the fine size everywhere (in the plastic regime the whole block
    finite-strain J2: what a user runs without deciding where it yields);
``mono-zoned``
    the same meshes, J2 only in the block's patch region, elastic elsewhere (the saving of the
    law apart from the saving of the mesh);
``graded``
    one conforming mesh per body, the fine size at the contact point growing away from it (the
    ball's graded O-grid, the block's graded grid), the laws of ``mono-zoned``.

Regimes: ``elastic`` (both bodies elastic, steel on steel, v0 = 1 m/s by default: 2e-4 of the
ball's bar wave speed, against Hertz's impact solution) and ``plastic`` (a copper block,
finite-strain J2 with linear hardening, in its patch; v0 = 10 m/s). Hertz (elastic regime): with
1/E* = (1 − ν₁²)/E₁ + (1 − ν₂²)/E₂ (the second term zero against the rigid wall) and the ball's
mass m (the block's is taken infinite: its base is far, the reflections weak),
δ_max = (15 m v0² / (16 E* √R))^{2/5}, F_max = 4/3 E* √R δ_max^{3/2}, t_c = 2.9432 δ_max/v0,
a_max = √(R δ_max).

Measured quantities: the contact force (N, from the multipliers, > 0 in compression), the
contact duration (the last step with a positive force; the contact starts at t = 0), its peak,
the restitution coefficient (the ball's mean velocity after / before), the dent depth (the
block's top point on the axis, after the run), the maximum equivalent plastic strain, the energy
balance of the integrator (kinetic + strain − works of the contact, coupling and supports,
against the largest energy).

Multi-time-step is the default of the ``arlequin`` model (``coarse_step_ratio=None``: the coarse
models' forces once every m ≤ 2 steps, :data:`DEFAULT_STEP_RATIO`; 1 turns it off).

Outputs (``out``): results.json (inputs and results with units), impact.csv (per step),
history.csv and fields/*.xdmf (energies and fields per record, ParaView), ball_impact.png.
SI units.

The package: :mod:`~.config` (:class:`BallImpactConfig`, the parameters and their checks, the
command's options), :mod:`~.meshes`, :mod:`~.zoned` and :mod:`~.setup` (the bodies of each
model), :mod:`~.api` (:func:`run_ball_impact`, the Python entry point), :mod:`~.run` (the run as
named steps), :mod:`~.record` (what a
run records per step), :mod:`~.result` (:class:`BallImpactResult`, its keys and units, Hertz's
solution) and :mod:`~.report` (the results folder's files and picture).
"""

from ..config import register_runner
from . import run as _run
from .api import run_ball_impact
from .config import COPPER, DEFAULT_STEP_RATIO, MODELS, REGIMES, STEEL, BallImpactConfig
from .result import JSON_KEYS, BallImpactResult, hertz
from .run import BAND_WARNING

__all__ = [
    "BAND_WARNING",
    "COPPER",
    "DEFAULT_STEP_RATIO",
    "JSON_KEYS",
    "MODELS",
    "REGIMES",
    "STEEL",
    "BallImpactConfig",
    "BallImpactResult",
    "hertz",
    "run_ball_impact",
]

# the configuration runs through its package's runner (it does not import its run module)
register_runner(BallImpactConfig, _run.run_config)
