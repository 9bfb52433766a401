"""The options of the demos that grow their patch (``--adaptive`` and its four settings).

The pressure vessel, the plate with a hole and the ball impact declare the same five fields in
their configurations with these helpers (their defaults differ: the load steps or time steps
between checks, the plate's β, the cap), check them alike with :func:`check_adaptive_options`
and record them with :func:`adaptive_inputs`.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from .config import check_range, option

__all__ = [
    "adapt_buffer_option",
    "adapt_every_option",
    "adapt_threshold_option",
    "adaptive_inputs",
    "adaptive_option",
    "check_adaptive_options",
    "max_patch_fraction_option",
]


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
