"""The Taylor bar impact on one mesh: finite-strain J2, explicit dynamics, the level-set wall.

A copper bar (length L, radius R, axisymmetric Q1 mesh, F-bar) moving at −v₀ along z touches a
rigid frictionless wall z = 0 at t = 0 (DESIGN §4: L = 32.4 mm, R = 3.2 mm, v₀ = 227 m/s,
E = 117 GPa, ν = 0.35, ρ = 8930 kg/m³, σ_y0 = 0.4 GPa, H = 0.1 GPa, 80 µs). The wall is the
level-set contact model on the impact face and the lower lateral surface (which folds onto the
wall as the mushroom forms), lift-off allowed; the axis carries u_r = 0. Central differences
with the step re-estimated from the current configuration every few steps
(:class:`~arlequin.integrators.CriticalFraction`).

Energy balance, at every record: KE + W_el + D_p + D_visc + W_c = KE_0 with KE the explicit
scheme's kinetic energy ½ṽ^{n−½}·M v^{n+½}, W_el the stored (Hencky) energy, D_p and D_visc the
plastic and bulk-viscosity dissipations, W_c ≥ 0 the energy the wall removed (minus the work of
the contact forces on the bar, the loss of stopping the impact face at t = 0 included) and KE_0
= ½ v₀·M v₀ with the lumped mass. Reported: the final length (axial position of the top-face
node on the axis), the footprint (mushroom) radius (the largest distance from the axis of a
node of the impact face), the maximum equivalent plastic strain and the balance error
max_t |KE + W_el + D_p + D_visc + W_c − KE_0| / KE_0. SI units throughout.

The run writes its results as it goes (``out=DIR``): results.json (inputs with units, then the
results), history.csv (one row per record), fields/bar.xdmf (u, v, ε̄p and the von Mises
stress on the reference mesh; warp by ``displacement`` in ParaView) and, at the end,
taylor_bar.png (the final shape coloured by ε̄p) and taylor_bar_history.png.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp
import skfem

from ..integrators import CriticalFraction, solve
from ..io import JsonResult, ResultsFolder
from ..models import (
    HARDENING_LAWS,
    BulkViscosity,
    ContactSurface,
    FiniteStrainJ2,
    J2Material,
    LevelSetContact,
    PlaneObstacle,
    RigidContactPair,
    make_hardening,
)
from ..system import Block, BlockTerm, CoupledSystem, LinearConstraint
from .taylor_record import HISTORY_UNITS, TaylorRecorder, write_results

__all__ = [
    "HISTORY_UNITS",
    "JSON_KEYS",
    "TAYLOR_REFERENCE",
    "TaylorBarResult",
    "hardening_parameters",
    "run_taylor_bar",
    "taylor_bar_mesh",
]

logger = logging.getLogger(__name__)

#: The keys of the JSON document of ``arlequin taylor-bar --json`` (the Interface of issue 10).
JSON_KEYS = (
    "final_length",
    "mushroom_radius",
    "max_plastic_strain",
    "energy_balance_error",
    "n_elements",
    "mesh_size",
    "n_steps",
    "wall_time_s",
    "history",
)


#: Published converged values at 80 µs (DESIGN §4: 3D, 1.5M elements), m.
TAYLOR_REFERENCE = {"final_length": 21.43e-3, "mushroom_radius": 7.23e-3}

#: Default parameters of each hardening law (Pa, dimensionless, 1/s); σ_y0 and H come from
#: ``yield_stress`` and ``hardening`` for every law.
LAW_DEFAULTS: dict[str, dict[str, float]] = {
    "linear": {},
    "voce": {"voce_saturation": 0.1e9, "voce_rate": 10.0},
    "johnson-cook": {"jc_b": 0.292e9, "jc_n": 0.31, "jc_c": 0.0, "jc_reference_rate": 1.0},
}

_INPUT_UNITS = {
    "length": "m", "radius": "m", "velocity": "m/s", "young": "Pa", "poisson": "1",
    "density": "kg/m^3", "yield_stress": "Pa", "hardening": "Pa", "t_end": "s",
    "elements_radial": "1", "elements_axial": "1", "mesh_size": "m", "safety": "1",
    "estimate_every": "1", "sample_interval": "s", "frame_interval": "s", "voce_saturation": "Pa",
    "voce_rate": "1", "jc_b": "Pa", "jc_n": "1", "jc_c": "1", "jc_reference_rate": "1/s",
    "bulk_viscosity_linear": "1", "bulk_viscosity_quadratic": "1",
}  # fmt: skip

_RESULT_UNITS = {
    "final_length": "m", "mushroom_radius": "m", "max_plastic_strain": "1",
    "energy_balance_error": "1", "n_elements": "1", "mesh_size": "m", "n_steps": "1",
    "wall_time_s": "s", "initial_kinetic_energy": "J", "impact_loss": "J", "min_dt": "s",
    "max_plastic_strain_at": "m", "final_energies": "J", "qp_updates_per_second": "1/s",
    "setup_time_s": "s",
}  # fmt: skip


@dataclass
class TaylorBarResult(JsonResult):
    """One Taylor bar run (SI units).

    Attributes
    ----------
    final_length : float
        Axial position of the top-face node on the axis at the end (m).
    mushroom_radius : float
        Largest distance from the axis of a node of the impact face at the end (m).
    max_plastic_strain : float
        Largest equivalent plastic strain ε̄p over the quadrature points at the end.
    energy_balance_error : float
        max over the records of |KE + W_el + D_p + D_visc + W_c − KE_0| / KE_0.
    n_elements : int
        Cells of the mesh.
    mesh_size : float
        Cell edge across the radius, R / elements_radial (m).
    n_steps : int
        Time steps taken.
    wall_time_s : float
        Wall time of the run (s): the integrator's set-up (the critical step of the initial
        configuration) and the explicit loop, compilation of the kernel excluded.
    history : dict
        Column -> list, one entry per record (every ``sample_interval``): t (s), length (m),
        radius (m), kinetic, elastic, plastic_dissipation, viscous_dissipation, contact_work
        (J; contact_work = W_c ≥ 0, the energy removed by the wall), contact_force (N, the
        wall's axial force averaged since the previous record, from the accumulated impulse;
        at t = 0 that of the impulse stopping the face), dt (s, the step that ended there).
    elements_radial, elements_axial : int
    max_plastic_strain_at : list of float
        Reference (r, z) of the quadrature point of the maximum ε̄p (m).
    initial_kinetic_energy : float
        KE_0 = ½ v₀·M v₀, lumped mass (J).
    impact_loss : float
        W_c after the impulse of t = 0 (J): ½ m_face v₀² of the nodes stopped by the wall.
    min_dt : float
        Smallest step of the run (s).
    qp_updates_per_second : float
        Quadrature-point updates per second of the explicit loop (contact and records
        included), n_qp n_steps / (wall_time_s − setup_time_s).
    setup_time_s : float
        The set-up part of wall_time_s (s).
    config : dict
        The inputs.
    reference : dict
        The published values at 80 µs (m), :data:`TAYLOR_REFERENCE`.
    model, u, state : the model, the final displacement (m) and the final quadrature state
        (not in the JSON).
    """

    final_length: float
    mushroom_radius: float
    max_plastic_strain: float
    energy_balance_error: float
    n_elements: int
    mesh_size: float
    n_steps: int
    wall_time_s: float
    history: dict[str, list[float]]
    elements_radial: int
    elements_axial: int
    max_plastic_strain_at: list[float]
    initial_kinetic_energy: float
    impact_loss: float
    min_dt: float
    qp_updates_per_second: float
    setup_time_s: float
    config: dict[str, Any] = field(default_factory=dict)
    reference: dict[str, float] = field(default_factory=lambda: dict(TAYLOR_REFERENCE))
    model: Any = field(default=None, repr=False)
    u: Any = field(default=None, repr=False)
    state: Any = field(default=None, repr=False)

    json_exclude = ("model", "u", "state")

    def to_json(self) -> dict[str, Any]:
        data = super().to_json()
        # the Interface keys first, then the rest
        return {**{k: data[k] for k in JSON_KEYS}, **{k: v for k, v in data.items()
                                                       if k not in JSON_KEYS}}  # fmt: skip

    def summary(self) -> str:
        ref = TAYLOR_REFERENCE
        return (
            f"Taylor bar, {self.elements_radial} x {self.elements_axial} cells: final length "
            f"{self.final_length * 1e3:.3f} mm ({self.final_length / ref['final_length'] - 1:+.2%}"
            f" vs 21.43), mushroom radius {self.mushroom_radius * 1e3:.3f} mm "
            f"({self.mushroom_radius / ref['mushroom_radius'] - 1:+.2%} vs 7.23), max plastic "
            f"strain {self.max_plastic_strain:.3f}, energy balance error "
            f"{self.energy_balance_error:.2e}, {self.n_steps} steps in {self.wall_time_s:.1f} s"
        )


def taylor_bar_mesh(length: float, radius: float, elements_radial: int) -> skfem.MeshQuad:
    """Meridional (r, z) Q1 mesh of the bar: ``elements_radial`` cells across the radius and
    round(L / h) along the axis, h = R / elements_radial (nearly square cells), z ∈ [0, L]."""
    n_r = int(elements_radial)
    n_z = max(1, round(length / (radius / n_r)))
    return skfem.MeshQuad.init_tensor(np.linspace(0.0, radius, n_r + 1),
                                      np.linspace(0.0, length, n_z + 1))  # fmt: skip


def hardening_parameters(law: str, yield_stress: float, hardening: float, **params: float):
    """The :class:`~arlequin.models.Hardening` of a law name and the CLI's parameters.

    ``linear``: σ_y0 + H ε̄p; ``voce``: σ_y0 + Q(1 − e^{−b ε̄p}) + H ε̄p (``voce_saturation`` Q,
    ``voce_rate`` b); ``johnson-cook``: (σ_y0 + B ε̄p^n)(1 + C ln(ε̄̇p/ε̄̇0)) (``jc_b``, ``jc_n``,
    ``jc_c``, ``jc_reference_rate``; H unused).
    """
    if law not in HARDENING_LAWS:
        raise ValueError(f"hardening law must be one of {HARDENING_LAWS}, got {law!r}")
    p = {**LAW_DEFAULTS[law], **{k: v for k, v in params.items() if v is not None}}
    unknown = set(p) - set(LAW_DEFAULTS[law])
    if unknown:
        raise ValueError(f"parameters {sorted(unknown)} do not belong to the {law} law")
    if law == "linear":
        return make_hardening("linear", yield_stress=yield_stress, modulus=hardening)
    if law == "voce":
        return make_hardening("voce", yield_stress=yield_stress, saturation=p["voce_saturation"],
                              rate=p["voce_rate"], modulus=hardening)  # fmt: skip
    return make_hardening("johnson-cook", a=yield_stress, b=p["jc_b"], n=p["jc_n"], c=p["jc_c"],
                          reference_rate=p["jc_reference_rate"])  # fmt: skip


def _positive(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.number)):
        raise ValueError(f"{name} must be a number, got {name}={value!r}")
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} must be positive and finite, got {name}={value}")
    return float(value)


def _elements_radial(elements_radial, mesh_size, radius) -> int:
    if elements_radial is not None and mesh_size is not None:
        raise ValueError(
            f"give elements_radial or mesh_size, not both (got elements_radial={elements_radial}, "
            f"mesh_size={mesh_size})"
        )
    if mesh_size is not None:
        h = _positive("mesh_size", mesh_size)
        if h > radius:
            raise ValueError(f"mesh_size must not exceed the radius {radius} m, got {h}")
        return max(1, round(radius / h))
    n = 10 if elements_radial is None else elements_radial
    if isinstance(n, bool) or int(n) != n or n < 1:
        raise ValueError(f"elements_radial must be a positive integer, got elements_radial={n}")
    return int(n)


def run_taylor_bar(
    model: str = "mono",
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
    fbar: bool = True,
    backend: str = "auto",
    safety: float = 0.8,
    estimate_every: int = 10,
    sample_interval: float = 0.5e-6,
    frame_interval: float = 2e-6,
    out: str | Path | None = None,
    progress: Callable[[float], None] | None = None,
    **law_parameters: float,
) -> TaylorBarResult:
    """Run the Taylor bar impact on one axisymmetric mesh (see the module docstring).

    Parameters
    ----------
    model : {"mono"}
        One finite-strain mesh over the whole bar (the Arlequin variant comes next).
    elements_radial : int, optional
        Cells across the radius (default 10); or ``mesh_size`` (m), the cell edge across the
        radius (then elements_radial = round(R / mesh_size)). The axial count is round(L / h).
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
    if model != "mono":
        raise ValueError(f"model must be 'mono' (one mesh over the whole bar), got {model!r}")
    for name, value in [("t_end", t_end), ("velocity", velocity), ("length", length),
                        ("radius", radius), ("sample_interval", sample_interval),
                        ("frame_interval", frame_interval)]:  # fmt: skip
        _positive(name, value)
    n_r = _elements_radial(elements_radial, mesh_size, radius)
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
    mesh = taylor_bar_mesh(length, radius, n_r)
    n_z = mesh.t.shape[1] // n_r
    config = {
        "model": model, "elements_radial": n_r, "elements_axial": n_z, "mesh_size": radius / n_r,
        "t_end": t_end, "velocity": velocity, "young": young, "poisson": poisson,
        "density": density, "yield_stress": yield_stress, "hardening": hardening,
        "hardening_law": hardening_law, "length": length, "radius": radius,
        "bulk_viscosity": bool(visc), "fbar": bool(fbar), "backend": backend, "safety": safety,
        "estimate_every": int(estimate_every), "sample_interval": sample_interval,
        "frame_interval": frame_interval,
        **{k: v for k, v in law_parameters.items() if v is not None},
    }  # fmt: skip
    if visc:
        config.update(bulk_viscosity_linear=visc.linear, bulk_viscosity_quadratic=visc.quadratic)
    bar = FiniteStrainJ2(mesh, material, "axisymmetric", fbar, backend=backend,
                         bulk_viscosity=visc)  # fmt: skip
    if bar.backend == "numba":
        from ..models.j2_kernel import warm_up

        warm_up()  # compile (or load) the kernel before the clock starts
    dofs = bar.nodal_dofs()
    p = mesh.p
    tol = 1e-9 * radius
    axis = np.nonzero(p[0] < tol)[0]
    rows = sp.csr_matrix((np.ones(axis.size), (np.arange(axis.size), dofs[0, axis])),
                         shape=(axis.size, bar.n_dofs))  # fmt: skip
    system = CoupledSystem(
        [Block("bar", bar, [BlockTerm(bar)])],
        [LinearConstraint(rows, None, name="axis", kind="dirichlet")],
    )
    # the impact face and the lower part of the lateral surface (it folds onto the wall)
    lateral = 0.3 * length

    def on_wall_side(x):
        return (x[1] < tol) | ((x[0] > radius - tol) & (x[1] < lateral))

    surface = ContactSurface(mesh, where=on_wall_side, offset=system.dofmap["bar"],
                             axisymmetric=True)  # fmt: skip
    wall = PlaneObstacle(np.zeros(2), np.array([0.0, 1.0]))
    con = LevelSetContact(RigidContactPair(surface, wall, system.dofmap), material=material.elastic,
                          name="wall")  # fmt: skip
    v0 = np.zeros(bar.n_dofs)
    v0[dofs[1]] = -velocity
    m_lumped = bar.mass(lumped=True)
    ke0 = 0.5 * float(v0 @ (m_lumped * v0))
    axis_top = int(np.nonzero((p[0] < tol) & (p[1] > length - tol))[0][0])
    face = np.nonzero(p[1] < tol)[0]
    frames = np.arange(0.0, t_end * (1 + 1e-12), frame_interval)
    # every input checked: the results folder opens (results.json with the inputs, "running")
    folder = None
    if out is not None:
        folder = ResultsFolder(out, "arlequin taylor-bar", config, _INPUT_UNITS)
    rec = TaylorRecorder(bar, con.name, surface.weights, axis_top, face, ke0, folder, frames,
                         progress)  # fmt: skip
    n_samples = max(1, round(t_end / sample_interval))
    t_eval = np.linspace(0.0, t_end, n_samples + 1)[1:]
    logger.info("Taylor bar: %d x %d cells, %s backend", n_r, n_z, bar.backend)
    start = time.perf_counter()
    try:
        res = solve(system, "explicit", t_end=t_end, v0=v0, constraints=[con],
                    step_controller=controller, t_eval=t_eval, on_record=[rec])  # fmt: skip
    except Exception as exc:
        if folder is not None:
            folder.finish("failed", str(exc))
        raise
    end = time.perf_counter()
    wall_time = end - start
    loop_time = end - (rec.loop_start if rec.loop_start is not None else start)
    u, state = res.u, res.states["bar"][0]
    ip = int(np.argmax(state.eqps))
    xq = bar.quadrature_points().reshape(2, -1)[:, ip]
    steps = np.asarray(res.step_sizes if res.step_sizes is not None else [res.dt])
    n_qp = state.eqps.size
    hist = rec.history
    result = TaylorBarResult(
        final_length=hist["length"][-1],
        mushroom_radius=hist["radius"][-1],
        max_plastic_strain=float(state.eqps.max()),
        energy_balance_error=float(max(rec.balance)),
        n_elements=int(mesh.t.shape[1]),
        mesh_size=radius / n_r,
        n_steps=int(res.n_steps),
        wall_time_s=wall_time,
        history=hist,
        elements_radial=n_r,
        elements_axial=n_z,
        max_plastic_strain_at=[float(xq[0]), float(xq[1])],
        initial_kinetic_energy=ke0,
        impact_loss=hist["contact_work"][0],
        min_dt=float(steps[steps > 0].min()) if np.any(steps > 0) else float(res.dt),
        qp_updates_per_second=n_qp * res.n_steps / loop_time,
        setup_time_s=wall_time - loop_time,
        config=config,
        model=bar,
        u=u,
        state=state,
    )
    if folder is not None:
        write_results(folder, result, _RESULT_UNITS)
    logger.info(result.summary())
    return result
