"""The ball impact's configuration (:class:`BallImpactConfig`): its parameters, their checks and
the values a run resolves from them (:class:`~.setup.ResolvedInputs`).

Every parameter of :func:`~arlequin.demos.ball_impact.run_ball_impact` is one field, and every
field but the two material objects (``ball_material``, ``block_material``: Python only) one
option of ``arlequin ball-impact``; the command line gives the materials by their properties
(``--ball-young``, ..., ``--block-hardening``), which change the default or given material.
Making the configuration checks every input and resolves the defaults that depend on others
(the velocity, the patches' radii, the cell sizes rounded to the ball's O-grid, the
multi-time-step ratio): a bad value is a ``ValueError`` naming it before any work. SI units.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any, ClassVar

from ...models import IsotropicElastic, J2Material
from ..adaptive_options import (
    adapt_buffer_option,
    adapt_every_option,
    adapt_threshold_option,
    adaptive_inputs,
    adaptive_option,
    check_adaptive_options,
    max_patch_fraction_option,
)
from ..config import DemoConfig, _plain, check_choice, option
from .result import INPUT_UNITS, hertz
from .setup import BallSizes, ResolvedInputs, ball_sizes, mono_cells

__all__ = [
    "ARC_COARSE",
    "COPPER",
    "DEFAULT_STEP_RATIO",
    "MODELS",
    "MONO_LIMIT",
    "PATCH_LIMIT",
    "REGIMES",
    "STEEL",
    "BallImpactConfig",
]

logger = logging.getLogger(__name__)

MODELS = ("arlequin", "mono", "mono-zoned", "graded")
REGIMES = ("elastic", "plastic")
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

#: The material fields the command line gives, by body: (option suffix, material field).
_BALL_PROPERTIES = (("young", "young"), ("poisson", "poisson"), ("density", "density"))
_BLOCK_PROPERTIES = (*_BALL_PROPERTIES, ("yield_stress", "yield_stress"),
                     ("hardening", "hardening_modulus"))  # fmt: skip


def _material_record(material: Any) -> Any:
    """A material as plain JSON: an object of its named fields (a hardening law's too); a
    value JSON cannot hold (a :class:`CallableHardening`'s function) as its repr."""
    plain = _plain(material)
    if isinstance(plain, dict):
        return {k: _material_record(v) for k, v in plain.items()}
    if isinstance(plain, list):
        return [_material_record(v) for v in plain]
    if plain is None or isinstance(plain, (str, bool, int, float)):
        return plain
    return repr(plain)


def _positive(name: str, value: float) -> float:
    if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} must be a positive number (SI units), got {name}={value!r}")
    return float(value)


@dataclass(frozen=True)
class BallImpactConfig(DemoConfig):
    """The ball impact's parameters (SI units; :mod:`arlequin.demos.ball_impact`).

    Each field is a keyword of :func:`~arlequin.demos.ball_impact.run_ball_impact` and, but
    for the material objects, an option of ``arlequin ball-impact``. The material properties
    (``ball_young``, ..., ``block_hardening``) change the given material, or the default one
    (steel; the plastic regime's block :data:`COPPER`). :attr:`resolved` holds the values the
    run uses.
    """

    command: ClassVar[str] = "ball-impact"
    title: ClassVar[str] = (
        "elastic ball striking a thick block, each body a coarse model plus a patch"
    )
    description: ClassVar[str] = (
        "An elastic ball (radius R) moving at -V along the axis strikes a thick block (or "
        "--rigid-wall), axisymmetric; level-set contact between the bodies' refined patches. "
        "Elastic regime: against Hertz's impact (peak force, contact duration); plastic "
        "regime: finite-strain J2 in the block's patch (dent, restitution). SI units."
    )

    regime: str = option(
        "elastic",
        "elastic: steel on steel, against Hertz; plastic: a copper block, finite-strain J2 in "
        "its patch",
        "",
        choices=REGIMES,
    )
    model: str = option(
        "arlequin",
        "arlequin: coarse models plus patches; mono: one uniformly fine mesh per body (J2 in the "
        "whole block); mono-zoned: the same, J2 in the patch region only; graded: conforming "
        "meshes graded from the contact",
        "",
        choices=MODELS,
    )
    velocity: float | None = option(
        None, "impact velocity v0", "m/s", metavar="V", default_help="1 (elastic) or 10 (plastic)"
    )
    ball_radius: float = option(0.01, "ball radius R", "m", metavar="R")
    block_radius: float = option(0.1, "block radius R_B", "m", metavar="RB")
    block_height: float = option(0.1, "block height H_B", "m", metavar="HB")
    ball_young: float | None = option(
        None, "ball Young's modulus", "Pa", metavar="E", default_help="steel, 210e9"
    )
    ball_poisson: float | None = option(
        None, "ball Poisson's ratio", "1", metavar="NU", default_help="0.3"
    )
    ball_density: float | None = option(
        None, "ball density", "kg/m^3", metavar="RHO", default_help="7850"
    )
    block_young: float | None = option(
        None,
        "block Young's modulus",
        "Pa",
        metavar="E",
        default_help="steel, 210e9 (plastic regime: copper, 117e9)",
    )
    block_poisson: float | None = option(
        None,
        "block Poisson's ratio",
        "1",
        metavar="NU",
        default_help="0.3 (plastic regime: copper, 0.35)",
    )
    block_density: float | None = option(
        None,
        "block density",
        "kg/m^3",
        metavar="RHO",
        default_help="7850 (plastic regime: copper, 8930)",
    )
    block_yield_stress: float | None = option(
        None, "block yield stress (plastic regime)", "Pa", metavar="S", default_help="0.4e9"
    )
    block_hardening: float | None = option(
        None,
        "block linear hardening modulus (plastic regime)",
        "Pa",
        metavar="H",
        default_help="0.1e9",
    )
    patch_size: float | None = option(
        None,
        "radius of the patches around the contact point",
        "m",
        metavar="RP",
        default_help="0.2 R (elastic), 0.4 R (plastic)",
    )
    block_patch_size: float | None = option(
        None,
        "radius of the block's patch, if larger",
        "m",
        metavar="RP",
        default_help="--patch-size (elastic), 0.8 R (plastic)",
    )
    fine_size: float | None = option(
        None,
        "cell size of the patches",
        "m",
        metavar="H",
        default_help="10 cells across Hertz's contact radius "
        "(elastic), half the coarse size (plastic)",
    )
    coarse_size: float | None = option(
        None,
        "cell size of the coarse models at the contact",
        "m",
        metavar="H",
        default_help="pi R/120",
    )
    friction: float = option(
        0.0, "Coulomb coefficient between the bodies (0: frictionless)", metavar="MU"
    )
    rigid_wall: bool = option(False, "the ball against a rigid plane instead of the block", "")
    coarse_step_ratio: int | None = option(
        None,
        "multi-time-step: the coarse models' forces "
        "once every m <= M steps, the largest stable m (1: "
        "off)",
        metavar="M",
        parse=int,
        default_help="2 with --model arlequin, else 1",
    )
    t_end: float | None = option(
        None,
        "simulated time",
        "s",
        metavar="T",
        default_help="1.4 x Hertz's contact duration (elastic), 1.5 pi sqrt(m/k) (plastic)",
    )
    adaptive: bool = adaptive_option(
        "(--regime plastic) a block patch seeded with radius --patch-size at the contact that "
        "grows where the block nears yield"
    )
    adapt_threshold: float = adapt_threshold_option(0.8)
    adapt_buffer: int = adapt_buffer_option()
    adapt_every: int = adapt_every_option(50, "(and the yield check) every N time steps")
    max_patch_fraction: float = max_patch_fraction_option(0.5, "block")
    ball_material: IsotropicElastic | None = option(  # noqa: RUF009 (frozen materials)
        None, "the ball's material (default steel)", "", cli=False
    )
    block_material: IsotropicElastic | J2Material | None = option(  # noqa: RUF009
        None, "the block's material (default steel, or copper in the plastic regime)", "", cli=False
    )

    # -- checks -------------------------------------------------------------------------------
    def check(self) -> None:
        """Every input checked (and the dependent defaults resolved, :attr:`resolved`)."""
        _ = self.resolved

    @cached_property
    def resolved(self) -> ResolvedInputs:
        """The values the run uses (class docstring); ``ValueError`` on a bad input."""
        check_choice("regime", self.regime, REGIMES)
        check_choice("model", self.model, MODELS)
        plastic = self.regime == "plastic"
        velocity = (10.0 if plastic else 1.0) if self.velocity is None else _positive(
            "velocity", self.velocity)  # fmt: skip
        big = _positive("ball_radius", self.ball_radius)
        block_radius = _positive("block_radius", self.block_radius)
        block_height = _positive("block_height", self.block_height)
        ball, block = self._materials()
        self._check_options(block)
        coarse, fine = self._cell_sizes(big, velocity, ball, block)
        sizes = self._patch_sizes(big, coarse, fine, block_radius, block_height)
        adapt = self._check_adaptive()
        ratio = self.coarse_step_ratio
        if ratio is None:
            # 2: larger ratios resonate (the rigid-wall default, three levels, at m = 4: the
            # energy check stopped it at a balance error of 1.05%)
            ratio = DEFAULT_STEP_RATIO if self.model == "arlequin" else 1
        self._check_cells(sizes, fine, block_radius, block_height)
        t_end = None if self.t_end is None else _positive("t_end", self.t_end)
        record = {"regime": self.regime, "model": self.model, "velocity": velocity,
                  "ball_radius": big, "block_radius": block_radius,
                  "block_height": block_height, "patch_size": sizes.reach,
                  "block_patch_size": sizes.block_patch, "fine_size": self.fine_size,
                  "coarse_size": self.coarse_size, "friction": self.friction,
                  "rigid_wall": bool(self.rigid_wall), "coarse_step_ratio": int(ratio),
                  "t_end": t_end, "ball_material": _material_record(ball),
                  "block_material": _material_record(block),
                  "adaptive": bool(self.adaptive), **self._adapt_values()}  # fmt: skip
        return ResolvedInputs(self.regime, self.model, velocity, big, block_radius,
                              block_height, ball, block, fine, sizes, self.friction,
                              bool(self.rigid_wall), int(ratio), t_end, record,
                              adapt)  # fmt: skip

    def _check_adaptive(self) -> dict[str, Any] | None:
        """The adaptive options checked; their values (None without ``adaptive``)."""
        check_adaptive_options(self)
        if not self.adaptive:
            return None
        if self.model != "arlequin" or self.regime != "plastic" or self.rigid_wall:
            raise ValueError(f"adaptive grows the block's J2 patch: it needs model='arlequin' "
                             f"and regime='plastic' against the block, got model={self.model!r}, "
                             f"regime={self.regime!r}, rigid_wall={self.rigid_wall}")  # fmt: skip
        if self.block_patch_size is not None:
            raise ValueError(f"adaptive starts from a seed of radius patch_size at the contact: "
                             f"give no block_patch_size, got {self.block_patch_size}")  # fmt: skip
        return self._adapt_values()

    def _adapt_values(self) -> dict[str, Any]:
        """The adaptive options as recorded (with or without ``adaptive``)."""
        return adaptive_inputs(self)

    def _materials(self) -> tuple[IsotropicElastic, IsotropicElastic | J2Material]:
        """The ball's and the block's materials: the given (or default) ones with the given
        properties, checked against the regime."""
        plastic = self.regime == "plastic"
        block_given = {field: getattr(self, f"block_{name}") for name, field in _BLOCK_PROPERTIES
                       if getattr(self, f"block_{name}") is not None}  # fmt: skip
        if not plastic and ({"yield_stress", "hardening_modulus"} & set(block_given)):
            raise ValueError("--block-yield-stress and --block-hardening are for --regime plastic")
        ball_given = {field: getattr(self, f"ball_{name}") for name, field in _BALL_PROPERTIES
                      if getattr(self, f"ball_{name}") is not None}  # fmt: skip
        ball = self.ball_material
        if ball_given:
            ball = dataclasses.replace(STEEL if ball is None else ball, **ball_given)
        block = self.block_material
        if block_given:
            block = dataclasses.replace((COPPER if plastic else STEEL) if block is None else block,
                                        **block_given)  # fmt: skip
        ball = STEEL if ball is None else ball
        if not isinstance(ball, IsotropicElastic):
            raise ValueError(f"ball_material must be an IsotropicElastic (the ball stays "
                             f"elastic), got {type(ball).__name__}")  # fmt: skip
        if self.rigid_wall and block is not None:
            raise ValueError("block_material has no effect with rigid_wall (there is no block)")
        if block is None:
            block = COPPER if plastic else STEEL
        if plastic != isinstance(block, J2Material):
            raise ValueError(f"the {self.regime} regime needs a block_material that is "
                             f"{'a J2Material' if plastic else 'an IsotropicElastic'}, got "
                             f"{type(block).__name__}")  # fmt: skip
        return ball, block

    def _check_options(self, block: IsotropicElastic | J2Material) -> None:
        """The wall, the friction and the multi-time-step ratio."""
        if self.rigid_wall and self.regime == "plastic":
            raise ValueError("rigid_wall removes the block, and the plastic regime is the "
                             "block's yielding: give one of them")  # fmt: skip
        friction = self.friction
        if not (isinstance(friction, (int, float)) and math.isfinite(friction)
                and friction >= 0.0):  # fmt: skip
            raise ValueError(f"friction must be a non-negative number, got friction={friction}")
        ratio = self.coarse_step_ratio
        if ratio is not None and (
            isinstance(ratio, bool)
            or not isinstance(ratio, (int, float))
            or int(ratio) != ratio
            or ratio < 1
        ):
            raise ValueError(f"coarse_step_ratio must be a positive integer, got {ratio!r}")
        if ratio is not None and ratio > 1 and self.model != "arlequin":
            raise ValueError("coarse_step_ratio > 1 needs the arlequin model (coarse models)")

    def _cell_sizes(self, big: float, velocity: float, ball: IsotropicElastic,
                    block: IsotropicElastic | J2Material) -> tuple[float, float]:  # fmt: skip
        """The requested coarse and fine sizes (m), before the rounding to the O-grid."""
        coarse = ARC_COARSE * big if self.coarse_size is None else _positive(
            "coarse_size", self.coarse_size)  # fmt: skip
        if self.fine_size is not None:
            fine = _positive("fine_size", self.fine_size)
        elif self.regime == "plastic":
            fine = 0.5 * coarse
        else:
            # ≥ 10 fine cells across Hertz's contact radius (against the elastic block or the
            # wall)
            ref = None if self.rigid_wall else block
            a_max = hertz(big, 4.0 / 3.0 * math.pi * big**3 * ball.density, velocity, ball,
                          ref)["hertz_contact_radius"]  # fmt: skip
            fine = coarse / 2.0 ** math.ceil(math.log2(10.0 * coarse / a_max))
        if fine >= coarse:
            raise ValueError(f"fine_size={fine:.4g} m must be smaller than coarse_size="
                             f"{coarse:.4g} m")  # fmt: skip
        return coarse, fine

    def _patch_sizes(self, big: float, coarse: float, fine: float, block_radius: float,
                     block_height: float) -> BallSizes:  # fmt: skip
        """The patches' radii (checked against the bodies) and the rounded cell sizes."""
        plastic = self.regime == "plastic"
        reach = (0.4 if plastic else 0.2) * big if self.patch_size is None else _positive(
            "patch_size", self.patch_size)  # fmt: skip
        block_size = math.inf if self.rigid_wall else min(block_radius, block_height)
        if reach >= 0.5 * big or reach >= block_size:
            what = "half the ball radius" + ("" if self.rigid_wall else " and the block's size")
            raise ValueError(f"the patches' radius {reach:.4g} m (patch_size) must stay below "
                             f"{what}")  # fmt: skip
        if self.block_patch_size is not None:
            block_reach = _positive("block_patch_size", self.block_patch_size)
        elif plastic:  # the plastic zone reaches beyond the contact radius
            block_reach = max(reach, min(0.8 * big, 0.5 * block_size))
        else:
            block_reach = reach
        if not self.rigid_wall and (block_reach < reach or block_reach >= 0.9 * block_size):
            raise ValueError(f"block_patch_size={block_reach:.4g} m must lie between "
                             f"patch_size={reach:.4g} m and 0.9 of the block's size")  # fmt: skip
        return ball_sizes(big, coarse, fine, reach, block_reach)

    def _check_cells(self, sizes: BallSizes, fine: float, block_radius: float,
                     block_height: float) -> None:  # fmt: skip
        """The patches' and the uniform meshes' cell counts against their limits."""
        # the patches' cells, about: their half discs at the fine size (the block's too)
        block_reach = 0.0 if self.rigid_wall else sizes.block_reach
        patch_cells = 0.5 * math.pi * (sizes.reach**2 + block_reach**2) / sizes.fine**2
        if patch_cells > PATCH_LIMIT:
            raise ValueError(f"the patches would hold about {patch_cells:.3g} cells at the fine "
                             f"size {sizes.fine:.4g} m (limit {PATCH_LIMIT:.3g}): a larger "
                             "fine_size or smaller patches")  # fmt: skip
        if abs(sizes.fine - fine) > 1e-9 * fine:
            logger.info("fine size %.4g m rounded to %.4g m (coarse %.4g m / 2^%d)", fine,
                        sizes.fine, sizes.coarse, sizes.levels)  # fmt: skip
        if self.model in ("mono", "mono-zoned"):
            cells = mono_cells(sizes, block_radius, block_height, self.rigid_wall)
            if cells > MONO_LIMIT:
                raise ValueError(f"the uniform (mono) meshes would have {cells} cells at the "
                                 f"fine size {sizes.fine:.4g} m (limit {MONO_LIMIT}): a smaller "
                                 "block or a larger fine_size")  # fmt: skip

    # -- records ----------------------------------------------------------------------------
    def inputs(self) -> dict[str, Any]:
        """The inputs recorded in ``results.json`` and the JSON (the keys of the run's record:
        the resolved velocity, patches' radii and multi-time-step ratio; the materials as
        objects of their named fields)."""
        return dict(self.resolved.record)

    @classmethod
    def units(cls) -> dict[str, str]:
        """The SI unit of each recorded input (the materials' fields: Pa, 1, kg/m^3)."""
        return dict(INPUT_UNITS)

    # -- running ----------------------------------------------------------------------------
    def progress_scale(self) -> tuple[float, str, float, str]:
        """The progress bar: the fraction of the simulated time, in percent."""
        return 100.0, "%", 100.0, "ball impact"
