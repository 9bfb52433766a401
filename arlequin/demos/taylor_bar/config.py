"""The Taylor bar's configuration: :class:`TaylorBarConfig`, one field a parameter (SI units).

It is the single source of the ``arlequin taylor-bar`` options (generated from its fields), of
the study keys (the field names) and of the units of the inputs recorded in ``results.json``.
Its :meth:`~TaylorBarConfig.check` resolves and validates every input
(:func:`~arlequin.demos.taylor_bar.setup.resolve`) when the configuration is made, before any
mesh is built or anything written.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ..config import DemoConfig, option
from .checkpoint import load_checkpoint
from .result import GEOMETRIES, MODELS
from .setup import resolve

__all__ = ["TaylorBarConfig"]

_ARL = "arlequin: "


@dataclass(frozen=True)
class TaylorBarConfig(DemoConfig):
    """The inputs of a Taylor bar run (SI units; ``None``: the default the run computes).

    Parameters
    ----------
    model : {"arlequin", "mono", "graded"}
        ``"arlequin"`` (default): a coarse linear-elastic bar plus a refined finite-strain J2
        patch over the impacted end (:class:`~arlequin.demos.taylor_bar.models.ArlequinBar`);
        ``"mono"``: one uniform finite-strain mesh over the whole bar; ``"graded"``: one
        conforming finite-strain mesh, the patch's fine cells over the patch region, a 2:1
        transition row, the coarse cells above (:func:`~arlequin.demos.taylor_bar.meshes.
        graded_bar_mesh`).
    elements_radial : int, optional
        Cells across the radius (default 10; the fine cells of the patch under ``arlequin``); or
        ``mesh_size`` (m), the cell edge across the radius (then elements_radial =
        round(R / mesh_size)); under ``arlequin`` also ``fine_size``, an alias of ``mesh_size``.
        The axial count is round(L / h).
    t_end : float
        End time (s), default 80 µs.
    velocity : float
        Impact speed v₀ (m/s), > 0 (the bar moves towards the wall).
    young, poisson, density, yield_stress, hardening : float
        E (Pa), ν, ρ (kg/m³), σ_y0 (Pa) and the linear hardening modulus H (Pa; also the linear
        term of the Voce law).
    hardening_law : {"linear", "voce", "johnson-cook"}
        With its parameters (the ``voce_*`` and ``jc_*`` fields).
    length, radius : float
        Bar length L and radius R (m).
    bulk_viscosity : bool or BulkViscosity
        Artificial bulk viscosity (off by default; True: linear 0.06, quadratic 1.5).
    patch_length, gluing_width, coarse_size : float, optional
        ``arlequin`` only (m): the patch's length from the impact face (default 0.9 L), the
        gluing band's width at its top (default two coarse rows), both rounded to whole coarse
        rows, and the coarse cell edge across the radius (default twice the fine size, or the
        smallest multiple dividing the radius for an odd count: 3 or 5 cells across give one
        coarse cell); ``graded`` uses patch_length and coarse_size too; see
        :func:`~arlequin.demos.taylor_bar.meshes.arlequin_bar_sizes`. In 3D ``mono`` takes
        ``coarse_size`` too: its mesh is then the coarse O-grid refined to the fine size (the
        Arlequin patch's nodes over the whole bar).
    weights, mediator, coupling : str, optional
        ``arlequin`` only: ``"ramp"`` (default), ``"constant"`` (½ in the band) or any
        :class:`~arlequin.PartitionWeights`; the ``"fine"`` (default) or ``"coarse"`` mediator
        space; ``"H1"`` (default) or ``"L2"`` coupling. The fine mediator ties the patch to the
        coarse field everywhere in the band; the coarse one leaves the patch's fine-scale motion
        free there, and where the ramp makes the patch light (its top edge) the mediator's
        impulses raise spurious plastic flow (docs/arlequin_taylor.md).
    coarse_step_ratio : int, optional
        ``arlequin`` only: the largest number M of patch (fine) steps per coarse step (default 1,
        one step for the coupled system). With M > 1 the coarse model's internal force is
        applied once every m ≤ M fine steps
        (:class:`~arlequin.solvers.SubcycledCentralDifference`, m the largest ratio keeping
        the coarse model within its own stable step; without its resonance bound, the run
        stopped with a :class:`~arlequin.contract.SimulationError` if the energy balance
        error passes 1%).
    friction : float
        Coulomb coefficient μ between the bar and the wall (default 0: the frictionless model,
        no tangential rows); the history then gains ``friction_work`` (J, ≤ 0).
    band_warning : float, optional
        ``arlequin`` only: warn (:class:`GluingBandPlasticityWarning`) when ε̄p in the gluing
        band exceeds this (default 0.02): the coarse model there is elastic.
    backend : {"auto", "numba", "numpy"}
        The internal-force path of :class:`~arlequin.models.FiniteStrainJ2`.
    safety : float
        Δt = safety × the critical step, re-estimated every ``estimate_every`` steps from the
        current configuration.
    sample_interval : float
        Interval of the records (s): history, balance and progress (default 0.5 µs).
    frame_interval : float
        Interval of the field frames written to ``out`` (s, default 2 µs).
    checkpoint_interval : float
        With ``out``: simulated time (s) between checkpoints (``checkpoint.pkl`` in the
        folder, default 10 µs; removed when the run completes).
    geometry : {"axisymmetric", "3d"}
        ``"axisymmetric"`` (default): Q1 cells of the (r, z) section; ``"3d"``: the quarter bar
        x, y ≥ 0 of 8-node F-bar hexahedra on an O-grid section with symmetry conditions
        (:mod:`~arlequin.demos.taylor_bar.models_3d`; energies and forces of the quarter;
        ``elements_radial`` ≥ 2 counts the O-grid's cells across the radius, and for
        ``arlequin`` the coarse size must be a power-of-two multiple of the fine size).
    patch_surface : trimesh.Trimesh, path or SurfaceRegion, optional
        ``arlequin`` with ``geometry="3d"`` only: the patch region as a closed surface (m): the
        coarse cells whose centroid lies inside are refined (instead of the layers below
        ``patch_length``). It must contain the impact face's cells and a band of whole layers at
        its top (the gluing band is the top ``gluing_width`` of the patch).
    no_fbar : bool
        Plain (locking) Q1 cells instead of the F-bar cells (default False; ``fbar=False``
        of :func:`~arlequin.demos.taylor_bar.run_taylor_bar`).
    voce_saturation, voce_rate, jc_b, jc_n, jc_c, jc_reference_rate : float, optional
        The hardening law's parameters (None: the law's default; see
        :func:`~arlequin.demos.taylor_bar.models.hardening_parameters`).
    estimate_every : int
        Steps between estimates of the critical step (default 10).
    """

    command: ClassVar[str] = "taylor-bar"
    title: ClassVar[str] = (
        "Taylor bar impact: a copper bar hits a rigid wall (Arlequin: a coarse elastic bar "
        "plus a refined finite-strain J2 patch; or one mesh)"
    )
    description: ClassVar[str] = (
        "A bar (length L, radius R) moving at V hits a rigid frictionless wall at t = 0. "
        "Default (--model arlequin): a coarse linear-elastic model of the whole bar and a "
        "refined finite-strain J2 patch over the impacted end, glued by a mediator in a band at "
        "the patch's top; --model mono: one finite-strain mesh. Axisymmetric Q1 F-bar cells "
        "(--geometry 3d: a quarter bar of F-bar hexahedra), central differences with the step "
        "re-estimated in the current configuration, the level-set contact model at the wall (on "
        "the patch). SI units; lengths in m, element edges in the reference configuration. "
        "Reports the final length, the footprint (mushroom) radius, the maximum equivalent "
        "plastic strain and the energy balance error (a fraction). --resume --out DIR continues "
        "an interrupted run from its last checkpoint, with its recorded inputs."
    )
    switches: ClassVar[tuple[str, ...]] = ("json", "quiet", "out", "resume")

    # -- the model and its meshes ------------------------------------------------------------
    model: str = option(
        "arlequin",
        "arlequin: coarse elastic bar + refined elastoplastic "
        "patch; mono: one uniform finite-strain mesh; graded: one conforming "
        "mesh, fine over the patch region, coarse above, a 2:1 transition row",
        "",
        choices=MODELS,
    )
    geometry: str = option(
        "axisymmetric",
        "axisymmetric: Q1 cells of the (r, z) section; 3d: "
        "the quarter bar x, y >= 0 of F-bar hexahedra on an O-grid section, "
        "symmetry conditions on x = 0 and y = 0 (energies and forces of the "
        "quarter)",
        "",
        choices=GEOMETRIES,
    )
    patch_surface: str | None = option(
        None,
        "arlequin, --geometry 3d: the patch region as a closed "
        "surface (STL/OBJ/PLY, m; from Python also a trimesh.Trimesh or a "
        "SurfaceRegion): the coarse cells whose centroid lies inside are "
        "refined (it must hold the impact face)",
        "",
        metavar="FILE",
        parse=str,
    )
    elements_radial: int | None = option(
        None,
        "cells across the radius (arlequin: of the patch); the axial count is round(L/h)",
        "1",
        metavar="N",
        exclusive="size",
        parse=int,
        default_help="10",
    )
    mesh_size: float | None = option(
        None,
        "cell edge across the radius (arlequin: an alias of --fine-size)",
        "m",
        metavar="H",
        exclusive="size",
        default_help="R/10",
    )
    fine_size: float | None = option(
        None,
        _ARL + "the patch's cell edge",
        "m",
        metavar="H",
        exclusive="size",
        default_help="R/10",
    )
    coarse_size: float | None = option(
        None,
        _ARL + "the coarse cell edge, a multiple of the fine size",
        "m",
        metavar="H",
        default_help="2x the fine size",
    )
    patch_length: float | None = option(
        None,
        _ARL + "patch length from the impact face (whole coarse rows)",
        "m",
        metavar="LP",
        default_help="0.9 L",
    )
    gluing_width: float | None = option(
        None,
        _ARL + "gluing band width at the patch's top",
        "m",
        metavar="W",
        default_help="2 coarse rows",
    )
    weights: str | None = option(
        None,
        _ARL + "partition weights across the band (from Python also a PartitionWeights)",
        "",
        choices=("ramp", "constant"),
        parse=str,
        default_help="ramp",
    )
    mediator: str | None = option(
        None,
        _ARL + "mediator space",
        "",
        choices=("coarse", "fine"),
        parse=str,
        default_help="fine",
    )
    coupling: str | None = option(
        None, _ARL + "coupling operator", "", choices=("L2", "H1"), parse=str, default_help="H1"
    )
    friction: float = option(
        0.0, "Coulomb friction between the bar and the wall (0: frictionless)", "1", metavar="MU"
    )
    coarse_step_ratio: int | None = option(
        None,
        _ARL + "multi-time-step, at most M patch steps per coarse step",
        "1",
        metavar="M",
        parse=int,
        default_help="1",
    )
    band_warning: float | None = option(
        None,
        _ARL + "warn if the plastic strain in the gluing band exceeds this",
        "1",
        metavar="EPS",
        default_help="0.02",
    )
    # -- the impact and the material ---------------------------------------------------------
    t_end: float = option(80e-6, "end time", "s", metavar="T")
    velocity: float = option(227.0, "impact speed", "m/s", metavar="V")
    young: float = option(117e9, "Young's modulus", "Pa", metavar="E")
    poisson: float = option(0.35, "Poisson's ratio", "1", metavar="NU")
    density: float = option(8930.0, "density", "kg/m^3", metavar="RHO")
    yield_stress: float = option(0.4e9, "initial yield stress", "Pa", metavar="S")
    hardening: float = option(
        0.1e9, "linear hardening modulus (the linear term of the Voce law)", "Pa", metavar="H"
    )
    hardening_law: str = option(
        "linear", "hardening law", "", choices=("linear", "voce", "johnson-cook")
    )
    voce_saturation: float | None = option(
        None, "Voce: saturation stress Q", "Pa", metavar="Q", default_help="0.1e9"
    )
    voce_rate: float | None = option(
        None, "Voce: saturation rate b", "1", metavar="B", default_help="10"
    )
    jc_b: float | None = option(
        None, "Johnson-Cook: B (A is --yield-stress)", "Pa", metavar="B", default_help="0.292e9"
    )
    jc_n: float | None = option(
        None, "Johnson-Cook: exponent n", "1", metavar="N", default_help="0.31"
    )
    jc_c: float | None = option(
        None, "Johnson-Cook: strain-rate coefficient C", "1", metavar="C", default_help="0: off"
    )
    jc_reference_rate: float | None = option(
        None, "Johnson-Cook: reference strain rate", "1/s", metavar="R", default_help="1"
    )
    length: float = option(32.4e-3, "bar length", "m", metavar="L")
    radius: float = option(3.2e-3, "bar radius", "m", metavar="R")
    # a bool, or a BulkViscosity from Python (True: linear 0.06, quadratic 1.5)
    bulk_viscosity: bool = option(
        False, "artificial bulk viscosity (linear 0.06, quadratic 1.5)", ""
    )
    no_fbar: bool = option(
        False, "plain Q1 cells (they lock under plastic flow; for comparison)", ""
    )
    backend: str = option(
        "auto",
        "internal-force path (auto: the compiled kernel)",
        "",
        choices=("auto", "numba", "numpy"),
    )
    # -- the time stepping, the records and the checkpoints ----------------------------------
    safety: float = option(0.8, "time step: this fraction of the critical step", "1", metavar="F")
    estimate_every: int = option(
        10,
        "steps between estimates of the critical step in the current configuration",
        "1",
        metavar="N",
    )
    sample_interval: float = option(
        0.5e-6, "interval of the records (history, balance, progress)", "s", metavar="DT"
    )
    frame_interval: float = option(
        2e-6, "interval of the field frames written to --out", "s", metavar="DT"
    )
    checkpoint_interval: float = option(
        10e-6,
        "with --out: simulated time between checkpoints (removed when the run completes)",
        "s",
        metavar="DT",
    )

    def check(self) -> None:
        """Resolve and validate every input (a ``ValueError`` naming the quantity and its
        value), nothing built or written."""
        resolve(self)

    def law_parameters(self) -> dict[str, float]:
        """The hardening law's parameters that were given (the others take the law's
        defaults)."""
        names = ("voce_saturation", "voce_rate", "jc_b", "jc_n", "jc_c", "jc_reference_rate")
        return {k: getattr(self, k) for k in names if getattr(self, k) is not None}

    def progress_scale(self) -> tuple[float, str, float, str]:
        """The progress bar in µs of simulated time."""
        return self.t_end * 1e6, "µs", 1e6, "simulated time"

    @classmethod
    def resume_progress_scale(cls, out: str) -> tuple[float, str, float, str]:
        """The progress bar of :meth:`resume`: µs of simulated time up to the checkpointed
        run's end."""
        t_end = load_checkpoint(out, None)["call"].t_end
        return t_end * 1e6, "µs", 1e6, "simulated time"
