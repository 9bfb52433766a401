"""1D elastic wave through an Arlequin overlap: reflected and transmitted energy.

Set-up (lengths in coarse elements h, all SI: h = 1 cm, E = 200 GPa, ρ = 7800 kg/m³, A = 1 cm²,
so c = √(E/ρ) ≈ 5064 m/s):

::

    0      a            a+W     X_p        X_p+G                                   L
    |------[== pulse ==>]-------|~~ band ~~|---------- patch free zone ----------|
    coarse everywhere;          refined patch on [X_p, L], gluing band [X_p, X_p+G]

with a = max(5, G), X_p = a + W + 5 and L = X_p + W + G + 15. The pulse is the right-going wave
u(x, 0) = A₀ sin⁴(π (x − a)/W) on [a, a + W], v(x, 0) = −c ∂u/∂x, on the coarse model only (the
patch starts at rest: the initial condition is coupling-consistent).

Reflection is measured so that numerical dispersion is not counted: the reflected wave is the
difference, in the coarse-only region [0, X_p], between the coupled coarse solution and a single
coarse-mesh run of the same pulse with the same integrator and time step, taken at the snapshot
time t_m = (W + G + 10) h / c, when the pulse's tail (moving at most at c) has cleared the gluing
band by 5 h, while the transmitted pulse is still 10 h short of the far end (nothing reflected from
it can have returned). Its energy (kinetic with the integrator's mass, plus strain, on the coarse
elements of [0, X_p]) over the incident energy (the pulse's initial energy) is the reflected
fraction. The transmitted fraction is the α-weighted energy of both models in the patch's free
zone [X_p + G, L] at t_m over the incident energy. The energy drift is max_t |E(t) − E(0)|/E(0)
of the coupled run (E the α-weighted kinetic plus strain energy).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import skfem

from ..io import DynamicRunWriter, JsonResult, ResultsFolder
from ..models import IsotropicElastic, LinearElastic
from ..problem.arlequin_problem import ArlequinProblem, Patch
from ..problem.system import Block, BlockTerm, CoupledSystem
from ..solvers import (
    DEFAULT_SAFETY,
    CentralDifference,
    check_time_step,
    get_integrator,
    solve,
    stable_time_step,
)
from ..solvers.controllers import check_step
from .plots import plot_wave

__all__ = ["INTEGRATORS", "WaveResult", "plot_wave", "run_wave", "wave_layout"]

logger = logging.getLogger(__name__)

#: CLI integrator names -> registry names
INTEGRATORS = {"explicit": "explicit", "implicit": "newmark"}

H = 0.01  # coarse element size (m)
YOUNG = 200e9  # Pa
DENSITY = 7800.0  # kg/m³
AREA = 1e-4  # m²
AMPLITUDE = 1e-6  # m


@dataclass
class WaveResult(JsonResult):
    """Result of :func:`run_wave` (fractions are dimensionless, dt in s).

    ``to_json()`` gives the five keys of the CLI's JSON output.
    """

    reflected_energy_fraction: float
    transmitted_energy_fraction: float
    energy_drift: float
    dt: float
    n_steps: int
    incident_energy: float = 0.0
    config: dict = field(default_factory=dict)
    multiplier_max: float = 0.0
    coupling_work_max: float = 0.0
    fields: dict = field(default_factory=dict, repr=False)
    dynamic: Any = field(default=None, repr=False)

    json_keys = (
        "reflected_energy_fraction",
        "transmitted_energy_fraction",
        "energy_drift",
        "dt",
        "n_steps",
    )

    def summary(self) -> str:
        """One line: the reflected and transmitted energy fractions."""
        c = self.config
        return (
            f"wave ratio {c.get('ratio')} W={c.get('pulse_width')} G={c.get('gluing_width')} "
            f"{c.get('coupling')} {c.get('mediator')} mediator {c.get('weights')} weights "
            f"{c.get('integrator')}: reflected {self.reflected_energy_fraction:.3e}, transmitted "
            f"{self.transmitted_energy_fraction:.6f}, drift {self.energy_drift:.3e}, "
            f"dt {self.dt:.4e} s, {self.n_steps} steps"
        )


def wave_layout(pulse_width: float, gluing_width: float) -> dict[str, float]:
    """Positions in coarse elements: a (pulse start), x_patch, band end, length, travel."""
    w, g = float(pulse_width), float(gluing_width)
    a = max(5.0, math.ceil(g))
    x_patch = a + math.ceil(w) + 5.0
    length = x_patch + math.ceil(w) + math.ceil(g) + 15.0
    return {
        "a": a,
        "x_patch": x_patch,
        "band_end": x_patch + g,
        "length": length,
        "travel": w + g + 10.0,
    }


def _pulse(x: np.ndarray, a: float, w: float) -> tuple[np.ndarray, np.ndarray]:
    s = np.clip((x - a) / w, 0.0, 1.0)
    u = np.sin(np.pi * s) ** 4
    du = 4.0 * np.sin(np.pi * s) ** 3 * np.cos(np.pi * s) * np.pi / w
    return u, du


def _region_energy(
    model: LinearElastic,
    weight: float,
    cells: np.ndarray,
    u: np.ndarray,
    v: np.ndarray,
    lumped: bool,
) -> float:
    """Energy (J) of the given cells of a 1D model (weight constant there)."""
    sub = LinearElastic(
        skfem.MeshLine(np.sort(model.mesh.p[0, np.unique(model.mesh.t[:, cells])])),
        model.material,
        area=model.area,
    )
    nodes = np.unique(model.mesh.t[:, cells])
    order = np.argsort(model.mesh.p[0, nodes])
    nodes = nodes[order]
    us, vs = u[nodes], v[nodes]
    k = sub.stiffness(weight)
    m = sub.mass(weight, lumped=lumped)
    kin = 0.5 * float(vs @ (m * vs if lumped else m @ vs))
    return kin + 0.5 * float(us @ (k @ us))


def run_wave(
    ratio: int = 4,
    pulse_width: float = 10,
    gluing_width: float = 10,
    coupling: str = "H1",
    mediator: str = "coarse",
    weights: str = "ramp",
    integrator: str = "explicit",
    dt: float | None = None,
    epsilon: float = 1e-3,
    length: float | None = None,
    out: str | Path | None = None,
    progress: Callable[[float], None] | None = None,
    check_only: bool = False,
) -> WaveResult | None:
    """Run the 1D wave demo (see the module docstring).

    Parameters
    ----------
    ratio : int
        Coarse/fine element size ratio (1 = identical meshes).
    pulse_width, gluing_width : float
        Pulse support and gluing band widths, in coarse elements (the band is snapped to fine
        cells by the problem).
    coupling : {"L2", "H1"}
    mediator : {"coarse", "fine"}
    weights : {"ramp", "constant"}
    integrator : {"explicit", "implicit"} or a registry name
        ``"implicit"`` is the trapezoidal Newmark scheme (β = ¼, γ = ½, consistent mass).
    dt : float, optional
        Time step (s); default: the default step of the explicit scheme on the coupled system
        (0.9 × its critical step), for both integrators.
    epsilon : float
        Floor of α_coarse in the patch's free zone.
    length : float, optional
        H1 coupling length ℓ in coarse elements; default: the problem's default (the mean
        coarse cell size on the gluing band, i.e. one coarse element here).
    out : path, optional
        Results folder to write (:class:`arlequin.io.ResultsFolder`): results.json,
        history.csv of the coupled run (energies and works per model, every step), its field
        series (51 frames: displacement, velocity, alpha, the multiplier field) and wave.png.
        The result then keeps the coupled run's :class:`~arlequin.solvers.DynamicResult`
        with its fields (``result.dynamic``).
    progress : callable, optional
        ``progress(fraction)`` with the fraction of the coupled run's steps done, about 200
        times over the run (the CLI's progress bar).
    check_only : bool
        Check every input and return None without running or writing anything.

    Returns
    -------
    WaveResult
    """
    ratio = int(ratio)
    if ratio < 1:
        raise ValueError(f"mesh ratio must be a positive integer, got ratio={ratio}")
    if not pulse_width > 0 or not gluing_width > 0:
        raise ValueError(
            f"pulse and gluing widths must be positive, got pulse_width={pulse_width}, "
            f"gluing_width={gluing_width}"
        )
    name = INTEGRATORS.get(integrator, integrator)
    cls = get_integrator(name)
    if dt is not None:
        dt = check_step(dt, "time step dt (s)")
    for what, value in (("pulse_width", pulse_width), ("gluing_width", gluing_width),
                        ("epsilon", epsilon)):  # fmt: skip
        if not math.isfinite(float(value)):
            raise ValueError(f"{what} must be finite, got {what}={value}")
    inputs = {"ratio": ratio, "pulse_width": pulse_width, "gluing_width": gluing_width,
              "coupling": coupling, "mediator": mediator, "weights": weights,
              "integrator": integrator, "dt": dt, "epsilon": epsilon, "length": length}  # fmt: skip
    units = {"ratio": "1", "pulse_width": "coarse elements", "gluing_width": "coarse elements",
             "dt": "s", "epsilon": "1", "length": "coarse elements"}  # fmt: skip
    if check_only:  # every input checked: nothing run, nothing written
        return None
    folder = ResultsFolder(out, "arlequin wave", inputs, units) if out is not None else None
    lay = wave_layout(pulse_width, gluing_width)
    n_c = round(lay["length"])
    n_patch = round(lay["length"] - lay["x_patch"])
    mat = IsotropicElastic(YOUNG, 0.0, DENSITY)
    c = math.sqrt(YOUNG / DENSITY)
    coarse_mesh = skfem.MeshLine(np.linspace(0.0, n_c * H, n_c + 1))
    fine_mesh = skfem.MeshLine(np.linspace(lay["x_patch"] * H, n_c * H, n_patch * ratio + 1))
    cm = LinearElastic(coarse_mesh, mat, area=AREA)
    fm = LinearElastic(fine_mesh, mat, area=AREA)
    patch = Patch(
        fm,
        gluing_width=gluing_width * H,
        weights=weights,
        coupling=coupling,
        mediator=mediator,
        epsilon=epsilon,
        length=None if length is None else float(length) * H,
    )
    problem = ArlequinProblem(cm, [patch])
    system = problem.system()
    xc = coarse_mesh.p[0]
    f, df = _pulse(xc / H, lay["a"], float(pulse_width))
    u0c = AMPLITUDE * f
    v0c = -c * AMPLITUDE * df / H
    u0 = {"coarse": u0c, "patch0": np.zeros(fm.n_dofs)}
    v0 = {"coarse": v0c, "patch0": np.zeros(fm.n_dofs)}
    stable = stable_time_step(system)
    if dt is None:
        dt = DEFAULT_SAFETY * stable.critical
    elif issubclass(cls, CentralDifference):
        check_time_step(dt, stable)  # implicit schemes are unconditionally stable here
    t_m = lay["travel"] * H / c
    n_steps = math.ceil(t_m / dt)
    lumped = bool(cls.lumped_default)
    opts = {"check_dt": False} if issubclass(cls, CentralDifference) else {}
    writers = []
    if folder is not None:
        frames = np.linspace(0.0, n_steps * dt, 51)
        writers.append(DynamicRunWriter(folder, system, problem.field_layout(), frames))
    if progress is not None:
        every = max(1, n_steps // 200)

        def report(integ, every=every, n=n_steps) -> None:
            if integ.step_count % every == 0 or integ.step_count == n:
                progress(integ.step_count / n)

        writers.append(report)
    res = solve(system, name, n_steps=n_steps, dt=dt, u0=u0, v0=v0, on_record=writers,
                save_fields=folder is not None, **opts)  # fmt: skip
    # reference: the coarse model alone, same pulse, integrator and dt
    ref_system = CoupledSystem([Block("coarse", cm, [BlockTerm(cm)])])
    ref = solve(
        ref_system,
        name,
        n_steps=n_steps,
        dt=dt,
        u0={"coarse": u0c},
        v0={"coarse": v0c},
        record_every=n_steps,
        **opts,
    )
    split = system.split(res.u)
    split_v = system.split(res.v)
    du = split["coarse"] - ref.u
    dv = split_v["coarse"] - ref.v
    centers = coarse_mesh.p[0, coarse_mesh.t].mean(axis=0) / H
    only = np.nonzero(centers < lay["x_patch"])[0]
    reflected = _region_energy(cm, 1.0, only, du, dv, lumped)
    e0 = float(res.total_energy[0])
    # transmitted: α-weighted energy of both models in the free zone
    band_end = problem.couplings[0].gluing_width / H + lay["x_patch"]
    free_c = np.nonzero(centers > band_end)[0]
    fcent = fine_mesh.p[0, fine_mesh.t].mean(axis=0) / H
    free_f = np.nonzero(fcent > band_end)[0]
    transmitted = _region_energy(cm, epsilon, free_c, split["coarse"], split_v["coarse"], lumped)
    transmitted += _region_energy(
        fm, 1.0 - epsilon, free_f, split["patch0"], split_v["patch0"], lumped
    )
    mult = [np.max(np.abs(m)) for k, m in res.multipliers.items() if k.startswith("coupling")]
    config = {
        "ratio": ratio,
        "pulse_width": pulse_width,
        "gluing_width": gluing_width,
        "coupling": coupling,
        "mediator": mediator,
        "weights": weights,
        "integrator": integrator,
        "epsilon": epsilon,
        "snapshot_time": n_steps * dt,
        "length": length,
    }
    fields = {
        "x_coarse": xc,
        "u_coarse": split["coarse"],
        "u_reference": ref.u,
        "u0_coarse": u0c,
        "x_fine": fine_mesh.p[0],
        "u_fine": split["patch0"],
        "x_patch": lay["x_patch"] * H,
        "band_end": band_end * H,
        "times": res.times,
        "energy": res.total_energy,
    }
    out = WaveResult(
        reflected_energy_fraction=reflected / e0,
        transmitted_energy_fraction=transmitted / e0,
        energy_drift=res.energy_drift(),
        dt=float(dt),
        n_steps=n_steps,
        incident_energy=e0,
        config=config,
        multiplier_max=float(max(mult)) if mult else 0.0,
        coupling_work_max=float(np.max(np.abs(res.coupling_work["coarse"]))),
        fields=fields,
        dynamic=res if folder is not None else None,
    )
    logger.info(out.summary())
    if folder is not None:
        folder.add_results(
            {**out.to_json(), "incident_energy": e0, "multiplier_max": out.multiplier_max,
             "coupling_work_max": out.coupling_work_max},
            {"reflected_energy_fraction": "1", "transmitted_energy_fraction": "1",
             "energy_drift": "1", "dt": "s", "n_steps": "1", "incident_energy": "J",
             "multiplier_max": "N/m", "coupling_work_max": "J"},
        )  # fmt: skip
        plot_wave(out, str(folder.picture("wave")))
        folder.finish()
    return out
