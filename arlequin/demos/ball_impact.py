"""The ball-impact demo: an elastic ball striking a thick block along the axis, axisymmetric.

``arlequin ball-impact`` runs it. The ball (radius R, centre (0, R)) moves at −v0 along z and
touches the block's top face z = 0 (radius R_B, height H_B, base on rollers) at t = 0; or, with
``rigid_wall``, the rigid plane z = 0. Models (:mod:`arlequin.demos.ball_setup`):

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
"""

from __future__ import annotations

import logging
import math
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..io import DynamicRunWriter, ResultsFolder
from ..models import IsotropicElastic, J2Material
from ..solvers import solve
from .ball_record import ImpactRecorder, write_outputs
from .ball_result import INPUT_UNITS, JSON_KEYS, BallImpactResult, hertz
from .ball_setup import ImpactBodies, ball_sizes
from .taylor_bar.result import GluingBandPlasticityWarning

__all__ = ["JSON_KEYS", "MODELS", "REGIMES", "BallImpactResult", "hertz", "run_ball_impact"]

logger = logging.getLogger(__name__)

MODELS = ("arlequin", "mono", "mono-zoned", "graded")
REGIMES = ("elastic", "plastic")
#: ε̄p in the block patch's gluing band above which a GluingBandPlasticityWarning is raised.
BAND_WARNING = 0.02
#: Patches above about this many cells are refused before they are built.
PATCH_LIMIT = 2_000_000
#: A uniform (``mono``) mesh above this many cells is refused before it is built.
MONO_LIMIT = 400_000
#: The default multi-time-step bound M of the ``arlequin`` model.
DEFAULT_STEP_RATIO = 2
#: The default coarse size over R: the ball's O-grid with n = 30 (π/4 R / 30 along the arc).
ARC_COARSE = 0.25 * math.pi / 30

STEEL = IsotropicElastic(210e9, 0.3, 7850.0)
#: The plastic regime's block: the Taylor bar's copper (linear hardening).
COPPER = J2Material(117e9, 0.35, 8930.0, 0.4e9, 0.1e9)


def _positive(name: str, value: float) -> float:
    if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} must be a positive number (SI units), got {name}={value!r}")
    return float(value)


def _mono_cells(sizes, ball_radius, block_radius, block_height, rigid_wall) -> int:
    n_f = sizes.n * 2**sizes.levels
    cells = 6 * n_f**2
    if not rigid_wall:
        cells += math.ceil(block_radius / sizes.fine) * math.ceil(block_height / sizes.fine)
    return int(cells)


def run_ball_impact(
    regime: str = "elastic",
    model: str = "arlequin",
    velocity: float | None = None,
    ball_radius: float = 0.01,
    block_radius: float = 0.1,
    block_height: float = 0.1,
    ball_material: IsotropicElastic | None = None,
    block_material: IsotropicElastic | J2Material | None = None,
    patch_size: float | None = None,
    block_patch_size: float | None = None,
    fine_size: float | None = None,
    coarse_size: float | None = None,
    friction: float = 0.0,
    rigid_wall: bool = False,
    coarse_step_ratio: int | None = None,
    t_end: float | None = None,
    out: str | Path | None = None,
    progress: Callable[[float], None] | None = None,
    check_only: bool = False,
) -> BallImpactResult | None:
    """Run the ball impact (module docstring).

    Parameters
    ----------
    regime : {"elastic", "plastic"}
    model : {"arlequin", "mono", "mono-zoned", "graded"}
        See :class:`~arlequin.demos.ball_setup.ImpactBodies`.
    velocity : float, optional
        v0 (m/s); default 1 (elastic), 10 (plastic).
    ball_radius, block_radius, block_height : float
        R, R_B, H_B (m).
    ball_material : IsotropicElastic, optional
        Default steel (210 GPa, 0.3, 7850 kg/m³).
    block_material : IsotropicElastic or J2Material, optional
        Default steel (elastic regime) or :data:`COPPER` (plastic).
    patch_size : float, optional
        Radius of the patches around the contact point (m), below R/2; default 0.2 R
        (elastic), 0.4 R (plastic).
    block_patch_size : float, optional
        Radius of the block's patch (m), if larger (the plastic zone's extent); default
        ``patch_size`` (elastic), 0.8 R (plastic; at most half the block's size).
    fine_size, coarse_size : float, optional
        Cell sizes (m) of the patches and of the coarse models at the contact; default
        coarse π R/120 (the ball's O-grid n = 30) and fine the largest power-of-two refinement
        of it with 10 cells across Hertz's contact radius (elastic) or coarse/2 (plastic). The
        coarse size is rounded to the O-grid, the fine one to a power-of-two refinement of it.
    friction : float
        Coulomb coefficient μ between the bodies (0: frictionless).
    rigid_wall : bool
        The ball against the rigid plane z = 0 (no block).
    coarse_step_ratio : int, optional
        M > 1: the coarse models' forces once every m ≤ M steps, the largest m that keeps them
        stable (``"explicit-mts"``, :class:`~arlequin.solvers.SubcycledCentralDifference`
        with its resonance bound off and a 1% energy check), Arlequin only. 1: one step for
        every model. Default: :data:`DEFAULT_STEP_RATIO` (2) for ``arlequin``, 1 for the
        single-mesh models; larger ratios can resonate with the patches (the energy check
        then stops the run: the rigid-wall default at M = 8 did).
    t_end : float, optional
        Simulated time (s); default 1.4 × Hertz's duration (elastic) or 1.5 π √(m/k) with
        k = 6π R σ_y, the stiffness of a fully plastic contact at a mean pressure 3 σ_y
        (plastic).
    out : path, optional
        Results folder.
    progress : callable, optional
        ``progress(fraction)`` of the simulated time.
    check_only : bool
        Check every input and return None.

    Returns
    -------
    BallImpactResult
    """
    if regime not in REGIMES:
        raise ValueError(f"regime must be one of {REGIMES}, got {regime!r}")
    if model not in MODELS:
        raise ValueError(f"model must be one of {MODELS}, got {model!r}")
    plastic = regime == "plastic"
    velocity = (10.0 if plastic else 1.0) if velocity is None else _positive("velocity", velocity)
    big = _positive("ball_radius", ball_radius)
    block_radius = _positive("block_radius", block_radius)
    block_height = _positive("block_height", block_height)
    ball_material = STEEL if ball_material is None else ball_material
    if not isinstance(ball_material, IsotropicElastic):
        raise ValueError(f"ball_material must be an IsotropicElastic (the ball stays elastic), "
                         f"got {type(ball_material).__name__}")  # fmt: skip
    if rigid_wall and block_material is not None:
        raise ValueError("block_material has no effect with rigid_wall (there is no block)")
    if block_material is None:
        block_material = COPPER if plastic else STEEL
    if plastic != isinstance(block_material, J2Material):
        raise ValueError(f"the {regime} regime needs a block_material that is "
                         f"{'a J2Material' if plastic else 'an IsotropicElastic'}, got "
                         f"{type(block_material).__name__}")  # fmt: skip
    if rigid_wall and plastic:
        raise ValueError("rigid_wall removes the block, and the plastic regime is the block's "
                         "yielding: give one of them")  # fmt: skip
    if not (math.isfinite(friction) and friction >= 0.0):
        raise ValueError(f"friction must be a non-negative number, got friction={friction}")
    if coarse_step_ratio is not None and (
        isinstance(coarse_step_ratio, bool)
        or not isinstance(coarse_step_ratio, (int, float))
        or int(coarse_step_ratio) != coarse_step_ratio
        or coarse_step_ratio < 1
    ):
        raise ValueError(f"coarse_step_ratio must be a positive integer, got {coarse_step_ratio!r}")
    if coarse_step_ratio is not None and coarse_step_ratio > 1 and model != "arlequin":
        raise ValueError("coarse_step_ratio > 1 needs the arlequin model (coarse models)")
    coarse = ARC_COARSE * big if coarse_size is None else _positive("coarse_size", coarse_size)
    if fine_size is not None:
        fine = _positive("fine_size", fine_size)
    elif plastic:
        fine = 0.5 * coarse
    else:
        # ≥ 10 fine cells across Hertz's contact radius (against the elastic block or the wall)
        ref = None if rigid_wall else block_material
        a_max = hertz(big, 4.0 / 3.0 * math.pi * big**3 * ball_material.density, velocity,
                      ball_material, ref)["hertz_contact_radius"]  # fmt: skip
        fine = coarse / 2.0 ** math.ceil(math.log2(10.0 * coarse / a_max))
    if fine >= coarse:
        raise ValueError(f"fine_size={fine:.4g} m must be smaller than coarse_size={coarse:.4g} m")
    reach = (0.4 if plastic else 0.2) * big if patch_size is None else _positive(
        "patch_size", patch_size)  # fmt: skip
    block_size = math.inf if rigid_wall else min(block_radius, block_height)
    if reach >= 0.5 * big or reach >= block_size:
        what = "half the ball radius" + ("" if rigid_wall else " and the block's size")
        raise ValueError(f"the patches' radius {reach:.4g} m (patch_size) must stay below "
                         f"{what}")  # fmt: skip
    if block_patch_size is not None:
        block_reach = _positive("block_patch_size", block_patch_size)
    elif plastic:  # the plastic zone reaches beyond the contact radius
        block_reach = max(reach, min(0.8 * big, 0.5 * block_size))
    else:
        block_reach = reach
    if not rigid_wall and (block_reach < reach or block_reach >= 0.9 * block_size):
        raise ValueError(f"block_patch_size={block_reach:.4g} m must lie between patch_size="
                         f"{reach:.4g} m and 0.9 of the block's size")  # fmt: skip
    sizes = ball_sizes(big, coarse, fine, reach, block_reach)
    if coarse_step_ratio is None:
        # 2: larger ratios resonate (the rigid-wall default, three levels, at m = 4: the energy
        # check stopped it at a balance error of 1.05%)
        coarse_step_ratio = DEFAULT_STEP_RATIO if model == "arlequin" else 1
    # the patches' cells, about: their half discs at the fine size (the block's too)
    patch_cells = (
        0.5 * math.pi * (reach**2 + (0.0 if rigid_wall else block_reach**2)) / sizes.fine**2
    )
    if patch_cells > PATCH_LIMIT:
        raise ValueError(f"the patches would hold about {patch_cells:.3g} cells at the fine size "
                         f"{sizes.fine:.4g} m (limit {PATCH_LIMIT:.3g}): a larger fine_size or "
                         "smaller patches")  # fmt: skip
    if abs(sizes.fine - fine) > 1e-9 * fine:
        logger.info(
            "fine size %.4g m rounded to %.4g m (coarse %.4g m / 2^%d)",
            fine,
            sizes.fine,
            sizes.coarse,
            sizes.levels,
        )
    if model in ("mono", "mono-zoned"):
        cells = _mono_cells(sizes, big, block_radius, block_height, rigid_wall)
        if cells > MONO_LIMIT:
            raise ValueError(f"the uniform (mono) meshes would have {cells} cells at the fine "
                             f"size {sizes.fine:.4g} m (limit {MONO_LIMIT}): a smaller block "
                             "or a larger fine_size")  # fmt: skip
    if t_end is not None:
        t_end = _positive("t_end", t_end)
    config = {"regime": regime, "model": model, "velocity": velocity, "ball_radius": big,
              "block_radius": block_radius, "block_height": block_height, "patch_size": reach,
              "block_patch_size": block_reach,
              "fine_size": fine_size, "coarse_size": coarse_size, "friction": friction,
              "rigid_wall": bool(rigid_wall), "coarse_step_ratio": int(coarse_step_ratio),
              "t_end": t_end, "ball_material": repr(ball_material),
              "block_material": repr(block_material)}  # fmt: skip
    if check_only:
        return None
    if not plastic:
        bar_speed = math.sqrt(ball_material.young / ball_material.density)
        if velocity > 1e-3 * bar_speed:
            logger.warning("velocity %.4g m/s is above 1e-3 of the ball's bar wave speed "
                           "(%.4g m/s): Hertz's quasi-static solution is only a guide", velocity,
                           bar_speed)  # fmt: skip
        if not rigid_wall and block_size < 10.0 * big:
            logger.warning(
                "a block under 10 ball radii (%.4g m) is not the half-space of Hertz's solution",
                block_size,
            )
    return _run(config, sizes, ball_material, block_material, out, progress)


def _run(config, sizes, ball_material, block_material, out, progress) -> BallImpactResult:
    big, velocity = config["ball_radius"], config["velocity"]
    plastic = config["regime"] == "plastic"
    bodies = ImpactBodies(config["model"], sizes, big, config["block_radius"],
                          config["block_height"], ball_material, block_material,
                          rigid_wall=config["rigid_wall"], friction=config["friction"])  # fmt: skip
    ref = None if config["rigid_wall"] else (block_material.elastic if plastic else block_material)
    values = {} if plastic else hertz(big, bodies.ball_mass, velocity, ball_material, ref)
    t_end = config["t_end"]
    if t_end is None:
        if plastic:
            # a fully plastic contact: F = 3 σ_y π a², a² = 2 R d, a spring k = 6π R σ_y whose
            # half period π √(m/k) is the loading; 1.5 × it covers the elastic unloading
            stiffness = 6.0 * math.pi * big * block_material.yield_stress
            t_end = 1.5 * math.pi * math.sqrt(bodies.ball_mass / stiffness)
        else:
            t_end = 1.4 * values["hertz_contact_duration"]
    folder = ResultsFolder(out, "arlequin ball-impact", config, INPUT_UNITS) if out else None
    recorder = ImpactRecorder(bodies, folder, t_end, progress)
    frames = np.linspace(0.0, t_end, 11)[1:]
    writers = ([DynamicRunWriter(folder, bodies.system, layout=bodies.layout, frame_times=frames)]
               if folder else [])  # fmt: skip
    options: dict[str, Any] = {}
    integrator = "explicit"
    if config["coarse_step_ratio"] > 1:
        integrator = "explicit-mts"
        options = {"slow_blocks": bodies.slow_blocks, "step_ratio": config["coarse_step_ratio"],
                   "resonance_bound": False, "energy_tolerance": 0.01}  # fmt: skip
    tic = time.perf_counter()
    try:
        res = solve(bodies.system, integrator, t_end=t_end,
                    v0=bodies.initial_velocity(velocity), constraints=[bodies.contact],
                    on_step=[recorder], on_record=writers,
                    t_eval=frames, **options)  # fmt: skip
    except Exception as exc:
        if folder is not None:
            folder.finish("failed", str(exc))
        raise
    wall = time.perf_counter() - tic
    mono = _mono_cells(sizes, big, config["block_radius"], config["block_height"],
                       config["rigid_wall"])  # fmt: skip
    # Arlequin: its patches' elements; a reference: all its elements, over the uniform meshes'
    p = (bodies.fine_elements if config["model"] == "arlequin" else bodies.n_elements) / mono
    try:
        result = recorder.result(res, wall, p, values, config)
    except ValueError as exc:  # still in contact at the end: the folder says so
        if folder is not None:
            folder.finish("failed", str(exc))
        raise
    result.t_end = float(t_end)
    if result.band_max_plastic_strain > BAND_WARNING:
        warnings.warn(f"equivalent plastic strain in the block's gluing band reaches "
                      f"{result.band_max_plastic_strain:.4f} > {BAND_WARNING}: the coarse model "
                      f"glued there is elastic; enlarge it (block_patch_size="
                      f"{sizes.block_patch:.4g} m)",
                      GluingBandPlasticityWarning, stacklevel=2)  # fmt: skip
    if folder is not None:
        write_outputs(folder, result, bodies, res)
    logger.info(result.summary())
    return result
