"""What the ball-impact demo records at each step.

:class:`ImpactRecorder` is an ``on_step`` listener. At every step: the contact force (its peak
and the contact's end) and the contact radius. At every sample (:data:`SAMPLES` over the run,
and the last step): the integrator's energy balance and a history row (the contact force, the
ball's mean velocity, the energies: kinetic, elastic, plastic dissipation, contact and coupling
works; with an adaptive block patch, its share of the block's area), written to ``impact.csv``
as the run goes when a results folder is open. The energies cost a product with every linear
stiffness, and the J2 model's stored energy 3.6 of its internal-force evaluations (measured),
hence the samples. An adaptive run's rejected interval (``on_rewind``) drops the steps, samples
and ``impact.csv`` rows taken after the committed time. SI units.
"""

from __future__ import annotations

import numpy as np

from .result import HISTORY_KEYS, HISTORY_UNITS, BallImpactResult

__all__ = ["SAMPLES", "ImpactRecorder"]

#: History rows over the run (at least one per step when the run has fewer steps).
SAMPLES = 1000


class ImpactRecorder:
    """The per-step records of a ball-impact run (module docstring).

    Parameters
    ----------
    bodies : ImpactBodies
    folder : ResultsFolder or None
    t_end : float
        Simulated time (s), for the progress fraction.
    progress : callable, optional
        ``progress(fraction)`` at each new percent.
    adapt : BodyAdaptation, optional
        The adaptive block patch: each row gains its ``patch_fraction`` (its share of the
        block's coarse mesh's (r, z) area, as in the growths' records).
    """

    def __init__(self, bodies, folder, t_end: float, progress=None, adapt=None) -> None:
        self.bodies = bodies
        self.t_end = float(t_end)
        self.progress = progress
        self.adapt = adapt
        self.keys = HISTORY_KEYS + (("patch_fraction",) if adapt is not None else ())
        self.rows: dict[str, list[float]] = {k: [] for k in self.keys}
        self.times: list[float] = []  # every step's time and contact force
        self.forces: list[float] = []
        self._next = 0.0
        self.balance: list[float] = []
        self.scale = 0.0
        self.contact_radius = 0.0
        # the running maxima per step / per sample, so that a rejected interval's can be undone
        self._radii: list[float] = []
        self._scales: list[float] = []
        self._pct = -1
        self.csv = folder.history(list(self.keys), HISTORY_UNITS, name="impact") if folder \
            else None  # fmt: skip
        part = bodies.plastic_part()
        self._j2_block = None if part is None else part[1]
        self._e0: float | None = None
        # the outermost contact point: once it touches, the contact would spread beyond the
        # contact surfaces (the patches' zone inside their gluing bands) unseen
        self._edge = float(bodies.slave_r.max()) * (1.0 - 1e-9)
        self.macro_ratios: list[int] | None = None

    def __call__(self, integ) -> None:
        b = self.bodies
        self.macro_ratios = getattr(integ, "ratios", None)  # multi-time-step's m per macro step
        st = integ.constraint_states.get("contact")
        active = getattr(st, "active", None)
        if active is not None and np.any(active):
            self.contact_radius = max(self.contact_radius, float(b.slave_r[active].max()))
            if self.contact_radius >= self._edge:
                raise ValueError(
                    f"the contact reached the edge of the contact surfaces (radius "
                    f"{self.contact_radius:.4g} m, the outermost point, at t = {integ.t:.4g} s): "
                    f"the contact area would grow beyond them unseen (the bodies "
                    f"interpenetrating there); "
                    f"give a larger patch_size (now {b.sizes.reach:.4g} m: the zone is "
                    f"patch_size − 3 coarse cells) or a smaller coarse_size")  # fmt: skip
        force = b.contact_force(integ.multipliers)
        self.times.append(integ.t)
        self.forces.append(force)
        self._radii.append(self.contact_radius)
        if self.progress is not None:
            pct = int(100 * integ.t / self.t_end)
            if pct != self._pct:
                self._pct = pct
                self.progress(min(integ.t / self.t_end, 1.0))
        if integ.t < self._next and integ.t < self.t_end * (1 - 1e-12):
            return
        self._next = integ.t + self.t_end / SAMPLES
        # the energies at the samples only: each costs a product with every linear stiffness
        e = integ.energies()
        kinetic = sum(e["kinetic"].values())
        strain = sum(e["strain"].values())  # nonlinear blocks: the internal work
        works = sum(sum(e[k].values()) for k in ("external_work", "coupling_work",
                                                   "constraint_work", "damping_work"))  # fmt: skip
        total = kinetic + strain - works
        if self._e0 is None:
            self._e0 = total
        self.scale = max(self.scale, abs(kinetic + strain))
        self._scales.append(self.scale)
        self.balance.append(total - self._e0)
        elastic, plastic = strain, 0.0
        if self._j2_block is not None:
            # the J2 block's strain is its internal work: its elastic part and its dissipation
            stored, plastic = b.block_energies(integ.u, integ.states, e)
            elastic = strain - e["strain"][self._j2_block] + stored
        row = {"t": integ.t, "contact_force": force,
               "ball_velocity": b.ball_velocity(integ.v), "kinetic": kinetic,
               "elastic": elastic, "plastic_dissipation": plastic,
               "contact_work": float(getattr(st, "work", 0.0)),
               "coupling_work": float(sum(e["coupling_work"].values())),
               "friction_work": float(getattr(st, "friction_work", 0.0))}  # fmt: skip
        if self.adapt is not None:  # a sum over the coarse cells' areas: cheap
            row["patch_fraction"] = self.adapt.patch_fraction
        for k in self.keys:
            self.rows[k].append(float(row[k]))
        if self.csv is not None:
            self.csv.append(row)

    def on_adapt(self, integ, adapt) -> None:
        """The block's patch grew: the measures follow the new set-up, the balance moves by
        the growth's energy change (recorded with the growth)."""
        # the grown system and contact the integrator runs on (not built twice)
        contact = next((c for c in integ.unilateral if c.name == "contact"), None)
        self.bodies.regrow(adapt.problem, integ.system, contact)
        change = adapt.records[-1].energy_change
        if self._e0 is not None and change is not None:
            self._e0 += change

    def on_rewind(self, integ) -> None:
        """An interval was rejected, the integrator is back at its committed state: the steps
        and samples after its time are dropped (from ``impact.csv`` too), the running maxima
        (contact radius, energy scale; the peak force is taken from the kept steps) are those
        of the kept records."""
        t = integ.t
        n = int(np.searchsorted(self.times, t, side="right"))
        del self.times[n:], self.forces[n:], self._radii[n:]
        self.contact_radius = self._radii[-1] if n else 0.0
        m = int(np.searchsorted(self.rows["t"], t, side="right"))
        for values in self.rows.values():
            del values[m:]
        del self.balance[m:], self._scales[m:]
        self.scale = self._scales[-1] if m else 0.0
        self._next = self.rows["t"][-1] + self.t_end / SAMPLES if m else 0.0
        if not m:
            self._e0 = None
        if self.csv is not None:
            self.csv.truncate(m)
        self._pct = -1

    def result(self, res, wall: float, patch_fraction: float, hertz: dict,
               config: dict) -> BallImpactResult:  # fmt: skip
        """The run's :class:`BallImpactResult` from its records and its final state ``res``."""
        b = self.bodies
        t = np.asarray(self.times)
        force = np.asarray(self.forces)
        touching = np.nonzero(force > 0.0)[0]
        duration = float(t[touching[-1]]) if touching.size else 0.0
        if touching.size and touching[-1] == t.size - 1:
            raise ValueError(f"the ball is still in contact at the end of the run "
                             f"(t_end={t[-1]:.4g} s): give a longer t_end")  # fmt: skip
        max_eqps = band_eqps = 0.0
        where: list[float] | None = None
        part = b.plastic_part()
        if part is not None:
            eqps = res.states[part[1]][part[2]].eqps
            max_eqps = float(np.max(eqps))
            cell, point = np.unravel_index(int(np.argmax(eqps)), eqps.shape)
            where = np.asarray(part[0].quadrature_points())[:, cell, point].tolist()
            if b.band_cells.size:
                band_eqps = float(np.max(eqps[b.band_cells]))
        v0 = float(config.get("velocity", 0.0))  # the impact velocity, before any contact
        scale = max(self.scale, 1e-300)
        return BallImpactResult(
            contact_duration=duration, peak_force=float(force.max()) if force.size else 0.0,
            restitution=float(self.rows["ball_velocity"][-1] / v0) if v0 else 0.0,
            dent_depth=b.dent_depth(res.u), max_plastic_strain=max_eqps,
            energy_balance_error=float(np.max(np.abs(self.balance)) / scale),
            patch_fraction=float(patch_fraction), n_elements=b.n_elements, wall_time_s=wall,
            history={k: list(v) for k, v in self.rows.items()}, hertz=dict(hertz),
            n_steps=int(res.n_steps), fine_size=b.sizes.fine, coarse_size=b.sizes.coarse,
            contact_radius_cells=self.contact_radius / b.sizes.fine,
            band_max_plastic_strain=band_eqps, config=dict(config),
            band_plastic_fraction=res.band_plastic_fraction, max_plastic_strain_position=where,
            coarse_step_ratio=int(config.get("coarse_step_ratio", 1)),
            mean_step_ratio=float(np.mean(self.macro_ratios)) if self.macro_ratios else 1.0,
        )  # fmt: skip
