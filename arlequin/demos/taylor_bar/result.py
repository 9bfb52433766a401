"""The result of a Taylor bar run: :class:`TaylorBarResult`, the JSON keys, the reference.

SI units throughout.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ...io import JsonResult
from ...io.folder import jsonable

__all__ = [
    "ARLEQUIN_JSON_KEYS",
    "DERIVED_INPUT_UNITS",
    "GEOMETRIES",
    "JSON_KEYS",
    "MODELS",
    "RESULT_UNITS",
    "TAYLOR_REFERENCE",
    "GluingBandPlasticityWarning",
    "TaylorBarResult",
]

#: The keys of the JSON document of ``arlequin taylor-bar --json``, in their interface order.
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

#: The keys ``--model arlequin`` adds.
ARLEQUIN_JSON_KEYS = ("coarse_elements", "fine_elements", "coarse_size", "fine_size",
                      "patch_fraction")  # fmt: skip

#: The models of the bar.
MODELS = ("arlequin", "mono", "graded")

#: The bar's geometries: the (r, z) section, or the quarter bar of hexahedra.
GEOMETRIES = ("axisymmetric", "3d")


#: Units of the recorded inputs that are not parameters of the configuration (resolved counts
#: and sizes; the parameters' units come from the configuration's fields).
DERIVED_INPUT_UNITS = {
    "elements_axial": "1", "mesh_size": "m", "coarse_radial": "1", "coarse_axial": "1",
    "ratio": "1", "patch_rows": "1", "band_rows": "1", "epsilon": "1",
    "bulk_viscosity_linear": "1", "bulk_viscosity_quadratic": "1",
}  # fmt: skip

#: Units of the results written to results.json.
RESULT_UNITS = {
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


class GluingBandPlasticityWarning(UserWarning):
    """Plastic flow reached the gluing band, where the coarse (elastic) model is glued."""


#: Published converged values at 80 µs (3D, 1.5M elements), m.
TAYLOR_REFERENCE = {"final_length": 21.43e-3, "mushroom_radius": 7.23e-3}


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
        max over the records of abs(KE + W_el + D_p + D_visc + W_c − W_coupling − KE_0) / KE_0
        (W_coupling, the net work of the coupling forces, is 0 on one mesh).
    n_elements : int
        Cells of the mesh (``arlequin``: coarse and fine cells).
    mesh_size : float
        Cell edge across the radius, R / elements_radial (m) (``arlequin``: the fine size).
    n_steps : int
        Time steps taken.
    wall_time_s : float
        Wall time of the run (s): the integrator's set-up (the critical step of the initial
        configuration) and the explicit loop, compilation of the kernel excluded.
    history : dict
        Column -> list, one entry per record (every ``sample_interval``): t (s), length (m),
        radius (m), kinetic, elastic, plastic_dissipation, viscous_dissipation,
        coupling_work (``arlequin`` only: the net work of the mediator's forces), contact_work
        (J; contact_work = W_c ≥ 0, the energy removed by the wall), contact_force (N, the
        wall's axial force averaged since the previous record, from the accumulated impulse;
        at t = 0 that of the impulse stopping the face), dt (s, the step that ended there).
    elements_radial, elements_axial : int
        Cells of the finite-strain mesh across the radius and along the axis.
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
    fixed_point_iterations : dict or None
        The wall contact's fixed-point iterations per step: ``mean``, ``max`` and ``counts``
        (iterations -> steps).
    arlequin : dict or None
        ``arlequin`` (and, for its sizes, ``graded``), flattened into the JSON:
        coarse_elements, fine_elements, coarse_size and fine_size (m, edges across the radius),
        patch_fraction (p, the patch's share of the fine cells of a uniform mesh at its
        resolution), patch_length and gluing_width (m, as
        snapped to coarse rows), band_max_plastic_strain (largest ε̄p in the gluing band),
        multiplier_chatter (max_n abs(λ_n − (λ_{n−1} + λ_{n+1})/2) / max abs(λ) over the steps and
        mediator rows) and multiplier_chatter_per_row (the same against each row's own peak,
        rows whose peak exceeds 1% of the largest).
    model, u, state, setup : the finite-strain model, the final displacement of the whole
        system (m), the finite-strain model's final quadrature state and the set-up
        (:class:`~arlequin.demos.taylor_bar.models.MonoBar` or ``ArlequinBar``), not in the JSON.
    multiplier_history : MultiplierHistory or None
        ``arlequin``: the per-step mediator multipliers (not in the JSON).
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
    setup: Any = field(default=None, repr=False)
    arlequin: dict[str, Any] | None = None
    fixed_point_iterations: dict[str, Any] | None = None
    multiplier_history: Any = field(default=None, repr=False)

    json_exclude = ("model", "u", "state", "setup", "arlequin", "multiplier_history")

    def to_json(self) -> dict[str, Any]:
        """The JSON document: the interface keys first, then the Arlequin ones, then the rest."""
        data = super().to_json()
        # the Interface keys first, then the Arlequin ones (flat), then the rest
        extra = {k: jsonable(v) for k, v in (self.arlequin or {}).items()}
        return {**{k: data[k] for k in JSON_KEYS}, **extra,
                **{k: v for k, v in data.items() if k not in JSON_KEYS}}  # fmt: skip

    def summary(self) -> str:
        """One line: the model and its cells, the quantities of interest (against the published
        values when the run ends at 80 µs, the time they belong to), balance, steps, time."""
        ref = TAYLOR_REFERENCE
        model = self.config.get("model", "mono")
        cells = f"{self.elements_radial} x {self.elements_axial} finite-strain cells"
        if self.arlequin and model == "arlequin":
            cells = (f"patch {cells} + {self.arlequin['coarse_elements']} coarse elastic "
                     f"cells")  # fmt: skip
        elif model == "graded":
            cells = f"{self.n_elements} graded cells ({self.elements_radial} across the patch)"
        t_end = self.history["t"][-1] if self.history.get("t") else 0.0
        at_80 = abs(t_end - 80e-6) <= 1e-9
        vs_l = f" ({self.final_length / ref['final_length'] - 1:+.2%} vs 21.43)" if at_80 else ""
        vs_r = (f" ({self.mushroom_radius / ref['mushroom_radius'] - 1:+.2%} vs 7.23)"
                if at_80 else "")  # fmt: skip
        return (
            f"Taylor bar ({model}), {cells}, t = {t_end * 1e6:.1f} µs: final length "
            f"{self.final_length * 1e3:.3f} mm{vs_l}, footprint radius "
            f"{self.mushroom_radius * 1e3:.3f} mm{vs_r}, max plastic strain "
            f"{self.max_plastic_strain:.3f}, energy balance error {self.energy_balance_error:.2e}, "
            f"{self.n_steps} steps in {self.wall_time_s:.1f} s"
        )
