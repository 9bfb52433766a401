"""The sliding block: an elastic block on a rigid plane with Coulomb friction.

``arlequin sliding-block`` runs it.

A block of height H (the last axis is vertical, the plane is z = 0 in 3D, y = 0 in 2D plane
strain) lies on a rigid plane; the level-set contact with Coulomb friction μ
(:class:`arlequin.models.CoulombContact`) acts at the nodes of its bottom face. Two loadings:

``pressure`` (default)
    a uniform normal pressure p on the top face. The block starts from the exact static state
    under p (the uniform stress σ_zz = −p, laterally free: the discrete solution of the
    bilinear elements too) and is launched at t = 0 with v0 along x. Exact, for the mean
    velocity (momentum / mass): v̄(t) = v0 − a t with a = μ p / (ρ H), stop at t = v0/a; then
    the block sticks (it may keep vibrating elastically).
``gravity``
    a body force ρ g (sin θ, −cos θ) on an incline θ (``incline``, degrees; x downslope),
    ramped from the block at rest on the plane over ``ramp_time`` (smooth step; default
    :data:`RAMP_TRANSITS` H/c_d), times counted from the end of the ramp. Exact after the
    ramp: the block sticks for tan θ < μ and slides with the acceleration g (sin θ − μ cos θ)
    for tan θ > μ. A launch (``velocity``) is given with the pressure loading only.

The sudden onset of friction at the launch sends shear waves of traction amplitude μp through
the block; their velocity amplitude relative to v0 is r = μp/(ρ c_s v0), which sets how far the
mean velocity wanders from the straight line, so the default pressure keeps r ≈ 1.2e-3.

Those waves, and the stop's, make an undamped block vibrate in shear for ever, its base traction
reaching the Coulomb limit at the contact's edges: the corners slip by turns (up to 9.7e-4 v0,
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

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import skfem

from ...io import DynamicRunWriter, JsonResult, ResultsFolder
from ...models import (
    ContactSurface,
    CoulombContact,
    IsotropicElastic,
    LevelSetContact,
    LinearElastic,
    PlaneObstacle,
    RigidContactPair,
)
from ...problem.system import Block, BlockTerm, CoupledSystem
from ...solvers import RayleighDamping, SmoothStep, solve

__all__ = ["DAMPING", "JSON_KEYS", "RAMP_TRANSITS", "SlidingBlockResult", "run_sliding_block"]

logger = logging.getLogger(__name__)

#: Ratio of the time step to the critical step of the block. Friction feeds the normal force
#: into the tangential one (a non-symmetric coupling) and lowers the stable step: measured on the
#: 3D block (μ = 0.3, 4 cells across), 0.9 diverges after about 1 ms when the steps vary to land
#: on the output times, 0.72 and 0.45 stay stable.
SAFETY = 0.6

#: Default damping ratio at the block's first shear mode (module docstring): 0.5%, the order of
#: a steel part's material damping; measured, 0.5% and 2% both end the edge slip within
#: 0.1 × the stop time after the stop, and the deceleration is unchanged (−6e-6 vs −4e-6).
DAMPING = 0.005

#: Default duration of the gravity ramp, in transit times H/c_d: a quasi-static ramp (about 40
#: shear periods). A ramp of 20 H/c_d (under 3 shear periods) leaves shear vibrations faster
#: than the slow sliding near tan θ = μ, so the base sticks by turns and the block slides faster
#: than the rigid one: measured at atan μ + 0.5° over 1 ms, +15% (20 H/c_d), +5.7% (100),
#: +0.53% (300).
RAMP_TRANSITS = 300.0

#: The block has stopped when its time-averaged mean velocity falls below this fraction of v0.
STOP_FRACTION = 1e-3

#: The keys of the Interface, in order (then the inputs and the other results).
JSON_KEYS = ("t", "mean_velocity", "friction_work", "contact_work", "total_energy", "stop_time",
             "sliding_distance", "fixed_point_iterations")  # fmt: skip

_UNITS = {"friction": "1", "velocity": "m/s", "incline": "deg", "pressure": "Pa",
          "gravity": "m/s^2", "elements": "1", "t_end": "s", "young": "Pa", "poisson": "1",
          "density": "kg/m^3", "height": "m", "width": "m", "dim": "1",
          "damping": "1", "ramp_time": "s"}  # fmt: skip
_RESULT_UNITS = {"stop_time": "s", "sliding_distance": "m", "acceleration": "m/s^2",
                 "expected_acceleration": "m/s^2", "energy_balance_error": "1",
                 "max_slip_after_stop": "m/s", "ramp_time": "s", "wall_time_s": "s",
                 "expected_stop_time": "s", "negative_dissipation_steps": "1",
                 "slipping_steps_after_stop": "1"}  # fmt: skip


@dataclass
class SlidingBlockResult(JsonResult):
    """What a sliding-block run computed (SI units; times counted from the launch or the end of
    the load ramp).

    Attributes
    ----------
    t : list of float
        Record times (s), one per step (decimated to at most 2000 in the JSON).
    mean_velocity : list of float
        Mean velocity along x (m/s): the block's momentum over its mass.
    friction_work, contact_work : list of float
        Works (J) of the tangential and normal contact multipliers since the start (≤ 0: minus
        the energy they removed).
    total_energy : list of float
        Kinetic + strain energy − the work of the loads since the start (J); with the works
        above and ``damping_work``, constant up to the scheme's energy error.
    stop_time : float or None
        When the time-averaged mean velocity (over one shear period 4H/c_s) falls below
        :data:`STOP_FRACTION` v0 (s).
    sliding_distance : float
        Mean displacement along x of the contact nodes at the end, from the start (m).
    fixed_point_iterations : dict
        Fixed-point iterations per step: ``mean``, ``max`` and ``counts`` (iterations -> steps).
    acceleration, expected_acceleration : float
        Fitted mean acceleration along x (m/s², a straight line through the sliding phase) and
        the exact one.
    energy_balance_error : float
        ``max |E + D_f + W_c + D_d − W_ext − E(0)|`` over the run, against the largest energy
        (1), D_d the energy the damping dissipated.
    max_slip_after_stop : float or None
        Largest slip velocity (m/s) of a contact node after 1.1 × the exact stop time.
    slipping_steps_after_stop : float or None
        Fraction of the steps after 1.1 × the exact stop time in which a contact node slips
        faster than 1e-6 v0.
    negative_dissipation_steps : int
        Steps whose friction work increment is positive beyond round-off (1e-12 of the
        largest energy; a sticking point's work is zero to round-off, of either sign).
    damping_work : list of float
        Work of the damping forces since the start (J, ≤ 0), one per record.
    """

    t: list[float]
    mean_velocity: list[float]
    friction_work: list[float]
    contact_work: list[float]
    total_energy: list[float]
    stop_time: float | None
    sliding_distance: float
    fixed_point_iterations: dict[str, Any]
    acceleration: float
    expected_acceleration: float
    expected_stop_time: float | None
    energy_balance_error: float
    max_slip_after_stop: float | None
    slipping_steps_after_stop: float | None
    negative_dissipation_steps: int
    ramp_time: float
    n_steps: int
    wall_time_s: float
    config: dict[str, Any] = field(default_factory=dict)
    damping_work: list[float] = field(default_factory=list)
    slip_velocity: np.ndarray | None = None

    json_exclude = ("slip_velocity",)

    def to_json(self) -> dict[str, Any]:
        """The Interface's keys first (histories decimated to ≤ 2000 points), then the rest."""
        data = super().to_json()
        step = max(1, math.ceil(len(self.t) / 2000))
        for k in (
            "t",
            "mean_velocity",
            "friction_work",
            "contact_work",
            "total_energy",
            "damping_work",
        ):
            data[k] = data[k][::step]
        config = data.pop("config")
        ordered = {k: data.pop(k) for k in JSON_KEYS}
        return {**ordered, **config, **data}

    def summary(self) -> str:
        """One line: acceleration, stop time, energy error, iterations."""
        if self.config.get("gravity") is not None:
            moved = abs(self.sliding_distance) > 1e-6 * float(self.config.get("width", 0.02))
            return (f"sliding block on a {self.config.get('incline')}° incline: it "
                    f"{'slides' if moved else 'sticks'} (sliding distance "
                    f"{self.sliding_distance:.3e} m), acceleration {self.acceleration:.6e} m/s^2 "
                    f"(exact {self.expected_acceleration:.6e}), energy balance "
                    f"{self.energy_balance_error:.2e}, fixed point "
                    f"{self.fixed_point_iterations['mean']:.2f} iterations per step")  # fmt: skip
        stop = "none" if self.stop_time is None else f"{self.stop_time:.6e} s"
        exp = "" if self.expected_stop_time is None else f" (exact {self.expected_stop_time:.6e})"
        return (f"sliding block: acceleration {self.acceleration:.6e} m/s^2 (exact "
                f"{self.expected_acceleration:.6e}), stop {stop}{exp}, sliding distance "
                f"{self.sliding_distance:.3e} m, energy balance {self.energy_balance_error:.2e}, "
                f"fixed point {self.fixed_point_iterations['mean']:.2f} iterations per step "
                f"(max {self.fixed_point_iterations['max']}), damping ratio "
                f"{self.config.get('damping')}" + (f"; the base still slips after the stop in "
                f"{100 * self.slipping_steps_after_stop:.0f}% of the steps" if
                self.slipping_steps_after_stop else ""))  # fmt: skip


def _check(dim, friction, velocity, incline, pressure, gravity, elements, t_end, young, poisson,
           density, height, width, damping) -> None:  # fmt: skip
    if dim not in (2, 3):
        raise ValueError(f"dim must be 2 or 3, got dim={dim!r}")
    if not (math.isfinite(damping) and 0.0 <= damping < 1.0):
        raise ValueError(f"damping must be a ratio in [0, 1), got damping={damping}")
    for name, value in (("young", young), ("density", density), ("height", height),
                        ("width", width)):  # fmt: skip
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"{name} must be positive and finite, got {name}={value}")
    if not (math.isfinite(friction) and friction >= 0.0):
        raise ValueError(f"friction must be a non-negative number, got friction={friction}")
    if not (-1.0 < poisson < 0.5):
        raise ValueError(f"poisson must lie in (-1, 0.5), got poisson={poisson}")
    if int(elements) != elements or elements < 1:
        raise ValueError(f"elements must be a positive integer, got elements={elements}")
    if not math.isfinite(velocity) or velocity < 0.0:
        raise ValueError(f"velocity must be a non-negative number (m/s), got {velocity}")
    if not (math.isfinite(incline) and 0.0 <= incline < 90.0):
        raise ValueError(f"incline must lie in [0, 90) degrees, got incline={incline}")
    if pressure is not None and gravity is not None:
        raise ValueError("give one of pressure and gravity, got both")
    if gravity is None:
        if incline:
            raise ValueError(f"incline={incline} needs the gravity loading (give gravity)")
        if not (math.isfinite(pressure) and pressure > 0.0):
            raise ValueError(f"pressure must be positive (Pa), got pressure={pressure}")
        if not velocity > 0.0:
            raise ValueError(f"the pressure loading launches the block: velocity must be > 0, "
                             f"got velocity={velocity}")  # fmt: skip
    else:
        if not (math.isfinite(gravity) and gravity > 0.0):
            raise ValueError(f"gravity must be positive (m/s^2), got gravity={gravity}")
        if velocity:
            raise ValueError(f"a launch (velocity={velocity}) is given with the pressure "
                             f"loading only; under gravity the block starts at rest")  # fmt: skip
    if t_end is not None and not (math.isfinite(t_end) and t_end > 0.0):
        raise ValueError(f"t_end must be positive (s), got t_end={t_end}")


def run_sliding_block(
    dim: int = 2,
    friction: float = 0.3,
    velocity: float = 1.0,
    incline: float = 0.0,
    pressure: float | None = None,
    gravity: float | None = None,
    elements: int = 4,
    t_end: float | None = None,
    damping: float = DAMPING,
    ramp_time: float | None = None,
    young: float = 210e9,
    poisson: float = 0.3,
    density: float = 7850.0,
    height: float = 0.01,
    width: float = 0.02,
    out: str | Path | None = None,
    progress: Callable[[float], None] | None = None,
    check_only: bool = False,
) -> SlidingBlockResult | None:
    """Run the sliding block (see the module docstring).

    Parameters
    ----------
    dim : {2, 3}
        Plane strain (Q1) or 3D (Q1 hexahedra, a square base width × width).
    friction : float
        Coulomb coefficient μ (0: the frictionless model, no tangential rows).
    velocity : float
        Launch velocity v0 along x (m/s), pressure loading.
    incline : float
        Incline θ of the plane (degrees), gravity loading.
    pressure, gravity : float, optional
        The loading: a top pressure p (Pa; default 1e5 Pa when neither is given) or gravity g
        (m/s²).
    elements : int
        Elements across the height (2 × as many along the width).
    t_end : float, optional
        Simulated time after the launch or the ramp (s); default 1.3 × the exact stop time, or
        200 H/c_d under gravity.
    damping : float
        Damping ratio ξ₁ at the first shear mode (module docstring; 0: undamped).
    ramp_time : float, optional
        Duration of the gravity ramp (s); default :data:`RAMP_TRANSITS` H/c_d.
    young, poisson, density : float
        E (Pa), ν, ρ (kg/m³).
    height, width : float
        H and the base width (m).
    out : path, optional
        Results folder (see the module docstring).
    progress : callable, optional
        ``progress(fraction)`` of the simulated time, at each new percent.
    check_only : bool
        Check every input and return None without running or writing anything.

    Returns
    -------
    SlidingBlockResult
    """
    if pressure is None and gravity is None:
        pressure = 1.0e5
    _check(dim, friction, velocity, incline, pressure, gravity, elements, t_end, young, poisson,
           density, height, width, damping)  # fmt: skip
    if ramp_time is not None and not (math.isfinite(ramp_time) and ramp_time > 0.0):
        raise ValueError(f"ramp_time must be positive (s), got ramp_time={ramp_time}")
    if ramp_time is not None and gravity is None:
        raise ValueError("ramp_time is the gravity ramp's: give gravity")
    if check_only:
        return None
    n = int(elements)
    config = {"dim": dim, "friction": friction, "velocity": velocity, "incline": incline,
              "pressure": pressure, "gravity": gravity, "elements": n, "t_end": t_end,
              "young": young, "poisson": poisson, "density": density, "height": height,
              "width": width, "damping": damping, "ramp_time": ramp_time}  # fmt: skip
    folder = ResultsFolder(out, "arlequin sliding-block", config, _UNITS) if out else None
    mat = IsotropicElastic(young, poisson, density)
    lat = np.linspace(0.0, width, 2 * n + 1)
    z = np.linspace(0.0, height, n + 1)
    if dim == 2:
        mesh = skfem.MeshQuad.init_tensor(lat, z)
        model = LinearElastic(mesh, mat, kind="plane_strain")
    else:
        mesh = skfem.MeshHex.init_tensor(lat, lat, z)
        model = LinearElastic(mesh, mat, kind="3d")
    lam_l = young * poisson / ((1 + poisson) * (1 - 2 * poisson))
    mu_l = young / (2 * (1 + poisson))
    c_d = math.sqrt((lam_l + 2 * mu_l) / density)
    c_s = math.sqrt(mu_l / density)
    rayleigh = (RayleighDamping.from_ratio(damping, 0.5 * math.pi * c_s / height) if damping
                else None)  # fmt: skip
    x = mesh.p
    n_dofs = model.n_dofs
    u0 = np.zeros(n_dofs)
    v0 = np.zeros(n_dofs)
    ramp = 0.0
    if gravity is None:
        top = mesh.facets_satisfying(lambda p: np.isclose(p[-1], height), boundaries_only=True)
        traction = np.zeros(dim)
        traction[-1] = -pressure
        f_top = model.traction_vector(top, traction)

        def load(t: float) -> np.ndarray:
            return f_top

        # the exact static state under p, laterally free (uniform stress σ_zz = −p)
        if dim == 2:
            e_zz = -pressure * (1 - poisson**2) / young
            e_lat = pressure * poisson * (1 + poisson) / young
        else:
            e_zz, e_lat = -pressure / young, pressure * poisson / young
        for k in range(dim - 1):
            u0[k::dim] = e_lat * (x[k] - 0.5 * width)
        u0[dim - 1 :: dim] = e_zz * x[-1]
        v0[0::dim] = velocity
        a_exact = -friction * pressure / (density * height)
        t_stop = velocity / -a_exact if friction > 0 else None
        t_run = 1.3 * t_stop if t_end is None and t_stop else (t_end or 200 * height / c_d)
    else:
        th = math.radians(incline)
        g_vec = np.zeros(dim)
        g_vec[0], g_vec[-1] = gravity * math.sin(th), -gravity * math.cos(th)
        f_g = model.body_force_vector(density * g_vec)
        ramp = RAMP_TRANSITS * height / c_d if ramp_time is None else float(ramp_time)
        smooth = SmoothStep(ramp)

        def load(t: float) -> np.ndarray:
            return smooth(t) * f_g

        slide = gravity * (math.sin(th) - friction * math.cos(th))
        a_exact = max(slide, 0.0)
        t_stop = None
        t_run = t_end if t_end is not None else 200.0 * height / c_d
    system = CoupledSystem([Block("block", model, [BlockTerm(model)])], load=load)
    dofmap = system.dofmap
    surf = ContactSurface(mesh, where=lambda p: p[-1] < 1e-9 * height, offset=dofmap["block"])
    normal = np.zeros(dim)
    normal[-1] = 1.0
    pair = RigidContactPair(surf, PlaneObstacle(np.zeros(dim), normal), dofmap)
    con = (CoulombContact(pair, friction, material=mat, name="plane") if friction > 0
           else LevelSetContact(pair, material=mat, name="plane"))  # fmt: skip
    mass = system.mass(lumped=True)
    mx = mass[0::dim]
    bottom_x = dim * surf.nodes
    t_total = ramp + t_run
    steps: dict[str, list] = {k: [] for k in ("t", "v", "slip", "fw", "cw", "e", "it", "ux", "dw")}
    last_pct = [-1]

    def on_step(integ) -> None:
        v = integ.v
        st = integ.constraint_states[con.name]
        e = integ.energies()
        steps["t"].append(integ.t - ramp)
        steps["v"].append(float(mx @ v[0::dim]) / float(mx.sum()))
        steps["slip"].append(float(np.abs(v[bottom_x]).max()))
        steps["fw"].append(float(getattr(st, "friction_work", 0.0)))
        steps["cw"].append(float(st.work))
        steps["dw"].append(sum(e["damping_work"].values()))
        steps["e"].append(sum(e["kinetic"].values()) + sum(e["strain"].values())
                          - sum(e["external_work"].values()))  # fmt: skip
        steps["it"].append(int(integ.status_iterations))
        steps["ux"].append(float(integ.u[bottom_x].mean()))
        if progress is not None:
            pct = int(100 * integ.t / t_total)
            if pct != last_pct[0]:
                last_pct[0] = pct
                progress(min(integ.t / t_total, 1.0))

    writers = []
    t_eval = np.linspace(0.0, t_total, 101)[1:]
    if folder is not None:
        writers.append(DynamicRunWriter(folder, system, frame_times=t_eval[::5]))
    tic = time.perf_counter()
    try:
        res = solve(system, "explicit", t_end=t_total, u0=u0, v0=v0, constraints=[con],
                    t_eval=t_eval, on_step=[on_step], on_record=writers,
                    safety=SAFETY, damping=rayleigh)  # fmt: skip
    except Exception as exc:
        if folder is not None:
            folder.finish("failed", str(exc))
        raise
    wall = time.perf_counter() - tic
    arr = {k: np.asarray(v) for k, v in steps.items()}
    t, vbar = arr["t"], arr["v"]
    after = t >= 0.0
    # the straight line through the sliding phase (10%–90% of the launch velocity, or the
    # whole run after the ramp)
    if gravity is None:
        sel = after & (vbar > 0.1 * velocity) & (vbar < 0.9 * velocity)
    else:
        sel = after
    accel = float(np.polyfit(t[sel], vbar[sel], 1)[0]) if sel.sum() > 2 else 0.0
    # time-averaged mean velocity over one shear period, centred
    period = 4.0 * height / c_s
    stop_time = None
    if gravity is None and t.size:
        dt_mean = float(np.mean(np.diff(t))) if t.size > 1 else float(t[0])
        win = max(1, round(period / dt_mean))
        avg = np.convolve(vbar, np.ones(win) / win, mode="valid")
        centre = t[win // 2 : win // 2 + avg.size]
        k = np.nonzero(avg <= STOP_FRACTION * velocity)[0]
        stop_time = float(centre[k[0]]) if k.size else None
    e_total = arr["e"] - arr["fw"] - arr["cw"] - arr["dw"]
    scale = max(float(np.abs(arr["e"]).max()), 1e-300)
    balance = float(np.abs(e_total - e_total[0]).max() / scale) if e_total.size else 0.0
    slip_after = slipping = None
    if t_stop is not None and np.any(t > 1.1 * t_stop):
        late = arr["slip"][t > 1.1 * t_stop]
        slip_after = float(late.max())
        slipping = float(np.mean(late > 1e-6 * velocity))
    its = arr["it"]
    values, counts = np.unique(its, return_counts=True)
    # a sticking point's work is 0 to round-off, of either sign: 1e-12 of the energy scale
    neg = int(np.sum(np.diff(arr["fw"]) > 1e-12 * scale)) if arr["fw"].size > 1 else 0
    k0 = int(np.searchsorted(t, 0.0))
    result = SlidingBlockResult(
        t=t.tolist(), mean_velocity=vbar.tolist(), friction_work=arr["fw"].tolist(),
        contact_work=arr["cw"].tolist(), total_energy=arr["e"].tolist(), stop_time=stop_time,
        sliding_distance=float(arr["ux"][-1] - (arr["ux"][k0] if gravity is not None else
                                                 float(u0[bottom_x].mean()))),
        fixed_point_iterations={"mean": float(its.mean()), "max": int(its.max()),
                                "counts": {int(a): int(b) for a, b in zip(values, counts)}},
        acceleration=accel, expected_acceleration=float(a_exact), expected_stop_time=t_stop,
        energy_balance_error=balance, max_slip_after_stop=slip_after,
        slipping_steps_after_stop=slipping,
        negative_dissipation_steps=neg, ramp_time=ramp, n_steps=int(res.n_steps),
        wall_time_s=wall, config=config, damping_work=arr["dw"].tolist(),
        slip_velocity=arr["slip"],
    )  # fmt: skip
    if folder is not None:
        _write(folder, result, arr)
    logger.info(result.summary())
    return result


def _write(folder: ResultsFolder, result: SlidingBlockResult, arr: dict) -> None:
    from ..plots import plot_sliding_block

    cols = ["t", "mean_velocity", "slip_velocity", "friction_work", "contact_work",
            "damping_work", "total_energy", "fixed_point_iterations"]  # fmt: skip
    units = {"t": "s", "mean_velocity": "m/s", "slip_velocity": "m/s", "friction_work": "J",
             "contact_work": "J", "damping_work": "J", "total_energy": "J",
             "fixed_point_iterations": "1"}  # fmt: skip
    hist = folder.history(cols, units, name="sliding")
    for i in range(arr["t"].size):
        hist.append({"t": arr["t"][i], "mean_velocity": arr["v"][i],
                     "slip_velocity": arr["slip"][i], "friction_work": arr["fw"][i],
                     "contact_work": arr["cw"][i], "damping_work": arr["dw"][i],
                     "total_energy": arr["e"][i],
                     "fixed_point_iterations": arr["it"][i]})  # fmt: skip
    data = result.to_json()
    keys = [k for k in _RESULT_UNITS if k in data] + ["fixed_point_iterations"]
    folder.add_results({k: data[k] for k in keys}, _RESULT_UNITS)
    plot_sliding_block(result, str(folder.picture("sliding_block")))
    folder.finish()
