"""Isotropic hardening laws σ_y(ε̄p, ε̄̇p) of J2 plasticity: the flow stress and its slope.

Every law gives the flow stress ``flow_stress(eqps, rate)`` (Pa) and its derivative with
respect to ε̄p, ``slope(eqps, rate)`` (Pa), vectorised over numpy arrays; ``rate`` is the
equivalent plastic strain rate ε̄̇p (1/s), used only by rate-dependent laws. The built-in laws
also give ``kernel_code`` and ``kernel_params``, their description for the compiled kernel
(:mod:`arlequin.models.plasticity.j2_kernel`); a user law (:class:`CallableHardening`) runs on the
numpy path only.

================  ==================================================================
``linear``        σ_y = σ_y0 + H ε̄p
``voce``          σ_y = σ_y0 + Q (1 − exp(−b ε̄p)) + H ε̄p
``johnson-cook``  σ_y = (A + B ε̄p^n)(1 + C ln(max(ε̄̇p / ε̄̇0, 1)))  (C = 0: rate independent)
================  ==================================================================
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = [
    "HARDENING_LAWS",
    "CallableHardening",
    "Hardening",
    "JohnsonCookHardening",
    "LinearHardening",
    "VoceHardening",
    "make_hardening",
]

#: ε̄p below which Johnson–Cook's slope n B ε̄p^(n−1) is evaluated at this value (it is
#: infinite at 0 for n < 1)
_JC_EQPS_FLOOR = 1e-9


def _number(name: str, value, positive: bool = False, nonnegative: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.number)):
        raise ValueError(f"{name} must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{name} must be finite, got {name}={value}")
    if positive and not value > 0.0:
        raise ValueError(f"{name} must be positive, got {name}={value}")
    if nonnegative and not value >= 0.0:
        raise ValueError(f"{name} must be >= 0, got {name}={value}")
    return value


class Hardening:
    """Base class of the hardening laws (see the module docstring)."""

    #: code of the law in the compiled kernel (None: numpy path only)
    kernel_code: int | None = None
    #: True if the flow stress depends on the plastic strain rate
    rate_dependent = False

    def flow_stress(self, eqps, rate=0.0):
        """σ_y (Pa) at ε̄p (dimensionless) and ε̄̇p (1/s)."""
        raise NotImplementedError

    def slope(self, eqps, rate=0.0):
        """∂σ_y/∂ε̄p (Pa) at ε̄p and ε̄̇p."""
        raise NotImplementedError

    def rate_slope(self, eqps, rate=0.0):
        """∂σ_y/∂ε̄̇p (Pa·s) at ε̄p and ε̄̇p (0 for rate-independent laws)."""
        return np.zeros_like(np.asarray(eqps, dtype=float))

    @property
    def initial_yield_stress(self) -> float:
        """σ_y(0) at a vanishing rate (Pa)."""
        return float(self.flow_stress(np.zeros(1))[0])

    @property
    def kernel_params(self) -> np.ndarray:
        """Parameters of the law for the compiled kernel, shape (6,)."""
        raise NotImplementedError


@dataclass(frozen=True)
class LinearHardening(Hardening):
    """σ_y = σ_y0 + H ε̄p.

    Parameters
    ----------
    yield_stress : float
        σ_y0 (Pa), > 0.
    modulus : float
        H (Pa), ≥ 0.
    """

    yield_stress: float
    modulus: float = 0.0
    kernel_code = 0

    def __post_init__(self) -> None:
        _number("yield_stress", self.yield_stress, positive=True)
        _number("hardening modulus", self.modulus, nonnegative=True)

    def flow_stress(self, eqps, rate=0.0):
        return self.yield_stress + self.modulus * np.asarray(eqps, dtype=float)

    def slope(self, eqps, rate=0.0):
        return np.full_like(np.asarray(eqps, dtype=float), self.modulus)

    @property
    def kernel_params(self) -> np.ndarray:
        return np.array([self.yield_stress, self.modulus, 0.0, 0.0, 0.0, 0.0])


@dataclass(frozen=True)
class VoceHardening(Hardening):
    """σ_y = σ_y0 + Q (1 − exp(−b ε̄p)) + H ε̄p (saturating, with an optional linear term).

    Parameters
    ----------
    yield_stress : float
        σ_y0 (Pa), > 0.
    saturation : float
        Q (Pa), ≥ 0: the stress the exponential term adds at saturation.
    rate : float
        b (dimensionless), > 0.
    modulus : float
        H (Pa), ≥ 0.
    """

    yield_stress: float
    saturation: float
    rate: float
    modulus: float = 0.0
    kernel_code = 1

    def __post_init__(self) -> None:
        _number("yield_stress", self.yield_stress, positive=True)
        _number("Voce saturation stress", self.saturation, nonnegative=True)
        _number("Voce rate", self.rate, positive=True)
        _number("hardening modulus", self.modulus, nonnegative=True)

    def flow_stress(self, eqps, rate=0.0):
        e = np.asarray(eqps, dtype=float)
        return (
            self.yield_stress + self.saturation * (1.0 - np.exp(-self.rate * e)) + self.modulus * e
        )

    def slope(self, eqps, rate=0.0):
        e = np.asarray(eqps, dtype=float)
        return self.saturation * self.rate * np.exp(-self.rate * e) + self.modulus

    @property
    def kernel_params(self) -> np.ndarray:
        return np.array([self.yield_stress, self.saturation, self.rate, self.modulus, 0.0, 0.0])


@dataclass(frozen=True)
class JohnsonCookHardening(Hardening):
    """σ_y = (A + B ε̄p^n)(1 + C ln(max(ε̄̇p/ε̄̇0, 1))); no thermal softening.

    Parameters
    ----------
    a : float
        A (Pa), > 0: the initial yield stress.
    b : float
        B (Pa), ≥ 0.
    n : float
        Exponent, > 0.
    c : float
        Strain-rate coefficient C (dimensionless), ≥ 0; 0 (default) turns the rate term off.
    reference_rate : float
        ε̄̇0 (1/s), > 0.
    """

    a: float
    b: float
    n: float
    c: float = 0.0
    reference_rate: float = 1.0
    kernel_code = 2

    def __post_init__(self) -> None:
        _number("Johnson-Cook A", self.a, positive=True)
        _number("Johnson-Cook B", self.b, nonnegative=True)
        _number("Johnson-Cook n", self.n, positive=True)
        _number("Johnson-Cook C", self.c, nonnegative=True)
        _number("Johnson-Cook reference rate", self.reference_rate, positive=True)

    @property
    def rate_dependent(self) -> bool:  # type: ignore[override]
        return self.c > 0.0

    def _rate_factor(self, rate):
        if self.c == 0.0:
            return 1.0
        ratio = np.maximum(np.asarray(rate, dtype=float) / self.reference_rate, 1.0)
        return 1.0 + self.c * np.log(ratio)

    def flow_stress(self, eqps, rate=0.0):
        e = np.maximum(np.asarray(eqps, dtype=float), 0.0)
        return (self.a + self.b * e**self.n) * self._rate_factor(rate)

    def slope(self, eqps, rate=0.0):
        e = np.maximum(np.asarray(eqps, dtype=float), _JC_EQPS_FLOOR)
        return self.n * self.b * e ** (self.n - 1.0) * self._rate_factor(rate)

    def rate_slope(self, eqps, rate=0.0):
        e = np.maximum(np.asarray(eqps, dtype=float), 0.0)
        r = np.asarray(rate, dtype=float)
        active = r > self.reference_rate
        return np.where(
            active, (self.a + self.b * e**self.n) * self.c / np.where(active, r, 1.0), 0.0
        )

    @property
    def kernel_params(self) -> np.ndarray:
        return np.array([self.a, self.b, self.n, self.c, self.reference_rate, _JC_EQPS_FLOOR])


@dataclass(frozen=True)
class CallableHardening(Hardening):
    """A user law: ``stress(eqps, rate)`` and its slope ``slope_fn(eqps, rate)`` (Pa), numpy
    vectorised (numpy path only).

    Parameters
    ----------
    stress : callable
        σ_y(ε̄p, ε̄̇p) (Pa).
    slope_fn : callable
        ∂σ_y/∂ε̄p (Pa), ≥ 0 for the return map to converge.
    rate_dependent : bool
        True if ``stress`` depends on ε̄̇p; then give ``rate_slope_fn``.
    rate_slope_fn : callable, optional
        ∂σ_y/∂ε̄̇p (Pa·s) (rate-dependent laws: the Newton iterations of the return need it).
    """

    stress: Callable
    slope_fn: Callable
    rate_dependent: bool = False  # type: ignore[assignment]
    rate_slope_fn: Callable | None = None

    def __post_init__(self) -> None:
        if not (callable(self.stress) and callable(self.slope_fn)):
            raise ValueError("CallableHardening needs the stress and its slope as callables")
        if self.rate_dependent and not callable(self.rate_slope_fn):
            raise ValueError(
                "a rate-dependent CallableHardening needs rate_slope_fn, ∂σ_y/∂ε̄̇p (Pa·s)"
            )
        s0 = np.asarray(self.stress(np.zeros(1), np.zeros(1)), dtype=float)
        if s0.shape != (1,) or not s0[0] > 0.0:
            raise ValueError(f"the initial flow stress must be positive, got {s0.tolist()}")

    def flow_stress(self, eqps, rate=0.0):
        e = np.asarray(eqps, dtype=float)
        return np.asarray(self.stress(e, np.broadcast_to(rate, e.shape)), dtype=float)

    def slope(self, eqps, rate=0.0):
        e = np.asarray(eqps, dtype=float)
        return np.asarray(self.slope_fn(e, np.broadcast_to(rate, e.shape)), dtype=float)

    def rate_slope(self, eqps, rate=0.0):
        e = np.asarray(eqps, dtype=float)
        if self.rate_slope_fn is None:
            return np.zeros_like(e)
        return np.asarray(self.rate_slope_fn(e, np.broadcast_to(rate, e.shape)), dtype=float)


#: Names of the built-in laws.
HARDENING_LAWS = ("linear", "voce", "johnson-cook")


def make_hardening(law: str, **params) -> Hardening:
    """A built-in law by name: ``linear`` (yield_stress, modulus), ``voce`` (yield_stress,
    saturation, rate, modulus), ``johnson-cook`` (a, b, n, c, reference_rate)."""
    classes = {
        "linear": LinearHardening,
        "voce": VoceHardening,
        "johnson-cook": JohnsonCookHardening,
    }
    if law not in classes:
        raise ValueError(f"hardening law must be one of {HARDENING_LAWS}, got {law!r}")
    return classes[law](**params)
