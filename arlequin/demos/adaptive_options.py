"""The options of the demos that grow their patch (``--adaptive`` and its four settings).

The pressure vessel, the plate with a hole and the ball impact declare the same five fields in
their configurations with these helpers (their defaults differ: the load steps or time steps
between checks, the plate's β, the cap), check them alike with :func:`check_adaptive_options`
and record them with :func:`adaptive_inputs`.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from ..problem.adapt import AdaptivePatch
from .config import check_range, option

__all__ = [
    "ADAPTATIONS_UNIT",
    "adapt_buffer_option",
    "adapt_every_option",
    "adapt_threshold_option",
    "adaptive_inputs",
    "adaptive_option",
    "adaptive_patch",
    "check_adaptive_options",
    "fixed_patch",
    "growth_title",
    "max_patch_fraction_option",
]

#: The unit (description) of the results' ``adaptations`` list in results.json, the same for
#: the three demos (the entries of :meth:`arlequin.adapt.Adaptation.to_json`).
ADAPTATIONS_UNIT = (
    "list, one entry a growth: step (1, the step after which the patch grew), time (the "
    "committed state it grew from: load factor λ, 1, of a quasi-static run; time, s, of an "
    "explicit one), n_fine_elements (1), patch_fraction (1, the grown patch's share of the "
    "adaptive body's coarse-mesh area: the vessel's wall, the plate, the ball's block in "
    "(r, z)), energy_jump (1, relative change of the stored energy across the growth), "
    "rejected (the step after the growth was computed again), newton_iterations (1), "
    "rebuild_time_s, system_time_s, resolve_time_s, discarded_time_s (s)"
)


def adaptive_option(seed: str) -> Any:
    """``--adaptive``: off by default; ``seed`` says where the patch starts."""
    return option(False, f"adaptive patch: {seed}", "")


def adapt_threshold_option(default: float = 0.8) -> Any:
    """``--adapt-threshold BETA``: the fraction of σy at which coarse cells join the patch."""
    return option(default, "coarse cells whose von Mises stress reaches BETA σy join the patch",
                  "1", metavar="BETA")  # fmt: skip


def adapt_buffer_option(default: int = 1) -> Any:
    """``--adapt-buffer RINGS``: rings of coarse cells added around the flagged ones."""
    return option(default, "rings of coarse cells added around the flagged ones", "1",
                  metavar="RINGS")  # fmt: skip


def adapt_every_option(default: int, what: str) -> Any:
    """``--adapt-every N``: the checks' spacing, ``what`` completing its help."""
    return option(default, f"evaluate the indicator {what}", "1", metavar="N")


def max_patch_fraction_option(default: float, body: str) -> Any:
    """``--max-patch-fraction F``: the cap on the patch's share of ``body``."""
    return option(default, f"largest share of the {body} the adaptive patch may cover "
                  "(beyond: the run stops)", "1", metavar="F")  # fmt: skip


def _count(name: str, value: Any, low: int) -> None:
    ok = not isinstance(value, bool) and isinstance(value, (int, float)) and int(value) == value
    if not (ok and value >= low):
        raise ValueError(f"{name} must be an integer >= {low}, got {name}={value!r}")


_SETTINGS = ("adapt_threshold", "adapt_buffer", "adapt_every", "max_patch_fraction")


def check_adaptive_options(config: Any) -> None:
    """Refuse β outside (0, 1], a negative buffer, a spacing < 1 and a cap outside (0, 1]
    (checked with or without ``adaptive``, so a bad value never waits for the flag), and a
    setting other than its default without ``adaptive`` (it would be silently ignored)."""
    check_range("adapt_threshold", config.adapt_threshold, 0.0, 1.0, closed="(]")
    _count("adapt_buffer", config.adapt_buffer, 0)
    _count("adapt_every", config.adapt_every, 1)
    check_range("max_patch_fraction", config.max_patch_fraction, 0.0, 1.0, closed="(]")
    if config.adaptive:
        return
    defaults = {f.name: f.default for f in dataclasses.fields(config)}
    for name in _SETTINGS:
        value = getattr(config, name)
        if value != defaults[name]:
            flag = "--" + name.replace("_", "-")
            raise ValueError(f"{name}={value!r} ({flag}) applies to an adaptive patch only: "
                             "add --adaptive, or drop it")  # fmt: skip


def adaptive_inputs(config: Any) -> dict[str, Any]:
    """The four settings as plain JSON values."""
    return {"adapt_threshold": float(config.adapt_threshold),
            "adapt_buffer": int(config.adapt_buffer), "adapt_every": int(config.adapt_every),
            "max_patch_fraction": float(config.max_patch_fraction)}  # fmt: skip


def growth_title(count: int, load: str, rejected: bool, share: str) -> str:
    """The title of ``patch_K.png``: growth ``count``, the ``load`` it grew at (``"P = 150
    MPa"``, ``"t = 12 µs"``), ``"after a rejected step"`` when the step was computed again,
    and the patch's ``share`` (``"0.31 of the wall"``) on a second line (one line is
    clipped beside the colour bar)."""
    after = ", after a rejected step" if rejected else ""
    return f"growth {count} at {load}{after}\npatch: {share}"


def fixed_patch(config: Any, **changes: Any) -> Any:
    """``config`` without ``adaptive`` (its four settings back to their defaults, which a
    configuration without ``adaptive`` requires), with ``changes``: the fixed-patch probes
    an adaptive run makes (its first yield)."""
    defaults = {f.name: f.default for f in dataclasses.fields(config) if f.name in _SETTINGS}
    return dataclasses.replace(config, **{"adaptive": False, **defaults, **changes})


def adaptive_patch(config: Any, **options: Any) -> AdaptivePatch:
    """An :class:`~arlequin.problem.adapt.AdaptivePatch` with the configuration's four
    settings (β, buffer, spacing, cap) and the demo's own ``options`` (its refinement, model
    factory, closure, ...)."""
    return AdaptivePatch(threshold=config.adapt_threshold, buffer=config.adapt_buffer,
                         every=config.adapt_every, max_fraction=config.max_patch_fraction,
                         **options)  # fmt: skip
