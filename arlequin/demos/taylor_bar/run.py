"""The Taylor bar impact: finite-strain J2, explicit dynamics, the level-set wall.

A copper bar (length L, radius R, axisymmetric Q1 F-bar cells) moving at −v₀ along z touches a
rigid frictionless wall z = 0 at t = 0 (L = 32.4 mm, R = 3.2 mm, v₀ = 227 m/s,
E = 117 GPa, ν = 0.35, ρ = 8930 kg/m³, σ_y0 = 0.4 GPa, H = 0.1 GPa, 80 µs). Three models
(:mod:`arlequin.demos.taylor_models`): ``arlequin`` (default) a coarse linear-elastic bar plus a
refined finite-strain patch over the impacted end, glued by a mediator in a band at the patch's
top (docs/arlequin_taylor.md); ``mono`` one uniform finite-strain mesh; ``graded`` one
conforming finite-strain mesh, fine over the patch region and coarse above. The wall is the
level-set contact model on the impact face and the lower lateral surface (which folds onto the
wall as the mushroom forms), lift-off allowed; the axis carries u_r = 0. Central differences
with the step re-estimated from the current configuration every few steps
(:class:`~arlequin.solvers.CriticalFraction`).

Energy balance, at every record: KE + W_el + D_p + D_visc + W_c = KE_0 with KE the explicit
scheme's kinetic energy ½ṽ^{n−½}·M v^{n+½}, W_el the stored (Hencky) energy, D_p and D_visc the
plastic and bulk-viscosity dissipations, W_c ≥ 0 the energy the wall removed (minus the work of
the contact forces on the bar, the loss of stopping the impact face at t = 0 included) and KE_0
= ½ v₀·M v₀ with the lumped mass. Reported: the final length (axial position of the top-face
node on the axis), the footprint (mushroom) radius (the largest distance from the axis of a
node of the impact face), the maximum equivalent plastic strain and the balance error
max_t abs(KE + W_el + D_p + D_visc + W_c − W_coupling − KE_0) / KE_0 (W_coupling, the net work of
the mediator's forces, is zero on one mesh). SI units throughout.

The run writes its results as it goes (``out=DIR``): results.json (inputs with units, then the
results), history.csv (one row per record), fields/bar.xdmf (u, v, ε̄p and the von Mises
stress on the reference mesh; warp by ``displacement`` in ParaView; ``arlequin``:
fields/coarse.xdmf and fields/patch.xdmf with the weights and the multipliers) and, at the end,
taylor_bar.png (the final shape coloured by ε̄p; ``arlequin``: both models, initial and final)
and taylor_bar_history.png.
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

from ..coupling.weights import PartitionWeights
from ..io import ResultsFolder
from ..models import BulkViscosity, J2Material
from ..solvers import CriticalFraction, solve
from .taylor_checkpoint import CheckpointWriter, load_checkpoint, read_frames
from .taylor_meshes import (
    elements_radial_of,
    fine_radial,
    positive,
    taylor_bar_mesh,
)
from .taylor_models import LAW_DEFAULTS, ArlequinBar, hardening_parameters
from .taylor_models_3d import ArlequinBar3D
from .taylor_record import HISTORY_UNITS, MultiplierHistory, TaylorRecorder, write_results
from .taylor_result import (
    ARLEQUIN_JSON_KEYS,
    JSON_KEYS,
    MODELS,
    TAYLOR_REFERENCE,
    GluingBandPlasticityWarning,
    TaylorBarResult,
)
from .taylor_setup import build_bar

__all__ = [
    "ARLEQUIN_JSON_KEYS",
    "HISTORY_UNITS",
    "JSON_KEYS",
    "MODELS",
    "TAYLOR_REFERENCE",
    "GluingBandPlasticityWarning",
    "TaylorBarResult",
    "hardening_parameters",
    "resume_taylor_bar",
    "run_taylor_bar",
    "taylor_bar_mesh",
]

logger = logging.getLogger(__name__)

_INPUT_UNITS = {
    "length": "m", "radius": "m", "velocity": "m/s", "young": "Pa", "poisson": "1",
    "density": "kg/m^3", "yield_stress": "Pa", "hardening": "Pa", "t_end": "s",
    "elements_radial": "1", "elements_axial": "1", "mesh_size": "m", "safety": "1",
    "estimate_every": "1", "sample_interval": "s", "frame_interval": "s", "voce_saturation": "Pa",
    "voce_rate": "1", "jc_b": "Pa", "jc_n": "1", "jc_c": "1", "jc_reference_rate": "1/s",
    "bulk_viscosity_linear": "1", "bulk_viscosity_quadratic": "1", "coarse_radial": "1",
    "coarse_axial": "1", "ratio": "1", "patch_rows": "1", "band_rows": "1", "coarse_size": "m",
    "fine_size": "m", "patch_length": "m", "gluing_width": "m", "epsilon": "1",
    "band_warning": "1", "coarse_step_ratio": "1", "friction": "1",
}  # fmt: skip

_RESULT_UNITS = {
    "final_length": "m", "mushroom_radius": "m", "max_plastic_strain": "1",
    "energy_balance_error": "1", "n_elements": "1", "mesh_size": "m", "n_steps": "1",
    "wall_time_s": "s", "initial_kinetic_energy": "J", "impact_loss": "J", "min_dt": "s",
    "max_plastic_strain_at": "m", "final_energies": "J", "qp_updates_per_second": "1/s",
    "setup_time_s": "s", "elements_radial": "1", "elements_axial": "1",
    "coarse_elements": "1", "fine_elements": "1", "coarse_size": "m",
    "fine_size": "m", "patch_fraction": "1", "patch_length": "m", "gluing_width": "m",
    "band_max_plastic_strain": "1", "multiplier_chatter": "1",
    "multiplier_chatter_per_row": "1",
}  # fmt: skip


def run_taylor_bar(
    model: str = "arlequin",
    elements_radial: int | None = None,
    mesh_size: float | None = None,
    t_end: float = 80e-6,
    velocity: float = 227.0,
    young: float = 117e9,
    poisson: float = 0.35,
    density: float = 8930.0,
    yield_stress: float = 0.4e9,
    hardening: float = 0.1e9,
    hardening_law: str = "linear",
    length: float = 32.4e-3,
    radius: float = 3.2e-3,
    bulk_viscosity: bool | BulkViscosity = False,
    *,
    patch_length: float | None = None,
    gluing_width: float | None = None,
    coarse_size: float | None = None,
    fine_size: float | None = None,
    weights: str | PartitionWeights | None = None,
    mediator: str | None = None,
    coupling: str | None = None,
    coarse_step_ratio: int | None = None,
    band_warning: float | None = None,
    friction: float = 0.0,
    fbar: bool = True,
    backend: str = "auto",
    safety: float = 0.8,
    estimate_every: int = 10,
    sample_interval: float = 0.5e-6,
    frame_interval: float = 2e-6,
    out: str | Path | None = None,
    progress: Callable[[float], None] | None = None,
    checkpoint_interval: float = 10e-6,
    resume: bool = False,
    check_only: bool = False,
    geometry: str = "axisymmetric",
    patch_surface: Any = None,
    **law_parameters: float,
) -> TaylorBarResult | None:
    """Run the Taylor bar impact (see the module docstring).

    Parameters
    ----------
    model : {"arlequin", "mono", "graded"}
        ``"arlequin"`` (default): a coarse linear-elastic bar plus a refined finite-strain J2
        patch over the impacted end (:class:`~arlequin.demos.taylor_models.ArlequinBar`);
        ``"mono"``: one uniform finite-strain mesh over the whole bar; ``"graded"``: one
        conforming finite-strain mesh, the patch's fine cells over the patch region, a 2:1
        transition row, the coarse cells above (:func:`~arlequin.demos.taylor_meshes.
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
        With its parameters as keywords (see :func:`hardening_parameters`).
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
        :func:`~arlequin.demos.taylor_models.arlequin_bar_sizes`. In 3D ``mono`` takes
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
    fbar : bool
        F-bar cells (default); False gives the plain (locking) Q1 cells.
    backend : {"auto", "numba", "numpy"}
        The internal-force path of :class:`~arlequin.models.FiniteStrainJ2`.
    safety : float
        Δt = safety × the critical step, re-estimated every ``estimate_every`` steps from the
        current configuration.
    sample_interval : float
        Interval of the records (s): history, balance and progress (default 0.5 µs).
    frame_interval : float
        Interval of the field frames written to ``out`` (s, default 2 µs).
    out : path, optional
        Results folder, written as the run goes.
    progress : callable, optional
        ``progress(t)`` at every record (the CLI's progress bar).
    checkpoint_interval : float
        With ``out``: simulated time (s) between checkpoints (``checkpoint.pkl`` in the
        folder, default 10 µs; removed when the run completes).
    check_only : bool
        Check every input and build the models, then return None without running or writing
        anything (a study checks its cases so before running any).
    geometry : {"axisymmetric", "3d"}
        ``"axisymmetric"`` (default): Q1 cells of the (r, z) section; ``"3d"``: the quarter bar
        x, y ≥ 0 of 8-node F-bar hexahedra on an O-grid section with symmetry conditions
        (:mod:`~arlequin.demos.taylor_models_3d`; energies and forces of the quarter;
        ``elements_radial`` ≥ 2 counts the O-grid's cells across the radius, and for
        ``arlequin`` the coarse size must be a power-of-two multiple of the fine size).
    patch_surface : trimesh.Trimesh, path or SurfaceRegion, optional
        ``arlequin`` with ``geometry="3d"`` only: the patch region as a closed surface (m): the
        coarse cells whose centroid lies inside are refined (instead of the layers below
        ``patch_length``). It must contain the impact face's cells and a band of whole layers at
        its top (the gluing band is the top ``gluing_width`` of the patch).
    resume : bool
        Continue the interrupted run of the folder ``out`` from its last checkpoint (the inputs
        must be the same; :func:`resume_taylor_bar` reads them from the checkpoint). Everything
        written until the checkpoint is kept and the values are those of an uninterrupted run.

    Returns
    -------
    TaylorBarResult

    Raises
    ------
    ValueError
        On bad input, before any computation; :class:`~arlequin.contract.SimulationError` if the
        run fails (an inverted cell names the cell, the step and the time), with the results
        folder marked failed and everything recorded until then kept.
    """
    call = {k: v for k, v in locals().items()
            if k not in ("out", "progress", "resume", "law_parameters")}  # fmt: skip
    call.update(law_parameters)
    if model not in MODELS:
        raise ValueError(f"model must be one of {MODELS}, got {model!r}")
    positive("checkpoint_interval", checkpoint_interval)
    for name, value in [("t_end", t_end), ("velocity", velocity), ("length", length),
                        ("radius", radius), ("sample_interval", sample_interval),
                        ("frame_interval", frame_interval)]:  # fmt: skip
        positive(name, value)
    only_arlequin = {k: v for k, v in (("gluing_width", gluing_width), ("weights", weights),
                     ("band_warning", band_warning),
                     ("mediator", mediator), ("coupling", coupling),
                     ("coarse_step_ratio", coarse_step_ratio)) if v is not None}  # fmt: skip
    if model != "arlequin" and only_arlequin:
        raise ValueError(f"{sorted(only_arlequin)} apply to model='arlequin' only, got "
                         f"model={model!r}")  # fmt: skip
    arlequin = model == "arlequin"
    # the patch's sizes apply (3D mono with coarse_size: the coarse O-grid refined)
    nested = model in ("arlequin", "graded") or (
        model == "mono" and geometry == "3d" and coarse_size is not None
    )
    if not nested:
        extra = {k: v for k, v in (("patch_length", patch_length), ("coarse_size", coarse_size))
                 if v is not None}  # fmt: skip
        if extra:
            raise ValueError(f"{sorted(extra)} apply to model='arlequin' or 'graded' only, got "
                             f"model={model!r}")  # fmt: skip
        if fine_size is not None:
            raise ValueError(f"fine_size applies to model='arlequin' or 'graded' only (use "
                             f"mesh_size), got "
                             f"model={model!r}")  # fmt: skip
        n_r = elements_radial_of(elements_radial, mesh_size, radius)
    else:
        n_r = fine_radial(elements_radial, mesh_size, fine_size, radius)
    weights = "ramp" if weights is None else weights
    mediator = "fine" if mediator is None else mediator
    coupling = "H1" if coupling is None else coupling
    coarse_step_ratio = 1 if coarse_step_ratio is None else coarse_step_ratio
    band_warning = 0.02 if band_warning is None else band_warning
    unknown = sorted(set(law_parameters) - {p for d in LAW_DEFAULTS.values() for p in d})
    if unknown:
        raise ValueError(f"unknown parameters {unknown}: neither an option of run_taylor_bar nor "
                         f"a parameter of a hardening law")  # fmt: skip
    if isinstance(coarse_step_ratio, bool) or int(coarse_step_ratio) != coarse_step_ratio \
            or coarse_step_ratio < 1:  # fmt: skip
        raise ValueError(f"coarse_step_ratio must be a positive integer, got {coarse_step_ratio!r}")
    if coarse_step_ratio != 1 and model != "arlequin":
        raise ValueError(f"coarse_step_ratio={coarse_step_ratio} needs a coarse model: it applies "
                         f"to model='arlequin' only, got model={model!r}")  # fmt: skip
    if not isinstance(weights, PartitionWeights) and weights not in ("ramp", "constant"):
        raise ValueError(f"weights must be 'ramp', 'constant' or a PartitionWeights, got "
                         f"weights={weights!r}")  # fmt: skip
    for name, value, choices in (("mediator", mediator, ("coarse", "fine")),
                                 ("coupling", coupling, ("L2", "H1"))):  # fmt: skip
        if value not in choices:
            raise ValueError(f"{name} must be one of {choices}, got {name}={value!r}")
    if isinstance(friction, bool) or not (
        isinstance(friction, (int, float)) and math.isfinite(friction) and friction >= 0.0
    ):
        raise ValueError(f"friction must be a non-negative number (Coulomb μ), got {friction!r}")
    if not (isinstance(band_warning, (int, float)) and band_warning >= 0.0):
        raise ValueError(f"band_warning must be a non-negative number, got {band_warning!r}")
    law = hardening_parameters(hardening_law, yield_stress, hardening, **law_parameters)
    material = J2Material.with_law(young, poisson, density, law)
    if int(estimate_every) != estimate_every or estimate_every < 1:
        raise ValueError(f"estimate_every must be a positive integer, got {estimate_every}")
    controller = CriticalFraction(safety, int(estimate_every))  # checks safety ∈ (0, 1]
    if not isinstance(bulk_viscosity, (bool, BulkViscosity)):
        raise ValueError(
            f"bulk_viscosity must be a bool or a BulkViscosity, got {bulk_viscosity!r}"
        )
    if not isinstance(fbar, bool):
        raise ValueError(f"fbar must be True or False, got fbar={fbar!r}")
    visc = BulkViscosity() if bulk_viscosity is True else (bulk_viscosity or None)
    config: dict[str, Any] = {"model": model, "geometry": geometry}
    bar, n_z, sizes = build_bar(
        model, geometry, length, radius, n_r, material, config, nested=nested,
        coarse_size=coarse_size, patch_length=patch_length, gluing_width=gluing_width,
        patch_surface=patch_surface, weights=weights, mediator=mediator, coupling=coupling,
        fbar=fbar, backend=backend, bulk_viscosity=visc, friction=friction,
    )  # fmt: skip
    if arlequin:
        config.update(weights=str(weights), mediator=mediator, coupling=coupling,
                      coarse_step_ratio=int(coarse_step_ratio), band_warning=band_warning,
                      epsilon=bar.problem.patches[0].epsilon)  # fmt: skip
    if check_only:  # every input checked, the models built: nothing run, nothing written
        return None
    fine_model = bar.model
    config.update({
        "elements_radial": n_r, "elements_axial": n_z, "mesh_size": radius / n_r,
        "t_end": t_end, "velocity": velocity, "young": young, "poisson": poisson,
        "density": density, "yield_stress": yield_stress, "hardening": hardening,
        "hardening_law": hardening_law, "length": length, "radius": radius,
        "bulk_viscosity": bool(visc), "fbar": bool(fbar), "backend": backend, "safety": safety,
        "estimate_every": int(estimate_every), "sample_interval": sample_interval,
        "frame_interval": frame_interval, "friction": float(friction),
        **{k: v for k, v in law_parameters.items() if v is not None},
    })  # fmt: skip
    if visc:
        config.update(bulk_viscosity_linear=visc.linear, bulk_viscosity_quadratic=visc.quadratic)
    if fine_model.backend == "numba":
        from ..models.plasticity.j2_kernel import warm_up
        from ..models.plasticity.j2_kernel_3d import warm_up_solid

        # compile (or load) before the clock starts
        warm_up_solid() if geometry == "3d" else warm_up()
    v0 = bar.initial_velocity(velocity)
    ke0 = 0.5 * float(v0 @ (bar.lumped_mass() * v0))
    frames = np.arange(0.0, t_end * (1 + 1e-12), frame_interval)
    ckpt = load_checkpoint(out, config) if resume else None
    # the frames written before the interruption, read before the folder's series reopen
    old_frames = read_frames(out, bar.series_meshes()) if ckpt is not None else {}
    # every input checked: the results folder opens (results.json with the inputs, "running")
    folder = None
    if out is not None:
        folder = ResultsFolder(out, "arlequin taylor-bar", config, _INPUT_UNITS)
    con = bar.contact
    rec = TaylorRecorder(bar, con.name, con.pair.slave.weights, ke0, folder, frames, progress)
    lam_history = MultiplierHistory("coupling:patch") if arlequin else None
    saver = None
    if folder is not None:
        saver = CheckpointWriter(folder.path, checkpoint_interval, config, call, rec, lam_history)
    if ckpt is not None:
        saver.resume_from(ckpt, old_frames)
    n_samples = max(1, round(t_end / sample_interval))
    t_eval = np.linspace(0.0, t_end, n_samples + 1)[1:]
    logger.info("Taylor bar (%s): %d x %d fine cells, %s backend", model, n_r, n_z,
                fine_model.backend)  # fmt: skip
    start = time.perf_counter()
    mts_seen: dict[str, Any] = {}
    try:
        # the fastest fine modes are those of the distorted cells at the impact face, far from
        # the gluing band the coarse force acts through: no resonance bound (it would keep
        # m = 1), the energy check at the Interface's 1% balance stops a resonating run
        mts = {"slow_blocks": (bar.coarse_block,), "step_ratio": int(coarse_step_ratio),
               "safety": safety, "resonance_bound": False,
               "energy_tolerance": 0.01} if coarse_step_ratio > 1 else {}  # fmt: skip
        on_step = [rec.count_step] + ([lam_history] if lam_history is not None else [])
        if mts:
            on_step.append(lambda integ: mts_seen.__setitem__("integ", integ))
        res = solve(
            bar.system,
            "explicit-mts" if mts else "explicit",
            t_end=t_end,
            v0=v0,
            constraints=[con],
            **mts,
            step_controller=controller,
            t_eval=t_eval,
            on_record=[rec],
            on_step=on_step,
            on_checkpoint=saver,
            restore=None if ckpt is None else (ckpt["snapshot"], ckpt["recorder"]),
        )
    except Exception as exc:
        if folder is not None:
            folder.finish("failed", str(exc))
        raise
    end = time.perf_counter()
    wall_time = end - start
    loop_time = end - (rec.loop_start if rec.loop_start is not None else start)
    u = res.u
    state = res.states[bar.fine_block][0]
    ip = int(np.argmax(state.eqps))
    xq = fine_model.quadrature_points().reshape(bar.fine_mesh.dim(), -1)[:, ip]
    steps = np.asarray(res.step_sizes if res.step_sizes is not None else [res.dt])
    n_qp = state.eqps.size
    hist = rec.history
    if not arlequin:  # the single-mesh history keeps the keys of its Interface
        hist.pop("coupling_work")
    result = TaylorBarResult(
        final_length=hist["length"][-1],
        mushroom_radius=hist["radius"][-1],
        max_plastic_strain=float(state.eqps.max()),
        energy_balance_error=float(max(rec.balance)),
        n_elements=bar.n_elements,
        mesh_size=radius / n_r,
        n_steps=int(res.n_steps),
        wall_time_s=wall_time,
        history=hist,
        elements_radial=n_r,
        elements_axial=n_z,
        max_plastic_strain_at=[float(x) for x in xq],
        initial_kinetic_energy=ke0,
        impact_loss=hist["contact_work"][0],
        fixed_point_iterations=rec.iteration_summary(),
        min_dt=float(steps[steps > 0].min()) if np.any(steps > 0) else float(res.dt),
        qp_updates_per_second=n_qp * res.n_steps / loop_time,
        setup_time_s=wall_time - loop_time,
        config=config,
        model=fine_model,
        u=u,
        state=state,
        setup=bar,
    )
    if model == "graded":
        fine_cells = bar.graded_fine_elements
        result.arlequin = {
            "coarse_elements": bar.n_elements - fine_cells, "fine_elements": fine_cells,
            "coarse_size": sizes.coarse_size, "fine_size": sizes.fine_size,
            "patch_length": sizes.patch_length,
        }  # fmt: skip
    if arlequin:
        assert isinstance(bar, (ArlequinBar, ArlequinBar3D)) and lam_history is not None
        s = bar.sizes
        band_eqps = bar.band_plastic_strain(state)
        chatter = lam_history.chatter()
        result.arlequin = {
            "coarse_elements": bar.coarse_elements, "fine_elements": bar.fine_elements,
            "coarse_size": s.coarse_size, "fine_size": s.fine_size,
            "patch_fraction": bar.patch_fraction,
            "patch_length": getattr(bar, "patch_top", s.patch_length),
            "gluing_width": s.gluing_width, "band_max_plastic_strain": band_eqps,
            "multiplier_chatter": chatter["global"],
            "multiplier_chatter_per_row": chatter["per_row"],
        }  # fmt: skip
        result.multiplier_history = lam_history
        integ = mts_seen.get("integ")
        result.arlequin["coarse_step_ratio"] = int(coarse_step_ratio)
        if integ is not None:  # the ratio each macro step could use (≤ coarse_step_ratio)
            result.arlequin["macro_steps"] = int(integ.macro_steps)
            result.arlequin["mean_step_ratio"] = float(np.mean(integ.ratios))
        if band_eqps > band_warning:
            msg = (f"equivalent plastic strain in the gluing band reaches {band_eqps:.4f} > "
                   f"{band_warning} (band_warning): the coarse model glued there is elastic; "
                   f"lengthen the patch (patch_length={s.patch_length:.4g} m)")  # fmt: skip
            warnings.warn(msg, GluingBandPlasticityWarning, stacklevel=2)
    if folder is not None:
        write_results(folder, result, _RESULT_UNITS)
    if saver is not None:
        saver.remove()
    logger.info(result.summary())
    return result


def resume_taylor_bar(out: str | Path, progress: Callable[[float], None] | None = None,
                      ) -> TaylorBarResult:  # fmt: skip
    """Continue the interrupted Taylor bar run of the results folder ``out`` from its last
    checkpoint, with the inputs the checkpoint recorded (see :func:`run_taylor_bar`).

    Raises
    ------
    ValueError
        If ``out`` has no (readable) checkpoint.
    """
    call = load_checkpoint(out, None)["call"]
    return run_taylor_bar(**call, out=out, progress=progress, resume=True)
