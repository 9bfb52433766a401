"""The registry of time integrators: a name or a class, like scipy's ``solve_ivp`` methods.

Integrator modules register their classes with :func:`register` when imported (the package
``arlequin.solvers`` imports them all); :func:`get_integrator` accepts a registered name or
an :class:`~arlequin.solvers.dynamics.base.Integrator` subclass.
"""

from __future__ import annotations

from collections.abc import Callable

from .base import Integrator

__all__ = ["REGISTRY", "get_integrator", "register"]

#: Registered integrator classes by name.
REGISTRY: dict[str, type[Integrator]] = {}


def register(*names: str) -> Callable[[type[Integrator]], type[Integrator]]:
    """Class decorator adding an integrator to :data:`REGISTRY` under ``names``."""

    def deco(cls: type[Integrator]) -> type[Integrator]:
        for n in names:
            REGISTRY[n] = cls
        return cls

    return deco


def get_integrator(name_or_class: str | type[Integrator]) -> type[Integrator]:
    """An integrator class from a registry name (``"explicit"``, ``"newmark"``...) or a class."""
    if isinstance(name_or_class, type) and issubclass(name_or_class, Integrator):
        return name_or_class
    if isinstance(name_or_class, str) and name_or_class in REGISTRY:
        return REGISTRY[name_or_class]
    raise ValueError(
        f"unknown integrator {name_or_class!r}; registered names are {sorted(REGISTRY)} "
        "(or pass an Integrator subclass)"
    )
